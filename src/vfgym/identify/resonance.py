"""A compliant transmission's resonance and damping from the motor encoder's capture.

The plan's resonance moves (:func:`vfgym.identify.plan.resonance_move`: bursts at the
top speed, each followed by a rest) make the load ring on its spring; the drive closes its
loops on the motor, so the encoder sees the ringing only as it pulls the motor against
the servo. The frequency the motor rings at is the closed loop's, not the resonance (on
the belt axis the spectrum's peak after a burst lay between 5 and 290 Hz for
resonances of 20-200 Hz, unrelated to them), so both estimates
come through the exact simulator:

- the guess (:func:`guess_resonance`): the residuals of the capture's resonance moves
  alone, on the nominal plant with its transmission set to each resonance of a log grid
  (steps of :data:`GRID_STEP`, :data:`GRID_SPAN` either side of the nominal's), the
  damping ratio the nominal's; the best few minima, apart by :data:`MINIMA_APART`, are
  refined by least squares on the same moves, the best kept;
- the refinement (:func:`refine_resonance`): least squares over the log resonance and the
  damping ratio (:func:`scipy.optimize.least_squares`, bounds, the Jacobian by central
  differences simulated in one batch) on the resonance moves of every capture (their
  ringing; later moves add little but a limit cycle's sensitivity, which a capture of a
  lightly damped axis may hold), on the plant the rigid fit found
  (:mod:`vfgym.identify.fit`, run on the guessed transmission), each capture from the
  state of rest that fit found. The load inertia is the nominal's, scaled with the
  inertia as :class:`~vfgym.axis.PlantVariant` does.

The stiffness and damping follow, K_S = ω_r²·μ and c_S = 2ζ·μ·ω_r
(:meth:`vfgym.Transmission.from_resonance`, docs/model.md §3.1). Their 95 % intervals come
from the Jacobian at the optimum with the residuals' own RMS (at least the count's
quantisation floor) as their spread, the resonance's at least as wide as the refinement
moved it from the guess. The capture shows the resonance
(:attr:`Resonance.shown`) when the resonance's interval is within :data:`SHOWN_SHARE` of
it and the damping ratio below :data:`OVERDAMPED`; else a note says which, and the
nominal's transmission is kept.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from vfgym.identify.fit import QUANTISATION_FLOOR, Z95
from vfgym.identify.model import SAMPLE_TICKS, Record, Start, respond_many
from vfgym.mechanics import RESONANCE_TICKS_MIN, Transmission
from vfgym.params import Plant, Settings

GRID_STEP = 0.02
"""Step of the guess's grid over the resonance (a factor of 1.02), on the first burst and
its rest alone: a ringing of n periods leaves minima about 1/(4n) wide."""

GRID_SPAN = 8.0
"""The guess's grid spans the nominal's resonance divided and multiplied by this."""

MINIMA_APART = 0.04
"""The guess refines the best minima of its grid at least this far apart (log)."""

MINIMA = 3
"""How many of the grid's minima the guess refines."""

SHOWN_SHARE = 0.05
"""The capture shows the resonance when its 95 % interval is within this share of it."""

OVERDAMPED = 0.5
"""A damping ratio from which a transmission hardly rings: the capture cannot show it."""

ZETA_MOST = 1.0
"""The damping ratio's upper bound in the least squares."""

STEP = np.array([0.002, 0.005])
"""Central-difference steps in (log resonance, damping ratio)."""


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


def with_resonance(plant: Plant, resonance_hz: float, damping_ratio: float) -> Plant:
    """The plant with its transmission at a resonance and damping ratio (its load inertia,
    friction and travel kept).

    Parameters
    ----------
    plant : Plant
        A compliant plant.
    resonance_hz : float
        f_r seen from the motor (Hz), > 0.
    damping_ratio : float
        ζ, in [0, 1].

    Returns
    -------
    Plant
        K_S and c_S from :meth:`vfgym.Transmission.from_resonance` on the motor's inertia.
    """
    tr = plant.transmission
    assert tr is not None
    new = Transmission.from_resonance(
        tr.load_inertia_kgm2,
        plant.motor.inertia_kgm2,
        resonance_hz,
        damping_ratio,
        tr.load_coulomb_nm,
        tr.travel_mm_per_rad,
    )
    return replace(plant, transmission=new)


def damping_ratio(plant: Plant) -> float:
    """A compliant plant's damping ratio ζ = c_S / (2·μ·ω_r).

    Parameters
    ----------
    plant : Plant
        A compliant plant.

    Returns
    -------
    float
        ζ (0 for an undamped spring).
    """
    tr = plant.transmission
    assert tr is not None
    jm, jl = plant.motor.inertia_kgm2, tr.load_inertia_kgm2
    mu = jm * jl / (jm + jl)
    return tr.damping_nm_s_rad / (2.0 * mu * math.sqrt(tr.stiffness_nm_rad / mu))


def resonance_segment(record: Record, ticks: int) -> Record:
    """The record up to ``ticks`` after its first pulse (the resonance moves, which come
    first in the plan), in whole samples.

    Parameters
    ----------
    record : Record
        A capture on the tick grid.
    ticks : int
        The resonance moves' length (ticks).

    Returns
    -------
    Record
        The same record, shorter.
    """
    first = int(np.flatnonzero(record.pulses)[0])
    n = min(record.n_ticks, (first + ticks) // SAMPLE_TICKS * SAMPLE_TICKS)
    k = n // SAMPLE_TICKS
    read = None if record.read_offset_s is None else record.read_offset_s[:k]
    return replace(
        record, pulses=record.pulses[:n], measured=record.measured[:k], read_offset_s=read
    )


def _highest_hz(plant: Plant) -> float:
    """The highest resonance the simulator takes on this plant (Hz): f/10."""
    return plant.tick_hz / RESONANCE_TICKS_MIN


class _Problem:
    """Residuals of the records over x = (log f_r, ζ), each plant simulated in a batch."""

    def __init__(
        self, records: Sequence[Record], plant: Plant, settings: Settings, starts: Sequence[Start]
    ) -> None:
        self.records = list(records)
        self.plant = plant
        self.settings = settings
        self.starts = list(starts)
        self.evaluations = 0
        self._cache: dict[bytes, list[np.ndarray]] = {}
        top = math.log(0.999 * _highest_hz(plant))
        self.lo = np.array([math.log(1.0), 0.0])
        self.hi = np.array([top, ZETA_MOST])

    def per_record(self, xs: Sequence[np.ndarray]) -> list[list[np.ndarray]]:
        todo = list({x.tobytes(): x for x in xs if x.tobytes() not in self._cache}.values())
        if todo:
            jobs = [
                (with_resonance(self.plant, math.exp(x[0]), float(x[1])), self.starts) for x in todo
            ]
            out = respond_many(self.records, jobs, self.settings)
            self.evaluations += len(todo)
            for x, resp in zip(todo, out, strict=True):
                self._cache[x.tobytes()] = [
                    r.residuals(s) for r, s in zip(self.records, resp, strict=True)
                ]
        return [self._cache[x.tobytes()] for x in xs]

    def many(self, xs: Sequence[np.ndarray]) -> list[np.ndarray]:
        return [np.concatenate(r) for r in self.per_record(xs)]

    def fun(self, x: np.ndarray) -> np.ndarray:
        return self.many([np.asarray(x, dtype=np.float64)])[0]

    def jac(self, x: np.ndarray) -> np.ndarray:
        pts, spans = [], []
        for i in range(2):
            up, dn = x.copy(), x.copy()
            up[i] = min(x[i] + STEP[i], self.hi[i])
            dn[i] = max(x[i] - STEP[i], self.lo[i])
            pts += [up, dn]
            spans.append(up[i] - dn[i])
        res = self.many(pts)
        return np.stack([(res[2 * i] - res[2 * i + 1]) / spans[i] for i in range(2)], axis=1)

    def solve(self, x0: np.ndarray) -> tuple[np.ndarray, float]:
        """scipy's trust-region least squares from ``x0``: the optimum and its cost."""
        from scipy.optimize import least_squares

        x0 = np.clip(x0, self.lo + 1e-9, self.hi - 1e-9)
        sol = least_squares(
            self.fun,
            x0,
            jac=self.jac,
            bounds=(self.lo, self.hi),
            method="trf",
            x_scale=np.array([0.01, 0.02]),
            xtol=1e-6,
            ftol=1e-8,
            max_nfev=40,
        )
        return np.asarray(sol.x, dtype=np.float64), float(sol.cost)


def _default_starts(records: Sequence[Record]) -> list[Start]:
    """Each record's state of rest before any fit: within its held count when enabled."""
    out = []
    for r in records:
        span = r.held_range()
        out.append(Start() if span is None else Start(0.5 * (span[0] + span[1]), 0))
    return out


def guess_resonance(
    records: Sequence[Record], plant: Plant, settings: Settings, ticks: int, grid_ticks: int
) -> tuple[float, float, int]:
    """The resonance and damping ratio from the resonance moves alone (module doc).

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
    grid_ticks : int
        The first burst's and its rest's (ticks): the grid's residuals.

    Returns
    -------
    tuple of (float, float, int)
        The resonance (Hz), the damping ratio, and the simulations run.
    """
    starts = _default_starts(records)
    short = _Problem([resonance_segment(r, grid_ticks) for r in records], plant, settings, starts)
    problem = _Problem([resonance_segment(r, ticks) for r in records], plant, settings, starts)
    f0 = plant.resonance_hz
    assert f0 is not None
    z0 = min(damping_ratio(plant), OVERDAMPED)
    lo = max(f0 / GRID_SPAN, 1.0)
    hi = min(f0 * GRID_SPAN, 0.999 * _highest_hz(plant))
    grid = np.log(np.geomspace(lo, hi, round(math.log(hi / lo) / math.log1p(GRID_STEP)) + 1))
    pts = [np.array([g, z0]) for g in grid]
    ss = np.array([float(r @ r) for r in short.many(pts)])
    picked: list[float] = []
    for i in np.argsort(ss).tolist():
        if all(abs(grid[i] - g) >= MINIMA_APART for g in picked):
            picked.append(float(grid[i]))
        if len(picked) == MINIMA:
            break
    best = None
    for g in picked:
        x, cost = problem.solve(np.array([g, z0]))
        if best is None or cost < best[1]:
            best = (x, cost)
    assert best is not None
    return math.exp(best[0][0]), float(best[0][1]), short.evaluations + problem.evaluations


def refine_resonance(
    records: Sequence[Record],
    plant: Plant,
    settings: Settings,
    starts: Sequence[Start],
    guess: tuple[float, float],
    *,
    nominal: Plant,
    evaluations: int = 0,
) -> Resonance:
    """The resonance and damping ratio over every capture, with their intervals (module
    doc).

    Parameters
    ----------
    records : sequence of Record
        The captures on the tick grid.
    plant : Plant
        The plant the rigid fit found (its transmission's load inertia scaled with the
        inertia).
    settings : Settings
        The servo's filter ratio in force.
    starts : sequence of Start
        The state of rest each capture starts from (the rigid fit's).
    guess : tuple of float
        The resonance (Hz) and damping ratio to start from.
    nominal : Plant
        The nominal axis's plant: its transmission is kept where the captures do not show
        the resonance.
    evaluations : int
        Simulations already run (the guess's), added to the count.

    Returns
    -------
    Resonance
        The estimates, or the nominal's transmission with a note.
    """
    from threadpoolctl import threadpool_limits  # type: ignore[import-untyped]

    problem = _Problem(records, plant, settings, starts)
    with threadpool_limits(1, user_api="blas"):
        x, _ = problem.solve(np.array([math.log(guess[0]), guess[1]]))
        jac = problem.jac(x)
        res = problem.fun(x)
    rms = float(np.sqrt(np.mean(res**2)))
    spread = max(rms, QUANTISATION_FLOOR)
    jtj = jac.T @ jac
    try:
        cov = spread**2 * np.linalg.inv(jtj)
        sd = np.sqrt(np.maximum(np.diag(cov), 0.0))
    except np.linalg.LinAlgError:
        sd = np.array([math.inf, math.inf])
    f, zeta = math.exp(x[0]), float(x[1])
    # a residual far above the floor (a limit cycle the simulator follows only so far)
    # leaves the Jacobian's interval too narrow: at least the move from the guess
    half_f = max(Z95 * sd[0], abs(x[0] - math.log(guess[0])))
    f_range = (
        (f * math.exp(-half_f), f * math.exp(half_f)) if math.isfinite(half_f) else (0.0, math.inf)
    )
    z_range = (max(0.0, zeta - Z95 * sd[1]), zeta + Z95 * sd[1])
    est = with_resonance(plant, f, zeta).transmission
    assert est is not None
    f0 = nominal.resonance_hz
    assert f0 is not None and nominal.transmission is not None
    width = f_range[1] / f - 1.0
    note = None
    if zeta >= OVERDAMPED:
        note = (
            f"transmission: the capture shows no ringing to measure (damping ratio "
            f"{zeta:.2g}, over-damped from {OVERDAMPED:g}): the nominal's transmission "
            f"({f0:.4g} Hz) is kept"
        )
    elif not width <= SHOWN_SHARE:
        note = (
            f"transmission: the capture does not resolve the resonance (its 95 % interval "
            f"{_hz(f_range)} is wider than +-{SHOWN_SHARE:.0%}: a transmission too stiff, or "
            f"a ringing too small for the encoder's counts): the nominal's transmission "
            f"({f0:.4g} Hz) is kept"
        )
    sizes = [r.used(r.measured).size for r in records]
    cuts = np.cumsum(sizes)[:-1]
    return Resonance(
        shown=note is None,
        transmission=est,
        resonance_hz=f,
        resonance_range_hz=f_range,
        damping_ratio=zeta,
        damping_ratio_range=z_range,
        guess_hz=guess[0],
        nominal_hz=f0,
        residual_rms_counts=rms,
        residuals=tuple(np.split(res, cuts)),
        evaluations=evaluations + problem.evaluations,
        note=note,
    )


def _hz(r: tuple[float, float]) -> str:
    return f"[{r[0]:.4g}, {r[1]:.4g}] Hz"


__all__ = [
    "GRID_SPAN",
    "GRID_STEP",
    "MINIMA",
    "MINIMA_APART",
    "OVERDAMPED",
    "SHOWN_SHARE",
    "STEP",
    "ZETA_MOST",
    "Resonance",
    "damping_ratio",
    "guess_resonance",
    "refine_resonance",
    "resonance_segment",
    "with_resonance",
]
