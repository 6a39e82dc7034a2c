"""The measures of a move (docs/model.md §5), each with one written definition.

The kernel streams raw accumulators over every tick (:mod:`vfgym.plant._layout`);
:func:`from_acc` turns them into the named measures below. The tests recompute the same
measures from a full per-tick trace with numpy, independently (``tests/oracles.py``), as
the oracle for the streamed values.

Conventions: the plant starts at rest at 0 rad; the *target* is the command's final value;
the in-position window is ``Measures.in_position_counts`` encoder counts around the target
(or ``in_position_pct`` % of the move); sample i is the state at the end of tick i,
time (i+1)·T.

Definitions
-----------
overshoot_rad
    max over the ticks at which the command is at rest (equal to its value on the
    previous tick) of d·(θ − P), where d is the sign of the command's last change;
    0 if never positive. A moving reference (a sine) has no at-rest ticks: use tracking.
    ``overshoot_pct`` is 100·overshoot/|target|, ``overshoot_counts`` in encoder counts;
    ``pulse_overshoot_rad`` is the same for the pulse position n·δ.
move_time_s
    time of the last sample outside the in-position window, (i+1)·T (0 if never out);
    ``settled`` is False when the last sample is still outside (then move_time_s is the
    run's duration: a lower bound). ``settling_time_s`` = move_time_s minus the time the
    command reached its final value. ``pulse_move_time_s``: the same for n·δ.
steady_state_error_rad
    mean of θ − target over the last ``steady_window_s`` (and ``pulse_…`` for n·δ).
peak_accel_pulse_rad_s2
    max over ticks of |x_i − 2·x_(i−w) + x_(i−2w)|·δ/(w·T)², the train at rest before
    tick 0, x the train's position in pulses (docs/model.md §5.1): for the V-F controller
    n + sum/value, its accumulated limited error over value, of which the pulse count n
    is the whole part (so no quantum: ``accel_quantum_rad_s2`` = 0); for an external
    train its count n, whose one-pulse quantum ``accel_quantum_rad_s2`` is 2δ/(wT)².
    w: :func:`accel_window_ticks`; ``accel_window_s`` reports w·T.
peak_accel_motor_rad_s2
    max over ticks of |ω_(i+1) − ω_i|/T (exact mean acceleration over each tick).
accel_ratio_pulse, accel_ratio_motor
    the peaks over the motor's acceleration limit. The acceleration constraint admits
    ``accel_ratio_pulse`` up to 1 + ``accel_tolerance_pct``/100, so a feasible run never
    reports more.
torque_limit_time_s
    ticks at which the torque command was clipped by the torque–speed curve, times T.
tracking_rms_rad, tracking_max_rad
    RMS and max over all ticks of P − θ (``pulse_tracking_…``: P − n·δ).
velocity_ripple_rad_s
    with v̄_k the motor's mean speed over servo sample period k, the RMS over k of
    (v̄_k − 2v̄_(k−1) + v̄_(k−2)), divided by √6: a constant acceleration contributes
    nothing, and independent per-period speed errors of standard deviation σ give σ.
    The patent's "torque unevenness" from the speed counter's ±1 count jitter shows here.
pulse_count, pulse_reversals, pulse_freq_max_hz, pulse_freq_mean_hz
    pulses output (either sign); sign changes between consecutive pulses; f over the
    shortest interval between two pulses; (pulses − 1)·f over the ticks from the first
    to the last pulse (0 with fewer than two pulses).
peak_torque_nm, peak_following_error_counts, peak_speed_rad_s
    max |τ|, max |position counter|, max |ω|.
final_error_rad, pulse_final_error_rad
    θ − target and n·δ − target after the last tick.

The load's measures (:data:`LOAD_NAMES`), only where the plant states a transmission: the
load's angle θ_L beyond the spring, at the motor shaft (docs/model.md §3.1), which the
encoder does not see.

load_overshoot_rad, load_overshoot_counts
    overshoot_rad's definition on θ_L.
load_move_time_s, load_settling_time_s, load_settled
    move_time_s's on θ_L: the last sample at which the load is outside the in-position
    window, the same window as the motor's.
load_residual_vibration_rad, load_residual_vibration_counts, load_residual_vibration_um
    the residual vibration: peak to peak of θ_L from the motor's move time (the first
    sample after its last outside the window: the encoder reads "in position" from there)
    to the run's end, in rad, in encoder counts, and in µm of travel where the
    transmission states ``travel_mm_per_rad`` (else NaN). 0 when the motor never settles
    (``settled`` false: nothing is residual).
load_tracking_rms_rad, load_tracking_max_rad
    RMS and max over all ticks of P − θ_L.
load_final_error_rad
    θ_L − target after the last tick.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from vfgym.params import Measures, Plant
from vfgym.plant import _layout as L

NAMES = (
    "overshoot_rad",
    "overshoot_pct",
    "overshoot_counts",
    "pulse_overshoot_rad",
    "move_time_s",
    "settling_time_s",
    "settled",
    "pulse_move_time_s",
    "steady_state_error_rad",
    "pulse_steady_state_error_rad",
    "peak_accel_pulse_rad_s2",
    "peak_accel_motor_rad_s2",
    "accel_ratio_pulse",
    "accel_ratio_motor",
    "accel_quantum_rad_s2",
    "accel_window_s",
    "torque_limit_time_s",
    "tracking_rms_rad",
    "tracking_max_rad",
    "pulse_tracking_rms_rad",
    "pulse_tracking_max_rad",
    "velocity_ripple_rad_s",
    "pulse_count",
    "pulse_reversals",
    "pulse_freq_max_hz",
    "pulse_freq_mean_hz",
    "peak_torque_nm",
    "peak_following_error_counts",
    "peak_speed_rad_s",
    "final_error_rad",
    "pulse_final_error_rad",
)


LOAD_NAMES = (
    "load_overshoot_rad",
    "load_overshoot_counts",
    "load_move_time_s",
    "load_settling_time_s",
    "load_settled",
    "load_residual_vibration_rad",
    "load_residual_vibration_counts",
    "load_residual_vibration_um",
    "load_tracking_rms_rad",
    "load_tracking_max_rad",
    "load_final_error_rad",
)
"""The load's measures, which :func:`from_acc` adds where the plant states a transmission."""


def accel_window_ticks(measures: Measures, plant: Plant, external: bool = False) -> int:
    """The pulse-acceleration window w in ticks (docs/model.md §5.1).

    The V-F controller's train position is not quantised, so its window is
    ``accel_window_s``. An external train is known only by its whole pulse counts, whose
    second difference over w ticks is off by up to two pulses, a quantum of 2δ/(wT)²:
    its window is the shortest of at least ``accel_window_s`` whose quantum is at most
    ``accel_tolerance_pct`` % of the loaded limit a, w ≥ √(2δ / (tol·a)) · f.

    Parameters
    ----------
    measures : Measures
        The window and the tolerance.
    plant : Plant
        The plant with the move's load (δ, f and the usable acceleration).
    external : bool
        An external pulse train (counts only) rather than the V-F controller.

    Returns
    -------
    int
        w in ticks, ≥ 1.
    """
    f = plant.tick_hz
    w = max(1, round(measures.accel_window_s * f))
    if not external:
        return w
    tol = measures.accel_tolerance_pct / 100.0
    shortest_s = math.sqrt(2.0 * plant.pulse_rad / (tol * plant.motor.usable_accel_rad_s2))
    return max(w, math.ceil(shortest_s * f))


def from_acc(
    acc: np.ndarray,
    plant: Plant,
    measures: Measures,
    target_rad: float,
    command_end_time_s: float,
) -> dict[str, Any]:
    """The named measures of one run from the kernel's streamed accumulator row
    (:data:`NAMES`, and :data:`LOAD_NAMES` where the plant states a transmission)."""
    f = plant.tick_hz
    T = plant.tick_s
    n = int(acc[L.A_TICKS])
    q = plant.motor.count_rad
    limit = plant.motor.usable_accel_rad_s2
    w = int(acc[L.A_ACC_WINDOW])
    ov = float(acc[L.A_OV_MOTOR])
    last_out = int(acc[L.A_LAST_OUT_MOTOR])
    last_out_p = int(acc[L.A_LAST_OUT_PULSE])
    move = (last_out + 1) * T
    pulses = int(acc[L.A_PULSES])
    first, last = int(acc[L.A_FIRST_PULSE]), int(acc[L.A_LAST_PULSE])
    min_iv = int(acc[L.A_MIN_INTERVAL])
    ss_n = max(1.0, float(acc[L.A_SS_COUNT]))
    rip_n = float(acc[L.A_RIPPLE_N])
    out = {
        "overshoot_rad": ov,
        "overshoot_pct": 100.0 * ov / abs(target_rad) if target_rad != 0.0 else math.nan,
        "overshoot_counts": ov / q,
        "pulse_overshoot_rad": float(acc[L.A_OV_PULSE]),
        "move_time_s": move,
        "settling_time_s": max(0.0, move - command_end_time_s),
        "settled": last_out < n - 1,
        "pulse_move_time_s": (last_out_p + 1) * T,
        "steady_state_error_rad": float(acc[L.A_SS_SUM_MOTOR]) / ss_n,
        "pulse_steady_state_error_rad": float(acc[L.A_SS_SUM_PULSE]) / ss_n,
        "peak_accel_pulse_rad_s2": float(acc[L.A_ACC_PULSE]),
        "peak_accel_motor_rad_s2": float(acc[L.A_ACC_MOTOR]),
        "accel_ratio_pulse": float(acc[L.A_ACC_PULSE]) / limit,
        "accel_ratio_motor": float(acc[L.A_ACC_MOTOR]) / limit,
        "accel_quantum_rad_s2": float(acc[L.A_ACC_QUANTUM]),
        "accel_window_s": w * T,
        "torque_limit_time_s": float(acc[L.A_SAT_TICKS]) * T,
        "tracking_rms_rad": math.sqrt(float(acc[L.A_TRK_SQ_MOTOR]) / n),
        "tracking_max_rad": float(acc[L.A_TRK_MAX_MOTOR]),
        "pulse_tracking_rms_rad": math.sqrt(float(acc[L.A_TRK_SQ_PULSE]) / n),
        "pulse_tracking_max_rad": float(acc[L.A_TRK_MAX_PULSE]),
        "velocity_ripple_rad_s": math.sqrt(float(acc[L.A_RIPPLE_SQ]) / (6.0 * rip_n))
        if rip_n > 0
        else 0.0,
        "pulse_count": pulses,
        "pulse_reversals": int(acc[L.A_REVERSALS]),
        "pulse_freq_max_hz": f / min_iv if min_iv > 0 else 0.0,
        "pulse_freq_mean_hz": (pulses - 1) * f / (last - first) if pulses >= 2 else 0.0,
        "peak_torque_nm": float(acc[L.A_TORQUE_MAX]),
        "peak_following_error_counts": float(acc[L.A_PC_MAX]),
        "peak_speed_rad_s": float(acc[L.A_SPEED_MAX]),
        "final_error_rad": float(acc[L.A_THETA]) - target_rad,
        "pulse_final_error_rad": float(acc[L.A_N]) * plant.pulse_rad - target_rad,
    }
    tr = plant.transmission
    if tr is None:
        return out
    ov_l = float(acc[L.A_OV_LOAD])
    last_out_l = int(acc[L.A_LAST_OUT_LOAD])
    move_l = (last_out_l + 1) * T
    resid = float(acc[L.A_RESIDUAL]) if last_out < n - 1 else 0.0
    out |= {
        "load_overshoot_rad": ov_l,
        "load_overshoot_counts": ov_l / q,
        "load_move_time_s": move_l,
        "load_settling_time_s": max(0.0, move_l - command_end_time_s),
        "load_settled": last_out_l < n - 1,
        "load_residual_vibration_rad": resid,
        "load_residual_vibration_counts": resid / q,
        "load_residual_vibration_um": (
            resid * tr.travel_mm_per_rad * 1e3 if tr.travel_mm_per_rad is not None else math.nan
        ),
        "load_tracking_rms_rad": math.sqrt(float(acc[L.A_TRK_SQ_LOAD]) / n),
        "load_tracking_max_rad": float(acc[L.A_TRK_MAX_LOAD]),
        "load_final_error_rad": float(acc[L.A_LOAD]) - target_rad,
    }
    return out


def command_end_s(command: np.ndarray, tick_hz: float) -> float:
    """Time at which the command reached its final value.

    Parameters
    ----------
    command : numpy.ndarray
        Position command per tick (rad).
    tick_hz : float
        Controller tick rate f (Hz).

    Returns
    -------
    float
        The tick of the command's last change times T (s). The plant starts at rest at
        0, so a step at tick 0 ends at 0, and a command that is 0 throughout at 0.
    """
    c = np.concatenate([[0.0], np.asarray(command, dtype=np.float64)])
    changes = np.flatnonzero(c[1:] != c[:-1])
    return float(changes[-1]) / tick_hz if changes.size else 0.0
