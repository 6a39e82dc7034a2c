"""The one scoring path: a move's measures → constraints → cost.

``params → simulate → trace → metrics → cost``: the plant (:mod:`vfgym.plant`) streams
the measures of a move; :func:`score` turns them into the constraint values, the
objectives and the scalar cost (``_cost``); :func:`evaluate` runs every
(controller, scenario) pair in one compiled call and scores each (``_evaluate``). The
Gymnasium envs' rewards, the Optuna objective and the reports all call it.
"""

from vfgym.scoring._cost import (
    CONSTRAINTS,
    DEFAULT_BOUNDS,
    DEFAULT_WEIGHTS,
    OBJECTIVES,
    Bounds,
    CostWeights,
    score,
)
from vfgym.scoring._evaluate import Evaluation, Move, evaluate, score_pairs

__all__ = [
    "CONSTRAINTS",
    "DEFAULT_BOUNDS",
    "DEFAULT_WEIGHTS",
    "OBJECTIVES",
    "Bounds",
    "CostWeights",
    "Evaluation",
    "Move",
    "evaluate",
    "score",
    "score_pairs",
]
