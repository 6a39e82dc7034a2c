"""Pulse sources that replace the V-F controller: one entry per controller tick.

Each source returns a numpy ``int8`` array with one entry per controller tick of
``1/tick_hz`` seconds, holding 0 or +1 (at most one pulse per tick; the caller negates the
train for a move in the negative direction). The digital servo takes such a train as its
movement command, exactly as it takes the V-F controller's output.

- :func:`scurve_pulses`: what a motion-control IC such as the NOVA MCX514 outputs in
  *S-curve fixed-pulse driving* with symmetric acceleration and deceleration and
  *triangle form prevention* (the profile itself: :mod:`vfgym.moves.scurve`). This is the
  industrial reference the V-F controller is compared against.
- :func:`fixed_frequency_pulses`: the common PLC practice the paper improves on, a
  constant pulse frequency for the whole move, with no acceleration ramp at all.

The S-curve train is computed from the exact continuous-time position ``p(t)`` (pulses,
piecewise cubic in time) sampled at the tick boundaries ``t_i = i/tick_hz``: tick ``i``
holds ``round(p(t_{i+1})) - round(p(t_i))`` pulses, with ``round(x) = floor(x + 1/2)``.
The cumulative count after any tick is the exact position rounded to the nearest pulse
(never more than half a pulse off), and pulse ``j`` is output in the tick where ``p``
passes ``j - 1/2``. Rounding rather than ``floor`` makes the train itself mirror
symmetric, as the profile is: the crossings of ``j - 1/2`` and ``P - j + 1/2`` sit at
mirror times, whereas with ``floor`` the first pulse would wait for ``p = 1`` (a whole
pulse period at the initial speed) while the last came at the very end of the move.

Units: speeds in pulses per second (pps), acceleration in pps/s, jerk in pps/s²,
times in seconds, ticks counted from 0.
"""

from __future__ import annotations

import math

import numpy as np

from vfgym._validate import check_int, check_real
from vfgym.moves.scurve import (
    _FLOOR_GUARD_ABS,
    _FLOOR_GUARD_REL,
    MAX_TICKS,
    ScurveProfile,
    scurve_profile,
)

__all__ = [
    "MAX_TICKS",
    "ScurveProfile",
    "fixed_frequency_pulses",
    "scurve_profile",
    "scurve_pulses",
]


def _counts_of_train(counts: np.ndarray, n_ticks: int, total: int) -> np.ndarray:
    """Cumulative counts at tick boundaries made a train's, at most one pulse per tick:
    the counts at boundaries 0 … length (length ≥ ``n_ticks``), starting at 0.

    ``counts`` holds samples past ``n_ticks``. Clamping and the one-per-tick cap only
    act on rounding artefacts (an increment of exactly one pulse per tick at
    ``DV = tick_hz``); the train is extended if the cap delays the last pulse.
    """
    counts = np.clip(counts, 0, total)
    counts = np.maximum.accumulate(counts)
    idx = np.arange(counts.size, dtype=np.int64)
    counts = idx + np.minimum.accumulate(counts - idx)
    done = np.flatnonzero(counts >= total)
    if done.size == 0:  # pragma: no cover - the padding always suffices
        raise RuntimeError("pulse train did not reach its pulse count")
    length = max(n_ticks, int(done[0]))
    return counts[: length + 1]


def scurve_pulses(
    total_pulses: int,
    *,
    initial_speed_pps: float,
    drive_speed_pps: float,
    jerk_pps3: float,
    tick_hz: float,
    triangle_prevention: bool = True,
    stop_tick: int | None = None,
) -> np.ndarray:
    """Pulse train of an MCX514-style S-curve fixed-pulse move, one entry per tick.

    The acceleration phase takes ``ta = 2 sqrt((DV - SV) / J)`` seconds and
    ``Pa = (DV + SV) sqrt((DV - SV) / J)`` pulses when the move reaches the drive speed;
    the deceleration is its mirror image. See :func:`scurve_profile` for the short-move
    and stop cases, and docs/model.md §4.

    Parameters
    ----------
    total_pulses : int
        Pulses to output, a whole number >= 1.
    initial_speed_pps : float
        Initial speed ``SV``, pps, in ``(0, drive_speed_pps]`` (the IC cannot start from
        speed 0).
    drive_speed_pps : float
        Drive speed ``DV``, pps, in ``(0, tick_hz]`` (one pulse per tick at most).
    jerk_pps3 : float
        Jerk ``J``, pps/s², > 0; the same jerk raises and lowers the acceleration and
        deceleration.
    tick_hz : float
        Controller tick frequency, Hz (> 0).
    triangle_prevention : bool
        Apply the rule of 1/12 (default, as the IC does).
    stop_tick : int or None
        Tick at which a decelerating stop is issued (>= 1), or ``None``. The move then
        ends early, with fewer than ``total_pulses`` pulses.

    Returns
    -------
    numpy.ndarray
        ``int8`` array of length ``n_ticks`` (see :func:`scurve_profile`), each entry 0 or
        1, summing to ``total_pulses`` (or the stopped move's pulse count). Tick ``i``
        holds ``round(p(t_{i+1})) - round(p(t_i))`` of the exact position ``p`` (pulses,
        ``round(x) = floor(x + 1/2)``), so the count never strays half a pulse from ``p``.

    Raises
    ------
    ValueError
        Naming the parameter, its value and the allowed range.
    """
    prof = scurve_profile(
        total_pulses,
        initial_speed_pps=initial_speed_pps,
        drive_speed_pps=drive_speed_pps,
        jerk_pps3=jerk_pps3,
        tick_hz=tick_hz,
        triangle_prevention=triangle_prevention,
        stop_tick=stop_tick,
    )
    return np.diff(scurve_counts(prof)).astype(np.int8)


def scurve_counts(prof: ScurveProfile) -> np.ndarray:
    """The pulses an S-curve fixed-pulse move has output by each tick boundary: the
    running count of its pulse train (:func:`scurve_pulses` is this array's steps), for
    callers that want positions, such as the S-curve command profile.

    Parameters
    ----------
    prof : ScurveProfile
        The move (:func:`scurve_profile`).

    Returns
    -------
    numpy.ndarray
        ``int64``, one entry per tick boundary 0 … len(train): 0 first, then the count
        after each tick.
    """
    n = prof.n_ticks
    pad = 8
    t = np.arange(n + 1 + pad, dtype=np.float64) / prof.tick_hz
    pos = prof.position_rising(t)
    guard = _FLOOR_GUARD_ABS + _FLOOR_GUARD_REL * prof.total_pulses
    counts = np.floor(pos + 0.5 + guard).astype(np.int64)
    counts[n:] = prof.output_pulses  # the move has ended at t_n >= t_end (up to rounding)
    counts[0] = 0
    return _counts_of_train(counts, n, prof.output_pulses)


def fixed_frequency_pulses(total_pulses: int, *, frequency_hz: float, tick_hz: float) -> np.ndarray:
    """Pulse train at one constant frequency for the whole move (plain PLC practice).

    Pulse ``j`` (``j = 0 .. total_pulses-1``) is output at tick
    ``floor(j * tick_hz / frequency_hz)``, so the first pulse is at tick 0 and the train
    ends with the tick of the last pulse. There is no acceleration ramp: the speed jumps
    from 0 to ``frequency_hz`` and back, which is what the V-F controller and the S-curve
    source improve on.

    Parameters
    ----------
    total_pulses : int
        Pulses to output, a whole number >= 1.
    frequency_hz : float
        Pulse frequency, pps, in ``(0, tick_hz]``.
    tick_hz : float
        Controller tick frequency, Hz (> 0).

    Returns
    -------
    numpy.ndarray
        ``int8`` array, one entry per tick, each 0 or 1, summing to ``total_pulses``.

    Raises
    ------
    ValueError
        Naming the parameter, its value and the allowed range, or when the move would be
        longer than :data:`MAX_TICKS` ticks.
    """
    P = check_int("total_pulses", total_pulses, 1)
    f = check_real("tick_hz", tick_hz, 0.0, lo_open=True)
    F = check_real("frequency_hz", frequency_hz, 0.0, f, lo_open=True)
    n_ticks = math.floor((P - 1) * f / F) + 1
    if n_ticks > MAX_TICKS:
        raise ValueError(
            f"total_pulses={P} gives a move of {n_ticks} ticks at frequency_hz={F:g}, more "
            f"than MAX_TICKS={MAX_TICKS}: raise frequency_hz or lower total_pulses"
        )
    j = np.arange(P, dtype=np.int64)
    ticks = np.floor(j * f / F).astype(np.int64)
    ticks = j + np.maximum.accumulate(ticks - j)  # strictly increasing despite rounding
    train = np.zeros(int(ticks[-1]) + 1, dtype=np.int8)
    train[ticks] = 1
    return train
