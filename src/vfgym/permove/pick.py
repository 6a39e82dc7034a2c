"""The pick model: settings for a new move picked from a library of training moves'
optima, by their cost on the training moves most like it (the shipped settings model).

With ``check`` > 1 the model also simulates its ``check`` best-ranked candidates on the
move itself (one batched compiled call, a few milliseconds) and returns the best of them,
feasible first: the plant is known exactly, so a candidate that breaks a constraint on
this move, or one beaten by the next, is never returned on the ranking's word alone.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from vfgym._validate import check_choice, check_int
from vfgym.axis import PlantVariant
from vfgym.moves.features import SCENARIO_FEATURES, scenario_features
from vfgym.moves.scenarios import Scenario
from vfgym.params import DEFAULT_MEASURES, PAPER_PLANT, Measures, Plant, Settings

from .optima import MoveOptimum
from .targets import TargetModel, model_head, settings_targets, target_settings

PICK_KIND = "vfgym-settings-pick"
INFEASIBLE_PENALTY = 1.0
"""Added to a candidate's cost ratio on a move where it breaks a constraint."""
RATIO_CAP = 10.0
"""Cost ratios are capped here, so one disastrous move does not outweigh its neighbours."""


def ratio_table(cost: np.ndarray, feasible: np.ndarray, best: np.ndarray) -> np.ndarray:
    """What the pick model averages: cost / the move's optimum, plus
    :data:`INFEASIBLE_PENALTY` where infeasible, capped at :data:`RATIO_CAP`.

    Parameters
    ----------
    cost : numpy.ndarray
        (moves, candidates): each candidate's cost on each move.
    feasible : numpy.ndarray
        bool, the same shape.
    best : numpy.ndarray
        (moves,): each move's optimum cost.

    Returns
    -------
    numpy.ndarray
        (moves, candidates).
    """
    r = cost / best[:, None] + np.where(feasible, 0.0, INFEASIBLE_PENALTY)
    return np.minimum(np.nan_to_num(r, nan=RATIO_CAP), RATIO_CAP)


def greedy_library(ratios: np.ndarray, size: int) -> np.ndarray:
    """Columns of ``ratios`` chosen one by one, each lowering most the sum over the moves
    of the best chosen candidate's ratio (ties: the lower index).

    Parameters
    ----------
    ratios : numpy.ndarray
        (moves, candidates), from :func:`ratio_table`.
    size : int
        Candidates to choose (at most all).

    Returns
    -------
    numpy.ndarray
        int, the chosen columns in the order chosen.
    """
    chosen: list[int] = []
    cur = np.full(ratios.shape[0], np.inf)
    for _ in range(min(size, ratios.shape[1])):
        gain = np.minimum(cur[:, None], ratios).sum(axis=0)
        gain[chosen] = np.inf
        j = int(np.argmin(gain))
        chosen.append(j)
        cur = np.minimum(cur, ratios[:, j])
    return np.array(chosen, dtype=np.int64)


@dataclass(frozen=True, eq=False)
class PickModel(TargetModel):
    """Settings picked from a library of candidates by the moves most like this one.

    Candidates are optimal settings of training moves in the regression's coordinates
    (:data:`TARGETS`, k relative to the move's k_a). For a new move: its ``neighbours``
    nearest training moves in standardised feature space, the candidate whose mean
    cost ratio over them (:func:`ratio_table`) is least, made settings on the move's plant.

    Attributes
    ----------
    neighbours : int
        Training moves averaged over.
    mean, scale : numpy.ndarray
        Standardisation of the features.
    points : numpy.ndarray
        (moves, features): the training moves' standardised features.
    library : numpy.ndarray
        (candidates, 4): the candidates' targets.
    ratios : numpy.ndarray
        (moves, candidates): each candidate's cost ratio on each training move.
    weights : numpy.ndarray
        (features,): each standardised feature's weight in the distance (0: ignored).
    accel_law : str
        The law of the picked settings.
    trained_on : dict or None
        The axis it was fitted on (:func:`vfgym.permove.tuners.trained_on`); ``None``: the
        paper's plant and measures.
    check : int
        Best-ranked candidates simulated on the move itself, the best of them returned
        (module doc); 0 or 1: the best-ranked one, unsimulated.
    """

    neighbours: int
    mean: np.ndarray
    scale: np.ndarray
    points: np.ndarray
    library: np.ndarray
    ratios: np.ndarray
    weights: np.ndarray
    accel_law: str = "rise"
    trained_on: dict[str, str] | None = None
    check: int = 0

    def __post_init__(self) -> None:
        object.__setattr__(self, "check", check_int("check", self.check, 0, len(self.library)))

    def ranked(self, features: np.ndarray) -> np.ndarray:
        """The library rows by their mean cost ratio over the move's nearest training
        moves, best first (ties: the lower row).

        Parameters
        ----------
        features : numpy.ndarray
            (len(SCENARIO_FEATURES),).

        Returns
        -------
        numpy.ndarray
            int, every row once.
        """
        z = (np.asarray(features, dtype=np.float64) - self.mean) / self.scale
        d = np.sum(((self.points - z) * self.weights) ** 2, axis=1)
        near = np.argsort(d, kind="stable")[: self.neighbours]
        return np.argsort(self.ratios[near].mean(axis=0), kind="stable")

    def pick(self, features: np.ndarray) -> int:
        """The library row ranked first for one move's features.

        Parameters
        ----------
        features : numpy.ndarray
            (len(SCENARIO_FEATURES),).

        Returns
        -------
        int
            The candidate's row.
        """
        return int(self.ranked(features)[0])

    def settings(
        self,
        scenario: Scenario,
        plant: Plant = PAPER_PLANT,
        measures: Measures = DEFAULT_MEASURES,
        plants: Sequence[PlantVariant] = (),
    ) -> Settings:
        """The settings the model picks for a move: the best-ranked candidate, or with
        :attr:`check` > 1 the best on the move of the ``check`` best-ranked (feasible
        first, then the least cost; ties: the better ranked).

        Parameters
        ----------
        scenario : Scenario
            The move.
        plant : Plant
            The base plant (an axis's), before the move's load.
        measures : Measures
            The axis's measures, which the check scores with.
        plants : sequence of PlantVariant
            True plants a candidate must also be feasible on in the check (the axis's
            :meth:`~vfgym.axis.Axis.design_plants`).

        Returns
        -------
        Settings
            Inside the search space.
        """
        from vfgym.scoring import Move, best_robust

        loaded = scenario.plant(plant)
        order = self.ranked(scenario_features(scenario, plant, loaded))
        cands = [target_settings(self.library[j], loaded, self.accel_law)
                 for j in order[: max(self.check, 1)]]  # fmt: skip
        if len(cands) == 1:
            return cands[0]
        return cands[best_robust(cands, Move.of(scenario, plant), plants, measures=measures)]

    def targets_of(self, features: np.ndarray) -> np.ndarray:
        """The picked candidate's targets for one move's features.

        Parameters
        ----------
        features : numpy.ndarray
            (len(SCENARIO_FEATURES),).

        Returns
        -------
        numpy.ndarray
            (4,), a row of :attr:`library`.
        """
        return self.library[self.pick(features)]

    def to_dict(self) -> dict[str, Any]:
        """The model as plain data (what :meth:`save` writes)."""
        return (
            model_head(PICK_KIND, self.accel_law)
            | {
                "neighbours": self.neighbours,
                "mean": self.mean.tolist(),
                "scale": self.scale.tolist(),
                "weights": self.weights.tolist(),
                "library": self.library.tolist(),
                "points": self.points.tolist(),
                "ratios": self.ratios.tolist(),
            }
            | ({} if self.trained_on is None else {"trained_on": dict(self.trained_on)})
            | ({"check": self.check} if self.check else {})
        )


def fit_pick_model(
    scenarios: Sequence[Scenario],
    optima: Sequence[MoveOptimum],
    cost: np.ndarray,
    feasible: np.ndarray,
    *,
    neighbours: int = 6,
    library: int = 64,
    ignore: Sequence[str] = ("direction",),
    plant: Plant = PAPER_PLANT,
) -> PickModel:
    """Fit the pick model: a greedy library of candidates and the training moves' table.

    Parameters
    ----------
    scenarios : sequence of Scenario
        The training moves.
    optima : sequence of MoveOptimum
        Their optima, in the same order.
    cost, feasible : numpy.ndarray
        (moves, moves): the cost (and feasibility) on move i of move j's optimum made
        settings on move i's plant (``experiments/candidate_costs.py``).
    neighbours : int
        Training moves averaged over, ≥ 1.
    library : int
        Candidates kept, ≥ 1.
    ignore : sequence of str
        Features left out of the distance (names of :data:`SCENARIO_FEATURES`).
    plant : Plant
        The base plant the optima were found on.

    Returns
    -------
    PickModel
        The fitted model.

    Raises
    ------
    ValueError
        If the inputs do not match or an argument is out of range.
    """
    n = len(scenarios)
    if [s.name for s in scenarios] != [o.scenario for o in optima]:
        raise ValueError("scenarios and optima differ: give the optima of these moves, in order")
    if np.shape(cost) != (n, n) or np.shape(feasible) != (n, n):
        raise ValueError(f"cost and feasible must be ({n}, {n}), one row and column per move")
    neighbours = check_int("neighbours", neighbours, 1, n)
    library = check_int("library", library, 1, n)
    for name in ignore:
        check_choice("ignore", name, SCENARIO_FEATURES)
    weights = np.array([0.0 if f in ignore else 1.0 for f in SCENARIO_FEATURES])
    loaded = [sc.plant(plant) for sc in scenarios]
    x = np.array([scenario_features(sc, plant, p) for sc, p in zip(scenarios, loaded, strict=True)])
    t = np.array([settings_targets(o.settings, p) for o, p in zip(optima, loaded, strict=True)])
    mean, scale = x.mean(axis=0), x.std(axis=0)
    scale[scale < 1e-12] = 1.0
    # 6 decimals: the shipped file stays small (a ratio's 1e-6 is far below the gaps)
    r = ratio_table(np.asarray(cost), np.asarray(feasible), np.array([o.cost for o in optima]))
    r = np.round(r, 6)
    cols = greedy_library(r, library)
    law = optima[0].settings.accel_law
    z = np.round((x - mean) / scale, 6)
    return PickModel(neighbours, mean, scale, z, t[cols], r[:, cols], weights, law)


__all__ = [
    "INFEASIBLE_PENALTY",
    "PICK_KIND",
    "RATIO_CAP",
    "PickModel",
    "fit_pick_model",
    "greedy_library",
    "ratio_table",
]
