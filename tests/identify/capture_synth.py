"""Captures as a logic analyser records them, simulated from plants drawn at random.

A true plant (never named by a test: drawn from a seed within the benchmark's ranges)
runs the pulse train after a long rest, as the machine did; the record starts at an
arbitrary instant during that rest, every edge is rounded to the analyser's 1 µs samples
(1 MHz), and the encoder is seen only as its A/B edges.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from vfgym.identify.signals import trace_edges, write_edges_vcd
from vfgym.params import PAPER_SETTINGS, Plant
from vfgym.plant import simulate
from vfgym.plant.uncertainty import PlantVariant

REST_S = 0.1
"""Rest simulated before the pulse train (s)."""


@dataclass(frozen=True)
class Truth:
    """A drawn true plant and its parameters as the fit states them."""

    plant: Plant
    inertia: float
    coulomb_nm: float
    viscous_nm_s_rad: float
    load_torque_nm: float
    torque_per_count: float = 1.0

    def value(self, name: str) -> float:
        return float(getattr(self, name))


def draw_truth(nominal: Plant, rng: np.random.Generator, *, inertia_ratio=(0.0, 8.0)) -> Truth:
    """A true plant: inertia ratio, Coulomb (≤ 5 % rated), viscous (≤ 3e-4), load (±5 %)."""
    rated = nominal.motor.rated_torque_nm
    r = rng.uniform(*inertia_ratio)
    factor = (1.0 + r) / (1.0 + nominal.motor.inertia_ratio)
    c = rng.uniform(0.0, 0.05) * rated
    b = rng.uniform(0.0, 3e-4)
    load = rng.uniform(-0.05, 0.05) * rated
    m = nominal.motor
    v = PlantVariant(
        inertia=factor,
        coulomb_offset_nm=c - m.coulomb_nm,
        viscous_offset_nm_s_rad=b - m.viscous_nm_s_rad,
        load_offset_nm=load - m.load_torque_nm,
    )
    return Truth(v.apply(nominal), factor, c, b, load)


def capture_vcd(
    plant: Plant,
    pulses: np.ndarray,
    path: Path,
    rng: np.random.Generator,
    *,
    tail_s: float = 0.05,
    names: tuple[str, str, str, str] = ("pulse", "dir", "enc_a", "enc_b"),
    scope: str = "vfgym",
) -> Path:
    """Record ``pulses`` run on ``plant`` as a 1 MHz logic analyser would (see the module doc)."""
    f = plant.tick_hz
    rest = round(REST_S * f)
    tail = round(tail_s * f)
    train = np.concatenate([np.zeros(rest, np.int8), pulses, np.zeros(tail, np.int8)])
    tr = simulate(np.zeros(train.size), PAPER_SETTINGS, plant, pulses=train)
    start = REST_S * rng.uniform(0.3, 0.9)
    edges = trace_edges(tr, start_s=start)
    return write_edges_vcd(edges, path, timescale="1 us", names=names, scope=scope)
