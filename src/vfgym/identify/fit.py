"""The estimator: the plant whose simulated response to the recorded pulses matches the
recorded encoder count, by least squares, with 95 % intervals.

Five parameters, relative to the nominal axis's plant (as a
:class:`~vfgym.axis.PlantVariant` applies them): a factor on the total
inertia, the Coulomb friction, the viscous friction, a constant load torque, and a factor
on the drive's gain K3 as set. They are fitted in scaled coordinates (log factors,
torques in % of the rated torque, viscous friction as its torque at the pulse train's top
speed in % of rated) by :func:`scipy.optimize.least_squares`, residuals in encoder counts
(:mod:`vfgym.identify.model`), with the Jacobian taken by central differences, every
perturbed plant simulated in one batch. A parameter the captures do not excite
(:mod:`vfgym.identify.excite`) is held at its nominal value; so is the load torque when
no capture holds the drive's enable and the torque never reaches its limit (below it a
load torque only adds to the error the servo holds, which is fitted with it).

Two things no capture records are fitted with them, one of each per capture
(:class:`~vfgym.identify.model.Start`): where the motor rests against the position the
servo holds when the capture starts (a coordinate of the least squares, within one count
on an enabled capture), and the phase of the servo's sample clock against the pulses
(its speed counter latches every Ns ticks), tried in steps of the residuals' sample from
the start and at every tick once the search has converged.

The intervals come from the Jacobian at the optimum: the sandwich with the covariance of
the count's quantisation error (:mod:`vfgym.identify.covariance`), which lasts as long as
a steady stretch of motion does, and of the tick grid's phase, which a sampled capture
fixes only to within :attr:`~vfgym.identify.model.Record.phase_width_s`; plus the spread
of the Gauss–Newton steps that the residuals at every other servo phase (in steps of
:data:`NUISANCE_PHASE_STEP` ticks) would take from the optimum; and, for a torque held
at its nominal value, how far the estimates move with it over its wide range.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from vfgym.axis import FACTOR_RANGE, PlantVariant
from vfgym.identify.covariance import pieces, quantisation_meat, resolution
from vfgym.identify.excite import MIN_SATURATED_S, Excitation, excitation
from vfgym.identify.model import SAMPLE_TICKS, Record, Response, Start, respond_many
from vfgym.params import Plant, Settings

PARAMS = ("inertia", "coulomb_nm", "viscous_nm_s_rad", "load_torque_nm", "torque_per_count")
"""The estimated quantities, named as the fields of an axis's ``uncertainty:`` block."""

STEPS = np.array([0.02, 0.3, 0.3, 0.3, 0.02])
"""Central-difference steps in the scaled coordinates (2 % on the factors, 0.3 % of rated
torque on the torques): large enough to step over the count's quantisation."""

Z95 = 1.959963984540054
"""The two-sided 95 % quantile of the normal distribution."""

HELD_TORQUES = ("coulomb_nm", "viscous_nm_s_rad", "load_torque_nm")
"""Quantities held at their nominal value whose range enters the others' covariance (the
gain's does not: without it the inertia is stated relative to K3 as set, and the
uncertainty block widens by the gain's range instead)."""

NUISANCE_PHASE_STEP = 5
"""Step (ticks) of the other servo phases whose effect on the estimate is added to the
covariance."""

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
    resolution : float
        The change of this quantity alone that moves no sample's simulated count by more
        than the quantisation floor: finer than one reading shows (its units; 0 when not
        excited). :mod:`vfgym.identify.written` makes it the least half-width of the range.
    """

    name: str
    value: float
    low: float
    high: float
    nominal: float
    excited: bool
    resolution: float = 0.0


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
    starts : tuple of Start
        The state of rest each capture was found to start from.
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
    starts: tuple[Start, ...] = ()

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
        self.phases = [0] * len(records)  # the servo's sample clock of each record
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
    saturates), every other parameter nominal, friction a little inside its bound; then
    each record's held error and servo phase (:func:`_settle_starts`)."""
    base = problem.base.copy()
    for i in (1, 2):
        if problem.free[i]:
            base[i] = max(base[i], 0.5)
    lo, hi = FACTOR_GRID
    grid = np.log(np.geomspace(lo, hi, round(math.log(hi / lo) / math.log(1 + GRID_STEP)) + 1))
    # a held error off by n counts shifts every count after the first move by n: where it
    # is free (a capture without the enable), the grid runs again once it is settled
    rounds = 1 if all(r.enabled for r in problem.records) else 2
    for _round in range(rounds):
        pts = []
        for g in grid:
            z = base.copy()
            z[0] = g
            pts.append(z)
        res = problem.residuals_of(pts)
        base = pts[int(np.argmin([float(r @ r) for r in res]))]
        base = _settle_starts(problem, base, range(0, problem.scale.nominal.servo.sample_ticks, 5))
    return base[problem.free]


def _settle_starts(problem: _Problem, z: np.ndarray, phases: Sequence[int]) -> np.ndarray:
    """Each record's state of rest at ``z``: its held error moved by its residuals' median
    after the first pulse (below the torque limit the first move forgets where the axis
    rested, so every later count is off by the same amount), then its servo phase, the
    best of ``phases``. Returns ``z`` with the new held errors; sets ``problem.phases``."""
    z = z.copy()
    k0 = len(PARAMS)
    for _ in range(2):
        rs = problem.per_record([z])[0]
        for k, (r, rec) in enumerate(zip(rs, problem.records, strict=True)):
            if rec.enabled:
                continue
            after = rec.used(np.arange(rec.measured.size)) >= _first_pulse_sample(rec)
            if np.any(after):
                z[k0 + k] = float(
                    np.clip(
                        z[k0 + k] + np.median(r[after]),
                        problem.scale.lo[k0 + k],
                        problem.scale.hi[k0 + k],
                    )
                )
    keep = list(problem.phases)
    best = [(math.inf, ph) for ph in keep]
    for ph in phases:
        problem.phases = [int(ph)] * len(keep)
        for k, r in enumerate(problem.per_record([z])[0]):
            best[k] = min(best[k], (float(r @ r), int(ph)))
    problem.phases = [ph for _, ph in best]
    return z


def _first_pulse_sample(record: Record) -> int:
    """The sample in which a record's first pulse falls."""
    return int(np.flatnonzero(record.pulses)[0]) // SAMPLE_TICKS


GRID_STEP = 0.05
"""Step of the starting grid over the inertia factor."""

FACTOR_GRID = (0.25, 16.0)
"""The inertia factors the starting grid spans."""

HELD_STEP = 0.5
"""Central-difference step of a record's held error (counts)."""

HELD_EDGE = 1e-6
"""An enabled capture's held error stays this far inside its count (counts)."""


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

    Notes
    -----
    Linear algebra runs on one thread: OpenBLAS's threads spin on vectors this short, a
    sum of squares ~300x slower on a busy machine (measured).
    """
    from threadpoolctl import threadpool_limits  # type: ignore[import-untyped]

    with threadpool_limits(1, user_api="blas"):
        return _fit(records, nominal, settings)


def _fit(records: Sequence[Record], nominal: Plant, settings: Settings) -> Fit:
    """:func:`fit` itself."""
    scale = _Scale(nominal, records)
    exc = excitation(records, nominal)
    enabled = any(r.enabled for r in records)
    free = np.array(
        [True, exc.coulomb, exc.viscous, exc.load and enabled, True] + [True] * len(records)
    )
    z = scale.z0.copy()
    evaluations = 0
    phases = [0] * len(records)
    all_phases = range(nominal.servo.sample_ticks)
    for attempt in range(3):
        problem = _Problem(records, scale, settings, free)
        problem.base = z.copy()
        problem.phases = list(phases)
        zf0 = _start(problem) if attempt == 0 else z[free]
        sol = _solve(problem, zf0)
        z = problem.full(sol.x)
        # the servo phase to the tick (the start chose it in steps of 5); solve again if moved
        before = list(problem.phases)
        z = _settle_starts(problem, z, all_phases)
        if problem.phases != before:
            sol = _solve(problem, z[free])
            z = problem.full(sol.x)
        phases = list(problem.phases)
        resp = respond_many(records, [(scale.plant(z), problem.starts(z))], settings)[0]
        evaluations += 1
        sat = _saturated_s(resp, nominal)
        gain_seen = sat >= MIN_SATURATED_S
        want = free.copy()
        want[4] = gain_seen
        want[3] = exc.load and (enabled or gain_seen)
        if np.array_equal(want, free):
            break
        evaluations += problem.evaluations  # the next attempt has a problem of its own
        free = want
        for i in (3, 4):
            if not free[i]:
                z[i] = scale.z0[i]
    jac = problem.jac(sol.x)
    res = problem.fun(sol.x)
    lengths = [r.used(r.measured).size for r in records]
    cov = _covariance(problem, z, jac)
    sd_z = np.sqrt(np.maximum(np.diag(cov), 0.0))
    res_z = resolution(jac, QUANTISATION_FLOOR)
    rms = float(np.sqrt(np.mean(res**2)))
    phys = scale.physical(z)
    nominal_phys = scale.physical(scale.z0)
    estimates = []
    k = 0
    for i, name in enumerate(PARAMS):
        if free[i]:
            half, d = Z95 * sd_z[k], scale.jacobian_diag(z)[i]  # d: physical per z
            r = float(res_z[k] * d)
            k += 1
            if i in (0, 4):
                lo, hi = math.exp(z[i] - half), math.exp(z[i] + half)
            else:
                lo, hi = phys[i] - half * d, phys[i] + half * d
                if name in ("coulomb_nm", "viscous_nm_s_rad"):
                    lo = max(0.0, lo)
            v, v0 = float(phys[i]), float(nominal_phys[i])
            estimates.append(Estimate(name, v, lo, hi, v0, True, r))
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
        starts=tuple(problem.starts(z)),
    )


def _covariance(problem: _Problem, z: np.ndarray, jac: np.ndarray) -> np.ndarray:
    """The covariance of the free coordinates (see the module doc): the sandwich with the
    count's quantisation error, plus the spread over the servo's sample phase."""
    A = jac.T @ jac
    try:
        Ainv = np.linalg.inv(A)
    except np.linalg.LinAlgError:
        Ainv = np.linalg.pinv(A)
    nominal = problem.scale.nominal
    groups, counts, shift = [], [], []
    start = 0
    for r, resp in zip(problem.records, problem.simulated(z), strict=True):
        groups += [piece + start for piece in pieces(r, nominal.tick_hz)]
        counts.append(r.used(resp.counts))
        # the tick grid's phase, known to within the record's phase width: the residuals'
        # change for a shift of the grid by δ is −(ω/q)·δ, δ uniform over that width
        g = np.zeros(jac.shape[0])
        g[start : start + counts[-1].size] = -r.used(resp.speed_rad_s) / nominal.motor.count_rad
        shift.append(jac.T @ g * (r.phase_width_s / math.sqrt(12.0)))
        start += counts[-1].size
    meat = quantisation_meat(jac, np.concatenate(counts), groups)
    meat = meat + sum(np.outer(v, v) for v in shift)
    cov = Ainv @ meat @ Ainv
    # the servo's sample clock against the pulses, which no capture records: the
    # Gauss–Newton step each other phase's residuals would take from the optimum
    steps = []
    keep = list(problem.phases)
    try:
        for ph in range(0, problem.scale.nominal.servo.sample_ticks, NUISANCE_PHASE_STEP):
            problem.phases = [(p0 + ph) % problem.scale.nominal.servo.sample_ticks for p0 in keep]
            if ph:
                steps.append(-Ainv @ (jac.T @ problem.residuals_of([z])[0]))
    finally:
        problem.phases = keep
    if steps:
        cov = cov + sum(np.outer(d, d) for d in steps) / len(steps)
    # a torque held at its nominal value (not excited) may be anywhere in its wide range:
    # the estimates move with it by −A⁻¹Jᵀ∂r/∂p, over its mean square offset in that range
    scale = problem.scale
    for i in np.flatnonzero(~problem.free[: len(PARAMS)]):
        if PARAMS[i] not in HELD_TORQUES:
            continue
        lo, hi = (v / scale.jacobian_diag(z)[i] for v in wide_range(PARAMS[i], nominal))
        zu, zd = z.copy(), z.copy()
        zu[i] += scale.steps[i]
        zd[i] -= scale.steps[i]
        ru, rd = problem.residuals_of([zu, zd])
        d = -Ainv @ (jac.T @ ((ru - rd) / (2.0 * scale.steps[i])))
        mean_square = ((hi - z[i]) ** 3 - (lo - z[i]) ** 3) / (3.0 * (hi - lo))
        cov = cov + np.outer(d, d) * mean_square
    return cov


__all__ = [
    "PARAMS",
    "QUANTISATION_FLOOR",
    "Estimate",
    "Fit",
    "fit",
    "wide_range",
]
