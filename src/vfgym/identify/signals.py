"""Writing pulse/direction and encoder A/B edges as a VCD, with pyvcd's writer.

The conventions are those of :mod:`vfgym.io.vcd`: a pulse of tick i rises at (i + ½)·T and
falls at (i + 1)·T, ``dir`` (1: positive) changes at the start i·T of the tick whose pulse
needs the other direction, and the encoder's A/B levels follow the count in Gray order
00, 10, 11, 01 counting up. Here every time may be offset (a capture that starts at an
arbitrary instant) and rounded to a coarser clock (a logic analyser's samples), and the
encoder channels may be left out (the pulse/direction train of a plan, to replay).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from vfgym.io.vcd import encoder_edges, parse_timescale
from vfgym.params import PAPER_SETTINGS, Plant, Settings
from vfgym.plant import simulate


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
    count_s: np.ndarray
    count: np.ndarray
    end_s: float


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
        count_s=np.zeros(0),
        count=np.zeros(0, dtype=np.int64),
        end_s=lead_s + pulses.size * T,
    )


def trace_edges(trace: object, *, start_s: float = 0.0, stop_s: float | None = None) -> Edges:
    """The edges of a simulated move (a :class:`vfgym.Trace` at every tick), the record
    starting ``start_s`` after the move's start (so the capture starts at an arbitrary
    instant).

    Parameters
    ----------
    trace : vfgym.Trace
        An undecimated trace.
    start_s : float
        When the record starts (s after the trace's tick 0).
    stop_s : float or None
        When it stops (default: the trace's end).

    Returns
    -------
    Edges
        Times relative to the record's start; the count relative to the count then.
    """
    f = trace.plant.tick_hz  # type: ignore[attr-defined]
    T = 1.0 / f
    p = trace.pulses  # type: ignore[attr-defined]
    e = train_edges(p, f, lead_s=-start_s)
    tick, frac, after, _ = encoder_edges(trace)
    ts = (tick + frac) * T - start_s
    before = np.flatnonzero(ts <= 0)
    c0 = int(after[before[-1]]) if before.size else 0  # the count when the record starts
    end = (trace.n_ticks * T if stop_s is None else stop_s) - start_s  # type: ignore[attr-defined]
    keep_p = (e.pulse_s > 0) & (e.pulse_s <= end)
    keep_c = (ts > 0) & (ts <= end)
    return Edges(
        pulse_s=e.pulse_s[keep_p],
        pulse_sign=e.pulse_sign[keep_p],
        pulse_fall_s=e.pulse_fall_s[keep_p],
        count_s=ts[keep_c],
        count=after[keep_c] - c0,
        end_s=end,
    )


def write_edges_vcd(
    edges: Edges,
    path: str | Path,
    *,
    timescale: str = "1 ns",
    names: tuple[str, str, str, str] = ("pulse", "dir", "enc_a", "enc_b"),
    encoder: bool = True,
    comment: str = "",
    scope: str = "vfgym",
) -> Path:
    """Write edges as a VCD, each time rounded to the timescale (a sampled record).

    Parameters
    ----------
    edges : Edges
        The edges.
    path : str or Path
        The file.
    timescale : str
        The VCD's unit, e.g. ``1 ns`` or ``1 us`` (a 1 MHz logic analyser).
    names : tuple of str
        Names of the pulse, dir, A and B signals.
    encoder : bool
        Write the encoder's A/B channels.
    comment : str
        A comment for the header.
    scope : str
        The module the signals sit in.

    Returns
    -------
    Path
        The file written.
    """
    from vcd import VCDWriter

    unit = parse_timescale(timescale)

    def at(t: np.ndarray) -> np.ndarray:
        return np.rint(np.asarray(t, dtype=np.float64) / unit).astype(np.int64)

    events: list[tuple[np.ndarray, int, int, np.ndarray]] = []
    sign = edges.pulse_sign > 0
    dir0 = bool(sign[0]) if sign.size else True
    events.append((at(edges.pulse_fall_s), 0, 0, np.zeros(sign.size, np.int8)))
    prev = np.concatenate([[dir0], sign[:-1]])
    ch = sign != prev
    half = float(edges.pulse_fall_s[0] - edges.pulse_s[0]) if sign.size else 0.0
    events.append((at(edges.pulse_s[ch] - half), 1, 1, sign[ch].astype(np.int8)))
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
    T = np.concatenate([e[0] for e in events])
    order = np.concatenate([np.full(e[0].size, e[1]) for e in events])
    W = np.concatenate([np.full(e[0].size, e[2]) for e in events])
    V = np.concatenate([e[3] for e in events])
    idx = np.lexsort((order, T))
    T, W, V = np.maximum(T[idx], 0), W[idx], V[idx]
    p = Path(path)
    count = 4 if encoder else 2
    with (
        p.open("w", encoding="ascii") as fh,
        VCDWriter(fh, timescale=timescale.strip(), comment=comment, version="vfgym") as w,
    ):
        init = (0, int(dir0), 0, 0)
        vars_ = [
            w.register_var(scope, names[k], "wire", size=1, init=init[k]) for k in range(count)
        ]
        for t, k, v in zip(T.tolist(), W.tolist(), V.tolist(), strict=True):
            w.change(vars_[k], t, v)
        w.flush(int(at(np.array([edges.end_s]))[0]))
    return p


def record_capture(
    plant: Plant,
    pulses: np.ndarray,
    path: str | Path,
    *,
    start_s: float,
    rest_s: float = 0.5,
    length_s: float | None = None,
    timescale: str = "1 us",
    settings: Settings = PAPER_SETTINGS,
) -> Path:
    """A capture of ``pulses`` run on ``plant`` as a logic analyser records it: the pulse
    train after ``rest_s`` at rest, the record starting ``start_s`` into that rest (an
    arbitrary instant), every edge rounded to ``timescale`` (``1 us``: 1 MHz), the encoder
    only as its A/B edges. For tests and benchmarks of the estimator, and a dry run.

    Parameters
    ----------
    plant : Plant
        The (true) plant.
    pulses : numpy.ndarray
        −1, 0, +1 per controller tick.
    path : str or Path
        The VCD to write.
    start_s : float
        When the record starts (s), in [0, ``rest_s``), or before 0: the simulation
        starts at the drive's enable (the servo holding no error, a load torque sagging
        the axis), so a negative start records the enable as a capture started before it
        does.
    rest_s : float
        Rest before the pulse train (s), from the enable.
    length_s : float or None
        Length of the record (s); default to 50 ms after the train.
    timescale : str
        The analyser's sample period as a VCD timescale.
    settings : Settings
        The servo's filter ratio in force.

    Returns
    -------
    Path
        The file written.
    """
    f = plant.tick_hz
    end_s = rest_s + pulses.size / f + 0.05 if length_s is None else start_s + length_s
    n = max(round(end_s * f) + 1, round(rest_s * f) + pulses.size)
    train = np.zeros(n, dtype=np.int8)
    train[round(rest_s * f) : round(rest_s * f) + pulses.size] = pulses
    tr = simulate(np.zeros(n), settings, plant, pulses=train)
    return write_edges_vcd(
        trace_edges(tr, start_s=start_s, stop_s=end_s), path, timescale=timescale
    )


__all__ = ["Edges", "record_capture", "trace_edges", "train_edges", "write_edges_vcd"]
