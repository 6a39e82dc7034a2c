"""Results across true plants: the same (controller, move) pairs on plants drawn within an
axis's uncertainty (:mod:`vfgym.axis`), as :func:`vfgym.evaluate` returns them
with ``plants=``."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from vfgym.axis import PlantVariant
from vfgym.moves.baselines import Baseline, Controller, FixedFrequency, SCurveSource
from vfgym.moves.scenarios import Scenario
from vfgym.params import DEFAULT_MEASURES, PAPER_PLANT, Measures, Plant, Settings
from vfgym.scoring._cost import (
    CONSTRAINTS,
    DEFAULT_BOUNDS,
    DEFAULT_WEIGHTS,
    Bounds,
    CostWeights,
    Score,
)
from vfgym.scoring._evaluate import Move, on_plant, score_pairs


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


def score_across(
    controllers: Sequence[Sequence[Controller | None]],
    scenarios: Sequence[Scenario],
    plants: Sequence[PlantVariant],
    *,
    plant: Plant = PAPER_PLANT,
    measures: Measures = DEFAULT_MEASURES,
    weights: CostWeights = DEFAULT_WEIGHTS,
    bounds: Bounds = DEFAULT_BOUNDS,
    seed: int | None = None,
) -> AcrossPlants:
    """Per-move controllers scored on true plants, in one batched call.

    What a verdict judges every tuner with (fixed settings, a baseline, per-move settings
    a model chose): the controller each ran on each move, on each true plant.

    Parameters
    ----------
    controllers : sequence of sequence
        ``controllers[c][s]``: controller ``c``'s choice on move ``s`` (settings, a pulse
        source, a baseline or its name; ``None``, or anything else, e.g. a scheduler's
        own run: not scored, NaN).
    scenarios : sequence of Scenario
        The moves.
    plants : sequence of PlantVariant
        The true plants, relative to the modelled one.
    plant, measures, weights, bounds : Plant, Measures, CostWeights, Bounds
        The axis's modelled plant, measures and scoring.
    seed : int or None
        The seed ``plants`` were drawn from, recorded with them.

    Returns
    -------
    AcrossPlants
        Cost and constraints of every (controller, plant, move).
    """
    kinds = (Settings, FixedFrequency, SCurveSource, Baseline)
    variants, scens = tuple(plants), list(scenarios)
    moves = [Move.of(sc, plant, v) for v in variants for sc in scens]
    ctrls: list[Controller] = []
    on: list[Move] = []
    at: list[tuple[int, int]] = []
    for ci, row in enumerate(controllers):
        for k, mv in enumerate(moves):
            c = row[k % len(scens)]
            c = Baseline(c) if isinstance(c, str) else c
            if isinstance(c, kinds):
                ctrls.append(c)
                on.append(mv)
                at.append((ci, k))
    scored = score_pairs(ctrls, on, measures=measures, weights=weights, bounds=bounds)
    rows: list[list[Score | None]] = [[None] * len(moves) for _ in controllers]
    for (ci, k), res in zip(at, scored, strict=True):
        rows[ci][k] = res
    return across_arrays(rows, variants, seed, len(scens))


def across_arrays(
    rows: list[list[Score | None]], plants: tuple[PlantVariant, ...], seed: int | None, ns: int
) -> AcrossPlants:
    """Each controller's scores on the true plants (``rows[c]`` plant-major: plant ``p``,
    move ``s`` at ``p * ns + s``), as arrays."""
    nc, npl = len(rows), len(plants)
    cost = np.full((nc, npl, ns), np.nan)
    cons = np.full((nc, npl, ns, len(CONSTRAINTS)), np.nan)
    for ci, row in enumerate(rows):
        for k, res in enumerate(row):
            if res is not None:
                pi, si = divmod(k, ns)
                cost[ci, pi, si], cons[ci, pi, si] = res.cost, res.constraints
    return AcrossPlants(plants, seed, cost, cons)


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
    n, out = len(variants), []
    for k in range(len(moves)):
        worst = np.full(len(CONSTRAINTS), np.nan)
        for r in scored[k * n : (k + 1) * n]:
            if r is not None:
                worst = np.fmax(worst, r.constraints)
        out.append(worst)
    return out


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
        out[i] = r._replace(constraints=np.fmax(r.constraints, w))
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
