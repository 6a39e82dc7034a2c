"""A simulated move's pulse/direction and encoder A/B signals as a Value Change Dump.

The file opens in GTKWave or PulseView. Four 1-bit wires in module ``vfgym``:

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
    (0, 0), 1 → (1, 0), 2 → (1, 1), 3 → (0, 1), so A leads B when θ rises. At tick
    boundaries the count is the simulated one exactly; a tick that crosses several counts
    places each edge where θ, interpolated linearly over the tick, crosses the count
    boundary (times rounded to the timescale but kept inside their tick, after its start,
    and strictly increasing, so no edge is lost or moved across a tick boundary).

Times are whole multiples of the timescale (default 1 ns): tick i starts at
round(i·T / unit), so rounding never accumulates (the comment block states T exactly).
Only value changes are written, after the initial ``$dumpvars``.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import numpy as np

# The traces written here are vfgym.Trace, typed as Any: io sits below plant
# (docs/architecture.md) and imports nothing of vfgym, not even for type checking.

SIGNALS = (("pulse", "!"), ("dir", "%"), ("enc_a", "&"), ("enc_b", "'"))
"""(name, VCD identifier) of the wires, in declaration order."""

_UNITS = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9, "ps": 1e-12, "fs": 1e-15}


def parse_timescale(timescale: str) -> float:
    """Seconds per unit of a VCD timescale such as ``1 ns`` or ``100ps``."""
    m = re.fullmatch(r"\s*(1|10|100)\s*(s|ms|us|ns|ps|fs)\s*", str(timescale))
    if not m:
        raise ValueError(
            f"timescale={timescale!r} is not allowed: 1, 10 or 100 followed by s, ms, us, "
            "ns, ps or fs"
        )
    return int(m.group(1)) * _UNITS[m.group(2)]


def encoder_edges(trace: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Every encoder count step of a move, in time order: (tick, fraction of the tick in
    [0, 1] at which θ crosses, count after the step, the boundary b crossed, between
    counts b − 1 and b)."""
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


def _ascii(text: str) -> str:
    """A comment line in plain ASCII (VCD files are ASCII); ``$end`` cannot close it early."""
    table = {"−": "-", "θ": "theta", "δ": "delta", "×": "x", "·": "*", "±": "+/-"}
    text = "".join(table.get(ch, ch) for ch in text).replace("$end", "end")
    return text.encode("ascii", "replace").decode("ascii")


def vcd_text(
    trace: Any,
    *,
    timescale: str = "1 ns",
    comment: str = "",
) -> str:
    """The VCD file's text for an undecimated :class:`vfgym.Trace` (see the module doc)."""
    if trace.decimation != 1:
        raise ValueError(f"decimation={trace.decimation} is not allowed: the VCD needs every tick")
    unit = parse_timescale(timescale)
    f = trace.plant.tick_hz
    per_tick = 1.0 / (f * unit)
    if per_tick < 4.0:
        raise ValueError(
            f"timescale={timescale!r} is too coarse for tick_hz={f:g}: one tick must span at "
            "least 4 units; choose a finer timescale"
        )

    def at(x: np.ndarray) -> np.ndarray:
        return np.rint(np.asarray(x, dtype=np.float64) * per_tick).astype(np.int64)

    p = trace.pulses
    pt = np.flatnonzero(p)
    sign = p[pt] > 0
    dir0 = bool(sign[0]) if pt.size else True
    ids = dict(SIGNALS)

    # events: (time, order, id, value); order keeps a same-time fall before a rise
    times, order, who, val = [], [], [], []

    def add(t: np.ndarray, o: int, name: str, v: np.ndarray) -> None:
        times.append(t)
        order.append(np.full(t.size, o))
        who.append(np.full(t.size, ids[name], dtype=object))
        val.append(np.asarray(v, dtype=np.int8))

    add(at(pt + 0.5), 2, "pulse", np.ones(pt.size))
    add(at(pt + 1.0), 0, "pulse", np.zeros(pt.size))
    prev = np.concatenate([[dir0], sign[:-1]])
    ch = pt[sign != prev]
    add(at(ch), 1, "dir", sign[sign != prev].astype(np.int8))

    tick, frac, after, b = encoder_edges(trace)
    te = np.clip(at(tick + frac), at(tick) + 1, at(tick + 1))  # inside its tick, after its start
    k = np.arange(te.size)
    te = np.maximum.accumulate(np.maximum(te, 1) - k) + k  # strictly increasing, > 0
    m = np.mod(after, 4)
    is_a = np.mod(b, 2) == 1  # boundaries 0|1 and 2|3 toggle A, 1|2 and 3|0 toggle B
    a_level = ((m == 1) | (m == 2)).astype(np.int8)
    b_level = ((m == 2) | (m == 3)).astype(np.int8)
    add(te[is_a], 3, "enc_a", a_level[is_a])
    add(te[~is_a], 3, "enc_b", b_level[~is_a])

    T = np.concatenate(times)
    Ord = np.concatenate(order)
    W = np.concatenate(who)
    V = np.concatenate(val)
    idx = np.lexsort((Ord, T))
    T, W, V = T[idx], W[idx], V[idx]

    period_s = 1.0 / f
    head = [
        "$version vfgym VCD export $end",
        "$comment",
        f"  tick_hz {f!r} (T = {period_s!r} s = {per_tick!r} units); times are round(i*T/unit)",
        "  pulse: high in the second half of a tick with a pulse; dir: 1 = positive",
        "  enc_a/enc_b: quadrature of floor(theta/q), Gray order 00,10,11,01 counting up",
    ]
    head += [f"  {_ascii(line)}" for line in comment.splitlines() if line.strip()]
    head += [
        "$end",
        f"$timescale {timescale.strip()} $end",
        "$scope module vfgym $end",
        *(f"$var wire 1 {i} {name} $end" for name, i in SIGNALS),
        "$upscope $end",
        "$enddefinitions $end",
        "#0",
        "$dumpvars",
        f"0{ids['pulse']}",
        f"{int(dir0)}{ids['dir']}",
        f"0{ids['enc_a']}",
        f"0{ids['enc_b']}",
        "$end",
    ]
    out = head
    last = 0
    for t, w, v in zip(T.tolist(), W.tolist(), V.tolist(), strict=True):
        if t != last:
            out.append(f"#{t}")
            last = t
        out.append(f"{v}{w}")
    end = at(np.array([trace.n_ticks]))[0]
    if end > last:
        out.append(f"#{end}")
    return "\n".join(out) + "\n"


def write_vcd(trace: Any, path: str | Path, *, timescale: str = "1 ns", comment: str = "") -> Path:
    """Write :func:`vcd_text` to ``path`` atomically."""
    from vfgym.io.runs import write_text

    return write_text(path, vcd_text(trace, timescale=timescale, comment=comment))


def edge_counts(trace: Any) -> dict[str, int]:
    """What the VCD holds, counted from the trace: pulses by sign and encoder steps."""
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
    "SIGNALS",
    "edge_counts",
    "encoder_edges",
    "parse_timescale",
    "vcd_text",
    "write_vcd",
]
