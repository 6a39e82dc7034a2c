"""The one scoring path: a move's measures → constraints → cost.

``params → simulate → trace → metrics → cost``: the plant (:mod:`vfgym.plant`) streams
the measures of a move; :func:`score` turns them into the constraint values, the
objectives and the scalar cost (``_cost``), as a :class:`Score`; :func:`evaluate` runs
every (controller, move, plant) triple and scores each (``_evaluate``), the fixed
controllers in one compiled call (``_batch``); ``_plants`` holds the results across true
plants and the robust rule. The Gymnasium envs' rewards, the Optuna objective and the
reports all call it. The one compiled copy of the cost, the VFServo-v0 env's running cost,
sits beside it (``_cost_compiled``), tested against :func:`score`.
"""

from vfgym.scoring._batch import Move, on_plant, score_pairs
from vfgym.scoring._cost import (
    CONSTRAINTS,
    DEFAULT_BOUNDS,
    DEFAULT_WEIGHTS,
    OBJECTIVES,
    Bounds,
    CostTerms,
    CostWeights,
    Score,
    Yardsticks,
    arrival_constraint,
    arrival_term,
    residual_term,
    score,
    yardsticks,
)
from vfgym.scoring._evaluate import Evaluation, evaluate
from vfgym.scoring._plants import (
    AcrossPlants,
    PlantSummary,
    best_robust,
    robust_constraints,
    score_robust,
    worst_on,
)
from vfgym.scoring._scheduled import Scheduler

__all__ = [
    "CONSTRAINTS",
    "DEFAULT_BOUNDS",
    "DEFAULT_WEIGHTS",
    "OBJECTIVES",
    "AcrossPlants",
    "Bounds",
    "CostTerms",
    "CostWeights",
    "Evaluation",
    "Move",
    "PlantSummary",
    "Scheduler",
    "Score",
    "Yardsticks",
    "arrival_constraint",
    "arrival_term",
    "best_robust",
    "evaluate",
    "on_plant",
    "residual_term",
    "robust_constraints",
    "score",
    "score_pairs",
    "score_robust",
    "worst_on",
    "yardsticks",
]
