"""vfgym: exact simulation and tuning of a V-F transformation pulse-train position controller.

The plant (MODEL.md): V-F controller (paper) → digital servo with a filtered speed loop
(patent) → motor, load and quadrature encoder; MCX514-style S-curve pulse source.
"""

from vfgym import baselines, envs  # importing envs registers vfgym/VFTune-v0, VFServo-v0
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
    paper_k,
)
from vfgym.pulse_sources import fixed_frequency_pulses, scurve_pulses
from vfgym.scenarios import SCENARIOS, Scenario, get_scenario, random_scenario, scenario_set
from vfgym.scoring import Bounds, CostWeights, Evaluation, evaluate
from vfgym.simulate import Trace, simulate, step_command, vf_pulses

__version__ = "0.1.0"

__all__ = [
    "DEFAULT_MEASURES",
    "PAPER_ACCEL_LIMIT_RAD_S2",
    "PAPER_K",
    "PAPER_PLANT",
    "PAPER_PULSE_RAD",
    "PAPER_SETTINGS",
    "PAPER_STEP_RAD",
    "PAPER_TICK_HZ",
    "SCENARIOS",
    "SGME_02A",
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
    "baselines",
    "envs",
    "evaluate",
    "fixed_frequency_pulses",
    "get_scenario",
    "paper_k",
    "random_scenario",
    "scenario_set",
    "scurve_pulses",
    "simulate",
    "step_command",
    "vf_pulses",
]
