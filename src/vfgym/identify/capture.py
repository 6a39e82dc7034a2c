"""Reading a logic analyser's capture: pulse/direction edges and the encoder's count.

Two formats, both giving a :class:`Capture` (times in s from the capture's start):

VCD
    As a logic analyser saves it (sigrok-cli, PulseView) or ``vfgym export --format vcd``
    writes it: four 1-bit signals, found by name (``pulse``, ``dir``, ``enc_a``,
    ``enc_b``; another name per signal with :func:`parse_signal_map`, e.g. sigrok's
    ``D0`` … ``D3``). A command pulse is a rising edge of ``pulse``, its sign the level of
    ``dir`` then (1: positive). The encoder's count is decoded from the A/B levels in
    Gray order 00 → 10 → 11 → 01 counting up (A leads B), as :mod:`vfgym.io.vcd` writes
    them; the sample clock must be at least 4× the fastest edge, so that A and B never
    change in the same sample but for a rare coincidence, which is taken as two steps
    on in the direction of travel. Tokens are read by pyvcd's reader; sigrok-cli 0.7.2
    writes a stray ``META ...`` line before the header, which is skipped. The header is read
    by pyvcd's tokenizer, the value changes by a split on white space (the body's grammar
    is a handful of token forms, and pyvcd takes ~7 s on a 2 s capture at 1 MHz).
CSV
    A header row and one row per controller tick (or finer) with the columns
    ``time_s``, ``pulse_count`` (signed command pulses so far) and ``encoder_count``
    (counts so far), as ``vfgym export --format csv`` writes them; other columns are
    ignored. A row's pulse is taken half a row before its time (the row is the end of
    the tick in which it happened).

Every problem is one ``ValueError`` line naming the file, the signal or column and what
is expected.
"""

from __future__ import annotations

import csv
import io
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from vfgym.io.vcd import parse_timescale

SIGNALS = ("pulse", "dir", "enc_a", "enc_b")
"""The four signals a VCD capture must hold, by their default names."""

CSV_COLUMNS = ("time_s", "pulse_count", "encoder_count")
"""The columns a CSV capture must hold."""

_GRAY = {(0, 0): 0, (1, 0): 1, (1, 1): 2, (0, 1): 3}


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
        True for a VCD: every edge stands at one of the analyser's samples (multiples of
        ``resolution_s`` from the start), not at its own instant; a CSV row holds the
        count at its own time.
    """

    source: str
    pulse_s: np.ndarray
    pulse_sign: np.ndarray
    count_s: np.ndarray
    count: np.ndarray
    end_s: float
    resolution_s: float
    sampled: bool = False

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


def parse_signal_map(text: str | None) -> dict[str, str]:
    """The signal names of a VCD capture from ``--signals`` text.

    Parameters
    ----------
    text : str or None
        ``pulse=D0,dir=D1,enc_a=D2,enc_b=D3`` (any subset; the others keep their default
        names), or ``None`` for the defaults.

    Returns
    -------
    dict
        Name in the file of each of :data:`SIGNALS`.

    Raises
    ------
    ValueError
        For an entry that is not ``signal=name`` or names an unknown signal.
    """
    names = {s: s for s in SIGNALS}
    if not text:
        return names
    for item in text.split(","):
        key, eq, value = item.strip().partition("=")
        if not eq or key.strip() not in SIGNALS or not value.strip():
            raise ValueError(
                f"--signals={text!r} is not allowed: give signal=name pairs separated by "
                f"commas, signals among {', '.join(SIGNALS)} (e.g. pulse=D0,dir=D1,enc_a=D2,"
                "enc_b=D3)"
            )
        names[key.strip()] = value.strip()
    return names


def read_capture(path: str | Path, signals: dict[str, str] | None = None) -> Capture:
    """A capture from a VCD or CSV file (by its suffix; ``.csv`` is CSV, anything else VCD).

    Parameters
    ----------
    path : str or Path
        The file.
    signals : dict or None
        A VCD's signal names (:func:`parse_signal_map`); default the names of
        :data:`SIGNALS`.

    Returns
    -------
    Capture
        Its pulses and encoder count.

    Raises
    ------
    ValueError
        One line naming the file, for an unreadable or corrupt file, a missing signal or
        column, or a capture with no pulse.
    """
    p = Path(path)
    try:
        data = p.read_bytes()
    except OSError as exc:
        raise ValueError(
            f"{p}: cannot be read ({exc.strerror or exc}): expected a VCD or CSV capture"
        ) from None
    cap = _read_csv(p, data) if p.suffix.lower() == ".csv" else _read_vcd(p, data, signals)
    if cap.pulse_s.size == 0:
        raise ValueError(
            f"{p}: holds no command pulse: expected the pulse train of the moves (rising "
            "edges of the pulse signal, or a changing pulse_count)"
        )
    return cap


def _header(p: Path, text: bytes) -> tuple[float, dict[str, str], int]:
    """The VCD header read with pyvcd's tokenizer: (seconds per time unit, identifier of
    each variable name, byte offset of the body after ``$enddefinitions $end``)."""
    from vcd.reader import Timescale, TokenKind, VarDecl, VCDParseError, tokenize

    unit = 1e-9
    ids: dict[str, str] = {}
    lines = text.split(b"\n")
    try:
        for tok in tokenize(io.BytesIO(text)):
            data = tok.data
            if isinstance(data, Timescale):
                unit = parse_timescale(f"{int(data.magnitude)} {data.unit.value}")
            elif isinstance(data, VarDecl):
                ids.setdefault(data.reference, data.id_code)
            elif tok.kind is TokenKind.ENDDEFINITIONS:
                end = tok.span.end
                offset = sum(len(x) + 1 for x in lines[: end.line - 1]) + end.column - 1
                return unit, ids, offset
    except VCDParseError as exc:
        raise ValueError(f"{p}: is not a readable VCD ({exc}): expected a VCD capture") from None
    except (UnicodeDecodeError, KeyError, AttributeError, ValueError) as exc:
        raise ValueError(f"{p}: is not a readable VCD ({exc}): expected a VCD capture") from None
    raise ValueError(f"{p}: has no complete VCD header ($enddefinitions): expected a VCD capture")


def _body(p: Path, body: bytes) -> Iterator[tuple[int, bytes, int]]:
    """The value changes of a VCD body: (time, identifier, value) in file order, and
    (time, ``b""``, 0) at each time stamp.

    The body's grammar is small (``#time``, ``0id``/``1id``/``xid``/``zid``, and the
    ``$dumpvars`` … ``$end`` keywords around initial values), so it is split on white
    space here rather than tokenised by pyvcd, about 30× faster on a capture of a
    million edges; a vector or real value (``b…``, ``r…``) of a 1-bit signal is refused."""
    time = None
    skip = False
    for tok in body.split():
        c = tok[0]
        if c == 35:  # '#'
            try:
                t = int(tok[1:])
            except ValueError:
                raise ValueError(
                    f"{p}: time stamp {tok.decode(errors='replace')!r} is not a whole number: "
                    "expected #TIME"
                ) from None
            if time is not None and t < time:
                raise ValueError(
                    f"{p}: time #{t} goes back (after #{time}): expected increasing time stamps"
                )
            time = t
            yield t, b"", 0  # a stamp with no change still lengthens the capture
        elif c == 36:  # '$'
            if tok == b"$comment":
                skip = True
            elif tok == b"$end":
                skip = False
        elif skip:
            continue
        elif c in (48, 49, 120, 122, 88, 90):  # 0 1 x z X Z
            if time is None:
                raise ValueError(f"{p}: a value change comes before any #time: expected #0 first")
            yield time, tok[1:], 1 if c == 49 else 0
        elif c in (98, 66, 114, 82):  # vector or real: the identifier is the next token
            raise ValueError(
                f"{p}: holds a vector or real value ({tok.decode(errors='replace')!r}): "
                "expected 1-bit signals"
            )
        else:
            raise ValueError(
                f"{p}: is not a readable VCD (unexpected {tok.decode(errors='replace')!r} "
                "after the header): expected a VCD capture"
            )


def _read_vcd(p: Path, data: bytes, signals: dict[str, str] | None) -> Capture:
    names = signals or {s: s for s in SIGNALS}
    start = data.find(b"$")
    if start < 0:
        raise ValueError(f"{p}: is not a VCD file (no $ keyword): expected a VCD capture")
    text = data[start:]  # sigrok-cli 0.7.2 writes a stray "META samplerate" line first
    unit, ids, offset = _header(p, text)
    missing = [s for s in SIGNALS if names[s] not in ids]
    if missing:
        s = missing[0]
        raise ValueError(
            f"{p}: signal {s!r} (named {names[s]!r}) is missing: the file has "
            f"{', '.join(ids) or 'no signal'}; give the names with --signals "
            "pulse=NAME,dir=NAME,enc_a=NAME,enc_b=NAME"
        )
    role_of: dict[bytes, list[int]] = {}
    for r, s in enumerate(SIGNALS):
        role_of.setdefault(ids[names[s]].encode(), []).append(r)
    level = [0, 0, 0, 0]
    pulse_t: list[int] = []
    pulse_sign: list[int] = []
    count_t: list[int] = []
    count_v: list[int] = []
    first: int | None = None
    time = -1
    count = 0
    state = 0
    last_dir = 0
    enc_dirty = False

    def end_stamp() -> None:
        """What the time stamp ``time`` left: the encoder's step, the pulses' signs."""
        nonlocal state, count, last_dir, enc_dirty
        _fill_signs(pulse_sign, level[1])
        if not enc_dirty:
            return
        enc_dirty = False
        new = _GRAY[(level[2], level[3])]
        step = (new - state) % 4
        state = new
        if time == first or step == 0:  # the initial levels: where the count starts
            return
        if step == 2:
            if last_dir == 0:
                raise ValueError(
                    f"{p}: enc_a and enc_b changed in the same sample at "
                    f"{(time - (first or 0)) * unit:.9g} s before any count: expected a "
                    "sample clock at least 4x the fastest edge"
                )
            d = 2 * last_dir
        else:
            d = 1 if step == 1 else -1
            last_dir = d
        count += d
        count_t.append(time)
        count_v.append(count)

    for t, ident, v in _body(p, text[offset:]):
        if t != time:
            if first is None:
                first = t
            else:
                end_stamp()
            time = t
        roles = role_of.get(ident)
        if not roles:
            continue
        for r in roles:
            if r == 0 and v == 1 and level[0] == 0 and first is not None and time > first:
                pulse_t.append(time)
                pulse_sign.append(0)  # the dir level is read once the stamp ends
            level[r] = v
            if r >= 2:
                enc_dirty = True
    if first is None:
        raise ValueError(f"{p}: holds no value change: expected a capture of the moves")
    end_stamp()
    sign = np.where(np.asarray(pulse_sign, dtype=np.int8) > 0, 1, -1).astype(np.int8)
    return Capture(
        source=str(p),
        pulse_s=(np.asarray(pulse_t, dtype=np.float64) - first) * unit,
        pulse_sign=sign,
        count_s=(np.asarray(count_t, dtype=np.float64) - first) * unit,
        count=np.asarray(count_v, dtype=np.int64),
        end_s=(time - first) * unit,
        resolution_s=unit,
        sampled=True,
    )


def _fill_signs(signs: list[int], dir_level: int) -> None:
    """Give the pulses of the time stamp just ended (sign 0) the ``dir`` level."""
    i = len(signs) - 1
    while i >= 0 and signs[i] == 0:
        signs[i] = 1 if dir_level else -1
        i -= 1


def _read_csv(p: Path, data: bytes) -> Capture:
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        raise ValueError(
            f"{p}: is not a text CSV: expected columns {', '.join(CSV_COLUMNS)}"
        ) from None
    rows = csv.reader(io.StringIO(text))
    header = next(rows, None)
    if header is None:
        raise ValueError(f"{p}: is empty: expected a header row {','.join(CSV_COLUMNS)}")
    header = [h.strip() for h in header]
    cols = {}
    for name in CSV_COLUMNS:
        if name not in header:
            raise ValueError(
                f"{p}: column {name!r} is missing: expected a header row with "
                f"{', '.join(CSV_COLUMNS)} (got {', '.join(header) or 'none'})"
            )
        cols[name] = header.index(name)
    values: list[list[float]] = [[], [], []]
    for line, row in enumerate(rows, start=2):
        if not row:
            continue
        for j, name in enumerate(CSV_COLUMNS):
            try:
                values[j].append(float(row[cols[name]]))
            except (IndexError, ValueError):
                cell = row[cols[name]] if cols[name] < len(row) else ""
                raise ValueError(
                    f"{p}: line {line}: column {name!r} holds {cell!r}: expected a number"
                ) from None
    t, pc, ec = (np.asarray(v, dtype=np.float64) for v in values)
    if t.size < 2:
        raise ValueError(f"{p}: holds {t.size} row(s): expected one row per controller tick")
    if not (np.all(np.isfinite(t)) and np.all(np.diff(t) > 0)):
        raise ValueError(f"{p}: column 'time_s' is not finite and increasing: expected times (s)")
    for name, col in (("pulse_count", pc), ("encoder_count", ec)):
        if not np.all(col == np.round(col)):
            raise ValueError(f"{p}: column {name!r} holds a fraction: expected whole counts")
    dt = float(np.median(np.diff(t)))
    dp = np.diff(pc, prepend=pc[0])
    if np.any(np.abs(dp) > 1):
        i = int(np.flatnonzero(np.abs(dp) > 1)[0])
        raise ValueError(
            f"{p}: column 'pulse_count' jumps by {int(dp[i])} at time_s={t[i]:.9g}: expected "
            "one row per controller tick or finer (at most one pulse between rows)"
        )
    at = np.flatnonzero(dp)
    de = np.flatnonzero(np.diff(ec, prepend=ec[0]))
    t0 = t[0]
    return Capture(
        source=str(p),
        pulse_s=t[at] - t0 - 0.5 * dt,
        pulse_sign=np.sign(dp[at]).astype(np.int8),
        count_s=t[de] - t0,
        count=(ec[de] - ec[0]).astype(np.int64),
        end_s=float(t[-1] - t0),
        resolution_s=dt,
    )


__all__ = ["CSV_COLUMNS", "SIGNALS", "Capture", "parse_signal_map", "read_capture"]
