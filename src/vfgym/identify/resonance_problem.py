"""The resonance moves' records and their residuals over a compliant transmission's
resonance, damping ratio and a gain factor (:mod:`vfgym.identify.resonance` searches
them).

x = (log f_r, ζ, log g): the plant's transmission at the resonance f_r seen from the motor
and the damping ratio ζ (:func:`with_resonance`), the drive's gain times g (as
:class:`~vfgym.axis.PlantVariant` scales it). Each record is simulated from one servo
period before its first pulse (:func:`trimmed`), a record's residuals may be restricted
to one burst and its rest (:func:`window`), and the servo phase a record starts from is
ranked over its sample clock (:func:`ranked_phases`, :func:`best_phases`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from vfgym.axis import PlantVariant
from vfgym.identify.model import SAMPLE_TICKS, Record, Start, respond_many
from vfgym.mechanics import RESONANCE_TICKS_MIN, Transmission
from vfgym.params import Plant, Settings

SIMPLEX = np.array([0.03, 0.03, 0.03])
"""The Nelder–Mead search's first steps in (log f_r, ζ, log g)."""

SEARCH_EVALS = 150
"""Simulations each Nelder–Mead search may run."""

PHASES = 3
"""The guess's least squares runs from this many of the best servo phases (a phase far
from the true one, the resonance bent to it, can be a local optimum)."""

PHASES_APART = 10
"""…at least this many ticks apart."""

GAIN_SPAN = 0.3
"""Bounds of log g, the gain factor the resonance moves see (×0.74 to ×1.35)."""

ZETA_MOST = 1.0
"""The damping ratio's upper bound."""

STEP = np.array([0.002, 0.005, 0.002])
"""Central-difference steps in (log resonance, damping ratio, log gain factor)."""


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
    """A compliant plant's damping ratio ζ (:meth:`vfgym.Transmission.damping_ratio`).

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
    return tr.damping_ratio(plant.motor.inertia_kgm2)


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


def highest_hz(plant: Plant) -> float:
    """The highest resonance the simulator takes on this plant (Hz): f/10.

    Parameters
    ----------
    plant : Plant
        Gives the tick rate f.

    Returns
    -------
    float
        f / :data:`~vfgym.mechanics.RESONANCE_TICKS_MIN`.
    """
    return plant.tick_hz / RESONANCE_TICKS_MIN


def trimmed(record: Record, plant: Plant) -> Record:
    """The record without most of its rest before the first pulse: the same residuals,
    fewer ticks to simulate.

    The cut is a whole number of residual samples and of the servo's sample periods, so
    the state of rest at the new start, the servo's phase included, is the one at the
    old (:class:`~vfgym.identify.model.Start`); one such period is kept before the first
    pulse.

    Parameters
    ----------
    record : Record
        A capture on the tick grid.
    plant : Plant
        Gives the servo's sample period (ticks).

    Returns
    -------
    Record
        The record from the cut on.
    """
    step = math.lcm(SAMPLE_TICKS, plant.servo.sample_ticks)
    first = int(np.flatnonzero(record.pulses)[0])
    cut = max(0, (first - step) // step * step)
    k = cut // SAMPLE_TICKS
    read = None if record.read_offset_s is None else record.read_offset_s[k:]
    return replace(
        record,
        pulses=record.pulses[cut:],
        measured=record.measured[k:],
        read_offset_s=read,
        first_sample=max(0, record.first_sample - k),
    )


def window(record: Record, burst: int, burst_ticks: int) -> Record:
    """The record's residuals on one burst and its rest alone (the simulation still runs
    from the record's start)."""
    first = int(np.flatnonzero(record.pulses)[0])
    seg = resonance_segment(record, (burst + 1) * burst_ticks)
    begin = (first + burst * burst_ticks) // SAMPLE_TICKS
    return replace(seg, first_sample=max(seg.first_sample, begin))


class ResonanceProblem:
    """Residuals of the records over x = (log f_r, ζ, log g): g a factor on the drive's
    gain; each batch of plants simulated at once."""

    def __init__(
        self, records: Sequence[Record], plant: Plant, settings: Settings, starts: Sequence[Start]
    ) -> None:
        self.records = list(records)
        self.plant = plant
        self.settings = settings
        self.starts = list(starts)
        self.evaluations = 0
        self._cache: dict[bytes, list[np.ndarray]] = {}
        top = math.log(0.999 * highest_hz(plant))
        self.lo = np.array([math.log(1.0), 0.0, -GAIN_SPAN])
        self.hi = np.array([top, ZETA_MOST, GAIN_SPAN])

    def plant_at(self, x: np.ndarray) -> Plant:
        """The plant at x (its gain as :class:`~vfgym.axis.PlantVariant` scales it)."""
        p = with_resonance(self.plant, math.exp(x[0]), float(x[1]))
        return PlantVariant(torque_per_count=math.exp(x[2])).apply(p)

    def per_record(self, xs: Sequence[np.ndarray]) -> list[list[np.ndarray]]:
        todo = list({x.tobytes(): x for x in xs if x.tobytes() not in self._cache}.values())
        if todo:
            jobs = [(self.plant_at(x), self.starts) for x in todo]
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

    def cost(self, x: np.ndarray) -> float:
        """The sum of squares at x clipped into the bounds (for the simplex search)."""
        r = self.fun(np.clip(np.asarray(x, dtype=np.float64), self.lo, self.hi))
        return float(r @ r)

    def jac(self, x: np.ndarray) -> np.ndarray:
        pts, spans = [], []
        for i in range(x.size):
            up, dn = x.copy(), x.copy()
            up[i] = min(x[i] + STEP[i], self.hi[i])
            dn[i] = max(x[i] - STEP[i], self.lo[i])
            pts += [up, dn]
            spans.append(up[i] - dn[i])
        res = self.many(pts)
        return np.stack([(res[2 * i] - res[2 * i + 1]) / spans[i] for i in range(x.size)], axis=1)

    def solve(self, x0: np.ndarray, max_nfev: int = 30) -> tuple[np.ndarray, float]:
        """scipy's trust-region least squares from ``x0``: the optimum and its cost."""
        from scipy.optimize import least_squares

        x0 = np.clip(x0, self.lo + 1e-9, self.hi - 1e-9)
        sol = least_squares(
            self.fun,
            x0,
            jac=self.jac,
            bounds=(self.lo, self.hi),
            method="trf",
            x_scale=np.array([0.01, 0.02, 0.01]),
            xtol=1e-6,
            ftol=1e-8,
            max_nfev=max_nfev,
        )
        return np.asarray(sol.x, dtype=np.float64), float(sol.cost)

    def search(self, x0: np.ndarray) -> tuple[np.ndarray, float]:
        """scipy's Nelder–Mead from ``x0`` (the sum of squares is rough far from its
        minimum: the servo's quantised loop), at most :data:`SEARCH_EVALS` simulations."""
        from scipy.optimize import minimize

        simplex = np.array([x0] + [x0 + np.eye(3)[i] * SIMPLEX[i] for i in range(3)])
        sol = minimize(
            self.cost,
            x0,
            method="Nelder-Mead",
            options={
                "initial_simplex": simplex,
                "xatol": 1e-3,
                "fatol": 1.0,
                "maxfev": SEARCH_EVALS,
            },
        )
        return np.clip(np.asarray(sol.x, dtype=np.float64), self.lo, self.hi), float(sol.fun)


def default_starts(records: Sequence[Record]) -> list[Start]:
    """Each record's state of rest before any fit: within its held count when enabled."""
    out = []
    for r in records:
        span = r.held_range()
        out.append(Start() if span is None else Start(0.5 * (span[0] + span[1]), 0))
    return out


def best_phases(
    records: Sequence[Record],
    plant: Plant,
    settings: Settings,
    starts: Sequence[Start],
    step: int,
) -> tuple[list[Start], int]:
    """Each record's servo phase (in steps of ``step`` ticks) that fits it best on
    ``plant``, and the simulations run."""
    out, n = [], 0
    for rec, st in zip(records, starts, strict=True):
        phases = list(range(0, plant.servo.sample_ticks, step))
        tries = [Start(st.held_counts, p) for p in phases]
        resp = respond_many([rec], [(plant, [t]) for t in tries], settings)
        n += len(tries)
        ss = [float(np.sum(rec.residuals(r[0]) ** 2)) for r in resp]
        out.append(tries[int(np.argmin(ss))])
    return out, n


def ranked_phases(
    records: Sequence[Record], plant: Plant, settings: Settings, starts: Sequence[Start]
) -> tuple[list[list[Start]], int]:
    """The :data:`PHASES` best servo phases of each record on ``plant`` (in steps of the
    residuals' sample, at least :data:`PHASES_APART` ticks apart), as start lists, and the
    simulations run."""
    ns = plant.servo.sample_ticks
    per: list[list[Start]] = []
    n = 0
    for rec, st in zip(records, starts, strict=True):
        tries = [Start(st.held_counts, p) for p in range(0, ns, SAMPLE_TICKS)]
        resp = respond_many([rec], [(plant, [t]) for t in tries], settings)
        n += len(tries)
        ss = [float(np.sum(rec.residuals(r[0]) ** 2)) for r in resp]
        kept: list[Start] = []
        for i in np.argsort(ss).tolist():
            ph = tries[i].servo_phase
            if all(min((ph - k.servo_phase) % ns, (k.servo_phase - ph) % ns) >= PHASES_APART
                   for k in kept):  # fmt: skip
                kept.append(tries[i])
            if len(kept) == PHASES:
                break
        per.append(kept)
    depth = min(len(k) for k in per)
    return [[k[i] for k in per] for i in range(depth)], n


__all__ = [
    "GAIN_SPAN",
    "PHASES",
    "PHASES_APART",
    "SEARCH_EVALS",
    "SIMPLEX",
    "STEP",
    "ZETA_MOST",
    "ResonanceProblem",
    "best_phases",
    "damping_ratio",
    "default_starts",
    "highest_hz",
    "ranked_phases",
    "resonance_segment",
    "trimmed",
    "window",
    "with_resonance",
]
