"""A capture simulated as a logic analyser records it: pulses run on a plant, with rest
before and after.

:func:`record_capture` runs a pulse train (an identification plan's) on a plant from the
drive's enable, and writes what an analyser started at a given instant records: every
edge rounded to its sample clock, the encoder only as its A/B edges (the conventions of
:mod:`vfgym.io.vcd`, which writes the file). For the dry run of ``vfgym identify --plan``,
a capture of a "true" axis file's plant, and the tests and benchmarks of the estimator.
"""

from __future__ import annotations

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


__all__ = ["record_capture"]
