"""vfgym: exact simulation and tuning of a V-F transformation pulse-train position controller.

The plant (``docs/model.md``): V-F controller (paper) → digital servo with a filtered speed
loop (patent) → motor, load and quadrature encoder; MCX514-style S-curve pulse source.

The package reads like its block diagram, ``params → simulate → trace → metrics → cost``:
:mod:`vfgym.params` and :mod:`vfgym.space` (the vocabulary), :mod:`vfgym.plant` (the
simulator), :mod:`vfgym.moves` (what the plant is asked to do), :mod:`vfgym.scoring` (the
one scoring path), then :mod:`vfgym.tuning`, :mod:`vfgym.report` and :mod:`vfgym.envs`
on top, :mod:`vfgym.permove` (per-move settings models, torch-free) above those, and
:mod:`vfgym.agents` (stable-baselines3) and :mod:`vfgym.commands` above the public API.

:func:`load_tuner` reads a per-move settings model (the shipped one by default) as a
callable from a move to its settings, without torch.
"""

from vfgym import envs  # importing envs registers vfgym/VFTune-v0, VFServo-v0
from vfgym.axis import LOADS_AXIS, PAPER_AXIS, Axis, load_axis
from vfgym.moves import baselines
from vfgym.moves.distribution import get_scenario, random_scenario, scenario_set
from vfgym.moves.pulse_sources import fixed_frequency_pulses, scurve_pulses
from vfgym.moves.scenarios import SCENARIOS, Scenario
from vfgym.params import (
    DEFAULT_MEASURES,
    PAPER_ACCEL_LIMIT_RAD_S2,
    PAPER_K,
    PAPER_PLANT,
    PAPER_PULSE_RAD,
    PAPER_SETTINGS,
    PAPER_STEP_RAD,
    PAPER_TICK_HZ,
    SGME_02A,
    Measures,
    Motor,
    Plant,
    Servo,
    Settings,
    Transmission,
    paper_k,
)
from vfgym.permove import load_tuner
from vfgym.plant import Trace, simulate, step_command, vf_pulses
from vfgym.scoring import Bounds, CostWeights, Evaluation, evaluate

__version__ = "0.1.0"

__all__ = [
    "DEFAULT_MEASURES",
    "LOADS_AXIS",
    "PAPER_ACCEL_LIMIT_RAD_S2",
    "PAPER_AXIS",
    "PAPER_K",
    "PAPER_PLANT",
    "PAPER_PULSE_RAD",
    "PAPER_SETTINGS",
    "PAPER_STEP_RAD",
    "PAPER_TICK_HZ",
    "SCENARIOS",
    "SGME_02A",
    "Axis",
    "Bounds",
    "CostWeights",
    "Evaluation",
    "Measures",
    "Motor",
    "Plant",
    "Scenario",
    "Servo",
    "Settings",
    "Trace",
    "Transmission",
    "baselines",
    "envs",
    "evaluate",
    "fixed_frequency_pulses",
    "get_scenario",
    "load_axis",
    "load_tuner",
    "paper_k",
    "random_scenario",
    "scenario_set",
    "scurve_pulses",
    "simulate",
    "step_command",
    "vf_pulses",
]
