"""What the plant is asked to do: commands, pulse sources, scenarios and baselines.

Modules
-------
profiles
    Position commands, one value per controller tick (step, trapezoid, S-curve, sine …).
pulse_sources
    Pulse trains that replace the V-F controller (fixed frequency, MCX514 S-curve).
scenarios
    Named frozen moves (a command and the plant it drives) and the seeded random
    distribution with disjoint train and test splits.
baselines
    What tuned settings are judged against: the paper's settings, a rule of thumb, a
    fixed-frequency train and the S-curve source.

An axis (one machine, its moves and what it does not know) is :mod:`vfgym.axis`, the layer
above this one.
"""

from vfgym.moves import baselines, profiles, pulse_sources, scenarios
from vfgym.moves.distribution import (
    DEFAULT_DISTRIBUTION,
    LOAD_DISTRIBUTION,
    MoveDistribution,
    get_scenario,
    random_scenario,
    scenario_set,
)
from vfgym.moves.pulse_sources import fixed_frequency_pulses, scurve_pulses
from vfgym.moves.scenarios import SCENARIOS, Scenario

__all__ = [
    "DEFAULT_DISTRIBUTION",
    "LOAD_DISTRIBUTION",
    "SCENARIOS",
    "MoveDistribution",
    "Scenario",
    "baselines",
    "fixed_frequency_pulses",
    "get_scenario",
    "profiles",
    "pulse_sources",
    "random_scenario",
    "scenario_set",
    "scenarios",
    "scurve_pulses",
]
