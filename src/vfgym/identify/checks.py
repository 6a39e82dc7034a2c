"""What a capture must be before it is fitted, and what in it does not belong.

- **Lost encoder edges.** An edge lost on one encoder line (noise, a ground loop, an
  analyser threshold set too high) turns four counts of motion into a step back and a
  step on: the count reverses and comes back at speed. A real reversal needs the motor to
  stop: after a whole count in time Δ′ and back across the same edge in time Δ, the
  acceleration it asks is at least q / (Δ′·(Δ/2 + Δ′)), which beyond
  :data:`ACCEL_MARGIN` times the motor's peak torque over its rotor's inertia alone no
  axis makes (:func:`lost_edges`; above about 30 rad/s on the paper's motor, where every
  planned move runs). Such a capture is refused.
- **A and B swapped, or counting against the pulses.** A servo whose encoder counted
  against its pulses would run away, so a capture that does shows its A and B (or its
  ``dir``) wired the other way round (:func:`check_direction`, from
  :func:`counts_per_pulse`). Refused, with the ``--signals`` that swaps them.
- **Not the axis's plan.** The recorded pulse train against the plan of the axis
  (:func:`plan_match`): the same; the same but for a few ticks (pulses added, lost or
  signed wrong on the pulse or dir line, named by their times); the plan's beginning
  only (a capture stopped or a file cut short); or other moves. Said in a note: the
  recorded pulses drive the model whatever they are, and what they do not excite is
  said apart.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from vfgym.identify.lines import Capture
from vfgym.identify.model import SAMPLE_TICKS, Record
from vfgym.params import Plant

ACCEL_MARGIN = 4.0
"""A reversal is impossible where it asks more than this many times the motor's peak
torque over its rotor's inertia alone (the lightest axis the motor can be)."""

PLAN_DIFFERS_MOST = 20
"""A pulse train differing from the plan at up to this many ticks is the plan with pulses
added, lost or signed wrong; beyond, other moves."""

SHOWN = 5
"""Times named in one line, at most."""


def times_text(t_s: Sequence[float] | np.ndarray, most: int = SHOWN) -> str:
    """Times for a message: ``0.5123, 0.61 s`` (the first ``most``, then how many more).

    Parameters
    ----------
    t_s : sequence of float
        Times (s).
    most : int
        How many to show.

    Returns
    -------
    str
        The text.
    """
    t = [float(x) for x in t_s]
    shown = ", ".join(f"{x:.6g}" for x in t[:most])
    return shown + (f" s and {len(t) - most} more" if len(t) > most else " s")


def lost_edges(capture: Capture, plant: Plant) -> np.ndarray:
    """Times of the count's reversals no motion can make (module doc).

    Parameters
    ----------
    capture : Capture
        The capture.
    plant : Plant
        Gives the count's angle, the motor's peak torque and its rotor's inertia.

    Returns
    -------
    numpy.ndarray
        Time (s) of each step against the direction of a whole count before it that
        comes back within an impossible time.
    """
    d = np.diff(capture.count, prepend=0)
    t = capture.count_s
    if d.size < 3:
        return np.zeros(0)
    q = plant.motor.count_rad
    a_max = ACCEL_MARGIN * plant.motor.peak_torque_nm / plant.motor.rotor_inertia_kgm2
    r = capture.resolution_s if capture.sampled else 0.0
    k = np.arange(2, d.size)
    rev = (np.sign(d[k]) != np.sign(d[k - 1])) & (np.sign(d[k - 1]) == np.sign(d[k - 2]))
    k = k[rev]
    before = t[k - 1] - t[k - 2] + r  # a whole count, the last before the reversal
    back = t[k] - t[k - 1] + r  # out past the edge and back across it
    return t[k[a_max * before * (0.5 * back + before) < q]]


def check_capture(capture: Capture, plant: Plant) -> None:
    """Refuse a capture whose encoder lost edges (module doc).

    Parameters
    ----------
    capture : Capture
        The capture.
    plant : Plant
        The axis's plant.

    Raises
    ------
    ValueError
        One line naming the file and the times.
    """
    lost = lost_edges(capture, plant)
    if lost.size:
        raise ValueError(
            f"{capture.source}: the encoder count reverses at speed {lost.size} times (at "
            f"{times_text(lost)}), faster than the motor can stop: encoder edges were lost; "
            "check the encoder's wiring and ground and the analyser's threshold voltage, "
            "and capture again"
        )


def rest_samples(record: Record, tick_hz: float) -> np.ndarray:
    """The last sample of each idle stretch of at least 20 ms (the axis at rest).

    Parameters
    ----------
    record : Record
        The capture on the tick grid.
    tick_hz : float
        The controller's tick rate (Hz).

    Returns
    -------
    numpy.ndarray
        Sample indices (into :attr:`Record.measured`).
    """
    s = SAMPLE_TICKS
    p = record.pulses
    n = p.size // s
    busy = np.abs(p[: n * s]).reshape(n, s).sum(axis=1) > 0
    need = max(1, round(0.02 * tick_hz / s))
    out = []
    run = 0
    for j in range(n):
        run = 0 if busy[j] else run + 1
        if run >= need and (j + 1 == n or busy[j + 1]):
            out.append(j)
    return np.asarray(out, dtype=np.int64)


def counts_per_pulse(records: Sequence[Record], tick_hz: float) -> float | None:
    """Encoder counts moved per command pulse, between rests of at least 20 ms, signed.

    Parameters
    ----------
    records : sequence of Record
        The captures.
    tick_hz : float
        The controller's tick rate (Hz).

    Returns
    -------
    float or None
        The least-squares ratio of the counts moved to the pulses between rests: the
        gear on a machine the axis file describes, its negative where the encoder counts
        against the pulses; ``None`` without two rests around a move.
    """
    moved: list[np.ndarray] = []
    pulses: list[np.ndarray] = []
    for r in records:
        n = np.cumsum(r.pulses.astype(np.int64))
        rest = rest_samples(r, tick_hz)
        rest = rest[rest >= r.first_sample]  # an enable's sag moves the axis with no pulse
        if rest.size >= 2:
            moved.append(np.diff(r.measured[rest]))
            pulses.append(np.diff(n[(rest + 1) * SAMPLE_TICKS - 1]).astype(np.float64))
    if not pulses:
        return None
    m, p = np.concatenate(moved), np.concatenate(pulses)
    den = float(p @ p)
    return float(m @ p) / den if den > 0 else None


def check_direction(records: Sequence[Record], plant: Plant) -> None:
    """Refuse captures whose encoder counts against the pulses (module doc).

    Parameters
    ----------
    records : sequence of Record
        The captures on the tick grid.
    plant : Plant
        Gives the gear and the tick.

    Raises
    ------
    ValueError
        One line naming the captures, the counts per pulse and the remedy.
    """
    ratio = counts_per_pulse(records, plant.tick_hz)
    if ratio is not None and ratio < 0.0:
        raise ValueError(
            f"{', '.join(r.source for r in records)}: the encoder counts against the pulses "
            f"({ratio:+.3g} counts per pulse between rests, where plant.servo.gear = "
            f"{plant.servo.gear}): enc_a and enc_b are swapped (or dir is inverted); give "
            "--signals enc_a=NAME_OF_B,enc_b=NAME_OF_A"
        )


@dataclass(frozen=True)
class PlanMatch:
    """How a recorded pulse train compares with the axis's plan.

    Attributes
    ----------
    kind : str
        ``plan`` (the same), ``differs`` (the same but for a few ticks), ``prefix`` (the
        plan's beginning only) or ``other`` (other moves).
    pulses : int
        Pulses recorded.
    plan_pulses : int
        Pulses of the plan.
    differ_s : tuple of float
        Capture times (s) of the ticks that differ (``differs``), or of the end of the
        recorded train (``prefix``), or of the first difference (``other``).
    start_tick : int
        The record's tick at which the plan's first pulse falls.
    fitted : str
        ``recorded`` or ``plan``: the train the identification fitted (for ``differs``,
        whichever explained the count better).
    """

    kind: str
    pulses: int
    plan_pulses: int
    differ_s: tuple[float, ...] = ()
    start_tick: int = 0
    fitted: str = "recorded"

    def note(self, source: str, axis_name: str) -> str | None:
        """One line for the notes, ``None`` for the plan itself.

        Parameters
        ----------
        source : str
            The capture's file.
        axis_name : str
            The axis's name.

        Returns
        -------
        str or None
            The line.
        """
        if self.kind == "plan":
            return None
        if self.kind == "differs":
            return (
                f"{source}: the pulse train differs from the plan of axis {axis_name} at "
                f"{len(self.differ_s)} ticks (at {times_text(self.differ_s)}): pulses added, "
                "lost or signed wrong on the pulse or dir line; "
                + (
                    "the plan's train explains the count better and is fitted there (the "
                    "drive got the plan's pulses; the capture did not show them as they were)"
                    if self.fitted == "plan"
                    else "the recorded train explains the count better and is fitted"
                )
            )
        if self.kind == "prefix":
            return (
                f"{source}: holds the first {self.pulses} of the {self.plan_pulses} pulses of "
                f"the plan of axis {axis_name}, up to {times_text(self.differ_s)}: a capture "
                "stopped early or a file cut short; what it lacks is noted below"
            )
        return (
            f"{source}: the pulse train is not the plan of axis {axis_name} (vfgym identify "
            f"--plan): {self.pulses} pulses against its {self.plan_pulses}, the first "
            f"difference at {times_text(self.differ_s)}; other moves identify what they "
            "excite, as noted below"
        )


def plan_match(record: Record, plan_pulses: np.ndarray, tick_hz: float) -> PlanMatch:
    """Compare a recorded pulse train with the axis's plan (module doc).

    The trains are aligned at a first pulse (of the record's first few, in case one is
    not the plan's) and compared tick by tick.

    Parameters
    ----------
    record : Record
        The capture on the tick grid.
    plan_pulses : numpy.ndarray
        The plan's train (−1, 0, +1 per tick).
    tick_hz : float
        The controller's tick rate (Hz).

    Returns
    -------
    PlanMatch
        The comparison.
    """
    rec = record.pulses.astype(np.int8)
    plan = np.asarray(plan_pulses, dtype=np.int8)
    mine, theirs = np.flatnonzero(rec), np.flatnonzero(plan)
    n_rec, n_plan = int(mine.size), int(theirs.size)
    if n_rec == 0 or n_plan == 0:
        return PlanMatch("other", n_rec, n_plan, ())
    body = plan[theirs[0] : theirs[-1] + 1]
    best: tuple[int, np.ndarray, bool] | None = None
    for i0 in mine[:SHOWN].tolist():
        span = int(mine[-1]) - i0 + 1  # from this first pulse to the record's last
        short = span < body.size - PLAN_DIFFERS_MOST  # the record stops before the plan
        n = span if short else body.size
        got = np.zeros(n, np.int8)
        part = rec[i0 : i0 + n]
        got[: part.size] = part
        diff = np.flatnonzero(got != body[:n])
        diff = np.concatenate([mine[mine < i0] - i0, diff])  # pulses before it: extra
        if best is None or diff.size < best[1].size:
            best = (i0, diff, short)
    assert best is not None
    i0, diff, short = best

    def at(ticks: np.ndarray) -> tuple[float, ...]:
        f0 = record.first_tick + record.phase + 0.5  # a pulse rises half a tick in
        return tuple(float((t + f0) / tick_hz) for t in ticks.tolist())

    if diff.size > PLAN_DIFFERS_MOST:
        return PlanMatch("other", n_rec, n_plan, at(diff[:1] + i0), i0)
    if short:
        return PlanMatch("prefix", n_rec, n_plan, at(mine[-1:]), i0)
    if diff.size:
        return PlanMatch("differs", n_rec, n_plan, at(diff + i0), i0)
    return PlanMatch("plan", n_rec, n_plan, (), i0)


__all__ = [
    "ACCEL_MARGIN",
    "PLAN_DIFFERS_MOST",
    "PlanMatch",
    "check_capture",
    "check_direction",
    "counts_per_pulse",
    "lost_edges",
    "plan_match",
    "rest_samples",
    "times_text",
]
