"""The scoring path's cost, compiled: :func:`vfgym.scoring.score`'s formula on the loop
state of a move in progress, for the VFServo-v0 env's per-interval rewards.

The env cannot call :func:`~vfgym.scoring.score` every control interval (it runs inside
the compiled step, for thousands of envs at once), so the part of the cost that can be
known while the move runs is written here again, in numba, reading the kernel's loop
state (:mod:`vfgym.plant._layout`) and a row of constants (layout below) that
:func:`constants` fills from the same :class:`~vfgym.scoring.Yardsticks`,
:class:`~vfgym.scoring.CostWeights` and :class:`~vfgym.scoring.Bounds` that ``score``
reads. What it leaves out is the arrival term, known only at the scenario's end, which
``score`` adds (:func:`vfgym.scoring._cost.arrival_term`) in its one place.

``tests/scoring/test_cost_compiled.py`` holds the two copies together: on random states,
plants, weights, scenarios and on simulated moves, :func:`cost_terms` at the end of a
move equals ``score``'s terms one by one, and :func:`violated` equals "a running
constraint > 0".
"""

from __future__ import annotations

import math

import numpy as np

from vfgym.plant import _jit as J
from vfgym.plant import _layout as L
from vfgym.scoring._cost import Bounds, CostWeights, Yardsticks

_jit = J.jit

# --- the constants row -------------------------------------------------------------------
K_TICKS = 0  # ticks of the whole move: the RMS tracking error is over all of them
K_IDEAL = 1  # Yardsticks.ideal_time_s
K_WIN = 2  # Yardsticks.window_rad
K_LIMIT = 3  # Yardsticks.accel_limit_rad_s2 (Motor.usable_accel_rad_s2)
K_TRACKING = 4  # 1: a moving reference (Yardsticks.tracking)
K_TRK_SCALE = 5  # Yardsticks.tracking_scale_rad
K_W_TIME = 6  # CostWeights.time
K_W_TRACK = 7  # CostWeights.tracking
K_W_OV = 8  # CostWeights.overshoot
K_W_ACC = 9  # CostWeights.accel
K_W_TQ = 10  # CostWeights.torque
K_B_OV = 11  # Bounds.overshoot_windows
K_B_TQ = 12  # Bounds.torque_limit_time_s
K_ACC_TOL = 13  # Yardsticks.accel_tolerance
K_LOAD = 14  # 1: the load is judged (Yardsticks.load: the plant states a transmission)
N_CONST = 15


def constants(y: Yardsticks, n_ticks: int, weights: CostWeights, bounds: Bounds) -> np.ndarray:
    """The constants row of a move for :func:`cost_terms` and :func:`violated`.

    Parameters
    ----------
    y : Yardsticks
        The move's yardsticks (:func:`vfgym.scoring.yardsticks`).
    n_ticks : int
        Ticks of the move (the command's length).
    weights : CostWeights
    bounds : Bounds

    Returns
    -------
    numpy.ndarray
        float64, :data:`N_CONST` long.
    """
    k = np.zeros(N_CONST, dtype=np.float64)
    k[K_TICKS] = n_ticks
    k[K_IDEAL] = y.ideal_time_s
    k[K_WIN] = y.window_rad
    k[K_LIMIT] = y.accel_limit_rad_s2
    k[K_TRACKING] = 1.0 if y.tracking else 0.0
    k[K_TRK_SCALE] = y.tracking_scale_rad
    k[K_W_TIME] = weights.time
    k[K_W_TRACK] = weights.tracking
    k[K_W_OV] = weights.overshoot
    k[K_W_ACC] = weights.accel
    k[K_W_TQ] = weights.torque
    k[K_B_OV] = bounds.overshoot_windows
    k[K_B_TQ] = bounds.torque_limit_time_s
    k[K_ACC_TOL] = y.accel_tolerance
    k[K_LOAD] = 1.0 if y.load else 0.0
    return k


@_jit
def accel_excess(st, prm, k) -> float:
    """The accel constraint on the peak so far: ratio − 1 − tolerance."""
    return st[L.S_D2MX] * prm[L.P_ACC_SCALE] / k[K_LIMIT] - 1.0 - k[K_ACC_TOL]


@_jit
def torque_time(st, prm) -> float:
    """Time at the torque limit so far (s)."""
    return st[L.S_SAT] * prm[L.P_TICK_S]


@_jit
def overshoot_windows(st, k) -> float:
    """Overshoot so far in in-position windows (0 for a zero window), of the motor or,
    where it is judged, of the load."""
    win = k[K_WIN]
    ov = st[L.S_OVL] if k[K_LOAD] != 0.0 else st[L.S_OVM]
    return ov / win if win > 0.0 else 0.0


@_jit
def cost_terms(st, prm, k):
    """The running terms of the cost (main, overshoot, accel, torque) on the measures
    streamed so far; their sum in this order is :func:`running_cost`."""
    T = prm[L.P_TICK_S]
    ideal = k[K_IDEAL]
    load = k[K_LOAD] != 0.0  # the load's measures are judged, not the motor's
    if k[K_TRACKING] != 0.0:
        main = 0.0
        if k[K_TRK_SCALE] > 0.0:
            sq = st[L.S_TSQL] if load else st[L.S_TSQM]
            main = k[K_W_TRACK] * (math.sqrt(sq / k[K_TICKS]) / k[K_TRK_SCALE])
    else:
        last_out = st[L.S_LOL] if load else st[L.S_LOM]
        main = k[K_W_TIME] * (((last_out + 1.0) * T) / ideal)
    return (
        main,
        k[K_W_OV] * overshoot_windows(st, k),
        k[K_W_ACC] * max(0.0, accel_excess(st, prm, k)),
        k[K_W_TQ] * torque_time(st, prm) / ideal,
    )


@_jit
def running_cost(st, prm, k) -> float:
    """:func:`vfgym.scoring.score`'s cost on the measures streamed so far, without the
    arrival term (see the module docstring)."""
    main, ov, acc, tq = cost_terms(st, prm, k)
    return main + ov + acc + tq


@_jit
def running_constraints(st, prm, k):
    """The constraints that can be known while the move runs (accel, torque, overshoot),
    as :func:`vfgym.scoring.score` computes them."""
    return (
        accel_excess(st, prm, k),
        torque_time(st, prm) - k[K_B_TQ],
        overshoot_windows(st, k) - k[K_B_OV],
    )


@_jit
def violated(st, prm, k) -> bool:
    """A running constraint is already violated (> 0)."""
    c_acc, c_tq, c_ov = running_constraints(st, prm, k)
    return c_acc > 0.0 or c_tq > 0.0 or c_ov > 0.0


# The functions here read the loop state's slot numbers, compiled in as constants.
J.guard_cache(running_cost, (L,))
