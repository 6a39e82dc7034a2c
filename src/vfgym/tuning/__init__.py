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

Storage and workers. The default storage is a SQLite file in the run folder; ``journal``
is Optuna's JournalStorage on a file (one machine, no server); a ``postgresql://`` URL
is Optuna's RDB storage on a server that workers on many machines share. Each worker
claims a trial under a study-wide lock (a file lock beside a SQLite or journal file,
a PostgreSQL advisory lock on a server) only while the completed, running and waiting
trials number fewer than asked, so a study ends with exactly the trials asked for,
however many workers share it. A worker that dies mid-trial leaves a running trial
behind: on RDB storages Optuna's heartbeat marks it failed after the grace period, on
the journal the other workers see that its process is gone; either way it is marked
failed and enqueued again with the settings it had drawn (the rest are drawn when it
runs). A SQLite file is kept in write-ahead-log mode, so no reader waits on a worker
frozen or killed mid-write; journal appends take an ``flock`` the kernel drops when its
holder dies. Ctrl-C is only acted on inside a
trial's evaluation or while waiting, so an interrupt never leaves a half-written trial:
the interrupted trial is marked failed and enqueued again, and running the same command
with the same ``--study`` continues where it stopped.

Over several scenarios the cost form minimises an aggregate of the per-scenario costs:
the mean (default), the CVaR (mean of the costliest share) or the worst
(``_aggregate``); a setting is feasible only if it is feasible on every scenario.

Modules: ``_config`` (sweep and grid configurations), ``_storage`` (storages and the claim
lock), ``_objective`` (a trial scored by the one path), ``_study`` (samplers, search space,
budget), ``_workers`` and ``_recovery`` (workers sharing a study), ``_results`` (best trial,
CSV, figures, the tuned settings against the paper's as a :class:`vfgym.report.Report`,
gap to a reference), ``_grid`` (the exhaustive grid).

The grid (:func:`run_grid`) evaluates :func:`vfgym.space.grid` through the batched kernel,
then refines around its best points; its best is the near-true optimum a sweep's best is
reported against (as a gap in %).
"""

from vfgym.tuning._aggregate import (
    AGGREGATES,
    DEFAULT_AGGREGATE,
    DEFAULT_CVAR_ALPHA,
    aggregate_costs,
    check_aggregate,
    cvar,
    describe,
    set_cost,
)
from vfgym.tuning._config import FORMS, SAMPLERS, SweepConfig, check_name
from vfgym.tuning._grid import (
    GridConfig,
    GridResult,
    GridRow,
    grid_reference,
    run_grid,
    write_grid_csv,
)
from vfgym.tuning._objective import Aggregate, Objective, aggregate, settings_key
from vfgym.tuning._recovery import WORKER_ATTR, counts
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
from vfgym.tuning._storage import (
    STORAGE_HELP,
    StorageSpec,
    find_storage,
    mask_url,
    open_storage,
    resolve_storage,
)
from vfgym.tuning._stored import StoredResult, stored_result
from vfgym.tuning._study import (
    SAMPLER_NEEDS,
    StudyMeta,
    baseline_params,
    check_sampler,
    create_or_load,
    make_sampler,
    relative_space,
    trial_budget,
    warm_starts,
)
from vfgym.tuning._workers import DeferredInterrupt, WorkerReport, run_worker, spawn_workers

__all__ = [
    "AGGREGATES",
    "DEFAULT_AGGREGATE",
    "DEFAULT_CVAR_ALPHA",
    "FORMS",
    "SAMPLERS",
    "SAMPLER_NEEDS",
    "STORAGE_HELP",
    "WORKER_ATTR",
    "Aggregate",
    "BestRecord",
    "DeferredInterrupt",
    "FoundReference",
    "GridConfig",
    "GridResult",
    "GridRow",
    "Objective",
    "ReferenceGap",
    "StorageSpec",
    "StoredResult",
    "StudyMeta",
    "SweepConfig",
    "WorkerReport",
    "aggregate",
    "aggregate_costs",
    "baseline_params",
    "best_record",
    "best_trial",
    "check_aggregate",
    "check_name",
    "check_sampler",
    "compare",
    "counts",
    "create_or_load",
    "cvar",
    "describe",
    "find_reference",
    "find_storage",
    "gap_pct",
    "grid_reference",
    "make_sampler",
    "mask_url",
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
