"""Which of a run's evaluated models is shipped as ``best_model.zip``: the validation
(move, true plant) pairs every evaluation scores, how many of them (more on an uncertain
axis), and the rule a later model must pass to replace the best so far (:func:`beats`).

The pairs are the train split's seeds from :data:`VALIDATION_SEED0` on, which training
(seeds drawn in [0, 2³¹)) never reaches, each on a true plant drawn once from
:data:`VALIDATION_PLANT_SEED`; the test split is kept for the final report.
"""

from __future__ import annotations

import csv
import json
import math
from os import PathLike
from pathlib import Path
from typing import Any

import numpy as np

from vfgym.axis import LOADS_AXIS, Axis, as_axis
from vfgym.io.runs import write_text
from vfgym.moves.scenarios import Scenario

VALIDATION_SEED0 = 2**40
"""First train-split seed of the held-out validation scenarios."""

SIGNIFICANCE = 2.0
"""A later model replaces the best one only if its mean validation cost is lower by more
than this many standard errors of the per-scenario differences (:func:`beats`)."""
MIN_GAIN = 0.005
"""... and by at least this share of the best's mean validation cost (:func:`beats`): two
models 0.04 % and 0.1 % cheaper on 256 validation pairs, beyond 2 standard errors, each
broke a limit the base holds on one held-out pair of 512 (docs/results/agents.md)."""


def beats(
    costs: np.ndarray,
    best: np.ndarray | None,
    z: float = SIGNIFICANCE,
    feasible: np.ndarray | None = None,
    best_feasible: np.ndarray | None = None,
    min_gain: float = MIN_GAIN,
) -> bool:
    """Whether a model with validation ``costs`` replaces the best so far, whose costs on
    the same scenarios are ``best``: it is feasible on every scenario where the best is
    (pairwise: a model that breaks a limit on one true plant and holds on another is not
    "as feasible" as one that holds on the first, whatever the counts), so that a model
    cheaper by breaking a limit never replaces one that holds (the start: the base,
    feasible on the axis's design); and its mean cost is lower by more than ``z``
    standard errors of the paired differences (the scenarios' spread), so that a model a
    hair better on these scenarios, and as likely worse on others, does not replace one
    that is known (a noise-level pick of a later model was worse on held-out moves more
    often than not), and by at least ``min_gain`` of the best's mean cost (a gain too
    small to be worth the risk of a limit broken on a pair validation did not see).

    Parameters
    ----------
    costs : numpy.ndarray
        The candidate's cost on each validation scenario.
    best : numpy.ndarray or None
        The best model's, on the same scenarios (None: no best yet, the candidate wins).
    z : float
        Standard errors required.
    feasible, best_feasible : numpy.ndarray or None
        Each one's feasibility on the same scenarios (None: not known, not compared).
    min_gain : float
        The least gain, as a share of the best's mean cost.

    Returns
    -------
    bool
        True if the candidate becomes the best.
    """
    costs = np.asarray(costs, dtype=np.float64)
    if best is None:
        return True
    known = feasible is not None and best_feasible is not None
    if known and not np.all(np.asarray(feasible, bool)[np.asarray(best_feasible, bool)]):
        return False
    diff = np.asarray(best, dtype=np.float64) - costs
    gain = float(diff.mean())
    if not (gain > 0.0 and gain >= min_gain * float(np.mean(best))):
        return False
    if len(diff) < 2:
        return True
    se = float(diff.std(ddof=1)) / math.sqrt(len(diff))
    return gain > z * se


VALIDATION_PLANT_SEED = 2**40
"""Seed of the validation moves' true plants on an axis with uncertainty (one a move)."""


def validation_plants(n: int, axis: Axis | str | PathLike[str] = LOADS_AXIS) -> list[Any]:
    """The true plant of each validation move: drawn within the axis's uncertainty from
    :data:`VALIDATION_PLANT_SEED` (fixed, so that every evaluation scores the same
    (move, plant) pairs and a model is compared with the best on them), or the modelled
    plant where the axis states none.

    Parameters
    ----------
    n : int
        Validation moves.
    axis : Axis, str or os.PathLike
        The axis (or its file) the envs draw from; default the envs' own,
        :data:`vfgym.axis.LOADS_AXIS`.

    Returns
    -------
    list of PlantVariant
        One per validation move.
    """
    from vfgym.axis import NOMINAL, draw_plants

    ax = as_axis(axis)
    if ax.uncertainty.exact:
        return [NOMINAL] * n
    return list(draw_plants(ax.uncertainty, ax.plant, n, VALIDATION_PLANT_SEED))


def validation_scenarios(n: int, axis: Axis | str | PathLike[str] = LOADS_AXIS) -> list[Scenario]:
    """The held-out scenarios the evaluation callback scores (never drawn in training);
    on an axis (an :class:`~vfgym.axis.Axis` or its file), its train move set's."""
    axis = as_axis(axis)
    return [axis.moves.train.pick(VALIDATION_SEED0 + i, "train", axis.plant) for i in range(n)]


def validation_size(params: dict[str, Any], axis: Axis | str | PathLike[str] = LOADS_AXIS) -> int:
    """How many validation (move, plant) pairs the best model is chosen on: on an axis
    with uncertainty ``n_eval_scenarios_uncertain`` (default ``n_eval_scenarios``), since
    there a model may break a limit on a few true plants only (1 % of them: missed by 32
    pairs 72 % of the time, by 256 pairs 8 %); else ``n_eval_scenarios`` (default 16).

    Parameters
    ----------
    params : dict
        The run's hyperparameters.
    axis : Axis, str or os.PathLike
        The axis (or its file) the envs draw from; default the envs' own,
        :data:`vfgym.axis.LOADS_AXIS` (its plant exact).

    Returns
    -------
    int
        Validation pairs.
    """
    n = int(params.get("n_eval_scenarios", 16))
    if as_axis(axis).uncertainty.exact:
        return n
    return int(params.get("n_eval_scenarios_uncertain", n))


def best_is_start(run: Path) -> bool:
    """Whether the run's best model is its first evaluation's (the untrained start; with
    residual actions, the base itself): no later model beat it (:func:`beats`)."""
    path = run / "evaluations.csv"
    if not path.is_file():
        return False
    with path.open() as fh:
        rows = list(csv.DictReader(fh))
    best = [i for i, r in enumerate(rows) if r.get("best") == "1"]
    return best == [0]


BEST_COSTS = "best_model_costs.json"
"""The best model's cost on each validation scenario, beside ``best_model.zip``."""


def best_so_far(run: Path) -> tuple[float, np.ndarray | None, np.ndarray | None]:
    """The best model's mean validation cost, its costs and feasibility by scenario, of a
    run being continued (``inf`` and None: none yet; the costs None for a run from before
    they were kept, whose best is then judged by its mean; the feasibility None for one
    from before it was)."""
    path, costs_path = run / "evaluations.csv", run / BEST_COSTS
    if not path.is_file():
        return float("inf"), None, None
    with path.open() as fh:
        rows = [r for r in csv.DictReader(fh) if r.get("best") == "1"]
    if not rows:
        return float("inf"), None, None
    doc = json.loads(costs_path.read_text()) if costs_path.is_file() else None
    if isinstance(doc, list):  # costs only, as first kept
        doc = {"cost": doc}
    costs = None if doc is None else np.array(doc["cost"], float)
    ok = None if doc is None or "feasible" not in doc else np.array(doc["feasible"], bool)
    return float(rows[-1]["mean_cost"]), costs, ok


def append_eval(run: Path, steps: int, mean: float, median: float, best: bool) -> None:
    path = run / "evaluations.csv"
    text = path.read_text() if path.is_file() else "timesteps,mean_cost,median_cost,best\n"
    write_text(path, text + f"{steps},{mean:.6g},{median:.6g},{int(best)}\n")
