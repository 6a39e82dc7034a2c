"""The one scoring path: controller settings → simulate → measures → constraints → cost.

:func:`evaluate` is what every part of vfgym asks "how good is this setting on this move":
the Gymnasium envs' reward, the Optuna objective and constraints, and the evaluation
reports. It takes a batch of controllers (V-F :class:`~vfgym.Settings` or a baseline pulse
source) and a list of scenarios, runs every pair in one compiled, multi-threaded call
that keeps only the streamed measures, and returns them with the constraint values, the
objectives and the scalar cost.

Cost of one run (lower is better; weights in :class:`CostWeights`)::

    cost = time · move_time / ideal_time          (point-to-point moves)
         | tracking · rms_tracking / (10 % of |amplitude|)  (a moving reference)
         + overshoot · overshoot / in-position window
         + accel · max(0, accel constraint)
         + torque · time at the torque limit / ideal_time
         + unsettled · [not settled at the end]

ideal_time is the bang–coast–bang time at δ·f and the motor's acceleration limit, so a
perfect move costs about 1 whatever its length, and scenarios average fairly.

Constraints (feasible when ≤ 0; :class:`Bounds`):

- ``accel``: peak pulse-train acceleration / limit − 1 − its one-pulse quantisation / limit
- ``torque``: time at the torque limit − ``Bounds.torque_limit_time_s``
- ``overshoot``: overshoot − ``Bounds.overshoot_windows`` in-position windows

Objectives (all minimised): overshoot in in-position windows, move time / ideal time
(tracking ratio for a moving reference), acceleration violation max(0, accel constraint).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from vfgym.moves.scenarios import Scenario
from vfgym.params import (
    Measures,
    Plant,
    in_position_rad,
)

CONSTRAINTS = ("accel", "torque", "overshoot")
OBJECTIVES = ("overshoot_windows", "time_ratio", "accel_violation")


@dataclass(frozen=True)
class CostWeights:
    """Weights of the scalar cost (the formula: the module docstring, docs/model.md §6).

    Parameters
    ----------
    time : float
        Weight of move time / ideal time (point-to-point moves).
    tracking : float
        Weight of RMS tracking error / 10 % of the amplitude (a moving reference).
    overshoot : float
        Weight of the overshoot in in-position windows.
    accel : float
        Weight of the acceleration violation max(0, accel constraint).
    torque : float
        Weight of the time at the torque limit / ideal time.
    unsettled : float
        Added when the move has not settled by the end of the run.
    """

    time: float = 1.0
    tracking: float = 1.0
    overshoot: float = 0.1
    accel: float = 5.0
    torque: float = 1.0
    unsettled: float = 5.0


@dataclass(frozen=True)
class Bounds:
    """Bounds of the constraints (feasible when each constraint ≤ 0; docs/model.md §6).

    Parameters
    ----------
    overshoot_windows : float
        Overshoot allowed, in in-position windows.
    torque_limit_time_s : float
        Time allowed at the torque limit (s).
    """

    overshoot_windows: float = 1.0
    torque_limit_time_s: float = 0.0


DEFAULT_WEIGHTS = CostWeights()
DEFAULT_BOUNDS = Bounds()


def score(
    m: dict[str, Any],
    scenario: Scenario,
    plant: Plant,
    measures: Measures,
    weights: CostWeights = DEFAULT_WEIGHTS,
    bounds: Bounds = DEFAULT_BOUNDS,
) -> tuple[float, np.ndarray, np.ndarray, dict[str, float]]:
    """Cost, constraints and objectives of one run's measures (docs/model.md §6).

    Parameters
    ----------
    m : dict
        The run's measures, as :attr:`vfgym.Trace.metrics` gives them.
    scenario : Scenario
        The scenario run (point-to-point or a moving reference; its ideal time).
    plant : Plant
        The plant it ran on (acceleration limit, encoder count).
    measures : Measures
        Windows and bands the measures were taken with (the in-position window).
    weights : CostWeights
        Weights of the cost.
    bounds : Bounds
        Bounds of the constraints.

    Returns
    -------
    tuple
        ``(cost, constraints, objectives, extra)``: the scalar cost (float); the
        constraint values in the order of :data:`CONSTRAINTS` and the objectives in the
        order of :data:`OBJECTIVES` (float arrays of 3); and ``extra``, a dict with
        ``ideal_time_s``, ``time_ratio`` and ``window_rad``.
    """
    ideal = scenario.ideal_time_s(plant)
    window = in_position_rad(measures, plant, scenario.command(plant)[-1])
    limit = plant.motor.usable_accel_rad_s2
    c_acc = m["accel_ratio_pulse"] - 1.0 - m["accel_quantum_rad_s2"] / limit
    c_tq = m["torque_limit_time_s"] - bounds.torque_limit_time_s
    ov_w = m["overshoot_rad"] / window if window > 0 else 0.0
    c_ov = ov_w - bounds.overshoot_windows
    if scenario.tracking:
        ratio = m["tracking_rms_rad"] / (0.1 * abs(scenario.distance_rad))
        main = weights.tracking * ratio
    else:
        ratio = m["move_time_s"] / ideal
        main = weights.time * ratio + (0.0 if m["settled"] else weights.unsettled)
    cost = (
        main
        + weights.overshoot * ov_w
        + weights.accel * max(0.0, c_acc)
        + weights.torque * m["torque_limit_time_s"] / ideal
    )
    extra = {"ideal_time_s": ideal, "time_ratio": ratio, "window_rad": window}
    return cost, np.array([c_acc, c_tq, c_ov]), np.array([ov_w, ratio, max(0.0, c_acc)]), extra
