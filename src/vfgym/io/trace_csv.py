"""Per-tick traces as CSV, one row per kept tick."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

# The traces written here are vfgym.Trace, typed as Any: io sits below plant
# (docs/architecture.md) and imports nothing of vfgym, not even for type checking.

TRACE_FIELDS = (
    "tick",
    "time_s",
    "command_rad",
    "pulse",
    "pulse_count",
    "pulse_rad",
    "motor_rad",
    "encoder_count",
    "speed_rad_s",
    "torque_nm",
    "servo_error_counts",
    "position_counter",
    "feedback_counts",
    "speed_count",
    "train_rad",
)
"""Columns of a trace CSV: sample j is the state at the end of tick ``tick`` (time
(tick+1)·T); ``pulse`` is that tick's pulse (−1, 0, +1; empty when decimated),
``encoder_count`` = floor(θ / count angle), the count the servo sees; ``train_rad`` the
pulse train's unquantised position (docs/model.md §5.1). A trace of a plant that states
a transmission adds :data:`LOAD_FIELDS`."""

LOAD_FIELDS = ("load_rad", "load_speed_rad_s", "load_mm")
"""The load's columns, after :data:`TRACE_FIELDS`, where the plant states a transmission
(docs/model.md §3.1): the load's angle θ_L beyond the spring and its speed, at the motor
shaft (rad, rad/s), and its position in mm of travel, θ_L · ``travel_mm_per_rad``, where
the transmission states that (else the column is left out)."""


def trace_columns(trace: Any) -> dict[str, np.ndarray]:
    """A :class:`vfgym.Trace` as named per-sample columns, in the CSV's order
    (:data:`TRACE_FIELDS`, then the load's where the plant states a transmission,
    :data:`LOAD_FIELDS`)."""
    n = trace.time_s.size
    dec = trace.decimation
    q = trace.plant.motor.count_rad
    cols: dict[str, np.ndarray] = {
        "tick": (np.arange(n, dtype=np.int64) + 1) * dec - 1,
        "time_s": trace.time_s,
        "command_rad": trace.command_rad,
        "pulse": trace.pulses if dec == 1 else np.zeros(0),
        "pulse_count": trace.pulse_count,
        "pulse_rad": trace.pulse_rad,
        "motor_rad": trace.motor_rad,
        "encoder_count": np.floor(trace.motor_rad / q).astype(np.int64),
        "speed_rad_s": trace.speed_rad_s,
        "torque_nm": trace.torque_nm,
        "servo_error_counts": trace.servo_error_counts,
        "position_counter": trace.position_counter,
        "feedback_counts": trace.feedback_counts,
        "speed_count": trace.speed_count,
        "train_rad": trace.train_rad,
    }
    tr = trace.plant.transmission
    if tr is not None:
        cols["load_rad"] = trace.load_rad
        cols["load_speed_rad_s"] = trace.load_speed_rad_s
        if tr.travel_mm_per_rad is not None:
            cols["load_mm"] = trace.load_rad * tr.travel_mm_per_rad
    return cols


def write_trace_csv(trace: Any, path: str | Path) -> Path:
    """Write a trace's per-sample columns as CSV (floats with 17 significant digits, so
    the file reads back bit for bit)."""
    from vfgym.io.runs import write_text

    cols = trace_columns(trace)
    names = tuple(cols)
    n = trace.time_s.size
    parts = []
    for name in names:
        c = cols[name]
        if c.size == 0:
            parts.append(np.full(n, "", dtype=object))
        elif np.issubdtype(c.dtype, np.integer):
            parts.append(c.astype(str))
        else:
            parts.append(np.char.mod("%.17g", c))
    body = "\n".join(",".join(row) for row in zip(*parts, strict=True))
    return write_text(path, ",".join(names) + "\n" + body + "\n")
