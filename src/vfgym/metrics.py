"""The measures of a move (MODEL.md §5), each with one written definition.

The kernel streams raw accumulators over every tick (:mod:`vfgym._layout`);
:func:`from_acc` turns them into the named measures below. :func:`from_trace` computes
the same measures from a full per-tick trace with numpy, independently, and serves as
the tests' oracle for the streamed values.

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
    max over ticks of |n_i − 2·n_(i−w) + n_(i−2w)|·δ/(w·T)², w = accel_window_s in ticks,
    the train at rest before tick 0: the pulse train's acceleration over a window w, whose
    one-pulse quantisation is ``accel_quantum_rad_s2`` = 2δ/(wT)².
peak_accel_motor_rad_s2
    max over ticks of |ω_(i+1) − ω_i|/T (exact mean acceleration over each tick).
accel_ratio_pulse, accel_ratio_motor
    the peaks over the motor's acceleration limit.
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
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from vfgym import _layout as L
from vfgym.params import Measures, Plant, in_position_rad
from vfgym.simulate import command_end_s

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


def accel_window_ticks(measures: Measures, plant: Plant) -> int:
    """The pulse-acceleration window w in ticks."""
    return max(1, round(measures.accel_window_s * plant.tick_hz))


def from_acc(
    acc: np.ndarray,
    plant: Plant,
    measures: Measures,
    target_rad: float,
    command_end_time_s: float,
) -> dict[str, Any]:
    """The named measures of one run from the kernel's streamed accumulator row."""
    f = plant.tick_hz
    T = plant.tick_s
    n = int(acc[L.A_TICKS])
    q = plant.motor.count_rad
    limit = plant.motor.accel_limit_rad_s2
    w = accel_window_ticks(measures, plant)
    ov = float(acc[L.A_OV_MOTOR])
    last_out = int(acc[L.A_LAST_OUT_MOTOR])
    last_out_p = int(acc[L.A_LAST_OUT_PULSE])
    move = (last_out + 1) * T
    pulses = int(acc[L.A_PULSES])
    first, last = int(acc[L.A_FIRST_PULSE]), int(acc[L.A_LAST_PULSE])
    min_iv = int(acc[L.A_MIN_INTERVAL])
    ss_n = max(1.0, float(acc[L.A_SS_COUNT]))
    rip_n = float(acc[L.A_RIPPLE_N])
    return {
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
        "accel_quantum_rad_s2": 2.0 * plant.pulse_rad / (w * T) ** 2,
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


def from_trace(trace: Any) -> dict[str, Any]:
    """The same measures from a full (undecimated) :class:`vfgym.Trace`, with numpy.

    Written from the definitions above without the kernel's streaming state; the tests
    compare it with :func:`from_acc`.
    """
    if trace.decimation != 1:
        raise ValueError("from_trace needs a trace with decimation=1")
    plant, measures = trace.plant, trace.measures
    f, T = plant.tick_hz, plant.tick_s
    P = trace.command_rad
    theta = trace.motor_rad
    n_pulses = trace.pulse_count
    pos = n_pulses * plant.pulse_rad
    n = P.size
    target = float(P[-1])
    win = in_position_rad(measures, plant, target)
    q = plant.motor.count_rad
    limit = plant.motor.accel_limit_rad_s2

    prev = np.concatenate([[0.0], P[:-1]])
    change = prev != P
    idx_change = np.flatnonzero(change)
    last_change = np.full(n, -1)
    last_change[idx_change] = idx_change
    last_change = np.maximum.accumulate(last_change)
    direction = np.where(last_change >= 0, np.sign(P[last_change] - prev[last_change]), 0.0)
    at_rest = (~change) & (direction != 0)

    def overshoot(x: np.ndarray) -> float:
        v = direction[at_rest] * (x[at_rest] - P[at_rest])
        return float(max(0.0, v.max())) if v.size else 0.0

    def last_out(x: np.ndarray) -> int:
        out = np.flatnonzero(np.abs(x - target) > win)
        return int(out[-1]) if out.size else -1

    ss_start = max(0, n - round(measures.steady_window_s * f))
    w = accel_window_ticks(measures, plant)
    padded = np.concatenate([np.zeros(2 * w, dtype=np.int64), n_pulses])
    d2 = np.abs(padded[2 * w :] - 2 * padded[w:-w] + padded[: -2 * w])
    speed = trace.speed_rad_s
    dw = np.abs(np.diff(np.concatenate([[0.0], speed])))

    # torque clipped: the command K3·u beyond what the curve allowed at last tick's speed
    m = plant.motor
    tau_cmd = plant.servo.torque_per_count_nm * trace.servo_error_counts
    w_prev = np.concatenate([[0.0], speed[:-1]])
    aw = np.abs(w_prev)
    slope = (m.torque_at_max_speed_nm - m.peak_torque_nm) / (m.max_speed_rad_s - m.knee_speed_rad_s)
    curve = np.where(
        aw <= m.knee_speed_rad_s,
        m.peak_torque_nm,
        np.where(aw < m.max_speed_rad_s, m.peak_torque_nm + slope * (aw - m.knee_speed_rad_s), 0.0),
    )
    lim = np.where(tau_cmd * w_prev > 0.0, curve, m.peak_torque_nm)
    sat = int(np.count_nonzero(np.abs(tau_cmd) > lim))

    ns = plant.servo.sample_ticks
    theta_start = np.concatenate([[0.0], theta[:-1]])  # θ at the start of each tick
    theta_samples = np.concatenate([[0.0], theta_start[ns - 1 :: ns]])
    vbar = np.diff(theta_samples) / (ns * T)
    d2v = vbar[2:] - 2 * vbar[1:-1] + vbar[:-2]

    ticks = np.flatnonzero(trace.pulses)
    signs = trace.pulses[ticks]
    lo = last_out(theta)
    move = (lo + 1) * T
    trk = P - theta
    trk_p = P - pos
    return {
        "overshoot_rad": overshoot(theta),
        "overshoot_pct": 100.0 * overshoot(theta) / abs(target) if target != 0 else math.nan,
        "overshoot_counts": overshoot(theta) / q,
        "pulse_overshoot_rad": overshoot(pos),
        "move_time_s": move,
        "settling_time_s": max(0.0, move - command_end_s(P, f)),
        "settled": lo < n - 1,
        "pulse_move_time_s": (last_out(pos) + 1) * T,
        "steady_state_error_rad": float(np.mean(theta[ss_start:] - target)),
        "pulse_steady_state_error_rad": float(np.mean(pos[ss_start:] - target)),
        "peak_accel_pulse_rad_s2": float(d2.max()) * plant.pulse_rad / (w * T) ** 2,
        "peak_accel_motor_rad_s2": float(dw.max()) / T,
        "accel_ratio_pulse": float(d2.max()) * plant.pulse_rad / (w * T) ** 2 / limit,
        "accel_ratio_motor": float(dw.max()) / T / limit,
        "accel_quantum_rad_s2": 2.0 * plant.pulse_rad / (w * T) ** 2,
        "torque_limit_time_s": sat * T,
        "tracking_rms_rad": float(np.sqrt(np.mean(trk**2))),
        "tracking_max_rad": float(np.abs(trk).max()),
        "pulse_tracking_rms_rad": float(np.sqrt(np.mean(trk_p**2))),
        "pulse_tracking_max_rad": float(np.abs(trk_p).max()),
        "velocity_ripple_rad_s": float(np.sqrt(np.mean(d2v**2) / 6.0)) if d2v.size else 0.0,
        "pulse_count": int(ticks.size),
        "pulse_reversals": int(np.count_nonzero(np.diff(signs))),
        "pulse_freq_max_hz": f / int(np.diff(ticks).min()) if ticks.size >= 2 else 0.0,
        "pulse_freq_mean_hz": (ticks.size - 1) * f / (ticks[-1] - ticks[0])
        if ticks.size >= 2
        else 0.0,
        "peak_torque_nm": float(np.abs(trace.torque_nm).max()),
        "peak_following_error_counts": float(np.abs(trace.position_counter).max()),
        "peak_speed_rad_s": float(np.abs(speed).max()),
        "final_error_rad": float(theta[-1]) - target,
        "pulse_final_error_rad": float(pos[-1]) - target,
    }


def of_trace(trace: Any) -> dict[str, Any]:
    """The streamed measures of a simulated :class:`vfgym.Trace` (any decimation)."""
    return from_acc(trace.acc, trace.plant, trace.measures, trace.target_rad, trace.command_end_s)
