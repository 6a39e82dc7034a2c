"""Results across true plants (the same (controller, move) pairs on plants drawn within an
axis's uncertainty, as :func:`vfgym.evaluate` returns them with ``plants=``) and the robust
rule a tuner ranks by: feasible on the modelled plant and on every true plant."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from vfgym.axis import PlantVariant
from vfgym.moves.baselines import Controller
from vfgym.params import DEFAULT_MEASURES, Measures
from vfgym.scoring._batch import Move, on_plant, score_pairs
from vfgym.scoring._cost import (
    CONSTRAINTS,
    DEFAULT_BOUNDS,
    DEFAULT_WEIGHTS,
    Bounds,
    CostWeights,
    Score,
)


@dataclass(frozen=True)
class PlantSummary:
    """One controller across the true plants.

    Attributes
    ----------
    feasible : int
        (move, plant) pairs on which every constraint holds.
    pairs : int
        (move, plant) pairs on which it has a cost.
    moves_feasible : int
        Moves feasible on every plant.
    moves : int
        Moves it has a cost on.
    mean_cost : float
        Mean cost over the pairs (NaN if none).
    worst_plant : str
        The plant with the fewest feasible moves (its label), ``""`` when all are feasible.
    """

    feasible: int
    pairs: int
    moves_feasible: int
    moves: int
    mean_cost: float
    worst_plant: str


@dataclass(frozen=True)
class AcrossPlants:
    """Costs and constraints of (controller, plant, move) triples.

    Attributes
    ----------
    plants : tuple of PlantVariant
        The true plants, relative to the modelled one.
    seed : int or None
        The seed they were drawn from (``None``: a fixed design, e.g. the ±5 % line).
    cost : numpy.ndarray
        (controllers, plants, moves); NaN where a controller cannot run a move.
    constraints : numpy.ndarray
        (controllers, plants, moves, 4), in the order of :data:`vfgym.scoring.CONSTRAINTS`.
    """

    plants: tuple[PlantVariant, ...]
    seed: int | None
    cost: np.ndarray
    constraints: np.ndarray

    @property
    def feasible(self) -> np.ndarray:
        """All constraints ≤ 0, per triple (False where not applicable)."""
        return np.all(self.constraints <= 0.0, axis=-1)

    def summary(self, c: int) -> PlantSummary:
        """One controller's feasibility and cost across the plants.

        Parameters
        ----------
        c : int
            The controller's index.

        Returns
        -------
        PlantSummary
            Its counts over (move, plant) pairs and moves.
        """
        ok, applies = self.feasible[c], np.isfinite(self.cost[c])
        per_plant = ok.sum(axis=1)
        worst = int(np.argmin(per_plant)) if ok.size else 0
        all_ok = bool(ok[applies].all()) if applies.any() else True
        moves = applies.any(axis=0)
        return PlantSummary(
            feasible=int(ok[applies].sum()),
            pairs=int(applies.sum()),
            moves_feasible=int((ok | ~applies).all(axis=0)[moves].sum()),
            moves=int(moves.sum()),
            mean_cost=float(np.nanmean(self.cost[c])) if applies.any() else float("nan"),
            worst_plant="" if all_ok else self.plants[worst].label(),
        )


def robust_constraints(nominal: np.ndarray, on_plants: np.ndarray, axis: int = 0) -> np.ndarray:
    """The robust rule, the one place it is written: a run is feasible only if it is
    feasible on the modelled plant and on every true plant, so its constraints are the worst
    of each over them. What a robust tuner ranks by (:func:`score_robust`, a sweep's
    aggregate through :attr:`vfgym.Evaluation.robust_constraints`); its cost stays the
    modelled plant's.

    Parameters
    ----------
    nominal : numpy.ndarray
        The constraints on the modelled plant (last axis: :data:`CONSTRAINTS`).
    on_plants : numpy.ndarray
        The same on the true plants, with one more axis for the plants at ``axis``; NaN
        where a plant was not run (ignored, as a run that cannot happen breaks nothing).
    axis : int
        The plants' axis of ``on_plants``.

    Returns
    -------
    numpy.ndarray
        Shaped as ``nominal``.
    """
    return np.fmax(nominal, np.fmax.reduce(on_plants, axis=axis))


def worst_on(
    controllers: Sequence[Controller],
    moves: Sequence[Move],
    plants: Sequence[PlantVariant],
    *,
    measures: Measures = DEFAULT_MEASURES,
    weights: CostWeights = DEFAULT_WEIGHTS,
    bounds: Bounds = DEFAULT_BOUNDS,
) -> list[np.ndarray]:
    """The worst constraints of ``controllers[i]`` on ``moves[i]`` over true plants, all
    pairs and plants in one batched call.

    Parameters
    ----------
    controllers, moves : sequence
        As :func:`score_pairs` takes them (the moves on their modelled plants).
    plants : sequence of PlantVariant
        The true plants.
    measures, weights, bounds : Measures, CostWeights, Bounds
        The scoring path's inputs.

    Returns
    -------
    list of numpy.ndarray
        Per pair, the largest value of each constraint over the plants (NaN where the
        controller cannot run the move).
    """
    variants = tuple(plants)
    scored = score_pairs(
        [c for c in controllers for _ in variants],
        [on_plant(mv, v) for mv in moves for v in variants],
        measures=measures,
        weights=weights,
        bounds=bounds,
    )
    n, nan = len(variants), np.full(len(CONSTRAINTS), np.nan)
    each = np.array([nan if r is None else r.constraints for r in scored]).reshape(-1, n, len(nan))
    return list(np.fmax.reduce(each, axis=1)) if n else [nan.copy() for _ in moves]


def score_robust(
    controllers: Sequence[Controller],
    moves: Sequence[Move],
    plants: Sequence[PlantVariant],
    *,
    measures: Measures = DEFAULT_MEASURES,
    weights: CostWeights = DEFAULT_WEIGHTS,
    bounds: Bounds = DEFAULT_BOUNDS,
) -> list[Score | None]:
    """Score ``controllers[i]`` on ``moves[i]`` as :func:`score_pairs` does, feasible only
    if feasible on every true plant too: what a robust tuner ranks by.

    The cost is the modelled plant's; the constraints are the worst over the modelled plant
    and ``plants``. A pair infeasible as modelled is not run on the plants (it cannot turn
    feasible), so the plants cost simulations only where they can change the answer; all
    of them run in one batched call.

    Parameters
    ----------
    controllers, moves : sequence
        As :func:`score_pairs` takes them.
    plants : sequence of PlantVariant
        The true plants (an axis's :meth:`~vfgym.axis.Axis.design_plants`); empty:
        :func:`score_pairs` alone.
    measures, weights, bounds : Measures, CostWeights, Bounds
        The scoring path's inputs.

    Returns
    -------
    list of Score or None
        One per pair, its constraints the worst over the plants.
    """
    out = score_pairs(controllers, moves, measures=measures, weights=weights, bounds=bounds)
    todo = [i for i, r in enumerate(out) if r is not None and r.feasible]
    if not plants or not todo:
        return out
    worst = worst_on(
        [controllers[i] for i in todo],
        [moves[i] for i in todo],
        plants,
        measures=measures,
        weights=weights,
        bounds=bounds,
    )
    for i, w in zip(todo, worst, strict=True):
        r = out[i]
        assert r is not None  # (todo: scored pairs)
        out[i] = r._replace(constraints=robust_constraints(r.constraints, w[np.newaxis]))
    return out


def best_robust(
    controllers: Sequence[Controller],
    move: Move,
    plants: Sequence[PlantVariant],
    *,
    measures: Measures = DEFAULT_MEASURES,
    weights: CostWeights = DEFAULT_WEIGHTS,
    bounds: Bounds = DEFAULT_BOUNDS,
    chunk: int = 4,
) -> int:
    """The index of the best controller on one move by :func:`score_robust`'s ranking
    (feasible on every plant first, then the least modelled cost, then the lower index),
    checking the plants lazily: the nominally feasible ones, cheapest first, ``chunk`` at a
    time, until one holds on every plant. The same answer as ranking all of
    :func:`score_robust`'s scores, for a fraction of the simulations.

    Parameters
    ----------
    controllers : sequence
        The candidates, as :func:`score_pairs` takes them (each runs the move).
    move : Move
        The move, on its modelled plant.
    plants : sequence of PlantVariant
        The true plants.
    measures, weights, bounds : Measures, CostWeights, Bounds
        The scoring path's inputs.
    chunk : int
        Candidates checked on the plants per batched call.

    Returns
    -------
    int
        The best candidate's index.
    """
    scored = score_pairs(
        controllers, [move] * len(controllers), measures=measures, weights=weights, bounds=bounds
    )
    cost = [math.inf if r is None else float(r.cost) for r in scored]
    ok = [r is not None and r.feasible for r in scored]
    order = sorted(range(len(controllers)), key=lambda i: (cost[i], i))
    todo = [i for i in order if ok[i]]
    if not plants:
        return todo[0] if todo else order[0]
    for at in range(0, len(todo), chunk):
        part = todo[at : at + chunk]
        worst = worst_on([controllers[i] for i in part], [move] * len(part), plants,
                         measures=measures, weights=weights, bounds=bounds)  # fmt: skip
        for i, w in zip(part, worst, strict=True):
            if not bool(np.any(w > 0.0)):  # (NaN: not run there, as score_robust's fmax)
                return i
    return order[0]
