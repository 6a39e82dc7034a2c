"""Reading a logic analyser's capture: pulse/direction edges and the encoder's count.

Three forms, each giving a :class:`~vfgym.identify.lines.Capture` (times in s from the
capture's start):

VCD
    As a logic analyser saves it (sigrok-cli, PulseView) or ``vfgym export --format vcd``
    writes it: four 1-bit signals, found by name (``pulse``, ``dir``, ``enc_a``,
    ``enc_b``; another name per signal with :func:`parse_signal_map`, e.g. sigrok's
    ``D0`` … ``D3``), read into each line's level changes and decoded by
    :func:`vfgym.identify.lines.decode`. sigrok-cli 0.7.2 writes a stray ``META ...``
    line before the header, which is skipped. The header is read by pyvcd's tokenizer,
    the value changes by a split on white space (the body's grammar is a handful of token
    forms, and pyvcd takes ~7 s on a 2 s capture at 1 MHz).
sigrok-cli's CSV and vfgym's trace CSV
    By the ``.csv`` suffix, read in :mod:`vfgym.identify.capture_csv`.

Every problem is one ``ValueError`` line naming the file, the signal or column and what
is expected; a file that ends mid-line is named as truncated.
"""

from __future__ import annotations

import io
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from vfgym.identify.capture_csv import CSV_COLUMNS, read_csv
from vfgym.identify.lines import SIGNALS, Capture, Lines, decode
from vfgym.io.vcd import parse_timescale


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
        An analyser's signal names (:func:`parse_signal_map`); default the names of
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
    names = signals or {s: s for s in SIGNALS}
    if p.suffix.lower() == ".csv":
        got = read_csv(p, data, names)
        cap = got if isinstance(got, Capture) else decode(got)
    else:
        cap = decode(_read_vcd(p, data, names))
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
    million edges; a vector or real value (``b…``, ``r…``) of a 1-bit signal is refused.
    A file that does not end with a line break was cut short (a VCD writer ends its
    last line): it is refused as truncated, its last token named."""
    toks = body.split()
    if toks and not body[-1:].isspace():
        raise ValueError(
            f"{p}: the file ends mid-line ({toks[-1].decode(errors='replace')!r}): a "
            "truncated file; expected the capture as the analyser saved it"
        )
    time = None
    skip = False
    for tok in toks:
        c = tok[0]
        if c == 35:  # '#'
            try:
                t = int(tok[1:])
            except ValueError:
                raise ValueError(
                    f"{p}: time stamp {tok.decode(errors='replace')!r} is not a whole "
                    "number: expected #TIME"
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


def _read_vcd(p: Path, data: bytes, names: dict[str, str]) -> Lines:
    """Each line's level changes in a VCD (see :class:`~vfgym.identify.lines.Lines`)."""
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
    changes: list[list[int]] = [[], [], [], []]
    first: int | None = None
    initial: tuple[int, int, int, int] = (0, 0, 0, 0)
    time = -1
    for t, ident, v in _body(p, text[offset:]):
        if t != time:
            if first is None:
                first = t
            elif time == first:
                initial = (level[0], level[1], level[2], level[3])  # after the first stamp
            time = t
        for r in role_of.get(ident, ()):
            if v != level[r]:
                level[r] = v
                if t != first:
                    changes[r].append(t)
    if first is None:
        raise ValueError(f"{p}: holds no value change: expected a capture of the moves")
    if time == first:
        initial = (level[0], level[1], level[2], level[3])
    return Lines(
        source=str(p),
        unit_s=unit,
        first=first,
        last=time,
        initial=initial,
        changes=(
            np.asarray(changes[0], dtype=np.int64),
            np.asarray(changes[1], dtype=np.int64),
            np.asarray(changes[2], dtype=np.int64),
            np.asarray(changes[3], dtype=np.int64),
        ),
    )


__all__ = ["CSV_COLUMNS", "SIGNALS", "Capture", "parse_signal_map", "read_capture"]
