"""Refinement: a short Optuna sweep on one move, warm-started from an amortised tuner's
settings (``vfgym predict --refine N``).

The study is the sweeps' own machinery (:mod:`vfgym.tuning`): the default sampler of
:class:`vfgym.tuning.SweepConfig` (:func:`vfgym.tuning.make_sampler`), the
:class:`vfgym.tuning.Objective` on the one move, and the best trial as a sweep picks it
(:func:`vfgym.tuning.best_trial`). The predicted settings are enqueued as trial 0, so
the refined settings are never worse than the prediction.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass

from vfgym._validate import check_int
from vfgym.axis import Axis
from vfgym.moves.scenarios import Scenario
from vfgym.params import Settings


@dataclass(frozen=True)
class Refinement:
    """What :func:`refine` found.

    Attributes
    ----------
    settings : Settings
        The best trial's settings.
    cost : float
        Its cost on the move.
    feasible : bool
        Every constraint ≤ 0.
    start_cost : float
        The cost of the settings it started from (trial 0).
    costs : tuple of float
        Every trial's cost, in order (trial 0: the start).
    """

    settings: Settings
    cost: float
    feasible: bool
    start_cost: float
    costs: tuple[float, ...]


def refine(
    scenario: Scenario,
    start: Settings,
    trials: int,
    *,
    axis: Axis,
    seed: int | None = 0,
) -> Refinement:
    """Run ``trials`` trials of the default sampler on one move, from ``start``.

    Parameters
    ----------
    scenario : Scenario
        The move.
    start : Settings
        The settings enqueued first (an amortised tuner's prediction).
    trials : int
        Trials in all, the enqueued one included, ≥ 1.
    axis : Axis
        The problem: its plant, measures and, where it states uncertainty, its design
        plants, on which every trial must also be feasible.
    seed : int or None
        The sampler's seed.

    Returns
    -------
    Refinement
        The best trial (feasible first, as a sweep picks it) and every trial's cost.

    Raises
    ------
    ValueError
        If ``trials`` is not a whole number ≥ 1.
    """
    trials = check_int("refine", trials, 1)
    return short_sweep([scenario], start, trials, axis=axis, seed=seed)


def short_sweep(
    scenarios: Sequence[Scenario],
    start: Settings,
    trials: int,
    *,
    axis: Axis,
    seed: int | None = 0,
    also: Sequence[Settings] = (),
) -> Refinement:
    """``trials`` trials of the default sampler on moves (the mean cost), ``start`` first.

    Parameters
    ----------
    scenarios : sequence of Scenario
        The moves.
    start : Settings
        The settings enqueued first; their law is the one searched.
    trials : int
        Trials in all, ≥ 1.
    axis : Axis
        The problem: its plant, measures and design plants (every trial must also be
        feasible on them).
    seed : int or None
        The sampler's seed.
    also : sequence of Settings
        More settings enqueued after ``start`` (a sweep's other warm starts).

    Returns
    -------
    Refinement
        The best trial (feasible first, as a sweep picks it) and every trial's cost.
    """
    import optuna

    from vfgym.tuning import (
        Objective,
        SweepConfig,
        baseline_params,
        best_trial,
        make_sampler,
        stored_result,
        trial_settings,
    )

    optuna.logging.set_verbosity(optuna.logging.WARNING)
    laws = (start.accel_law,)
    cfg = SweepConfig(laws=laws, seed=seed, plots=False, axis=axis)  # its sampler: the default
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        # coordinates from the moves on the axis's plant
        storage = optuna.storages.InMemoryStorage()
        sampler = make_sampler(cfg, cfg.seed, list(scenarios), storage)
        study = optuna.create_study(storage=storage, direction="minimize", sampler=sampler)
    for s in (start, *also):
        study.enqueue_trial(baseline_params(laws, s))
    objective = Objective(list(scenarios), laws, "cost", axis=cfg.axis)
    study.optimize(objective, n_trials=trials)
    done = study.trials
    best = best_trial(study)
    assert best is not None  # trials ≥ 1 completed
    results = [stored_result(t) for t in done]
    costs = tuple(r.cost for r in results if r is not None)
    top = stored_result(best)
    assert top is not None and results[0] is not None  # (scored by the objective)
    return Refinement(
        settings=trial_settings(best),
        cost=top.cost,
        feasible=top.feasible,
        start_cost=results[0].cost,
        costs=costs,
    )


__all__ = ["Refinement", "refine", "short_sweep"]
