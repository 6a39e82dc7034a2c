"""The estimator: the plant whose simulated response to the recorded pulses matches the
recorded encoder count, by least squares, with 95 % intervals.

The five parameters (:mod:`vfgym.identify.problem`: inertia, Coulomb and viscous
friction, load torque, the drive's gain) are fitted in scaled coordinates by
:func:`scipy.optimize.least_squares`, residuals in encoder counts, with the Jacobian taken
by central differences, every perturbed plant simulated in one batch. A parameter the
captures do not excite (:mod:`vfgym.identify.excite`) is held at its nominal value; so
is the load torque when no capture holds the drive's enable and the torque never reaches
its limit (below it a load torque only adds to the error the servo holds, which is
fitted with it); so is the gain where the torque is at its limit for less than
:data:`~vfgym.identify.excite.MIN_SATURATED_S`, or at a value given
(:mod:`vfgym.identify.prior` fits the plants along the gain's prior that way).

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

from vfgym.axis import PlantVariant
from vfgym.identify.covariance import estimate_covariance, resolution
from vfgym.identify.excite import MIN_SATURATED_S, Excitation, excitation
from vfgym.identify.model import SAMPLE_TICKS, Record, Response, Start, respond_many
from vfgym.identify.problem import PARAMS, Problem, Scale, wide_range
from vfgym.params import Plant, Settings

Z95 = 1.959963984540054
"""The two-sided 95 % quantile of the normal distribution."""

QUANTISATION_FLOOR = 1.0 / math.sqrt(12.0)
"""RMS error (counts) of reading a position as whole counts: the floor of the residual."""

EXPLAINED = 3.0
"""A fit whose RMS residual exceeds this many quantisation floors does not explain the
captures."""


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
    coordinates : numpy.ndarray or None
        The optimum in the problem's scaled coordinates (:class:`Scale`), where a fit
        near this one starts.
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
    coordinates: np.ndarray | None = None

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


def _saturated_s(responses: Sequence[Response], plant: Plant) -> float:
    ticks = sum(int(np.count_nonzero(r.saturated)) for r in responses) * SAMPLE_TICKS
    return ticks / plant.tick_hz


def _start(problem: Problem) -> list[tuple[np.ndarray, list[int]]]:
    """Starts for the local search: the best of one batch over the inertia factor on a
    log grid in steps of :data:`GRID_STEP` (the response is sharp in J where the torque
    saturates), every other parameter nominal, friction a little inside its bound; then
    each record's held error and servo phase (:func:`_settle_starts`). The servo phase
    makes the residual multimodal (a phase far from the true one, with the other
    parameters bent to it, can be a local optimum), so the start is returned twice: with
    the best phases, and with the best of those :data:`PHASE_APART` ticks or more away."""
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
    ns = problem.scale.nominal.servo.sample_ticks
    firsts = list(problem.phases)
    seconds = []
    for k, ranked in enumerate(problem.ranked):
        apart = [
            ph
            for _, ph in ranked
            if min((ph - firsts[k]) % ns, (firsts[k] - ph) % ns) >= PHASE_APART
        ]
        seconds.append(apart[0] if apart else firsts[k])
    out = [(base[problem.free], firsts)]
    if seconds != firsts:
        out.append((base[problem.free], seconds))
    return out


def _settle_starts(problem: Problem, z: np.ndarray, phases: Sequence[int]) -> np.ndarray:
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
    scores: list[list[tuple[float, int]]] = [[] for _ in keep]
    for ph in phases:
        problem.phases = [int(ph)] * len(keep)
        for k, r in enumerate(problem.per_record([z])[0]):
            scores[k].append((float(r @ r), int(ph)))
    problem.ranked = [sorted(sc) for sc in scores]
    problem.phases = [sc[0][1] if sc else ph for sc, ph in zip(problem.ranked, keep, strict=True)]
    return z


def _first_pulse_sample(record: Record) -> int:
    """The sample in which a record's first pulse falls."""
    return int(np.flatnonzero(record.pulses)[0]) // SAMPLE_TICKS


PHASE_APART = 10
"""The second start's servo phases are at least this many ticks from the first's."""

GRID_STEP = 0.05
"""Step of the starting grid over the inertia factor."""

FACTOR_GRID = (0.25, 16.0)
"""The inertia factors the starting grid spans."""


def _solve(problem: Problem, x0: np.ndarray) -> Any:
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
    *,
    gain: float | None = None,
    near: Fit | None = None,
    gain_range: tuple[float, float] | None = None,
    start_inertia: float | None = None,
    start_phases: Sequence[int] | None = None,
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
    gain : float or None
        Hold the drive's gain at this factor on K3 as set (not estimated).
    near : Fit or None
        Start from this fit's optimum (its inertia and torques scaled by ``gain``), its
        servo phases, instead of a search over the inertia.
    gain_range : tuple of float or None
        Fit the gain within this range (factors on K3 as set) whatever the time at the
        torque limit: where a capture saturates too briefly to separate the gain, yet the
        gain as set does not explain it. The gain's estimate is then not taken as
        separated: its interval is the range.
    start_inertia : float or None
        Start from this factor on the nominal inertia, every other parameter nominal,
        instead of a search over the inertia (a compliant axis's resonance moves give it,
        :mod:`vfgym.identify.resonance`).
    start_phases : sequence of int or None
        With ``start_inertia``: each capture's servo phase to start from (else 0).

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
        return _fit(records, nominal, settings, gain, near, gain_range, start_inertia, start_phases)


def _fit(
    records: Sequence[Record],
    nominal: Plant,
    settings: Settings,
    gain: float | None,
    near: Fit | None,
    gain_range: tuple[float, float] | None = None,
    start_inertia: float | None = None,
    start_phases: Sequence[int] | None = None,
) -> Fit:
    """:func:`fit` itself."""
    scale = Scale(nominal, records)
    if gain is not None:
        scale.z0[4] = math.log(gain)
    if gain_range is not None:
        scale.lo[4], scale.hi[4] = math.log(gain_range[0]), math.log(gain_range[1])
    exc = excitation(records, nominal)
    enabled = any(r.enabled for r in records)
    free = np.array(
        [True, exc.coulomb, exc.viscous, exc.load and enabled, gain is None] + [True] * len(records)
    )
    z = scale.z0.copy()
    evaluations = 0
    phases = [0] * len(records)
    warm = near is not None and near.coordinates is not None
    if near is not None and near.coordinates is not None:
        z = near.coordinates.copy()
        if gain is not None:  # along J/K3 and τ/K3: the inertia and torques by the gain
            g = gain / math.exp(z[4])
            z[0] += math.log(g)
            z[1:4] *= g
            z[4] = math.log(gain)
        z = np.clip(z, scale.lo, scale.hi)
        phases = [st.servo_phase for st in near.starts]
        free[3] = bool(near.estimate("load_torque_nm").excited)
    elif start_inertia is not None:
        warm = True
        z[0] = float(np.clip(math.log(start_inertia), scale.lo[0], scale.hi[0]))
        phases = [0] * len(records) if start_phases is None else [int(p) for p in start_phases]
    all_phases = range(nominal.servo.sample_ticks)
    for attempt in range(3):
        problem = Problem(records, scale, settings, free)
        problem.base = z.copy()
        problem.phases = list(phases)
        if attempt == 0 and not warm:
            best = None
            for zf0, phs in _start(problem):
                problem.phases = list(phs)
                got = _solve(problem, zf0)
                if best is None or got.cost < best[0].cost:
                    best = (got, list(phs))
            assert best is not None
            sol, problem.phases = best
        else:
            sol = _solve(problem, z[free])
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
        want[4] = (gain_seen or gain_range is not None) and gain is None
        want[3] = exc.load and (enabled or gain_seen or (gain_range is not None and free[3]))
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
    cov = estimate_covariance(problem, z, jac)
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
            if i == 4 and gain_range is not None and _saturated_s(resp, nominal) < MIN_SATURATED_S:
                estimates.append(Estimate(name, v, gain_range[0], gain_range[1], v0, False))
                continue
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
        coordinates=z,
    )


__all__ = [
    "EXPLAINED",
    "PARAMS",
    "QUANTISATION_FLOOR",
    "Estimate",
    "Fit",
    "fit",
    "wide_range",
]
