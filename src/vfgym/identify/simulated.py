"""A capture simulated as a logic analyser records it: pulses run on a plant, with rest
before and after.

:func:`record_capture` runs a pulse train (an identification plan's) on a plant from the
drive's enable, and writes what an analyser started at a given instant records: every
edge rounded to its sample clock, the encoder only as its A/B edges (the conventions of
:mod:`vfgym.io.vcd`, which writes the file). For the dry run of ``vfgym identify --plan``,
a capture of a "true" axis file's plant, and the tests and benchmarks of the estimator;
:func:`with_faults` puts into such a capture the faults a recording may hold (lost
edges, glitches, A and B swapped, a file cut short), for the tests and benchmarks of what
``vfgym identify`` refuses or flags.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from vfgym.io.vcd import trace_edges, write_edges
from vfgym.params import PAPER_SETTINGS, Plant, Settings
from vfgym.plant import simulate


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
    out = write_edges(trace_edges(tr, start_s=start_s, stop_s=end_s), path, timescale=timescale)
    assert out is not None
    return out


@dataclass(frozen=True)
class Faults:
    """The faults :func:`with_faults` put into a capture, with their times.

    Attributes
    ----------
    lost_s : tuple of float
        Times (s) of the encoder edges taken out (each with the next edge of its line,
        as a line that missed a pulse of its signal shows).
    glitch_s : tuple of (str, float)
        The line and time (s) of each one-sample glitch put in.
    swapped : bool
        ``enc_a`` and ``enc_b`` exchanged.
    cut_s : float or None
        Where the file was cut, mid-line (s).
    """

    lost_s: tuple[float, ...] = ()
    glitch_s: tuple[tuple[str, float], ...] = ()
    swapped: bool = False
    cut_s: float | None = None


def with_faults(
    src: str | Path,
    dst: str | Path,
    rng: np.random.Generator,
    *,
    lost: int = 0,
    glitches: int = 0,
    swap: bool = False,
    cut_s: float | None = None,
    mid_line: bool = True,
) -> Faults:
    """A VCD capture with the faults a recording may hold, for the tests and benchmarks of
    what ``vfgym identify`` refuses or flags.

    Parameters
    ----------
    src, dst : str or Path
        A capture as :func:`record_capture` writes it, and the file to write.
    rng : numpy.random.Generator
        Chooses where.
    lost : int
        Encoder edges to take out, each with the next edge of its line (a pulse of A or
        B the recording missed), chosen among all of A's and B's.
    glitches : int
        One-sample pulses to put on lines chosen at random (pulse, dir, enc_a, enc_b),
        at times chosen at random.
    swap : bool
        Exchange the names of ``enc_a`` and ``enc_b``.
    cut_s : float or None
        Cut the file at the first time stamp at or after this time (s).
    mid_line : bool
        Cut in the middle of that stamp's line (a file cut short as it was written), else
        just before it (a valid file that ends early).

    Returns
    -------
    Faults
        What was done, and where.
    """
    text = Path(src).read_text(encoding="ascii")
    split = text.index("$enddefinitions $end") + len("$enddefinitions $end\n")
    head, body = text[:split], text[split:]
    unit = _timescale_of(head)
    ids = {ln.split()[4]: ln.split()[3] for ln in head.splitlines() if ln.startswith("$var")}
    stamps: dict[int, list[str]] = {}
    order: list[int] = []
    time = 0
    dump: list[str] = []
    in_dump = False
    for tok in body.split():
        if tok.startswith("#"):
            time = int(tok[1:])
            if time not in stamps:
                stamps[time] = []
                order.append(time)
        elif tok in ("$dumpvars", "$end"):
            in_dump = tok == "$dumpvars"
            dump.append(tok)
        elif in_dump:
            dump.append(tok)
        else:
            stamps[time].append(tok)
    first, last = order[0], order[-1]
    changes = {name: [t for t in order for c in stamps[t] if c[1:] == ident]
               for name, ident in ids.items()}  # fmt: skip
    lost_s: list[float] = []
    edges = [(name, i) for name in ("enc_a", "enc_b") for i in range(len(changes[name]) - 1)]
    taken: set[tuple[str, int]] = set()
    for j in rng.permutation(len(edges)).tolist():
        if len(lost_s) >= lost:
            break
        name, i = edges[j]
        if {(name, i), (name, i + 1)} & taken:
            continue
        taken |= {(name, i), (name, i + 1)}
        for t in changes[name][i : i + 2]:
            stamps[t] = [c for c in stamps[t] if c[1:] != ids[name]]
        lost_s.append((changes[name][i] - first) * unit)
    glitch_s: list[tuple[str, float]] = []
    names = ("pulse", "dir", "enc_a", "enc_b")
    while len(glitch_s) < glitches:
        name = names[int(rng.integers(4))]
        t = int(rng.integers(first + 1, last - 1))
        if any(c[1:] == ids[name] for u in (t, t + 1) for c in stamps.get(u, [])):
            continue
        n_before = int(np.searchsorted(np.asarray(changes[name]), t, side="right"))
        level = (_initial(dump, ids[name]) + n_before) % 2
        for u, v in ((t, 1 - level), (t + 1, level)):
            if u not in stamps:
                stamps[u] = []
            stamps[u].append(f"{v}{ids[name]}")
        glitch_s.append((name, (t - first) * unit))
    if swap:
        a, b = ids["enc_a"], ids["enc_b"]
        head = head.replace(f" {a} enc_a $end", f" {a} enc_b_ $end")
        head = head.replace(f" {b} enc_b $end", f" {b} enc_a $end")
        head = head.replace(" enc_b_ $end", " enc_b $end")
    out = [head.rstrip("\n")]
    for k, t in enumerate(sorted(stamps)):
        out.append(f"#{t}")
        if k == 0:
            out += dump
        out += stamps[t]
    new = "\n".join(out) + "\n"
    cut_at = None
    if cut_s is not None:
        at = new.find(f"\n#{next(t for t in sorted(stamps) if (t - first) * unit >= cut_s)}")
        new = new[: at + 4] if mid_line else new[: at + 1]  # '#' and two digits, or none
        cut_at = cut_s
    Path(dst).write_text(new, encoding="ascii")
    return Faults(tuple(lost_s), tuple(sorted(glitch_s, key=lambda g: g[1])), swap, cut_at)


def _timescale_of(head: str) -> float:
    """Seconds per unit of a VCD header's ``$timescale``."""
    from vfgym.io.vcd import parse_timescale

    i = head.index("$timescale") + len("$timescale")
    return parse_timescale(head[i : head.index("$end", i)])


def _initial(dump: list[str], ident: str) -> int:
    """A line's level in the ``$dumpvars`` block."""
    return next((1 if c[0] == "1" else 0 for c in dump if c[1:] == ident), 0)


__all__ = ["Faults", "record_capture", "with_faults"]
