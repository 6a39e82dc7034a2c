"""Controllers that change their settings during a move (a VFServo-v0 agent): they run
the move themselves, and the scoring path scores the measures they return, so that
:func:`vfgym.evaluate` judges them on the same (move, plant) pairs as fixed settings and
per-move tuners."""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Sequence
from typing import Any

from vfgym.axis import PlantVariant
from vfgym.moves.scenarios import Scenario
from vfgym.params import Measures
from vfgym.plant.measures import NAMES as METRIC_NAMES
from vfgym.scoring._cost import Bounds, CostWeights, Score, score


class Scheduler(ABC):
    """A controller that schedules its settings during the move and runs it itself: a
    subclass implements :meth:`run_move`.

    :func:`vfgym.evaluate` calls :meth:`run_move` once per (move, plant) pair and scores
    the measures it returns with :func:`vfgym.scoring.score` on the move's true plant, so a
    scheduler's cost is computed as every other controller's.
    """

    @abstractmethod
    def run_move(self, scenario: Scenario, plant: PlantVariant) -> dict[str, Any]:
        """Run one move on a true plant and return its measures.

        Parameters
        ----------
        scenario : Scenario
            The move.
        plant : PlantVariant
            The true plant relative to the modelled one
            (:data:`vfgym.axis.NOMINAL`: the modelled plant).

        Returns
        -------
        dict
            At least the measures :mod:`vfgym.plant.measures` names, as
            :func:`vfgym.plant.measures.from_acc` gives them on the true plant.
        """


def score_scheduled(
    scheduler: Scheduler,
    moves: Sequence[Any],
    variants: Sequence[PlantVariant],
    measures: Measures,
    weights: CostWeights,
    bounds: Bounds,
) -> list[Score]:
    """A scheduler's scores on ``moves[i]``, each run on the true plant ``variants[i]``.

    Parameters
    ----------
    scheduler : Scheduler
        The scheduler.
    moves : sequence of Move
        The moves, each on the plant it is scored on (:class:`vfgym.scoring.Move`).
    variants : sequence of PlantVariant
        The true plant of each move, relative to the modelled one.
    measures, weights, bounds : Measures, CostWeights, Bounds
        The scoring path's inputs.

    Returns
    -------
    list of Score
        One per move.

    Raises
    ------
    ValueError
        If the scheduler returns something without the measures.
    """
    out = []
    for mv, v in zip(moves, variants, strict=True):
        m = scheduler.run_move(mv.scenario, v)
        missing = [k for k in METRIC_NAMES if k not in m] if isinstance(m, dict) else ["all"]
        if missing:
            raise ValueError(
                f"the scheduler {scheduler!r} returned no measure(s) {', '.join(missing)} for "
                f"move {mv.scenario.name!r}: a scheduler returns the measures of its run"
            )
        out.append(score({k: m[k] for k in METRIC_NAMES}, mv.scenario, mv.plant, measures,
                         weights, bounds))  # fmt: skip
    return out
