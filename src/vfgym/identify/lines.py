"""A capture's four lines: each one's level changes, decoded into pulses and the count.

A logic analyser's file, VCD or sigrok-cli's CSV, is first :class:`Lines`: for each of
the ``pulse``, ``dir``, ``enc_a`` and ``enc_b`` signals the times its level changed (the
levels alternate from the one it starts at). :func:`decode` makes a :class:`Capture` of
them:

- a command pulse is a rising edge of ``pulse``, its sign the level of ``dir`` once its
  time stamp has ended (1: positive);
- the encoder's count follows the A/B levels in Gray order 00 → 10 → 11 → 01 counting up
  (A leads B), as :mod:`vfgym.io.vcd` writes them. The sample clock must be at least 4×
  the fastest edge, so that A and B never change in the same sample; where they do, the
  state moves two steps and is taken as two steps in the direction of travel, and the
  times are kept (:attr:`Capture.double_steps_s`) for a note.

What cannot be a signal is taken out first, and its times kept
(:attr:`Capture.glitches`): a change of ``dir``, ``enc_a`` or ``enc_b`` undone within
:data:`GLITCH_SAMPLES` samples (on an encoder line, with no change of the other one in
between, and within one sample where the other one changes at the same time as either: a
back-and-forth no motion makes so fast, which leaves the count as it was). Where a glitch
meets a real edge of its line, the fewest changes are taken out that leave the others
apart (:func:`_unglitch`): the real edge stays, or moves by at most that much. A
pulse off the controller's tick grid is the grid's business
(:func:`vfgym.identify.model.record_of`).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field

import numpy as np

SIGNALS = ("pulse", "dir", "enc_a", "enc_b")
"""The four signals of a capture, by their default names."""

GLITCH_SAMPLES = 2
"""A change undone within this many samples is a glitch (a clock ≥ 4× the fastest edge
keeps an encoder line's level for at least 8 samples, and ``dir`` for a tick)."""

_GRAY = np.array([0, 3, 1, 2])  # state of (A, B) as index 2·A + B: 00 → 0, 01 → 3, 10 → 1, 11 → 2


@dataclass(frozen=True)
class Capture:
    """One capture's command pulses and encoder count, in time order.

    Attributes
    ----------
    source : str
        The file read.
    pulse_s : numpy.ndarray
        Time of each command pulse's rising edge (s from the capture's start).
    pulse_sign : numpy.ndarray
        int8, +1 or −1 for each pulse (the ``dir`` level).
    count_s : numpy.ndarray
        Time of each change of the encoder's count (s).
    count : numpy.ndarray
        int64, the count after each change, relative to the count at the start (0).
    end_s : float
        Length of the capture (s): its last time stamp.
    resolution_s : float
        Time resolution of the stamps (s): the VCD's timescale, or a CSV's row period.
    sampled : bool
        True for an analyser's file: every edge stands at one of the analyser's samples
        (multiples of ``resolution_s`` from the start), not at its own instant; a trace
        CSV's row holds the count at its own time.
    glitches : tuple of (str, float)
        The signal and time (s) of each glitch taken out (module doc).
    double_steps_s : numpy.ndarray
        Times (s) at which A and B changed in the same sample (two steps taken).
    """

    source: str
    pulse_s: np.ndarray
    pulse_sign: np.ndarray
    count_s: np.ndarray
    count: np.ndarray
    end_s: float
    resolution_s: float
    sampled: bool = False
    glitches: tuple[tuple[str, float], ...] = ()
    double_steps_s: np.ndarray = field(default_factory=lambda: np.zeros(0))

    def count_at(self, t_s: np.ndarray) -> np.ndarray:
        """The encoder count at each time (after every change at or before it).

        Parameters
        ----------
        t_s : numpy.ndarray
            Times (s from the capture's start).

        Returns
        -------
        numpy.ndarray
            int64 counts (0 before the first change).
        """
        idx = np.searchsorted(self.count_s, np.asarray(t_s, dtype=np.float64), side="right")
        padded = np.concatenate([[0], self.count])
        return padded[idx]


@dataclass(frozen=True)
class Lines:
    """Each signal's level changes, as an analyser's file holds them.

    Attributes
    ----------
    source : str
        The file read.
    unit_s : float
        Seconds per time unit (the VCD's timescale, or the CSV's sample period).
    first : int
        The capture's first time stamp (its start).
    last : int
        Its last time stamp (its end).
    initial : tuple of int
        The level of each of :data:`SIGNALS` at the first stamp.
    changes : tuple of numpy.ndarray
        For each of :data:`SIGNALS`, the int64 times of its changes after the first
        stamp, in order (several at one time are kept in their order).
    """

    source: str
    unit_s: float
    first: int
    last: int
    initial: tuple[int, int, int, int]
    changes: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]


def _unglitch(t: np.ndarray, other: np.ndarray | None, most: int) -> tuple[np.ndarray, np.ndarray]:
    """Changes of one line without its glitches (module doc), and the glitches' times.

    Changes closer than ``most`` to the next form a cluster; in each, the changes taken
    out are the fewest that leave the rest farther apart than ``most`` (else as far apart
    as they can be), taken out in runs of an even number (a level undone) that no change
    of ``other`` falls inside (a real edge has one between it and the next on its line)."""
    t = np.asarray(t, dtype=np.int64)
    if t.size < 2:
        return t, np.zeros(0, dtype=np.int64)
    close = np.flatnonzero(np.diff(t) <= most)
    keep = np.ones(t.size, dtype=bool)
    found: list[int] = []
    k = 0
    while k < close.size:
        lo = hi = int(close[k])
        while k + 1 < close.size and close[k + 1] == hi + 1:
            k += 1
            hi = int(close[k])
        k += 1
        cluster = t[lo : hi + 2]
        drop = _glitches_of(cluster, other, most)
        for j in drop:
            keep[lo + j] = False
        found += [int(cluster[j]) for j in drop[::2]]
    return t[keep], np.asarray(found, dtype=np.int64)


CLUSTER_MOST = 12
"""A cluster of more changes than this is left as it is (no glitch taken out of it)."""


def _glitches_of(c: np.ndarray, other: np.ndarray | None, most: int) -> list[int]:
    """Indices of the changes to take out of one cluster (see :func:`_unglitch`)."""
    n = c.size
    if n > CLUSTER_MOST:
        return []

    def removable(i: int, j: int) -> bool:  # the run c[i..j] inclusive
        if (j - i + 1) % 2:
            return False
        if other is None:
            return True
        a, b = c[i], c[j]
        inside = np.searchsorted(other, b, side="left") - np.searchsorted(other, a, side="right")
        ends = np.searchsorted(other, b, side="right") - np.searchsorted(other, a, side="left")
        return inside == 0 and (ends == 0 or b - a <= 1)

    best: tuple[int, int] | None = None
    choice: list[int] = []
    for mask in range(1 << n):
        kept = [i for i in range(n) if mask >> i & 1]
        bounds = [-1, *kept, n]
        if not all(b - a == 1 or removable(a + 1, b - 1) for a, b in itertools.pairwise(bounds)):
            continue
        near = sum(c[b] - c[a] <= most for a, b in itertools.pairwise(kept))
        score = (near, n - len(kept))
        if best is None or score < best:
            best, choice = score, [i for i in range(n) if not mask >> i & 1]
    return choice


def _level_at(initial: int, changes: np.ndarray, t: np.ndarray) -> np.ndarray:
    """A line's level after every change at or before each time."""
    n = np.searchsorted(changes, t, side="right")
    return (initial + n) % 2


def decode(lines: Lines) -> Capture:
    """The pulses and the encoder count of a capture's lines (module doc).

    Parameters
    ----------
    lines : Lines
        The level changes.

    Returns
    -------
    Capture
        Times in s from the first stamp, the count relative to its value then.

    Raises
    ------
    ValueError
        Naming the file, where A and B change in the same sample before any count gives
        the direction of travel.
    """
    p = lines.source
    unit, first = lines.unit_s, lines.first
    pulse_t, dir_t, a_t, b_t = (np.asarray(c, dtype=np.int64) for c in lines.changes)
    glitches: list[tuple[str, float]] = []
    dir_t, g = _unglitch(dir_t, None, GLITCH_SAMPLES)
    glitches += [("dir", (x - first) * unit) for x in g.tolist()]
    a_clean, ga = _unglitch(a_t, b_t, GLITCH_SAMPLES)
    b_clean, gb = _unglitch(b_t, a_t, GLITCH_SAMPLES)
    glitches += [("enc_a", (x - first) * unit) for x in ga.tolist()]
    glitches += [("enc_b", (x - first) * unit) for x in gb.tolist()]
    glitches.sort(key=lambda g: g[1])
    a_t, b_t = a_clean, b_clean
    p0, d0, a0, b0 = lines.initial
    # pulses: the rising edges (changes to 1), signed by dir once their stamp has ended
    rises = pulse_t[(p0 + np.arange(1, pulse_t.size + 1)) % 2 == 1]
    sign = np.where(_level_at(d0, dir_t, rises) == 1, 1, -1).astype(np.int8)
    # the encoder: its state after every stamp at which A or B changed
    stamps = np.unique(np.concatenate([a_t, b_t]))
    state = _GRAY[2 * _level_at(a0, a_t, stamps) + _level_at(b0, b_t, stamps)]
    prev = np.concatenate([[_GRAY[2 * a0 + b0]], state[:-1]])
    step = (state - prev) % 4
    moved = step != 0
    stamps, step = stamps[moved], step[moved]
    single = np.where(step == 1, 1, np.where(step == 3, -1, 0))
    double = step == 2
    if np.any(double):
        # the direction of travel: the last single step before each double one
        idx = np.maximum.accumulate(np.where(single != 0, np.arange(single.size), -1))
        k = int(np.flatnonzero(double)[0])
        if idx[k] < 0:
            raise ValueError(
                f"{p}: enc_a and enc_b changed in the same sample at "
                f"{(stamps[k] - first) * unit:.9g} s before any count: expected a sample "
                "clock at least 4x the fastest edge"
            )
        single = np.where(double, 2 * single[np.maximum(idx, 0)], single)
    return Capture(
        source=p,
        pulse_s=(rises - first).astype(np.float64) * unit,
        pulse_sign=sign,
        count_s=(stamps - first).astype(np.float64) * unit,
        count=np.cumsum(single).astype(np.int64),
        end_s=(lines.last - first) * unit,
        resolution_s=unit,
        sampled=True,
        glitches=tuple(glitches),
        double_steps_s=(stamps[double] - first).astype(np.float64) * unit,
    )


__all__ = ["GLITCH_SAMPLES", "SIGNALS", "Capture", "Lines", "decode"]
