"""A compliant transmission's resonance and damping from the motor encoder's capture.

The plan's resonance moves (:func:`vfgym.identify.plan.resonance_move`: bursts at the
top speed, each followed by a rest) make the load ring on its spring; the drive closes its
loops on the motor, so the encoder sees the ringing only as it pulls the motor against
the servo. The frequency the motor rings at is the closed loop's, not the resonance (on
the belt axis the spectrum's peak after a burst lay between 5 and 290 Hz for
resonances of 20-200 Hz, unrelated to them), so both estimates come through the exact
simulator, over x = (log f_r, ζ, log g), g a factor on the drive's gain that stands for
the ratio of the inertia to the gain the moves see (the torque saturates in a burst);
each record is simulated from one servo period before its first pulse
(:func:`~vfgym.identify.resonance_problem.trimmed`; the residuals' coordinates and
searches live in :mod:`vfgym.identify.resonance_problem`):

- the guess (:func:`guess_resonance`), on the nominal plant: the residuals of the first
  burst and its rest on a log grid of resonances (steps of :data:`GRID_STEP`,
  :data:`GRID_SPAN` either side of the nominal's) at each damping ratio of
  :data:`GRID_ZETAS`, g = 1; from each grid's best :data:`MINIMA` minima, apart by
  :data:`MINIMA_APART`, a Nelder–Mead
  search over x on the same burst (the sum of squares is rough away from its minimum,
  which misleads a gradient step); from the best, least squares
  (:func:`scipy.optimize.least_squares`, bounds, the Jacobian by central differences
  simulated in one batch) over every burst from each of the few best servo phases
  (:data:`~vfgym.identify.resonance_problem.PHASES`) of each capture (in steps of the
  residuals' sample), the best kept; then the servo phase to the tick, and least squares
  again where it moved;
- the refinement (:func:`refine_resonance`): the same least squares on the plant the
  rigid fit found (:mod:`vfgym.identify.fit`, run on the guessed transmission), each
  capture from the state of rest that fit found. The load inertia is the nominal's,
  scaled with the inertia as :class:`~vfgym.axis.PlantVariant` does.

The stiffness and damping follow, K_S = ω_r²·μ and c_S = 2ζ·μ·ω_r
(:meth:`vfgym.Transmission.from_resonance`, docs/model.md §3.1). Their 95 % intervals come
from the Jacobian at the optimum with the residuals' own RMS (at least the count's
quantisation floor) as their spread, the resonance's at least the Student-t interval of
the estimates from each burst alone (a servo that rings leaves residuals that are no
white noise) and the largest move of the estimate when each capture's start moves as
little as :func:`~vfgym.identify.ringing.nudged_starts` moves it, widened by the
refinement's move from the guess (the fitted plant's own errors). The capture shows the
resonance (:attr:`Resonance.shown`) when the resonance's interval is within
:data:`SHOWN_SHARE` of it and the damping ratio below :data:`OVERDAMPED`; else a note says
which (``vfgym identify`` refuses to write the axis).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from vfgym.identify.fit import QUANTISATION_FLOOR, Z95
from vfgym.identify.model import Record, Start
from vfgym.identify.resonance_problem import (
    ResonanceProblem,
    best_phases,
    default_starts,
    highest_hz,
    ranked_phases,
    resonance_segment,
    trimmed,
    window,
    with_resonance,
)
from vfgym.identify.ringing import NUDGES, nudged_starts
from vfgym.mechanics import Transmission
from vfgym.params import Plant, Settings

GRID_STEP = 0.02
"""Step of the guess's grid over the log resonance (a factor of 1.02), on the first burst
and its rest alone."""

GRID_SPAN = 8.0
"""The guess's grid spans the nominal's resonance divided and multiplied by this."""

MINIMA_APART = 0.05
"""The guess searches from the best minima of its grid at least this far apart (log)."""

MINIMA = 3
"""How many of the grid's minima the guess searches from, at each of :data:`GRID_ZETAS`."""

GRID_ZETAS = (0.05, 0.1)
"""The damping ratios of the guess's grids (with the nominal's alone, 0.03 on the belt
axis, the search from its minima ended in a gain far off, 0.82 and 1.08, on 2 of 10
plants)."""

BURST_EVALS = 10
"""Least-squares iterations of each burst's own estimate (from the joint optimum)."""

SHOWN_SHARE = 0.05
"""The capture shows the resonance when its 95 % interval is within this share of it."""

OVERDAMPED = 0.5
"""A damping ratio from which a transmission hardly rings: the capture cannot show it."""


@dataclass(frozen=True)
class Resonance:
    """What the captures show of the transmission.

    Attributes
    ----------
    shown : bool
        The captures show the resonance (module doc); else the nominal's transmission is
        kept and :attr:`note` says why.
    transmission : Transmission
        The estimated transmission (the load inertia as the inertia's estimate scales it).
    resonance_hz : float
        The estimated resonance seen from the motor (Hz).
    resonance_range_hz : tuple of float
        Its 95 % interval (Hz).
    damping_ratio : float
        The estimated damping ratio ζ.
    damping_ratio_range : tuple of float
        Its 95 % interval.
    guess_hz : float
        The guess from the resonance moves alone (Hz).
    nominal_hz : float
        The nominal axis's resonance (Hz).
    residual_rms_counts : float
        RMS of the residuals at the optimum (counts), every capture.
    residuals : tuple of numpy.ndarray
        Each capture's residuals at the optimum (counts).
    evaluations : int
        Simulations run (the guess's and the refinement's).
    burst_hz : tuple of float
        The resonance from each burst alone (Hz).
    note : str or None
        One line when the captures do not show the resonance.
    """

    shown: bool
    transmission: Transmission
    resonance_hz: float
    resonance_range_hz: tuple[float, float]
    damping_ratio: float
    damping_ratio_range: tuple[float, float]
    guess_hz: float
    nominal_hz: float
    residual_rms_counts: float
    residuals: tuple[np.ndarray, ...]
    evaluations: int
    burst_hz: tuple[float, ...] = ()
    note: str | None = None

    @property
    def stiffness_range_nm_rad(self) -> tuple[float, float]:
        """The stiffness's 95 % interval (N·m/rad): K_S scales as the resonance squared."""
        k, f = self.transmission.stiffness_nm_rad, self.resonance_hz
        return (
            k * (self.resonance_range_hz[0] / f) ** 2,
            k * (self.resonance_range_hz[1] / f) ** 2,
        )

    @property
    def damping_range_nm_s_rad(self) -> tuple[float, float]:
        """The damping's 95 % interval (N·m·s/rad), c_S = 2ζ·μ·ω_r at each end."""
        lo_f, hi_f = self.resonance_range_hz
        f, z = self.resonance_hz, self.damping_ratio
        c = self.transmission.damping_nm_s_rad
        if z <= 0.0:
            per = 0.0 if c <= 0.0 else c
            return (0.0, per * hi_f / f)
        lo_z, hi_z = self.damping_ratio_range
        return (c * max(lo_z, 0.0) / z * lo_f / f, c * hi_z / z * hi_f / f)


@dataclass(frozen=True)
class Guess:
    """The resonance found from the resonance moves on the nominal plant.

    Attributes
    ----------
    resonance_hz : float
        f_r seen from the motor (Hz).
    damping_ratio : float
        ζ.
    gain : float
        The factor on the drive's gain that the resonance moves see (it stands for the
        ratio of the inertia to the gain, which the rigid fit estimates).
    starts : tuple of Start
        Each capture's state of rest, its servo phase the best of the scan.
    evaluations : int
        Simulations run.
    """

    resonance_hz: float
    damping_ratio: float
    gain: float
    starts: tuple[Start, ...]
    evaluations: int


def guess_resonance(
    records: Sequence[Record], plant: Plant, settings: Settings, ticks: int, burst_ticks: int
) -> Guess:
    """The resonance, damping ratio and gain factor from the resonance moves alone, on the
    nominal plant (module doc).

    Parameters
    ----------
    records : sequence of Record
        The captures on the tick grid.
    plant : Plant
        The nominal (compliant) plant.
    settings : Settings
        The servo's filter ratio in force.
    ticks : int
        The resonance moves' length (ticks).
    burst_ticks : int
        The first burst's and its rest's (ticks): the grid's and the search's residuals.

    Returns
    -------
    Guess
        The estimates, each capture's start, and the simulations run.
    """
    from threadpoolctl import threadpool_limits  # type: ignore[import-untyped]

    starts = default_starts(records)
    short_recs = [trimmed(resonance_segment(r, burst_ticks), plant) for r in records]
    long_recs = [trimmed(resonance_segment(r, ticks), plant) for r in records]
    short = ResonanceProblem(short_recs, plant, settings, starts)
    f0 = plant.resonance_hz
    assert f0 is not None
    lo = max(f0 / GRID_SPAN, 1.0)
    hi = min(f0 * GRID_SPAN, 0.999 * highest_hz(plant))
    grid = np.log(np.geomspace(lo, hi, round(math.log(hi / lo) / GRID_STEP) + 1))
    with threadpool_limits(1, user_api="blas"):
        found = []
        for z0 in GRID_ZETAS:
            pts = [np.array([g, z0, 0.0]) for g in grid]
            ss = np.array([float(r @ r) for r in short.many(pts)])
            picked: list[float] = []
            for i in np.argsort(ss).tolist():
                if all(abs(grid[i] - g) >= MINIMA_APART for g in picked):
                    picked.append(float(grid[i]))
                if len(picked) == MINIMA:
                    break
            found += [short.search(np.array([g, z0, 0.0])) for g in picked]
        x = min(found, key=lambda t: t[1])[0]
        # the servo phase makes the sum of squares multimodal: least squares from each of
        # the best few phases (in steps of the residuals' sample), the best kept
        ranked, n_phase = ranked_phases(long_recs, short.plant_at(x), settings, starts)
        tried = []
        for best in ranked:
            problem = ResonanceProblem(long_recs, plant, settings, best)
            got = problem.solve(x)
            n_phase += problem.evaluations
            tried.append((got[1], got[0], best))
        _, x, best = min(tried, key=lambda t: t[0])
        problem = ResonanceProblem(long_recs, plant, settings, best)
        # the servo phase to the tick, then the least squares again where it moved
        again, n_tick = best_phases(long_recs, problem.plant_at(x), settings, best, 1)
        n_phase += n_tick
        if again != best:
            n_phase += problem.evaluations
            best = again
            problem = ResonanceProblem(long_recs, plant, settings, best)
            x, _ = problem.solve(x)
    return Guess(
        resonance_hz=math.exp(x[0]),
        damping_ratio=float(x[1]),
        gain=math.exp(x[2]),
        starts=tuple(best),
        evaluations=short.evaluations + n_phase + problem.evaluations,
    )


def refine_resonance(
    records: Sequence[Record],
    plant: Plant,
    settings: Settings,
    starts: Sequence[Start],
    guess: Guess,
    *,
    nominal: Plant,
    ticks: int,
    bursts: int,
    evaluations: int = 0,
) -> Resonance:
    """The resonance and damping ratio on the fitted plant, with their intervals (module
    doc).

    Parameters
    ----------
    records : sequence of Record
        The captures' resonance moves (:func:`~vfgym.identify.resonance_problem.resonance_segment`).
    plant : Plant
        The plant the rigid fit found (its transmission's load inertia scaled with the
        inertia).
    settings : Settings
        The servo's filter ratio in force.
    starts : sequence of Start
        The state of rest each capture starts from (the rigid fit's).
    guess : Guess
        :func:`guess_resonance`'s, to start from.
    nominal : Plant
        The nominal axis's plant (its resonance is reported beside the estimate).
    ticks : int
        The resonance moves' length (ticks).
    bursts : int
        The bursts in the resonance moves, of equal length: each gives an estimate of its
        own, whose spread widens the interval.
    evaluations : int
        Simulations already run (the guess's), added to the count.

    Returns
    -------
    Resonance
        The estimates, or a note saying what the captures cannot tell.
    """
    from scipy.stats import t as student_t
    from threadpoolctl import threadpool_limits  # type: ignore[import-untyped]

    recs = [trimmed(r, plant) for r in records]
    problem = ResonanceProblem(recs, plant, settings, starts)
    x0 = np.array([math.log(guess.resonance_hz), guess.damping_ratio, 0.0])
    per_burst: list[float] = []
    n_burst = 0
    with threadpool_limits(1, user_api="blas"):
        x, _ = problem.solve(x0)
        jac = problem.jac(x)
        res = problem.fun(x)
        for b in range(bursts):
            win = [window(r, b, ticks // bursts) for r in recs]
            one = ResonanceProblem(win, plant, settings, starts)
            xb, _ = one.solve(x, max_nfev=BURST_EVALS)
            per_burst.append(float(xb[0]))
            n_burst += one.evaluations
        # the starts no capture tells apart (a servo that rings depends on them): the
        # estimate from each nudged start
        per_start: list[float] = []
        for i in range(NUDGES):
            alt = [nudged_starts(st, plant)[i] for st in starts]
            one = ResonanceProblem(recs, plant, settings, alt)
            xn, _ = one.solve(x, max_nfev=BURST_EVALS)
            per_start.append(float(xn[0]))
            n_burst += one.evaluations
    rms = float(np.sqrt(np.mean(res**2)))
    spread = max(rms, QUANTISATION_FLOOR)
    try:
        cov = spread**2 * np.linalg.inv(jac.T @ jac)
        sd = np.sqrt(np.maximum(np.diag(cov), 0.0))
    except np.linalg.LinAlgError:
        sd = np.full(3, math.inf)
    # the residual is no white noise (a servo that rings follows its own limit cycle):
    # the bursts' own estimates, one each, show how far the resonance is known
    n = len(per_burst)
    half_b = float(student_t.ppf(0.975, n - 1) * np.std(per_burst, ddof=1) / math.sqrt(n))
    # and the plant under it is the rigid fit's: the move from the guess's (on the nominal
    # plant, its gain factor free) is how far that plant's errors carry
    half_s = max(abs(v - x[0]) for v in per_start)
    half_f = max(Z95 * sd[0], half_b, half_s) + abs(x[0] - math.log(guess.resonance_hz))
    f, zeta = math.exp(x[0]), float(x[1])
    f_range = (
        (f * math.exp(-half_f), f * math.exp(half_f)) if math.isfinite(half_f) else (0.0, math.inf)
    )
    z_range = (max(0.0, zeta - Z95 * sd[1]), zeta + Z95 * sd[1])
    est = with_resonance(plant, f, zeta).transmission
    assert est is not None
    f0 = nominal.resonance_hz
    assert f0 is not None
    width = f_range[1] / f - 1.0
    note = None
    if zeta >= OVERDAMPED:
        note = (
            f"transmission: the capture cannot tell the resonance: the spring hardly rings "
            f"(damping ratio {zeta:.2g}, over-damped from {OVERDAMPED:g})"
        )
    elif not width <= SHOWN_SHARE:
        note = (
            f"transmission: the capture cannot tell the resonance: its 95 % interval "
            f"{_hz(f_range)} is wider than +-{SHOWN_SHARE:.0%} (a transmission too stiff, "
            "or a ringing too small for the encoder's counts)"
        )
    sizes = [r.used(r.measured).size for r in recs]
    cuts = np.cumsum(sizes)[:-1]
    return Resonance(
        shown=note is None,
        transmission=est,
        resonance_hz=f,
        resonance_range_hz=f_range,
        damping_ratio=zeta,
        damping_ratio_range=z_range,
        guess_hz=guess.resonance_hz,
        nominal_hz=f0,
        residual_rms_counts=rms,
        residuals=tuple(np.split(res, cuts)),
        evaluations=evaluations + problem.evaluations + n_burst,
        burst_hz=tuple(math.exp(v) for v in per_burst),
        note=note,
    )


def _hz(r: tuple[float, float]) -> str:
    return f"[{r[0]:.4g}, {r[1]:.4g}] Hz"


__all__ = [
    "BURST_EVALS",
    "GRID_SPAN",
    "GRID_STEP",
    "GRID_ZETAS",
    "MINIMA",
    "MINIMA_APART",
    "OVERDAMPED",
    "SHOWN_SHARE",
    "Guess",
    "Resonance",
    "guess_resonance",
    "refine_resonance",
]
