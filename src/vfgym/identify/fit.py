"""The estimator: the plant whose simulated response to the recorded pulses matches the
recorded encoder count, by least squares, with 95 % intervals.

Five parameters, relative to the nominal axis's plant (as a
:class:`~vfgym.plant.uncertainty.PlantVariant` applies them): a factor on the total
inertia, the Coulomb friction, the viscous friction, a constant load torque, and a factor
on the drive's gain K3 as set. They are fitted in scaled coordinates (log factors,
torques in % of the rated torque, viscous friction as its torque at the pulse train's top
speed in % of rated) by :func:`scipy.optimize.least_squares`, residuals in encoder counts
(:mod:`vfgym.identify.model`), with the Jacobian taken by central differences, every
perturbed plant simulated in one batch. A parameter the captures do not excite
(:mod:`vfgym.identify.excite`) is held at its nominal value.

The intervals come from the Jacobian at the optimum. The residuals are not independent
from sample to sample (the count's quantisation and the loop's limit cycles last many
samples), so the covariance is the sandwich (JᵀJ)⁻¹ S (JᵀJ)⁻¹ with S the Newey–West
(Bartlett-weighted) sum of the score's autocovariances up to the residuals' correlation
length, rather than s²·(JᵀJ)⁻¹, which would be far too narrow. The load torque's
interval is also widened to where a profile along it (the others held) leaves the RMS
residual within 10 % of its least: below the torque limit it is bounded on one side
only, which the Jacobian at the optimum does not show.

One nuisance is fitted and then accounted for: the phase of the servo's sample clock
against the pulses (its speed counter latches every Ns ticks), which no capture records.
The start tries every phase in steps of the residuals' sample and keeps the best; the
covariance adds the spread of the Gauss–Newton steps the residuals at
:data:`NUISANCE_PHASES` other phases would take from the optimum, and likewise for where
within its first count the motor started (:data:`NUISANCE_STARTS`).
"""

from __future__ import annotations

import math
import struct
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from vfgym.identify.covariance import newey_west
from vfgym.identify.excite import MIN_SATURATED_S, Excitation, excitation
from vfgym.identify.model import SAMPLE_TICKS, Record, Response, respond_many
from vfgym.params import Plant, Settings
from vfgym.plant.uncertainty import FACTOR_RANGE, PlantVariant

PARAMS = ("inertia", "coulomb_nm", "viscous_nm_s_rad", "load_torque_nm", "torque_per_count")
"""The estimated quantities, named as the fields of an axis's ``uncertainty:`` block."""

STEPS = np.array([0.02, 0.3, 0.3, 0.3, 0.02])
"""Central-difference steps in the scaled coordinates (2 % on the factors, 0.3 % of rated
torque on the torques): large enough to step over the count's quantisation."""

Z95 = 1.959963984540054
"""The two-sided 95 % quantile of the normal distribution."""

NUISANCE_PHASES = 6
"""Other phases of the servo's sample clock whose effect on the estimate is added to the
covariance."""

NUISANCE_STARTS = (0.25, 0.5, 0.75)
"""Starting positions of the motor within its first count (counts) whose effect on the
estimate is added to the covariance."""

HAC_FLOOR_S = 0.15
"""The Newey–West bandwidth is at least this long (s), a move's length: the residuals'
nuisances (where within a count the axis started, the tick grid's phase) shift whole
moves at once, so the scores stay correlated over a move even where the residuals'
own autocorrelation has died out."""

QUANTISATION_FLOOR = 1.0 / math.sqrt(12.0)
"""RMS error (counts) of reading a position as whole counts: the floor of the residual."""


@dataclass(frozen=True)
class Estimate:
    """One estimated quantity.

    Attributes
    ----------
    name : str
        One of :data:`PARAMS`.
    value : float
        The estimate: a factor on the nominal total inertia or gain, else N·m or
        N·m·s/rad.
    low, high : float
        Its 95 % interval (the nominal value and a wide range when not excited).
    nominal : float
        The nominal axis's value (factor 1 for inertia and gain).
    excited : bool
        False when the captures cannot show it: held at its nominal value.
    one_sided : bool
        True when the residual stays flat along it for :data:`ONE_SIDED` % of the rated
        torque or more (the load torque below the torque limit): the interval is then
        a bound.
    """

    name: str
    value: float
    low: float
    high: float
    nominal: float
    excited: bool
    one_sided: bool = False


@dataclass(frozen=True)
class Fit:
    """The least-squares fit of the captures.

    Attributes
    ----------
    estimates : tuple of Estimate
        One per :data:`PARAMS`, in that order.
    variant : PlantVariant
        The estimate as a true plant relative to the nominal one.
    plant : Plant
        The fitted plant (the variant applied to the nominal plant).
    residual_rms_counts : float
        RMS of the residuals at the optimum (counts).
    residual_max_counts : float
        Largest residual (counts).
    samples : int
        Residuals (samples of all captures).
    saturated_s : float
        Time the fitted plant spends at its torque limit over the captures (s).
    excitation : Excitation
        The constant-speed segments found.
    evaluations : int
        Simulations run.
    residuals : tuple of numpy.ndarray
        The residuals of each capture (measured − simulated, counts).
    responses : tuple of Response
        The fitted plant's response to each capture.
    """

    estimates: tuple[Estimate, ...]
    variant: PlantVariant
    plant: Plant
    residual_rms_counts: float
    residual_max_counts: float
    samples: int
    saturated_s: float
    excitation: Excitation
    evaluations: int
    residuals: tuple[np.ndarray, ...]
    responses: tuple[Response, ...]

    def estimate(self, name: str) -> Estimate:
        """The estimate of one quantity.

        Parameters
        ----------
        name : str
            One of :data:`PARAMS`.

        Returns
        -------
        Estimate
            Its estimate.
        """
        return next(e for e in self.estimates if e.name == name)


class _Scale:
    """Scaled coordinates z ↔ the physical parameters, around a nominal plant."""

    def __init__(self, nominal: Plant) -> None:
        m = nominal.motor
        self.nominal = nominal
        self.tau = 0.01 * m.rated_torque_nm  # 1 % of rated torque
        self.speed = nominal.pulse_top_speed_rad_s
        self.z0 = np.array(
            [
                0.0,
                m.coulomb_nm / self.tau,
                m.viscous_nm_s_rad * self.speed / self.tau,
                m.load_torque_nm / self.tau,
                0.0,
            ]
        )
        lf, hf = math.log(FACTOR_RANGE[0]), math.log(FACTOR_RANGE[1])
        peak = m.peak_torque_nm / self.tau
        b_max = m.peak_torque_nm / m.knee_speed_rad_s * self.speed / self.tau
        self.lo = np.array([lf, 0.0, 0.0, -0.45 * peak, lf])
        self.hi = np.array([hf, 0.45 * peak, 0.95 * b_max, 0.45 * peak, hf])

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


class _Problem:
    """The residual function over the free coordinates, counting simulations."""

    def __init__(
        self, records: Sequence[Record], scale: _Scale, settings: Settings, free: np.ndarray
    ) -> None:
        self.records = list(records)
        self.scale = scale
        self.settings = settings
        self.free = free
        self.base = scale.z0.copy()
        self.evaluations = 0
        self.delay = 0  # ticks moving the servo's sample clock (model.respond)
        self.start = 0.0  # where within its first count the motor starts (model.respond)
        self._cache: dict[bytes, np.ndarray] = {}

    def full(self, zf: np.ndarray) -> np.ndarray:
        z = self.base.copy()
        z[self.free] = zf
        return z

    def residuals_of(self, zs: Sequence[np.ndarray]) -> list[np.ndarray]:
        """Residual vectors for several full coordinate vectors, simulated as one batch."""

        def key(z: np.ndarray) -> bytes:
            return z.tobytes() + self.delay.to_bytes(4, "little") + struct.pack("d", self.start)

        todo = [z for z in zs if key(z) not in self._cache]
        if todo:
            plants = [self.scale.plant(z) for z in todo]
            out = respond_many(self.records, plants, self.settings, self.delay, self.start)
            self.evaluations += len(todo)
            for z, resp in zip(todo, out, strict=True):
                self._cache[key(z)] = np.concatenate(
                    [r.measured - s.counts for r, s in zip(self.records, resp, strict=True)]
                )
        return [self._cache[key(z)] for z in zs]

    def at_delays(self, z: np.ndarray, delays: Sequence[int]) -> list[np.ndarray]:
        """Residuals of one point with the servo's sample clock moved by each delay."""
        keep = self.delay
        out = []
        try:
            for d in delays:
                self.delay = int(d)
                out.append(self.residuals_of([z])[0])
        finally:
            self.delay = keep
        return out

    def at_starts(self, z: np.ndarray, starts: Sequence[float]) -> list[np.ndarray]:
        """Residuals of one point with the motor starting elsewhere within its count."""
        keep = self.start
        out = []
        try:
            for f in starts:
                self.start = float(f)
                out.append(self.residuals_of([z])[0])
        finally:
            self.start = keep
        return out

    def fun(self, zf: np.ndarray) -> np.ndarray:
        return self.residuals_of([self.full(zf)])[0]

    def jac(self, zf: np.ndarray) -> np.ndarray:
        z = self.full(zf)
        pts, spans = [], []
        for i in np.flatnonzero(self.free):
            h = STEPS[i]
            up = min(z[i] + h, self.scale.hi[i])
            dn = max(z[i] - h, self.scale.lo[i])
            zu, zd = z.copy(), z.copy()
            zu[i], zd[i] = up, dn
            pts += [zu, zd]
            spans.append(up - dn)
        res = self.residuals_of(pts)
        cols = [(res[2 * k] - res[2 * k + 1]) / spans[k] for k in range(len(spans))]
        return np.stack(cols, axis=1)  # d(measured − simulated)/dz


def _saturated_s(responses: Sequence[Response], plant: Plant) -> float:
    ticks = sum(int(np.count_nonzero(r.saturated)) for r in responses) * SAMPLE_TICKS
    return ticks / plant.tick_hz


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


def _start(problem: _Problem) -> np.ndarray:
    """A start for the local search: the best of one batch over the inertia factor on a
    log grid in steps of :data:`GRID_STEP` (the response is sharp in J where the torque
    saturates), every other parameter nominal, friction a little inside its bound."""
    base = problem.base.copy()
    for i in (1, 2):
        if problem.free[i]:
            base[i] = max(base[i], 0.5)
    lo, hi = FACTOR_GRID
    grid = np.log(np.geomspace(lo, hi, round(math.log(hi / lo) / math.log(1 + GRID_STEP)) + 1))
    pts = []
    for g in grid:
        z = base.copy()
        z[0] = g
        pts.append(z)
    res = problem.residuals_of(pts)
    z = pts[int(np.argmin([float(r @ r) for r in res]))]
    return z[problem.free]


def _load_profile(problem: _Problem, z: np.ndarray, rms: float) -> tuple[float, float]:
    """How far the load torque moves (scaled units) with the others held before the RMS
    residual rises :data:`PROFILE_TOL` above its least, down and up.

    Below the torque limit a constant torque only shifts the servo's following error,
    which a count relative to the capture's start does not see; what remains visible is
    how it moves the Coulomb dead band's rest positions, which bounds it on one side only.
    The Jacobian's interval, taken at the optimum, does not show such a flat side."""
    steps = np.array(PROFILE_STEPS)
    pts = []
    for d in np.concatenate([-steps, steps]):
        zz = z.copy()
        zz[3] = min(max(z[3] + d, problem.scale.lo[3]), problem.scale.hi[3])
        pts.append(zz)
    res = problem.residuals_of(pts)
    flat = [math.sqrt(float(r @ r) / r.size) <= rms * (1.0 + PROFILE_TOL) for r in res]
    k = len(steps)
    down = up = 0.0
    for i in range(k):
        if not flat[i]:
            break
        down = pts[i][3] - z[3]
    for i in range(k):
        if not flat[k + i]:
            break
        up = pts[k + i][3] - z[3]
    return down, up


GRID_STEP = 0.05
"""Step of the starting grid over the inertia factor."""

LOAD_SPAN = 8.0
"""After the local search, the load torque is scanned within ±this % of the rated torque
in 1 % steps (the others held); a better point restarts the search: the load torque's
valley has side minima a local search stops in."""

LOAD_SCANS = 3
"""At most this many scans and restarts."""

PROFILE_STEPS = (0.5, 1.0, 2.0, 3.0, 5.0, 8.0, 12.0, 20.0)
"""Load torque offsets (% of rated) of the profile check (:func:`_load_profile`)."""

ONE_SIDED = 2.0
"""A profile flat for this % of the rated torque or more marks the load torque as seen
only as a bound (:attr:`Estimate.one_sided`)."""

PROFILE_TOL = 0.1
"""The profile check's rise of the RMS residual that counts as seen (10 %)."""

FACTOR_GRID = (0.25, 16.0)
"""The inertia factors the starting grid spans."""


def _solve(problem: _Problem, x0: np.ndarray) -> Any:
    """scipy's trust-region least squares from ``x0`` within the bounds."""
    from scipy.optimize import least_squares

    free = problem.free
    return least_squares(
        problem.fun,
        x0,
        jac=problem.jac,
        bounds=(problem.scale.lo[free], problem.scale.hi[free]),
        method="trf",
        x_scale=1.0,
        xtol=1e-6,
        ftol=1e-8,
        max_nfev=60,
    )


def fit(
    records: Sequence[Record],
    nominal: Plant,
    settings: Settings,
) -> Fit:
    """Fit the captures: the plant near ``nominal`` whose response best matches them.

    Parameters
    ----------
    records : sequence of Record
        The captures on the tick grid (:func:`vfgym.identify.model.record_of`).
    nominal : Plant
        The nominal axis's plant.
    settings : Settings
        The servo's filter ratio in force (:func:`vfgym.identify.model.respond`).

    Returns
    -------
    Fit
        The estimates with their 95 % intervals, and the residuals.
    """
    scale = _Scale(nominal)
    exc = excitation(records, nominal)
    free = np.array([True, exc.coulomb, exc.viscous, exc.load, True])
    z = scale.z0.copy()
    evaluations = 0
    delays = list(range(0, nominal.servo.sample_ticks, SAMPLE_TICKS))
    delay = 0
    for _attempt in range(3):
        problem = _Problem(records, scale, settings, free)
        problem.base = z.copy()
        problem.delay = delay
        zf0 = _start(problem) if _attempt == 0 else z[free]
        if _attempt == 0 and len(delays) > 1:
            # the servo's sample clock against the pulses: the best-fitting phase
            rs = problem.at_delays(problem.full(zf0), delays)
            delay = problem.delay = delays[int(np.argmin([float(r @ r) for r in rs]))]
        sol = _solve(problem, zf0)
        for _scan in range(LOAD_SCANS if free[3] else 0):
            # the load torque's valley has side minima: scan it, the others held
            zs = problem.full(sol.x)
            pts = []
            for d in np.arange(-LOAD_SPAN, LOAD_SPAN + 0.5):
                zz = zs.copy()
                zz[3] = min(max(zs[3] + d, scale.lo[3]), scale.hi[3])
                pts.append(zz)
            res_s = problem.residuals_of(pts)
            best = int(np.argmin([float(r @ r) for r in res_s]))
            if float(res_s[best] @ res_s[best]) >= 2.0 * sol.cost * (1.0 - 1e-3):
                break
            again = _solve(problem, pts[best][free])
            if again.cost >= sol.cost:
                break
            sol = again
        z = problem.full(sol.x)
        plant = scale.plant(z)
        resp = respond_many(records, [plant], settings, delay)[0]
        evaluations += 1
        sat = _saturated_s(resp, nominal)
        gain_seen = sat >= MIN_SATURATED_S
        if gain_seen == bool(free[4]):
            break
        evaluations += problem.evaluations  # the next attempt has a problem of its own
        free = free.copy()
        free[4] = gain_seen
        if not gain_seen:
            z[4] = scale.z0[4]
    jac = problem.jac(sol.x)
    res = problem.fun(sol.x)
    lengths = [r.measured.size for r in records]
    A = jac.T @ jac
    try:
        Ainv = np.linalg.inv(A)
    except np.linalg.LinAlgError:
        Ainv = np.linalg.pinv(A)
    floor = round(HAC_FLOOR_S * nominal.tick_hz / SAMPLE_TICKS)
    cov = Ainv @ newey_west(jac, res, lengths, floor) @ Ainv
    # the estimate's spread over the servo's sample-clock phase, which no capture records:
    # the Gauss–Newton step each other phase's residuals would take from the optimum
    others = [d for d in delays if d != delay][:: max(1, (len(delays) - 1) // NUISANCE_PHASES)]
    if others:
        steps = [-Ainv @ (jac.T @ r) for r in problem.at_delays(z, others)]
        cov = cov + sum(np.outer(d, d) for d in steps) / len(steps)
    # and over where within its first count the motor started, which no count shows
    steps = [-Ainv @ (jac.T @ r) for r in problem.at_starts(z, NUISANCE_STARTS)]
    cov = cov + sum(np.outer(d, d) for d in steps) / len(steps)
    sd_z = np.sqrt(np.maximum(np.diag(cov), 0.0))
    rms = float(np.sqrt(np.mean(res**2)))
    flat = _load_profile(problem, z, rms) if free[3] else (0.0, 0.0)
    phys = scale.physical(z)
    nominal_phys = scale.physical(scale.z0)
    estimates = []
    k = 0
    for i, name in enumerate(PARAMS):
        one_sided = False
        if free[i]:
            half = Z95 * sd_z[k]
            k += 1
            lo_z, hi_z = z[i] - half, z[i] + half
            if i in (0, 4):
                lo, hi = math.exp(lo_z), math.exp(hi_z)
            else:
                d = scale.jacobian_diag(z)[i]
                lo, hi = phys[i] - half * d, phys[i] + half * d
                if name == "load_torque_nm":  # a flat side the Jacobian does not show
                    lo, hi = min(lo, phys[i] + flat[0] * d), max(hi, phys[i] + flat[1] * d)
                    one_sided = max(-flat[0], flat[1]) >= ONE_SIDED
                if name in ("coulomb_nm", "viscous_nm_s_rad"):
                    lo = max(0.0, lo)
            estimates.append(
                Estimate(
                    name,
                    float(phys[i]),
                    lo,
                    hi,
                    float(nominal_phys[i]),
                    True,
                    one_sided=i not in (0, 4) and one_sided,
                )
            )
        else:
            lo, hi = wide_range(name, nominal)
            v = float(nominal_phys[i])
            estimates.append(Estimate(name, v, lo, hi, v, False))
    residuals = []
    start = 0
    for n in lengths:
        residuals.append(res[start : start + n])
        start += n
    return Fit(
        estimates=tuple(estimates),
        variant=scale.variant(z),
        plant=scale.plant(z),
        residual_rms_counts=rms,
        residual_max_counts=float(np.max(np.abs(res))),
        samples=int(res.size),
        saturated_s=_saturated_s(resp, nominal),
        excitation=exc,
        evaluations=evaluations + problem.evaluations,
        residuals=tuple(residuals),
        responses=tuple(resp),
    )


__all__ = [
    "PARAMS",
    "QUANTISATION_FLOOR",
    "Estimate",
    "Fit",
    "fit",
    "wide_range",
]
