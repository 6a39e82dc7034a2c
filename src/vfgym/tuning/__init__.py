"""Optuna sweeps over the tuned settings, and the exhaustive grid they are judged against.

A sweep is an Optuna study over :data:`vfgym.space.SPACE` (and the acceleration law, if
several are searched) on a scenario set. Its objective is the one scoring path,
``vfgym.evaluate(settings, scenarios)``, its cost aggregated over the scenarios (the mean,
CVaR or worst), its constraints the worst over the scenarios, set on each trial for the
samplers that learn them; the Pareto form minimises the three objectives' means. The
warm starts (the paper's settings, the rule of thumb) are the study's first trials, and a
setting already scored in the study is not simulated again.

Storage and workers are Optuna's (a SQLite file in the run folder by default, a journal
file, or PostgreSQL shared by machines; each worker is ``study.optimize``); the same
command with the same ``--study`` continues a stopped study (docs/guide/distributed.md).

The grid (:func:`run_grid`) evaluates :func:`vfgym.space.grid` through the batched kernel,
refined around its best points: the near-true optimum a sweep's best is reported against.

:func:`sweep` and :func:`grid` are ``vfgym sweep`` and ``vfgym grid`` as one call each: the
run folder written, the result returned (:class:`SweepResult`, :class:`GridRun`), as a
notebook runs them::

    from vfgym import tuning
    result = tuning.sweep(tuning.SweepConfig(scenarios="train", trials=100))
    print(result.text())

Importing the package loads neither Optuna nor scikit-learn: each is imported when a
study is opened or a model batch fitted.
"""

from vfgym.tuning._aggregate import AGGREGATES, Aggregate, aggregate, aggregate_costs
from vfgym.tuning._config import SAMPLERS, GridConfig, SweepConfig
from vfgym.tuning._grid import GridResult, GridRow, GridRun, GridStart, grid, run_grid
from vfgym.tuning._objective import Objective, StoredResult, stored_result
from vfgym.tuning._results import best_trial, trial_settings
from vfgym.tuning._storage import StorageSpec, find_storage, open_storage, resolve_storage
from vfgym.tuning._study import baseline_params, create_or_load, make_sampler, warm_starts
from vfgym.tuning._sweep import SweepProgress, SweepResult, SweepStart, TrialCounts, sweep
from vfgym.tuning._workers import WorkerReport, run_worker

__all__ = [
    "AGGREGATES",
    "SAMPLERS",
    "Aggregate",
    "GridConfig",
    "GridResult",
    "GridRow",
    "GridRun",
    "GridStart",
    "Objective",
    "StorageSpec",
    "StoredResult",
    "SweepConfig",
    "SweepProgress",
    "SweepResult",
    "SweepStart",
    "TrialCounts",
    "WorkerReport",
    "aggregate",
    "aggregate_costs",
    "baseline_params",
    "best_trial",
    "create_or_load",
    "find_storage",
    "grid",
    "make_sampler",
    "open_storage",
    "resolve_storage",
    "run_grid",
    "run_worker",
    "stored_result",
    "sweep",
    "trial_settings",
    "warm_starts",
]
