"""Independent oracles the tests check vfgym against.

:func:`measures_from_trace` recomputes every streamed measure of :mod:`vfgym.plant.measures`
from a full per-tick trace with numpy, written from the definitions without the kernel's
streaming state.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from vfgym.params import in_position_rad
from vfgym.plant.measures import accel_window_ticks, command_end_s


def vf_position(trace: Any, n_pulses: np.ndarray) -> np.ndarray:
    """The V-F controller's unquantised train position (pulses) after each tick, rebuilt
    from the command and the pulse counts alone (docs/model.md §1, §5.1): the count plus
    the phase (Σ limited error − value · count) / value, held to ±1; the limited error
    re-derived from the error limit and the law."""
    s = trace.settings
    d, lim, step = trace.plant.pulse_rad, s.error_limit_rad, s.value_rad / s.k
    e_prev, total = 0.0, 0.0
    out = np.empty(n_pulses.size)
    before = np.concatenate([[0], n_pulses[:-1]])
    for i, (P, n0) in enumerate(zip(trace.command_rad, before, strict=True)):
        e = min(max(P - n0 * d, -lim), lim)
        if s.accel_law == "slew":
            e = min(max(e, e_prev - step), e_prev + step)
        else:
            if e_prev >= 0.0:
                e = min(e, e_prev + step)
            if e_prev <= 0.0:
                e = max(e, e_prev - step)
        e_prev = e
        total += e
        phase = (total - s.value_rad * n_pulses[i]) / s.value_rad
        out[i] = n_pulses[i] + min(max(phase, -1.0), 1.0)
    return out


def measures_from_trace(trace: Any) -> dict[str, Any]:
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
    limit = plant.motor.usable_accel_rad_s2

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
    w = accel_window_ticks(measures, plant, trace.external)
    x = n_pulses.astype(np.float64) if trace.external else vf_position(trace, n_pulses)
    padded = np.concatenate([np.zeros(2 * w), x])
    d2 = np.abs(padded[2 * w :] - 2 * padded[w:-w] + padded[: -2 * w])
    speed = trace.speed_rad_s
    dw = np.abs(np.diff(np.concatenate([[0.0], speed])))

    # torque clipped: the command K3·u beyond what the curve allowed at last tick's speed
    m = plant.motor
    tau_cmd = plant.torque_per_count_nm * trace.servo_error_counts
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
        "accel_quantum_rad_s2": 2.0 * plant.pulse_rad / (w * T) ** 2 if trace.external else 0.0,
        "accel_window_s": w * T,
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
