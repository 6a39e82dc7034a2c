"""Optuna sweeps over the tuned settings, and the exhaustive grid they are judged against.

A sweep is a study over :data:`vfgym.space.SPACE` (and the acceleration law, if several
are searched) on a scenario set. Its objective is the one scoring path,
``vfgym.evaluate(settings, scenarios).cost`` aggregated over the scenarios (the mean by
default); its constraints are
:attr:`vfgym.Evaluation.constraints`, the worst (max) over the scenarios per constraint,
set on each trial with ``trial.set_constraint`` (Optuna 5's replacement for a
``constraints_func``; TPE, GP and NSGA-II use them, CMA-ES and grid ignore them);
the multi-objective (Pareto) form minimises :attr:`vfgym.Evaluation.objectives` averaged
over the scenarios. The paper's settings are enqueued as the study's first trial, and a
setting already scored in the study is not simulated again (its trial copies the result).

Storage and workers: Optuna's own. The default storage is a SQLite file in the run folder;
``journal`` is Optuna's JournalStorage on a file (processes on one machine, no server); a
``postgresql://`` URL is Optuna's RDB storage on a server that workers on many machines
share. Each worker is ``study.optimize`` in its own process; on RDB storages Optuna's
heartbeat fails the trial of a worker that died (``heartbeat_interval``/``grace_period``,
``fail_stale_trials``) and ``RetryHeartbeatStaleTrialCallback`` enqueues it again with its
settings. vfgym adds only what Optuna lacks (:mod:`vfgym.tuning._workers`): a study-wide
trial budget, dead workers on a journal, and Ctrl-C acted on only inside a simulation, so
an interrupt never leaves a half-written trial; running the same command with the same
``--study`` continues where it stopped (docs/guide/distributed.md).

Over several scenarios the cost form minimises an aggregate of the per-scenario costs:
the mean (default), the CVaR (mean of the costliest share) or the worst
(``_aggregate``); a setting is feasible only if it is feasible on every scenario.

Modules: ``_config`` (sweep and grid configurations), ``_storage`` (storages),
``_objective`` (a trial scored by the one path), ``_stored`` (how a trial stores its
result), ``_study`` (samplers, search space, budget), ``_workers`` (workers sharing a
study), ``_results`` (best trial,
CSV, figures, the tuned settings against the paper's as a :class:`vfgym.report.Report`,
gap to a reference), ``_grid`` (the exhaustive grid).

The grid (:func:`run_grid`) evaluates :func:`vfgym.space.grid` through the batched kernel,
then refines around its best points; its best is the near-true optimum a sweep's best is
reported against (as a gap in %).
"""

from vfgym.tuning._aggregate import (
    AGGREGATES,
    aggregate_costs,
    check_aggregate,
    cvar,
    describe,
    set_cost,
)
from vfgym.tuning._config import FORMS, SAMPLERS, SweepConfig
from vfgym.tuning._grid import (
    GridConfig,
    GridResult,
    GridRow,
    grid_reference,
    run_grid,
    write_grid_csv,
)
from vfgym.tuning._objective import Aggregate, Objective, aggregate, settings_key
from vfgym.tuning._results import (
    BestRecord,
    FoundReference,
    ReferenceGap,
    best_record,
    best_trial,
    compare,
    find_reference,
    gap_pct,
    trial_settings,
    write_plots,
    write_trials_csv,
)
from vfgym.tuning._storage import StorageSpec, find_storage, open_storage, resolve_storage
from vfgym.tuning._stored import StoredResult, stored_result
from vfgym.tuning._study import (
    baseline_params,
    check_sampler,
    create_or_load,
    make_sampler,
    relative_space,
    trial_budget,
    warm_starts,
)
from vfgym.tuning._workers import WorkerReport, run_worker, spawn_workers

__all__ = [
    "AGGREGATES",
    "FORMS",
    "SAMPLERS",
    "Aggregate",
    "BestRecord",
    "FoundReference",
    "GridConfig",
    "GridResult",
    "GridRow",
    "Objective",
    "ReferenceGap",
    "StorageSpec",
    "StoredResult",
    "SweepConfig",
    "WorkerReport",
    "aggregate",
    "aggregate_costs",
    "baseline_params",
    "best_record",
    "best_trial",
    "check_aggregate",
    "check_sampler",
    "compare",
    "create_or_load",
    "cvar",
    "describe",
    "find_reference",
    "find_storage",
    "gap_pct",
    "grid_reference",
    "make_sampler",
    "open_storage",
    "relative_space",
    "resolve_storage",
    "run_grid",
    "run_worker",
    "set_cost",
    "settings_key",
    "spawn_workers",
    "stored_result",
    "trial_budget",
    "trial_settings",
    "warm_starts",
    "write_grid_csv",
    "write_plots",
    "write_trials_csv",
]
