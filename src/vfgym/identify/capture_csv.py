"""Captures as CSV: sigrok-cli's (a logic analyser's samples) and vfgym's trace CSV.

sigrok-cli's CSV (``sigrok-cli ... -O csv``, with or without ``:time=true``)
    Comment lines starting with ``;`` (the first ones name the channels, ``; Channels
    (4/4): D0, D1, D2, D3``, and give the sample rate, ``; Samplerate: 1 MHz``; sigrok-cli
    0.7.2 also writes a stray ``META samplerate: N`` line), a header row, then one row of
    0/1 levels per sample. The header row holds the channel names (``label=channel``) or
    their units (``logic``, the default ``label=units``), so the names come from the
    header where it has them, else from the ``Channels`` comment; they are mapped to the
    four signals by name, as a VCD's (``--signals``). ``time=true`` adds a first column:
    the time of the sample in the unit the header names (``microseconds`` …, or
    ``Time`` in the unit sigrok chose for the sample rate). Each row is one sample (most
    repeat the one before); where sigrok leaves only the rows that change (``dedup``),
    the time column places them.
    A time column sigrok could not fill (all zeros: sigrok-cli 0.7.2 converting a file
    it has no sample rate for) is ignored where every sample has its row. The levels'
    changes are decoded as a VCD's (:func:`vfgym.identify.lines.decode`).
vfgym's trace CSV (``vfgym export --format csv``)
    A header row and one row per controller tick (or finer) with the columns
    ``time_s``, ``pulse_count`` (signed command pulses so far) and ``encoder_count``
    (counts so far); other columns are ignored. A row's pulse is taken half a row before
    its time (the row is the end of the tick in which it happened).

Every problem is one ``ValueError`` line naming the file and what is expected; a last
row cut short is named as a truncated file.
"""

from __future__ import annotations

import csv
import io
import re
from pathlib import Path

import numpy as np

from vfgym.identify.lines import SIGNALS, Capture, Lines

CSV_COLUMNS = ("time_s", "pulse_count", "encoder_count")
"""The columns a trace CSV must hold."""

TIME_UNITS = {
    "milliseconds": 1e-3,
    "microseconds": 1e-6,
    "nanoseconds": 1e-9,
    "picoseconds": 1e-12,
    "femtoseconds": 1e-15,
    "attoseconds": 1e-18,
}
"""The units sigrok names its time column by (``label=units``)."""

_RATE = re.compile(rb"samplerate:\s*([0-9.]+)\s*(hz|khz|mhz|ghz)?\s*$", re.IGNORECASE)
_SCALE = {b"": 1.0, b"hz": 1.0, b"khz": 1e3, b"mhz": 1e6, b"ghz": 1e9}


def read_csv(p: Path, data: bytes, names: dict[str, str]) -> Capture | Lines:
    """A CSV capture: a trace CSV's :class:`Capture`, or a sigrok CSV's :class:`Lines`.

    Parameters
    ----------
    p : Path
        The file (for messages).
    data : bytes
        Its content.
    names : dict
        The name in the file of each of :data:`~vfgym.identify.lines.SIGNALS`.

    Returns
    -------
    Capture or Lines
        The trace CSV's capture; a sigrok CSV's level changes.

    Raises
    ------
    ValueError
        One line naming the file, for a file that is neither.
    """
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        raise ValueError(
            f"{p}: is not a text CSV: expected sigrok-cli's CSV or columns {', '.join(CSV_COLUMNS)}"
        ) from None
    first_two = [line for line in text.splitlines()[:50] if line.strip()][:2]
    head = first_two[0] if first_two else ""
    if "time_s" in [c.strip() for c in head.split(",")]:
        return _read_trace_csv(p, text)
    cells = [c.strip() for c in first_two[-1].split(",")] if first_two else []
    sigrok = head.startswith((";", "META")) or (len(cells) >= 2 and all(c.isdigit() for c in cells))
    if not sigrok:
        return _read_trace_csv(p, text)
    return _read_sigrok(p, data, names)


def _read_sigrok(p: Path, data: bytes, names: dict[str, str]) -> Lines:
    """A sigrok-cli CSV's level changes (module doc)."""
    channels: list[str] | None = None
    rate: float | None = None
    header: list[str] | None = None
    body_at = 0
    pos = 0
    for raw in data.splitlines(keepends=True):
        line = raw.strip()
        pos += len(raw)
        if not line:
            body_at = pos
            continue
        if line.startswith((b";", b"META")):
            text = line.lstrip(b";").strip()
            if text.lower().startswith(b"channels") and b":" in text:
                channels = [c.strip() for c in text.split(b":", 1)[1].decode().split(",")]
            m = _RATE.search(text)
            if m:
                rate = float(m.group(1)) * _SCALE[(m.group(2) or b"").lower()]
            body_at = pos
            continue
        cells = [c.strip() for c in line.decode(errors="replace").split(",")]
        if not all(c.isdigit() for c in cells):
            header = cells
            body_at = pos
        break
    body = data[body_at:]
    if not body.strip():
        raise ValueError(f"{p}: holds no sample row: expected sigrok-cli's CSV of the capture")
    cut = not body.endswith(b"\n")
    try:
        rows = np.loadtxt(
            io.BytesIO(body), delimiter=",", dtype=np.int64, ndmin=2, comments=(";", "META")
        )
    except ValueError as exc:
        if cut:
            raise ValueError(
                f"{p}: the file ends mid-row: a truncated file; expected the capture as "
                "sigrok-cli wrote it"
            ) from None
        raise ValueError(
            f"{p}: a sample row is not whole numbers separated by commas ({exc}): expected "
            "sigrok-cli's CSV"
        ) from None
    if cut:  # a last row cut short may still read as numbers: it cannot be trusted
        rows = rows[:-1]
        if rows.shape[0] < 2:
            raise ValueError(f"{p}: the file ends mid-row: a truncated file")
    n = rows.shape[1]
    labels = header if header is not None and len(header) == n else None
    timed = (labels is not None and labels[0] in ("Time", "samples", *TIME_UNITS)) or (
        channels is not None and n == len(channels) + 1
    )
    cols = labels[1:] if (labels and timed) else labels
    if cols is None or all(c == "logic" for c in cols):
        cols = channels
    if cols is None or len(cols) != n - int(timed):
        raise ValueError(
            f"{p}: names no channel (no header row of names and no '; Channels' comment): "
            "expected sigrok-cli's CSV with its header (header=true)"
        )
    where = {}
    for s in SIGNALS:
        if names[s] not in cols:
            raise ValueError(
                f"{p}: signal {s!r} (named {names[s]!r}) is missing: the file has "
                f"{', '.join(cols)}; give the names with --signals "
                "pulse=NAME,dir=NAME,enc_a=NAME,enc_b=NAME"
            )
        where[s] = cols.index(names[s]) + int(timed)
    levels = rows[:, [where[s] for s in SIGNALS]]
    if np.any((levels != 0) & (levels != 1)):
        raise ValueError(f"{p}: a channel holds a value other than 0 or 1: expected logic levels")
    samples, unit = _sample_times(p, rows, timed, labels, rate)
    if np.any(np.diff(samples) <= 0):
        raise ValueError(f"{p}: the time column does not increase: expected sigrok-cli's CSV")
    changes = []
    for j in range(4):
        at = np.flatnonzero(np.diff(levels[:, j])) + 1
        changes.append(samples[at])
    return Lines(
        source=str(p),
        unit_s=unit,
        first=int(samples[0]),
        last=int(samples[-1]),
        initial=(
            int(levels[0, 0]),
            int(levels[0, 1]),
            int(levels[0, 2]),
            int(levels[0, 3]),
        ),
        changes=(changes[0], changes[1], changes[2], changes[3]),
    )


def _sample_times(
    p: Path, rows: np.ndarray, timed: bool, labels: list[str] | None, rate: float | None
) -> tuple[np.ndarray, float]:
    """Each row's sample number and the seconds per sample (module doc)."""
    lv = rows[:, int(timed) :]
    # a row per sample repeats the one before on most rows (a capture rests, and a clock
    # 4x the fastest edge keeps a level for several samples); sigrok's dedup repeats a
    # row only where a packet of samples starts or ends
    every = rows.shape[0] > 1 and float(np.mean(np.all(lv[1:] == lv[:-1], axis=1))) > 0.5
    t = rows[:, 0] if timed else None
    usable = t is not None and bool(np.all(np.diff(t) > 0))
    if rate is not None and (every or not usable):
        if not every:
            raise ValueError(
                f"{p}: holds only the rows that change and no time column to place them: "
                "expected sigrok-cli's CSV with time=true, or with dedup=false"
            )
        return np.arange(rows.shape[0], dtype=np.int64), 1.0 / rate
    if usable and t is not None:
        unit = TIME_UNITS.get(labels[0] if labels else "", 0.0)
        if unit == 0.0 and rate is not None:  # 'Time': sigrok's unit for the rate
            unit = 1.0
            while unit * rate > 1.0 + 1e-9:
                unit *= 1e-3
        if unit > 0.0:
            if rate is not None:
                return np.rint(t * unit * rate).astype(np.int64), 1.0 / rate
            return t.astype(np.int64), unit
    raise ValueError(
        f"{p}: gives no sample rate (no '; Samplerate' comment) and no time column in a "
        "named unit: expected sigrok-cli's CSV with its header (header=true)"
    )


def _read_trace_csv(p: Path, text: str) -> Capture:
    """A trace CSV's capture (module doc)."""
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
                f"{', '.join(CSV_COLUMNS)} (got {', '.join(header) or 'none'}), or "
                "sigrok-cli's CSV"
            )
        cols[name] = header.index(name)
    values: list[list[float]] = [[], [], []]
    cut = not text.endswith("\n")
    lines = list(enumerate(rows, start=2))
    for k, (line, row) in enumerate(lines):
        if not row:
            continue
        for j, name in enumerate(CSV_COLUMNS):
            try:
                values[j].append(float(row[cols[name]]))
            except (IndexError, ValueError):
                if cut and k == len(lines) - 1:
                    raise ValueError(
                        f"{p}: the file ends mid-row (line {line}): a truncated file; "
                        "expected the capture as written"
                    ) from None
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


__all__ = ["CSV_COLUMNS", "TIME_UNITS", "read_csv"]
