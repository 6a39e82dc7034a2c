"""Position commands, one value per controller tick (rad), for the V-F controller.

Each profile starts from rest at 0 rad (the plant's initial position). ``step`` and
``sine`` are the paper's Fig. 4 and Fig. 5; ``ramp``, ``trapezoid`` and ``scurve`` are
smooth point-to-point commands; ``multi`` strings several moves with dwells.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from vfgym._validate import check_int, check_real

PROFILES = ("step", "sine", "ramp", "trapezoid", "scurve", "multi")


def _ticks(duration_s: float, tick_hz: float) -> int:
    d = check_real("duration_s", duration_s, 0.0, lo_open=True)
    return check_int("n_ticks", max(1, round(d * tick_hz)), 1)


def _time(n: int, tick_hz: float) -> np.ndarray:
    return np.arange(n, dtype=np.float64) / tick_hz


def step(distance_rad: float, duration_s: float, tick_hz: float) -> np.ndarray:
    """A step to ``distance_rad`` at tick 0 (the paper's Fig. 4: 10 rad).

    Parameters
    ----------
    distance_rad : float
        The step (rad).
    duration_s : float
        Length of the command (s), > 0.
    tick_hz : float
        Controller tick rate f (Hz): one value per tick.

    Returns
    -------
    numpy.ndarray
        float64, the position (rad) at each tick, from tick 0 at time 0.
    """
    d = check_real("distance_rad", distance_rad)
    return np.full(_ticks(duration_s, tick_hz), d)


def sine(amplitude_rad: float, freq_hz: float, duration_s: float, tick_hz: float) -> np.ndarray:
    """A·sin(2π·f·t) from t = 0 (the paper's Fig. 5; the text gives neither A nor f).

    Parameters
    ----------
    amplitude_rad : float
        A (rad).
    freq_hz : float
        f (Hz), > 0.
    duration_s : float
        Length of the command (s), > 0.
    tick_hz : float
        Controller tick rate f (Hz): one value per tick.

    Returns
    -------
    numpy.ndarray
        float64, the position (rad) at each tick, from tick 0 at time 0.
    """
    a = check_real("amplitude_rad", amplitude_rad)
    f = check_real("freq_hz", freq_hz, 0.0, lo_open=True)
    return a * np.sin(2.0 * math.pi * f * _time(_ticks(duration_s, tick_hz), tick_hz))


def ramp(distance_rad: float, speed_rad_s: float, duration_s: float, tick_hz: float) -> np.ndarray:
    """Constant speed from 0 until ``distance_rad`` is reached, then hold.

    Parameters
    ----------
    distance_rad : float
        The move (rad); negative moves go backwards.
    speed_rad_s : float
        The speed (rad/s), > 0.
    duration_s : float
        Length of the command (s), > 0.
    tick_hz : float
        Controller tick rate f (Hz): one value per tick.

    Returns
    -------
    numpy.ndarray
        float64, the position (rad) at each tick, from tick 0 at time 0.
    """
    d = check_real("distance_rad", distance_rad)
    v = check_real("speed_rad_s", speed_rad_s, 0.0, lo_open=True)
    t = _time(_ticks(duration_s, tick_hz), tick_hz)
    return math.copysign(1.0, d) * np.minimum(v * t, abs(d))


def _trapezoid_phases(distance: float, v: float, a: float) -> tuple[float, float, float, float]:
    """(acceleration time, cruise time, end time, top speed) of a symmetric trapezoidal
    speed profile over ``distance``: triangular, below ``v``, when the move is short."""
    if distance * a >= v * v:  # reaches v
        ta = v / a
        tc = distance / v - ta
    else:
        ta = math.sqrt(distance / a)
        tc = 0.0
        v = a * ta
    return ta, tc, 2 * ta + tc, v


def trapezoid_position(t: np.ndarray, distance: float, v: float, a: float) -> np.ndarray:
    """Position of a symmetric trapezoidal (or triangular) speed profile over ``distance``.

    The move accelerates at ``a`` to ``v``, cruises and decelerates at ``a``; when it is too
    short to reach ``v`` the speed profile is a triangle.

    Parameters
    ----------
    t : numpy.ndarray
        Times from the start of the move (s).
    distance : float
        The move (rad), ≥ 0.
    v : float
        Cruise speed (rad/s), > 0.
    a : float
        Acceleration and deceleration (rad/s²), > 0.

    Returns
    -------
    numpy.ndarray
        The position (rad) at each time; ``distance`` from the end of the move on.
    """
    ta, tc, t_end, v = _trapezoid_phases(distance, v, a)
    p = np.where(
        t < ta,
        0.5 * a * t**2,
        np.where(
            t < ta + tc,
            0.5 * a * ta**2 + v * (t - ta),
            distance - 0.5 * a * np.clip(t_end - t, 0.0, None) ** 2,
        ),
    )
    return np.where(t >= t_end, distance, p)


def trapezoid(
    distance_rad: float, speed_rad_s: float, accel_rad_s2: float, duration_s: float, tick_hz: float
) -> np.ndarray:
    """Trapezoidal speed (constant acceleration, cruise, deceleration) to ``distance_rad``.

    Parameters
    ----------
    distance_rad : float
        The move (rad); negative moves go backwards.
    speed_rad_s : float
        Cruise speed (rad/s), > 0.
    accel_rad_s2 : float
        Acceleration and deceleration (rad/s²), > 0.
    duration_s : float
        Length of the command (s), > 0.
    tick_hz : float
        Controller tick rate f (Hz): one value per tick.

    Returns
    -------
    numpy.ndarray
        float64, the position (rad) at each tick, from tick 0 at time 0.
    """
    d = check_real("distance_rad", distance_rad)
    v = check_real("speed_rad_s", speed_rad_s, 0.0, lo_open=True)
    a = check_real("accel_rad_s2", accel_rad_s2, 0.0, lo_open=True)
    return math.copysign(1.0, d) * _trapezoid_ticks(
        _ticks(duration_s, tick_hz), tick_hz, abs(d), v, a
    )


def _trapezoid_ticks(n: int, tick_hz: float, distance: float, v: float, a: float) -> np.ndarray:
    """:func:`trapezoid_position` at the ticks ``i / tick_hz``, i < n, value for value: the
    times rise, so each phase is a run of ticks and is computed on its slice alone (the
    hold at ``distance``, most of a command, costs nothing)."""
    ta, tc, t_end, v = _trapezoid_phases(distance, v, a)
    t = _time(min(n, math.ceil(t_end * tick_hz) + 2), tick_hz)  # every t < t_end
    i1, i2, i3 = np.searchsorted(t, [ta, ta + tc, t_end], side="left")
    p = np.full(n, distance)
    p[:i1] = 0.5 * a * t[:i1] ** 2
    p[i1:i2] = 0.5 * a * ta**2 + v * (t[i1:i2] - ta)
    p[i2:i3] = distance - 0.5 * a * np.clip(t_end - t[i2:i3], 0.0, None) ** 2
    return p


def scurve(
    distance_rad: float,
    speed_rad_s: float,
    accel_rad_s2: float,
    duration_s: float,
    tick_hz: float,
    pulse_rad: float,
) -> np.ndarray:
    """The MCX514 S-curve fixed-pulse drive used as a position command (docs/model.md §4).

    The jerk is chosen so that the peak acceleration when reaching ``speed_rad_s`` is
    ``accel_rad_s2`` (see :func:`scurve_source_args`); triangle form prevention is on.

    Parameters
    ----------
    distance_rad : float
        The move (rad), rounded to whole pulses; negative moves go backwards.
    speed_rad_s : float
        Drive speed (rad/s), > 0 (at most one pulse a tick).
    accel_rad_s2 : float
        Peak acceleration (rad/s²), > 0.
    duration_s : float
        Length of the command (s), > 0.
    tick_hz : float
        Controller tick rate f (Hz): one value per tick.
    pulse_rad : float
        Pulse equivalent δ (rad per pulse).

    Returns
    -------
    numpy.ndarray
        float64, the position (rad) at each tick, from tick 0 at time 0.
        The position is the pulse count times δ.
    """
    from vfgym.moves.pulse_sources import scurve_counts
    from vfgym.moves.scurve import scurve_profile

    d = check_real("distance_rad", distance_rad)
    n = _ticks(duration_s, tick_hz)
    total = round(abs(d) / pulse_rad)
    out = np.zeros(n)
    if total == 0:
        return out
    # the pulse train's running count (scurve_pulses is its steps), after each tick
    counts = scurve_counts(
        scurve_profile(total, **scurve_source_args(speed_rad_s, accel_rad_s2, tick_hz, pulse_rad))
    )
    m = min(n, counts.size - 1)
    out[:m] = counts[1 : m + 1]
    out[m:] = out[m - 1] if m else 0.0
    return math.copysign(pulse_rad, d) * out


def scurve_source_args(
    speed_rad_s: float,
    accel_rad_s2: float,
    tick_hz: float,
    pulse_rad: float,
    initial_speed_rad_s: float | None = None,
) -> dict[str, float]:
    """MCX514 drive settings (pps units) for a top speed and a peak acceleration in rad.

    DV = speed/δ (at most one pulse a tick), SV = 1 % of DV by default (the IC cannot start
    from 0), jerk JK = a_peak²/(DV − SV) so that the S-curve reaching DV peaks at a_peak.

    Parameters
    ----------
    speed_rad_s : float
        Top speed (rad/s), > 0.
    accel_rad_s2 : float
        Peak acceleration (rad/s²), > 0.
    tick_hz : float
        Controller tick rate f (Hz); DV is at most f.
    pulse_rad : float
        Pulse equivalent δ (rad per pulse).
    initial_speed_rad_s : float or None
        Initial speed SV (rad/s), in (0, speed]; default 1 % of the drive speed.

    Returns
    -------
    dict
        Keyword arguments of :func:`vfgym.scurve_pulses`: ``initial_speed_pps``,
        ``drive_speed_pps``, ``jerk_pps3``, ``tick_hz``.
    """
    v = check_real("speed_rad_s", speed_rad_s, 0.0, lo_open=True)
    a = check_real("accel_rad_s2", accel_rad_s2, 0.0, lo_open=True)
    dv = min(v / pulse_rad, tick_hz)
    sv = 0.01 * dv if initial_speed_rad_s is None else initial_speed_rad_s / pulse_rad
    sv = check_real("initial_speed_rad_s", sv, 0.0, dv, lo_open=True)
    a_pps = a / pulse_rad
    jerk = a_pps**2 / max(dv - sv, 1e-9)
    return {
        "initial_speed_pps": sv,
        "drive_speed_pps": dv,
        "jerk_pps3": jerk,
        "tick_hz": tick_hz,
    }


def multi(
    moves: Sequence[tuple[float, float]], tick_hz: float, settle_s: float = 0.0
) -> np.ndarray:
    """Steps by the relative distances of ``moves``, each held for its dwell.

    E.g. ``((5.0, 0.05), (-8.0, 0.06), (3.0, 0.08))`` goes to 5, then −3, then 0 rad.

    Parameters
    ----------
    moves : sequence of (float, float)
        (relative distance rad, dwell s) pairs; dwells > 0.
    tick_hz : float
        Controller tick rate f (Hz): one value per tick.
    settle_s : float
        Time (s) to hold the last position after the last dwell.

    Returns
    -------
    numpy.ndarray
        float64, the position (rad) at each tick.

    Raises
    ------
    ValueError
        If ``moves`` is empty or a distance or dwell is out of range.
    """
    if not moves:
        raise ValueError("moves=() is not allowed: give at least one (distance_rad, dwell_s)")
    parts = []
    pos = 0.0
    for i, (dist, dwell) in enumerate(moves):
        pos += check_real(f"moves[{i}].distance_rad", dist)
        parts.append(
            np.full(
                _ticks(check_real(f"moves[{i}].dwell_s", dwell, 0.0, lo_open=True), tick_hz), pos
            )
        )
    if settle_s > 0:
        parts.append(np.full(_ticks(settle_s, tick_hz), pos))
    return np.concatenate(parts)
