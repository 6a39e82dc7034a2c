"""Results across true plants: the same (controller, move) pairs on plants drawn within an
axis's uncertainty (:mod:`vfgym.plant.uncertainty`), as :func:`vfgym.evaluate` returns them
with ``plants=``."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from vfgym.plant.uncertainty import PlantVariant


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
