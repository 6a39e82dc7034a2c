"""Captures as a logic analyser records them, simulated from plants drawn at random.

A true plant (never named by a test: drawn from a seed within the benchmark's ranges)
runs the pulse train after a rest from the drive's enable, as the machine did; the record
starts at an arbitrary instant during that rest (the axis already held) or, as the plan's
procedure asks, before the enable; every edge is rounded to the analyser's 1 µs samples
(1 MHz), and the encoder is seen only as its A/B edges.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from vfgym.axis import PAPER_AXIS, Axis, PlantVariant
from vfgym.identify.capture import read_capture
from vfgym.identify.fit import PARAMS
from vfgym.identify.pipeline import identify_axis
from vfgym.identify.simulated import record_capture
from vfgym.params import PAPER_SETTINGS, Plant

REST_S = 0.5
"""Rest simulated before the pulse train (s): the record starts after 40–90 % of it, the
axis long settled (a load torque sags it for tens of ms after the simulation's start)."""

ENABLE_REST_S = 0.2
"""From the drive's enable to the pulse train (s), for a record started before the
enable (10–100 ms before it)."""


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


def draw_truth(
    nominal: Plant, rng: np.random.Generator, *, inertia_ratio=(0.0, 8.0), gain: float = 1.0
) -> Truth:
    """A true plant: inertia ratio, Coulomb (≤ 5 % rated), viscous (≤ 3e-4), load (±5 %),
    the drive's gain ``gain`` times the one set."""
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
        torque_per_count=gain,
    )
    return Truth(v.apply(nominal), factor, c, b, load, gain)


def capture_vcd(
    plant: Plant,
    pulses: np.ndarray,
    path: Path,
    rng: np.random.Generator,
    *,
    from_enable: bool = False,
) -> Path:
    """Record ``pulses`` run on ``plant`` as a 1 MHz logic analyser would (see the module doc)."""
    u = rng.uniform(0.4, 0.9)
    if from_enable:
        return record_capture(plant, pulses, path, start_s=-0.01 - 0.1 * u, rest_s=ENABLE_REST_S)
    return record_capture(plant, pulses, path, start_s=REST_S * u, rest_s=REST_S)


def identify_vcd(path: Path, axis: Axis = PAPER_AXIS, *, from_enable: bool = True, **kw):
    """``vfgym identify``'s path on one capture: (Identified, records, plan matches)."""
    return identify_axis(axis, [read_capture(path)], PAPER_SETTINGS,
                         from_enable=True if from_enable else None, **kw)  # fmt: skip


def outside_block(ident, truth: Truth) -> list[str]:
    """The quantities whose true value lies outside the identified axis's uncertainty block
    (its inertia and gain factors are on the estimates; a gain left out is the one set)."""
    unc = ident.axis.uncertainty
    out = []
    for name in PARAMS:
        value = truth.value(name)
        if name in ("inertia", "torque_per_count"):
            value /= ident.fit.estimate(name).value
        lo, hi = getattr(unc, name) or (1.0, 1.0)
        if not lo - 1e-12 <= value <= hi + 1e-12:
            out.append(f"{name}: {value:.6g} not in [{lo:.6g}, {hi:.6g}]")
    return out
