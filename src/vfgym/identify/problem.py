"""The least-squares problem: the estimated quantities in scaled coordinates, and the
residuals of the captures at any point of them.

Five parameters, relative to the nominal axis's plant (as a
:class:`~vfgym.axis.PlantVariant` applies them): a factor on the total inertia, the
Coulomb friction, the viscous friction, a constant load torque, and a factor on the
drive's gain K3 as set (:data:`PARAMS`). They are fitted in scaled coordinates
(:class:`Scale`: log factors, torques in % of the rated torque, viscous friction as its
torque at the pulse train's top speed in % of rated), then one nuisance per capture:
where its motor rests against the position the servo holds when it starts. The residuals
(:class:`Problem`) are in encoder counts (:mod:`vfgym.identify.model`), every candidate
of a batch simulated at once and each point's residuals kept.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from vfgym.axis import FACTOR_RANGE, PlantVariant
from vfgym.identify.model import Record, Response, Start, respond_many
from vfgym.params import Plant, Settings

PARAMS = ("inertia", "coulomb_nm", "viscous_nm_s_rad", "load_torque_nm", "torque_per_count")
"""The estimated quantities, named as the fields of an axis's ``uncertainty:`` block."""

STEPS = np.array([0.02, 0.3, 0.3, 0.3, 0.02])
"""Central-difference steps in the scaled coordinates (2 % on the factors, 0.3 % of rated
torque on the torques): large enough to step over the count's quantisation."""

HELD_STEP = 0.5
"""Central-difference step of a record's held error (counts)."""

HELD_EDGE = 1e-6
"""An enabled capture's held error stays this far inside its count (counts)."""


class Scale:
    """Scaled coordinates z ↔ the physical parameters, around a nominal plant.

    z holds the five parameters of :data:`PARAMS`, then one nuisance per record: where its
    motor rests against the position the servo holds (:attr:`Start.held_counts`, counts).
    """

    def __init__(self, nominal: Plant, records: Sequence[Record]) -> None:
        m = nominal.motor
        self.nominal = nominal
        self.tau = 0.01 * m.rated_torque_nm  # 1 % of rated torque
        self.speed = nominal.pulse_top_speed_rad_s
        held_lo, held_hi, held0 = [], [], []
        wide = 0.95 * m.peak_torque_nm / nominal.torque_per_count_nm
        for r in records:
            span = r.held_range()
            if span is None:
                held_lo.append(-wide)
                held_hi.append(wide)
                held0.append(-0.5)
            else:  # an enabled capture: the servo's error is known, not where in the count
                held_lo.append(span[0] + HELD_EDGE)
                held_hi.append(span[1])
                held0.append(0.5 * (span[0] + span[1]))
        self.z0 = np.array(
            [
                0.0,
                m.coulomb_nm / self.tau,
                m.viscous_nm_s_rad * self.speed / self.tau,
                m.load_torque_nm / self.tau,
                0.0,
                *held0,
            ]
        )
        lf, hf = math.log(FACTOR_RANGE[0]), math.log(FACTOR_RANGE[1])
        peak = m.peak_torque_nm / self.tau
        b_max = m.peak_torque_nm / m.knee_speed_rad_s * self.speed / self.tau
        self.lo = np.array([lf, 0.0, 0.0, -0.45 * peak, lf, *held_lo])
        self.hi = np.array([hf, 0.45 * peak, 0.95 * b_max, 0.45 * peak, hf, *held_hi])
        self.steps = np.concatenate([STEPS, np.full(len(records), HELD_STEP)])

    def physical(self, z: np.ndarray) -> np.ndarray:
        return np.array(
            [
                math.exp(z[0]),
                z[1] * self.tau,
                z[2] * self.tau / self.speed,
                z[3] * self.tau,
                math.exp(z[4]),
            ]
        )

    def jacobian_diag(self, z: np.ndarray) -> np.ndarray:
        """d physical / d z for each parameter (each depends on its own z only)."""
        return np.array([math.exp(z[0]), self.tau, self.tau / self.speed, self.tau, math.exp(z[4])])

    def variant(self, z: np.ndarray) -> PlantVariant:
        p = self.physical(z)
        m = self.nominal.motor
        return PlantVariant(
            inertia=float(p[0]),
            coulomb_offset_nm=float(p[1]) - m.coulomb_nm,
            viscous_offset_nm_s_rad=float(p[2]) - m.viscous_nm_s_rad,
            load_offset_nm=float(p[3]) - m.load_torque_nm,
            torque_per_count=float(p[4]),
        )

    def plant(self, z: np.ndarray) -> Plant:
        return self.variant(z).apply(self.nominal)


class Problem:
    """The residual function over the free coordinates, counting simulations."""

    def __init__(
        self, records: Sequence[Record], scale: Scale, settings: Settings, free: np.ndarray
    ) -> None:
        self.records = list(records)
        self.scale = scale
        self.settings = settings
        self.free = free
        self.base = scale.z0.copy()
        self.evaluations = 0
        self.phases = [0] * len(records)  # the servo's sample clock of each record
        self.ranked: list[list[tuple[float, int]]] = [[] for _ in records]  # (ss, phase)
        self._cache: dict[bytes, list[np.ndarray]] = {}

    def full(self, zf: np.ndarray) -> np.ndarray:
        z = self.base.copy()
        z[self.free] = zf
        return z

    def starts(self, z: np.ndarray) -> list[Start]:
        return [Start(float(h), ph) for h, ph in zip(z[len(PARAMS) :], self.phases, strict=True)]

    def per_record(self, zs: Sequence[np.ndarray]) -> list[list[np.ndarray]]:
        """Each record's residuals at several full coordinate vectors, one batch."""

        def key(z: np.ndarray) -> bytes:
            return z.tobytes() + np.asarray(self.phases, dtype=np.int64).tobytes()

        todo = list({key(z): z for z in zs if key(z) not in self._cache}.values())
        if todo:
            jobs = [(self.scale.plant(z), self.starts(z)) for z in todo]
            out = respond_many(self.records, jobs, self.settings)
            self.evaluations += len(todo)
            for z, resp in zip(todo, out, strict=True):
                self._cache[key(z)] = [
                    r.residuals(s) for r, s in zip(self.records, resp, strict=True)
                ]
        return [self._cache[key(z)] for z in zs]

    def simulated(self, z: np.ndarray) -> list[Response]:
        """Each record's response at ``z`` (every sample, not only the used ones)."""
        jobs = [(self.scale.plant(z), self.starts(z))]
        self.evaluations += 1
        return respond_many(self.records, jobs, self.settings)[0]

    def residuals_of(self, zs: Sequence[np.ndarray]) -> list[np.ndarray]:
        """Residual vectors for several full coordinate vectors, simulated as one batch."""
        return [np.concatenate(r) for r in self.per_record(zs)]

    def fun(self, zf: np.ndarray) -> np.ndarray:
        return self.residuals_of([self.full(zf)])[0]

    def jac(self, zf: np.ndarray) -> np.ndarray:
        z = self.full(zf)
        pts, spans = [], []
        for i in np.flatnonzero(self.free):
            h = self.scale.steps[i]
            up = min(z[i] + h, self.scale.hi[i])
            dn = max(z[i] - h, self.scale.lo[i])
            zu, zd = z.copy(), z.copy()
            zu[i], zd[i] = up, dn
            pts += [zu, zd]
            spans.append(up - dn)
        res = self.residuals_of(pts)
        cols = [(res[2 * k] - res[2 * k + 1]) / spans[k] for k in range(len(spans))]
        return np.stack(cols, axis=1)  # d(measured − simulated)/dz


WIDE = {
    "inertia": (0.5, 2.0),
    "torque_per_count": (0.5, 2.0),
}
"""Ranges (factors) of a factor the captures leave unknown; torques: :func:`wide_range`."""


def wide_range(name: str, nominal: Plant) -> tuple[float, float]:
    """The wide range a quantity the captures do not excite is left with.

    Parameters
    ----------
    name : str
        One of :data:`PARAMS`.
    nominal : Plant
        The nominal plant (its rated torque and top speed give the torques' scale).

    Returns
    -------
    tuple of float
        Factors (0.5, 2) for inertia and gain; up to 10 % of rated torque for Coulomb
        friction, ±10 % for the load torque around nominal; viscous friction up to a
        torque of 10 % of rated at the pulse train's top speed.
    """
    m = nominal.motor
    t = 0.10 * m.rated_torque_nm
    if name in WIDE:
        return WIDE[name]
    if name == "coulomb_nm":
        return (0.0, max(m.coulomb_nm, t))
    if name == "viscous_nm_s_rad":
        return (0.0, max(m.viscous_nm_s_rad, t / nominal.pulse_top_speed_rad_s))
    return (m.load_torque_nm - t, m.load_torque_nm + t)


__all__ = [
    "HELD_EDGE",
    "HELD_STEP",
    "PARAMS",
    "STEPS",
    "WIDE",
    "Problem",
    "Scale",
    "wide_range",
]
