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
axis
    One machine and its moves from a YAML file: the plant, the measures, and the train
    and test move sets (a list of moves or a random distribution).
"""

from vfgym.moves import axis, baselines, profiles, pulse_sources, scenarios
from vfgym.moves.axis import PAPER_AXIS, Axis, MoveSet, load_axis, write_axis
from vfgym.moves.pulse_sources import fixed_frequency_pulses, scurve_pulses
from vfgym.moves.scenarios import (
    SCENARIOS,
    MoveDistribution,
    Scenario,
    get_scenario,
    random_scenario,
    scenario_set,
)

__all__ = [
    "PAPER_AXIS",
    "SCENARIOS",
    "Axis",
    "MoveDistribution",
    "MoveSet",
    "Scenario",
    "axis",
    "baselines",
    "fixed_frequency_pulses",
    "get_scenario",
    "load_axis",
    "profiles",
    "pulse_sources",
    "random_scenario",
    "scenario_set",
    "scenarios",
    "scurve_pulses",
    "write_axis",
]
