"""Pulse/direction and encoder A/B signals as a Value Change Dump, written with pyvcd.

Every VCD vfgym writes comes from here: a simulated move (``vfgym export``), the pulse
train of an identification plan to replay, and a simulated capture of one. The file opens
in GTKWave or PulseView. Four 1-bit wires (two for a pulse train alone):

``pulse``
    high during the second half of every tick that outputs a pulse: it rises at
    (i + ½)·T and falls at (i + 1)·T, so pulses in consecutive ticks (the top rate δ·f)
    still give one rising edge each. A rising edge is one command pulse.
``dir``
    1 for a positive pulse, 0 for a negative one; it changes at the start i·T of the
    tick whose pulse needs the other direction (half a tick of set-up before the rising
    edge) and otherwise holds. Its initial value is the first pulse's direction.
``enc_a``, ``enc_b``
    the motor encoder's quadrature channels. The count is c = floor(θ / q) (q = 2π /
    (4·lines), as the servo sees it); the levels follow c mod 4 in Gray order 0 → (A, B) =
    (0, 0), 1 → (1, 0), 2 → (1, 1), 3 → (0, 1), so A leads B when θ rises. A tick that
    crosses several counts places each edge where θ, interpolated linearly over the
    tick, crosses the count boundary.

The signals are first :class:`Edges` (times in s), then written by :func:`write_edges`,
every time rounded to the timescale. A move's export (:func:`vcd_text`) places its edges
on the timescale's grid itself: tick i starts at round(i·T / unit), so rounding never
accumulates (the comment block states T exactly), and each encoder edge is kept inside
its tick, after its start, and strictly after the one before, so that no edge is lost or
moved across a tick boundary. A simulated capture (:func:`trace_edges` with a start)
leaves several edges free to share a time stamp, as an analyser's samples do.
"""

from __future__ import annotations

import io
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

# The traces written here are vfgym.Trace, typed as Any: io sits below plant
# (docs/architecture.md) and imports nothing of vfgym, not even for type checking.

NAMES = ("pulse", "dir", "enc_a", "enc_b")
"""The wires' names, in declaration order."""

_UNITS = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9, "ps": 1e-12, "fs": 1e-15}


def parse_timescale(timescale: str) -> float:
    """Seconds per unit of a VCD timescale.

    Parameters
    ----------
    timescale : str
        ``1``, ``10`` or ``100`` and a unit, e.g. ``1 ns`` or ``100ps``.

    Returns
    -------
    float
        Seconds per unit.

    Raises
    ------
    ValueError
        For any other text.
    """
    m = re.fullmatch(r"\s*(1|10|100)\s*(s|ms|us|ns|ps|fs)\s*", str(timescale))
    if not m:
        raise ValueError(
            f"timescale={timescale!r} is not allowed: 1, 10 or 100 followed by s, ms, us, "
            "ns, ps or fs"
        )
    return int(m.group(1)) * _UNITS[m.group(2)]


@dataclass(frozen=True)
class Edges:
    """Level changes of the four signals, times in s.

    Attributes
    ----------
    pulse_s : numpy.ndarray
        Rising edge time of each pulse.
    pulse_sign : numpy.ndarray
        +1 / −1 per pulse.
    pulse_fall_s : numpy.ndarray
        Falling edge time of each pulse.
    pulse_start_s : numpy.ndarray
        Start of each pulse's tick: where ``dir`` changes for a pulse that needs the other
        direction.
    count_s : numpy.ndarray
        Time of each encoder count step.
    count : numpy.ndarray
        The count after each step.
    end_s : float
        The last time of the record.
    """

    pulse_s: np.ndarray
    pulse_sign: np.ndarray
    pulse_fall_s: np.ndarray
    pulse_start_s: np.ndarray
    count_s: np.ndarray
    count: np.ndarray
    end_s: float


def encoder_edges(trace: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Every encoder count step of a move, in time order.

    Parameters
    ----------
    trace : vfgym.Trace
        An undecimated trace.

    Returns
    -------
    tuple of numpy.ndarray
        (tick, fraction of the tick in [0, 1] at which θ crosses, count after the step,
        the boundary b crossed, between counts b − 1 and b).
    """
    q = trace.plant.motor.count_rad
    th1 = np.asarray(trace.motor_rad, dtype=np.float64)
    th0 = np.concatenate([[0.0], th1[:-1]])
    c1 = np.floor(th1 / q).astype(np.int64)
    c0 = np.concatenate([[0], c1[:-1]])
    dc = c1 - c0
    ticks = np.flatnonzero(dc)
    steps = np.abs(dc[ticks])
    if ticks.size == 0:
        none = np.zeros(0, np.int64)
        return none, np.zeros(0), none, none
    rep = np.repeat(ticks, steps)
    k = np.arange(rep.size) - np.repeat(np.cumsum(steps) - steps, steps)  # 0.. within a tick
    up = dc[rep] > 0
    b = np.where(up, c0[rep] + 1 + k, c0[rep] - k)  # boundary crossed (count b−1 | b)
    after = np.where(up, b, b - 1)
    a0, a1 = th0[rep], th1[rep]
    frac = np.clip((b * q - a0) / (a1 - a0), 0.0, 1.0)
    return rep, frac, after, b


def train_edges(pulses: np.ndarray, tick_hz: float, *, lead_s: float = 0.0) -> Edges:
    """The edges of a pulse train alone (no encoder), the first tick starting at ``lead_s``.

    Parameters
    ----------
    pulses : numpy.ndarray
        −1, 0, +1 per controller tick.
    tick_hz : float
        The controller's tick rate (Hz).
    lead_s : float
        Time of the first tick's start (s).

    Returns
    -------
    Edges
        The pulse edges; no encoder step.
    """
    T = 1.0 / tick_hz
    pt = np.flatnonzero(pulses)
    return Edges(
        pulse_s=lead_s + (pt + 0.5) * T,
        pulse_sign=np.sign(pulses[pt]).astype(np.int8),
        pulse_fall_s=lead_s + (pt + 1.0) * T,
        pulse_start_s=lead_s + pt * T,
        count_s=np.zeros(0),
        count=np.zeros(0, dtype=np.int64),
        end_s=lead_s + pulses.size * T,
    )


def trace_edges(
    trace: Any,
    *,
    start_s: float = 0.0,
    stop_s: float | None = None,
    grid_s: float | None = None,
) -> Edges:
    """The edges of a simulated move (an undecimated :class:`vfgym.Trace`).

    Parameters
    ----------
    trace : vfgym.Trace
        An undecimated trace.
    start_s : float
        When the record starts (s after the trace's tick 0): a capture that starts at an
        arbitrary instant.
    stop_s : float or None
        When it stops (default: the trace's end).
    grid_s : float or None
        A move's export (module doc): every time on this grid (the timescale's unit),
        tick i starting at round(i·T / unit), each encoder edge inside its tick, after
        its start and after the edge before it. ``None``: the times as simulated.

    Returns
    -------
    Edges
        Times relative to the record's start; the count relative to the count then.
    """
    f = trace.plant.tick_hz
    T = 1.0 / f
    p = trace.pulses
    tick, frac, after, _ = encoder_edges(trace)
    if grid_s is None:
        e = train_edges(p, f, lead_s=-start_s)
        ts = (tick + frac) * T - start_s
    else:
        per_tick = 1.0 / (f * grid_s)

        def at(x: np.ndarray) -> np.ndarray:
            return np.rint(np.asarray(x, dtype=np.float64) * per_tick).astype(np.int64)

        pt = np.flatnonzero(p)
        e = Edges(
            pulse_s=at(pt + 0.5) * grid_s - start_s,
            pulse_sign=np.sign(p[pt]).astype(np.int8),
            pulse_fall_s=at(pt + 1.0) * grid_s - start_s,
            pulse_start_s=at(pt) * grid_s - start_s,
            count_s=np.zeros(0),
            count=np.zeros(0, np.int64),
            end_s=float(at(np.array([trace.n_ticks]))[0]) * grid_s - start_s,
        )
        te = np.clip(at(tick + frac), at(tick) + 1, at(tick + 1))  # inside its tick
        k = np.arange(te.size)
        te = np.maximum.accumulate(np.maximum(te, 1) - k) + k  # strictly increasing, > 0
        ts = te * grid_s - start_s
    before = np.flatnonzero(ts <= 0)
    c0 = int(after[before[-1]]) if before.size else 0  # the count when the record starts
    end = (e.end_s + start_s if stop_s is None else stop_s) - start_s
    keep_p = (e.pulse_s > 0) & (e.pulse_s <= end)
    keep_c = (ts > 0) & (ts <= end)
    return Edges(
        pulse_s=e.pulse_s[keep_p],
        pulse_sign=e.pulse_sign[keep_p],
        pulse_fall_s=e.pulse_fall_s[keep_p],
        pulse_start_s=e.pulse_start_s[keep_p],
        count_s=ts[keep_c],
        count=after[keep_c] - c0,
        end_s=end,
    )


def _ascii(text: str) -> str:
    """A comment line in plain ASCII (VCD files are ASCII); ``$end`` cannot close it early."""
    table = {"−": "-", "θ": "theta", "δ": "delta", "×": "x", "·": "*", "±": "+/-"}
    text = "".join(table.get(ch, ch) for ch in text).replace("$end", "end")
    return text.encode("ascii", "replace").decode("ascii")


def write_edges(
    edges: Edges,
    out: str | Path | io.TextIOBase,
    *,
    timescale: str = "1 ns",
    names: tuple[str, str, str, str] = NAMES,
    encoder: bool = True,
    comment: str = "",
    scope: str = "vfgym",
    version: str = "vfgym",
) -> Path | None:
    """Write edges as a VCD with pyvcd's writer, each time rounded to the timescale.

    Parameters
    ----------
    edges : Edges
        The edges.
    out : str, Path or text stream
        The file (written atomically), or a stream to write into.
    timescale : str
        The VCD's unit, e.g. ``1 ns`` or ``1 us`` (a 1 MHz logic analyser).
    names : tuple of str
        Names of the pulse, dir, A and B signals.
    encoder : bool
        Write the encoder's A/B channels.
    comment : str
        A comment for the header (made plain ASCII).
    scope : str
        The module the signals sit in.
    version : str
        The header's ``$version``.

    Returns
    -------
    Path or None
        The file written (``None`` for a stream).
    """
    if not isinstance(out, (str, Path)):
        _write_stream(edges, out, timescale, names, encoder, comment, scope, version)
        return None
    from vfgym.io.runs import write_atomically

    def write(tmp: Path) -> None:
        with tmp.open("w", encoding="ascii") as fh:
            _write_stream(edges, fh, timescale, names, encoder, comment, scope, version)

    return write_atomically(out, write)


def _write_stream(
    edges: Edges,
    fh: Any,
    timescale: str,
    names: tuple[str, str, str, str],
    encoder: bool,
    comment: str,
    scope: str,
    version: str,
) -> None:
    """:func:`write_edges` into an open text stream."""
    from vcd import VCDWriter

    unit = parse_timescale(timescale)

    def at(t: np.ndarray) -> np.ndarray:
        return np.rint(np.asarray(t, dtype=np.float64) / unit).astype(np.int64)

    # (time, order, wire, value); the order keeps a same-time fall before a dir change
    # before a rise, and the encoder last
    events: list[tuple[np.ndarray, int, int, np.ndarray]] = []
    sign = edges.pulse_sign > 0
    dir0 = bool(sign[0]) if sign.size else True
    events.append((at(edges.pulse_fall_s), 0, 0, np.zeros(sign.size, np.int8)))
    prev = np.concatenate([[dir0], sign[:-1]])
    ch = sign != prev
    events.append((at(edges.pulse_start_s[ch]), 1, 1, sign[ch].astype(np.int8)))
    events.append((at(edges.pulse_s), 2, 0, np.ones(sign.size, np.int8)))
    if encoder:
        m = np.mod(edges.count, 4)
        a = ((m == 1) | (m == 2)).astype(np.int8)
        b = ((m == 2) | (m == 3)).astype(np.int8)
        prev_m = np.mod(np.concatenate([[0], edges.count[:-1]]), 4)
        prev_a = (prev_m == 1) | (prev_m == 2)
        is_a = a.astype(bool) != prev_a
        events.append((at(edges.count_s[is_a]), 3, 2, a[is_a]))
        events.append((at(edges.count_s[~is_a]), 3, 3, b[~is_a]))
    t = np.concatenate([e[0] for e in events])
    order = np.concatenate([np.full(e[0].size, e[1]) for e in events])
    wire = np.concatenate([np.full(e[0].size, e[2]) for e in events])
    value = np.concatenate([e[3] for e in events])
    idx = np.lexsort((order, t))
    t, wire, value = np.maximum(t[idx], 0), wire[idx], value[idx]
    count = 4 if encoder else 2
    lines = [_ascii(line) for line in comment.splitlines() if line.strip()]
    with VCDWriter(
        fh, timescale=timescale.strip(), date="", comment="\n".join(lines), version=version
    ) as w:
        init = (0, int(dir0), 0, 0)
        wires = [
            w.register_var(scope, names[k], "wire", size=1, init=init[k]) for k in range(count)
        ]
        for ti, k, v in zip(t.tolist(), wire.tolist(), value.tolist(), strict=True):
            w.change(wires[k], ti, v)
        w.flush(max(int(at(np.array([edges.end_s]))[0]), int(t[-1]) if t.size else 0))


def _export_comment(trace: Any, timescale: str, comment: str) -> str:
    """The header comment of a move's export: the tick, the conventions, ``comment``."""
    f = trace.plant.tick_hz
    per_tick = 1.0 / (f * parse_timescale(timescale))
    head = [
        f"tick_hz {f!r} (T = {1.0 / f!r} s = {per_tick!r} units); times are round(i*T/unit)",
        "pulse: high in the second half of a tick with a pulse; dir: 1 = positive",
        "enc_a/enc_b: quadrature of floor(theta/q), Gray order 00,10,11,01 counting up",
    ]
    return "\n".join(head + comment.splitlines())


def _export_edges(trace: Any, timescale: str) -> Edges:
    """A move's edges on the timescale's grid (module doc), after its checks."""
    if trace.decimation != 1:
        raise ValueError(f"decimation={trace.decimation} is not allowed: the VCD needs every tick")
    unit = parse_timescale(timescale)
    f = trace.plant.tick_hz
    if 1.0 / (f * unit) < 4.0:
        raise ValueError(
            f"timescale={timescale!r} is too coarse for tick_hz={f:g}: one tick must span at "
            "least 4 units; choose a finer timescale"
        )
    return trace_edges(trace, grid_s=unit)


def vcd_text(trace: Any, *, timescale: str = "1 ns", comment: str = "") -> str:
    """A move's VCD (``vfgym export``) as text.

    Parameters
    ----------
    trace : vfgym.Trace
        An undecimated trace.
    timescale : str
        The VCD's unit; a tick must span at least 4.
    comment : str
        Lines added to the header's comment.

    Returns
    -------
    str
        The file's text.

    Raises
    ------
    ValueError
        For a decimated trace or a timescale too coarse for the tick.
    """
    buf = io.StringIO()
    write_edges(
        _export_edges(trace, timescale),
        buf,
        timescale=timescale,
        comment=_export_comment(trace, timescale, comment),
        version="vfgym VCD export",
    )
    return buf.getvalue()


def write_vcd(trace: Any, path: str | Path, *, timescale: str = "1 ns", comment: str = "") -> Path:
    """Write a move's VCD (``vfgym export``) atomically.

    Parameters
    ----------
    trace : vfgym.Trace
        An undecimated trace.
    path : str or Path
        The file.
    timescale : str
        The VCD's unit; a tick must span at least 4.
    comment : str
        Lines added to the header's comment.

    Returns
    -------
    Path
        The file written.
    """
    out = write_edges(
        _export_edges(trace, timescale),
        path,
        timescale=timescale,
        comment=_export_comment(trace, timescale, comment),
        version="vfgym VCD export",
    )
    assert out is not None
    return out


def edge_counts(trace: Any) -> dict[str, int]:
    """What a move's VCD holds, counted from the trace.

    Parameters
    ----------
    trace : vfgym.Trace
        The trace.

    Returns
    -------
    dict
        ``pulses_pos``, ``pulses_neg``, ``encoder_steps`` and ``final_count``.
    """
    p = trace.pulses
    q = trace.plant.motor.count_rad
    c = np.floor(np.asarray(trace.motor_rad) / q).astype(np.int64)
    return {
        "pulses_pos": int(np.count_nonzero(p > 0)),
        "pulses_neg": int(np.count_nonzero(p < 0)),
        "encoder_steps": int(np.abs(np.diff(c, prepend=0)).sum()),
        "final_count": int(c[-1]) if c.size else 0,
    }


__all__ = [
    "NAMES",
    "Edges",
    "edge_counts",
    "encoder_edges",
    "parse_timescale",
    "trace_edges",
    "train_edges",
    "vcd_text",
    "write_edges",
    "write_vcd",
]
