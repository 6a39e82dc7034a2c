"""The MCX514's S-curve fixed-pulse driving as an exact continuous-time profile.

What a motion-control IC such as the NOVA MCX514 commands in *S-curve fixed-pulse
driving* with acceleration and deceleration symmetric (MCX514 manual p.26, docs/model.md
§4): the speed starts at the initial speed ``SV``, rises along an S-curve at constant jerk
to the drive speed ``DV``, cruises, falls back along the mirror image and stops exactly on
the requested pulse count. With *triangle form prevention* (the "rule of 1/12") a move
too short to reach ``DV``, or a decelerating stop issued while the acceleration is still
increasing, still gives a smooth speed curve instead of a triangle with a corner at its
peak. :func:`scurve_profile` gives the position ``p(t)`` (pulses, piecewise cubic in
time) in closed form; :func:`vfgym.moves.pulse_sources.scurve_pulses` samples it into the
pulse train.

Units: speeds in pulses per second (pps), acceleration in pps/s, jerk in pps/s²,
times in seconds.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from vfgym._validate import check_int, check_real

__all__ = ["MAX_TICKS", "ScurveProfile", "scurve_profile"]

MAX_TICKS = 10_000_000
"""Longest pulse train (ticks) a source builds: 71 s at 140 kHz. Longer moves raise."""

# A position within this many pulses below a rounding threshold counts as having reached
# it. Float error on p(t) is ~1e-16 * total_pulses; this only absorbs that error.
_FLOOR_GUARD_ABS = 1e-9
_FLOOR_GUARD_REL = 1e-13

# One segment of the acceleration phase: (start time s, start position pulses,
# start speed pps, start acceleration pps/s, jerk pps/s² held over the segment).
_Segment = tuple[float, float, float, float, float]


@dataclass(frozen=True)
class ScurveProfile:
    """Exact continuous-time S-curve move behind :func:`scurve_pulses`.

    The move is: acceleration phase ``[0, t_acc_end)`` (jerk ``+J`` until
    ``t_acc_increase``, then jerk ``-J``), constant speed ``peak_speed_pps`` on
    ``[t_acc_end, t_dec_start)`` (the cruise at drive speed, or the plateau of excess
    pulses at the speed peak of a short move), and a deceleration phase
    ``[t_dec_start, t_end)`` that is the time mirror of the acceleration phase:
    ``v(t_end - s) = v(s)``. Times in seconds.

    Built by :func:`scurve_profile`, which checks the settings.

    Attributes
    ----------
    total_pulses : int
        Pulses requested.
    output_pulses : int
        Pulses actually output; equals ``total_pulses`` unless a decelerating stop cut
        the move short: then ``round(end_position)``.
    end_position : float
        Exact position at the end of the move, pulses; ``total_pulses`` unless a
        decelerating stop cut the move short.
    initial_speed_pps, drive_speed_pps, jerk_pps3, tick_hz : float
        The settings (pps, pps, pps/s², Hz).
    triangle_prevention : bool
        Whether the rule of 1/12 was applied.
    stop_tick : int or None
        Tick at which a decelerating stop was issued, or ``None``.
    stopped : bool
        True when that stop changed the move (issued before deceleration).
    reached_drive_speed : bool
        True when the speed reaches ``drive_speed_pps``.
    t_acc_increase : float
        End of the acceleration-increasing (jerk ``+J``) section, s.
    t_acc_end : float
        End of the acceleration phase, s (acceleration back to zero, or the corner of a
        triangle profile).
    t_dec_start : float
        Start of the deceleration phase, s.
    t_end : float
        End of the move, s.
    peak_speed_pps : float
        Highest speed of the move, pps.
    accel_pulses : float
        Pulses output during the acceleration phase (exact, not whole); the deceleration
        phase uses the same number.
    n_ticks : int
        Ticks of the move, ``ceil(t_end * tick_hz)``: the length of the train.
    segments : tuple of (float, float, float, float, float)
        The acceleration-phase segments ``(t0, p0, v0, a0, jerk)``.
    """

    total_pulses: int
    output_pulses: int
    end_position: float
    initial_speed_pps: float
    drive_speed_pps: float
    jerk_pps3: float
    tick_hz: float
    triangle_prevention: bool
    stop_tick: int | None
    stopped: bool
    reached_drive_speed: bool
    t_acc_increase: float
    t_acc_end: float
    t_dec_start: float
    t_end: float
    peak_speed_pps: float
    accel_pulses: float
    n_ticks: int
    segments: tuple[_Segment, ...]

    @property
    def plateau_pulses(self) -> float:
        """Pulses output at constant peak speed between acceleration and deceleration."""
        return self.peak_speed_pps * (self.t_dec_start - self.t_acc_end)

    def tick_times(self) -> np.ndarray:
        """Tick boundaries of the move.

        Returns
        -------
        numpy.ndarray
            ``t_i = i / tick_hz`` (s) for ``i = 0 .. n_ticks``.
        """
        return np.arange(self.n_ticks + 1, dtype=np.float64) / self.tick_hz

    def _at_segments(self, s: np.ndarray) -> tuple[np.ndarray, ...]:
        """For times ``s`` inside the acceleration phase: the time into each one's segment
        and that segment's starting position, speed, acceleration and jerk."""
        seg = np.asarray(self.segments, dtype=np.float64)
        k = np.clip(np.searchsorted(seg[:, 0], s, side="right") - 1, 0, len(seg) - 1)
        t0, p0, v0, a0, jk = seg[k].T
        return s - t0, p0, v0, a0, jk

    @staticmethod
    def _segment_position(
        d: np.ndarray,
        p0: np.ndarray | float,
        v0: np.ndarray | float,
        a0: np.ndarray | float,
        jk: np.ndarray | float,
    ) -> np.ndarray:
        """Position ``d`` seconds into segments starting at p0, v0, a0 with jerk jk."""
        return p0 + d * (v0 + d * (a0 / 2.0 + d * (jk / 6.0)))

    def _acc_phase(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Position, speed and acceleration at times ``s`` inside the acceleration phase."""
        d, p0, v0, a0, jk = self._at_segments(s)
        pos = self._segment_position(d, p0, v0, a0, jk)
        vel = v0 + d * (a0 + d * (jk / 2.0))
        acc = a0 + d * jk
        return pos, vel, acc

    def _evaluate(self, t: np.ndarray | float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        t = np.asarray(t, dtype=np.float64)
        shape = t.shape
        t = t.ravel()
        pos = np.zeros_like(t)
        vel = np.zeros_like(t)
        acc = np.zeros_like(t)
        p_end = self.end_position

        m = (t >= 0.0) & (t < self.t_acc_end)
        pos[m], vel[m], acc[m] = self._acc_phase(t[m])

        m = (t >= self.t_acc_end) & (t < self.t_dec_start)
        pos[m] = self.accel_pulses + self.peak_speed_pps * (t[m] - self.t_acc_end)
        vel[m] = self.peak_speed_pps

        m = (t >= self.t_dec_start) & (t < self.t_end)
        p_m, v_m, a_m = self._acc_phase(np.maximum(self.t_end - t[m], 0.0))
        pos[m] = p_end - p_m
        vel[m] = v_m
        acc[m] = -a_m

        pos[t >= self.t_end] = p_end
        return pos.reshape(shape), vel.reshape(shape), acc.reshape(shape)

    def position(self, t: np.ndarray | float) -> np.ndarray:
        """Exact position at times ``t``.

        Parameters
        ----------
        t : numpy.ndarray or float
            Times (s).

        Returns
        -------
        numpy.ndarray
            Position in pulses (not rounded to whole pulses).
        """
        return self._evaluate(t)[0]

    def position_rising(self, t: np.ndarray) -> np.ndarray:
        """:meth:`position` at rising times, value for value, faster.

        Each phase is a run of ``t`` and is computed on its slice, without masks and
        without speed and acceleration (the pulse train needs positions only).

        Parameters
        ----------
        t : numpy.ndarray
            Rising times ``t >= 0`` (s), one-dimensional.

        Returns
        -------
        numpy.ndarray
            Position in pulses, as :meth:`position` gives it.
        """

        i_a, i_d, i_e = np.searchsorted(t, [self.t_acc_end, self.t_dec_start, self.t_end])
        pos = np.empty_like(t)
        # in _evaluate's order, so that where phases overlap the later one wins as there
        pos[:i_a] = self._rising_acc_position(t[:i_a])
        pos[i_a:i_d] = self.accel_pulses + self.peak_speed_pps * (t[i_a:i_d] - self.t_acc_end)
        # the deceleration's times into the move's mirror fall: reversed, they rise
        s = np.maximum(self.t_end - t[i_d:i_e], 0.0)[::-1]
        pos[i_d:i_e] = self.end_position - self._rising_acc_position(s)[::-1]
        pos[i_e:] = self.end_position
        return pos

    def _rising_acc_position(self, s: np.ndarray) -> np.ndarray:
        """``_segment_position(*_at_segments(s))`` for rising ``s``, value for value: each
        segment is a run of ``s``, computed on its slice with the segment's numbers as
        scalars (the same operations in the same order) instead of gathered per time."""
        out = np.empty_like(s)
        segs = self.segments
        # segment j holds the s with starts[j] <= s < starts[j+1] (the first also the s
        # before it, the last the s after it), as _at_segments' clipped search finds
        cuts = [0, *np.searchsorted(s, [g[0] for g in segs[1:]], side="left"), s.size]
        for (t0, p0, v0, a0, jk), lo, hi in zip(segs, cuts[:-1], cuts[1:], strict=True):
            d = s[lo:hi] - t0
            out[lo:hi] = self._segment_position(d, p0, v0, a0, jk)
        return out

    def speed(self, t: np.ndarray | float) -> np.ndarray:
        """Speed at times ``t``.

        Parameters
        ----------
        t : numpy.ndarray or float
            Times (s).

        Returns
        -------
        numpy.ndarray
            Speed (pps); 0 before the start and after the end.
        """
        return self._evaluate(t)[1]

    def acceleration(self, t: np.ndarray | float) -> np.ndarray:
        """Acceleration at times ``t``.

        At a phase boundary the value from the right is returned (so at ``t_dec_start``
        of a triangle profile the jump to deceleration is already taken).

        Parameters
        ----------
        t : numpy.ndarray or float
            Times (s).

        Returns
        -------
        numpy.ndarray
            Acceleration (pps/s); 0 outside the move and while cruising.
        """
        return self._evaluate(t)[2]


def _integrate(sv: float, pieces: Sequence[tuple[float, float]]) -> tuple[list[_Segment], tuple]:
    """Chain ``(duration, jerk)`` pieces from speed ``sv``; return segments and end state."""
    t = p = a = 0.0
    v = sv
    segs: list[_Segment] = []
    for dur, jk in pieces:
        segs.append((t, p, v, a, jk))
        p += dur * (v + dur * (a / 2.0 + dur * jk / 6.0))
        v += dur * (a + dur * jk / 2.0)
        a += dur * jk
        t += dur
    return segs, (t, p, v, a)


def _position_in(sv: float, pieces: Sequence[tuple[float, float]], t: float) -> float:
    """Position (pulses) at time ``t`` of the chained pieces, ``t`` within their span."""
    done = 0.0
    kept: list[tuple[float, float]] = []
    for dur, jk in pieces:
        kept.append((min(dur, max(t - done, 0.0)), jk))
        done += dur
    return _integrate(sv, kept)[1][1]


def _truncate(pieces: Sequence[tuple[float, float]], t: float) -> list[tuple[float, float]]:
    """The pieces cut off at time ``t``."""
    out: list[tuple[float, float]] = []
    done = 0.0
    for dur, jk in pieces:
        keep = min(dur, max(t - done, 0.0))
        if keep > 0.0:
            out.append((keep, jk))
        done += dur
    return out


def _solve_increasing(f: Callable[[float], float], target: float, lo: float, hi: float) -> float:
    """Root of ``f(t) = target`` for increasing ``f`` on ``[lo, hi]``, by bisection."""
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if mid in (lo, hi):
            break
        if f(mid) < target:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def _check_scurve_args(
    total_pulses: object,
    initial_speed_pps: object,
    drive_speed_pps: object,
    jerk_pps3: object,
    tick_hz: object,
    triangle_prevention: object,
    stop_tick: object,
) -> tuple[int, float, float, float, float, bool, int | None]:
    P = check_int("total_pulses", total_pulses, 1)
    f = check_real("tick_hz", tick_hz, 0.0, lo_open=True)
    DV = check_real("drive_speed_pps", drive_speed_pps, 0.0, f, lo_open=True)
    try:
        SV = check_real("initial_speed_pps", initial_speed_pps, 0.0, DV, lo_open=True)
    except ValueError as err:
        raise ValueError(f"{err} (the upper bound is drive_speed_pps={DV:g})") from None
    J = check_real("jerk_pps3", jerk_pps3, 0.0, lo_open=True)
    if not isinstance(triangle_prevention, (bool, np.bool_)):
        raise ValueError(
            f"triangle_prevention={triangle_prevention!r} is not allowed: True or False"
        )
    stop = None if stop_tick is None else check_int("stop_tick", stop_tick, 1)
    return P, SV, DV, J, f, bool(triangle_prevention), stop


def scurve_profile(
    total_pulses: int,
    *,
    initial_speed_pps: float,
    drive_speed_pps: float,
    jerk_pps3: float,
    tick_hz: float,
    triangle_prevention: bool = True,
    stop_tick: int | None = None,
) -> ScurveProfile:
    """Exact continuous-time S-curve fixed-pulse move (MCX514 manual p.26, docs/model.md §4).

    The acceleration phase, with
    ``T = sqrt((DV - SV) / J)``, is one of:

    - **Reaches drive speed** (``P >= 2 Pa``, ``Pa = (DV + SV) T``): jerk ``+J`` for
      ``T`` then ``-J`` for ``T``, so ``ta = 2T``; cruise at ``DV`` for the remaining
      ``P - 2 Pa`` pulses. This holds with or without triangle prevention.
    - **Too short, triangle prevention on** (rule of 1/12): jerk ``+J`` until the pulses
      output, ``SV t + J t³/6``, reach ``P/12`` (at ``t = tau``), then ``-J`` for ``tau``
      so the acceleration passes through zero at the speed peak ``SV + J tau²``. The
      deceleration mirrors it. Acceleration and deceleration use
      ``2 (2 SV tau + J tau³) = P - 8 SV tau`` pulses; the remaining ``8 SV tau`` are
      the excess the manual says "will be output at the peak of the speed": a plateau at
      the peak speed, which vanishes as ``SV -> 0``. The switch uses the continuous
      position, i.e. the exact instant the count passes ``P/12``.
    - **Too short, triangle prevention off**: the same S-curve as if heading for ``DV``,
      until the pulses output reach ``P/2`` (from then on the remaining pulses equal what
      the mirrored deceleration needs); the deceleration, the time mirror of the
      acceleration so far, starts at once. The acceleration jumps from ``+a`` to ``-a``
      at the peak: the speed curve is a triangle with a corner there.

    A decelerating stop at ``stop_tick`` (time ``ts = stop_tick / tick_hz``) issued
    before deceleration has begun ends the move early with fewer pulses:

    - while the acceleration is increasing: with prevention, the acceleration starts
      decreasing at ``ts`` (jerk ``-J`` for ``ts``), reaches zero at ``2 ts`` and the
      deceleration mirrors that, with no plateau; without prevention the deceleration
      (the mirror of the acceleration so far) starts at ``ts``, a triangle;
    - while the acceleration is decreasing: with prevention it goes on decreasing to zero
      and the mirrored deceleration follows; without prevention the deceleration starts
      at ``ts``;
    - while cruising (or on the plateau): the mirrored deceleration starts at ``ts``.

    A stop at or after the start of deceleration changes nothing, and the pulses output
    before the stop are never changed by it. The stopped move's exact length
    ``end_position`` is in general not a whole number of pulses; it outputs
    ``round(end_position)`` pulses (possibly 0), the pulse train being the rounded exact
    position as always, so the profile is exactly mirror symmetric and the train is
    within half a pulse of it.

    Parameters
    ----------
    total_pulses, initial_speed_pps, drive_speed_pps, jerk_pps3, tick_hz
        As in :func:`scurve_pulses`.
    triangle_prevention, stop_tick
        As in :func:`scurve_pulses`.

    Returns
    -------
    ScurveProfile
        The exact move: its phases, times and positions.

    Raises
    ------
    ValueError
        A setting out of range (see :func:`scurve_pulses`), or a move longer than
        :data:`MAX_TICKS` ticks.
    """
    P, SV, DV, J, f, prevention, stop = _check_scurve_args(
        total_pulses,
        initial_speed_pps,
        drive_speed_pps,
        jerk_pps3,
        tick_hz,
        triangle_prevention,
        stop_tick,
    )
    T = math.sqrt((DV - SV) / J)
    full = [(T, J), (T, -J)]
    Pa = (DV + SV) * T
    reached = 2.0 * Pa <= P
    if reached:
        pieces = full
        t_inc = T
    elif prevention:
        tau = _solve_increasing(lambda t: SV * t + J * t**3 / 6.0, P / 12.0, 0.0, T)
        pieces = [(tau, J), (tau, -J)]
        t_inc = tau
    else:
        t_star = _solve_increasing(lambda t: _position_in(SV, full, t), P / 2.0, 0.0, 2.0 * T)
        pieces = _truncate(full, t_star)
        t_inc = min(t_star, T)

    segs, (t_acc, p_acc, v_peak, _) = _integrate(SV, pieces)
    cruise = max(P - 2.0 * p_acc, 0.0) if (reached or prevention) else 0.0
    t_dec = t_acc + cruise / v_peak
    guard = _FLOOR_GUARD_ABS + _FLOOR_GUARD_REL * P
    output = P
    p_end = float(P)
    stopped = False
    if stop is not None and stop / f < t_dec:
        ts = stop / f
        stopped = True
        reached = reached and ts >= t_acc
        if ts < t_inc:
            pieces = [(ts, J), (ts, -J)] if prevention else [(ts, J)]
            t_inc = ts
        elif ts < t_acc and not prevention:
            pieces = _truncate(pieces, ts)
        segs, (t_acc, p_acc, v_peak, _) = _integrate(SV, pieces)
        t_dec = max(ts, t_acc)
        p_end = 2.0 * p_acc + v_peak * (t_dec - t_acc)
        output = min(P, math.floor(p_end + 0.5 + guard))

    t_end = t_dec + t_acc
    n_ticks = max(1, math.ceil(t_end * f - 1e-6))
    if n_ticks > MAX_TICKS:
        raise ValueError(
            f"total_pulses={P} gives a move of {n_ticks} ticks at tick_hz={f:g}, more than "
            f"MAX_TICKS={MAX_TICKS}: raise initial_speed_pps, drive_speed_pps or jerk_pps3"
        )
    return ScurveProfile(
        total_pulses=P,
        output_pulses=output,
        end_position=p_end,
        initial_speed_pps=SV,
        drive_speed_pps=DV,
        jerk_pps3=J,
        tick_hz=f,
        triangle_prevention=prevention,
        stop_tick=stop,
        stopped=stopped,
        reached_drive_speed=reached,
        t_acc_increase=t_inc,
        t_acc_end=t_acc,
        t_dec_start=t_dec,
        t_end=t_end,
        peak_speed_pps=v_peak,
        accel_pulses=p_acc,
        n_ticks=n_ticks,
        segments=tuple(segs),
    )
