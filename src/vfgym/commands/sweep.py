"""``vfgym sweep``: tune the V-F settings with Optuna on a scenario set.

One command, one run folder (``RUNS/sweep/STUDY/``) with everything in it: the resolved
config, the command line, the storage (a SQLite file by default), the trials as CSV, the
best settings as YAML (``vfgym evaluate --settings best.yaml``), plots, and the tuned
settings against the paper's on each scenario. Run it again with the same ``--study`` to
continue a stopped study; give ``--storage postgresql://...`` and the same ``--study`` on
several machines to share one study.
"""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from vfgym.tuning import SweepConfig, SweepProgress, SweepStart

OPTIONS = (
    ("--scenarios", "scenario set: a name, 'named', 'train', 'test' or a comma-separated list "
     "(default paper-step; with --axis, the axis's train moves)"),
    ("--scenario-count", "number of scenarios in a 'train'/'test' set (default 16; not with "
     "--axis, whose file sets its own)"),
    ("--first-seed", "first seed of a 'train'/'test' set (default 0; not with --axis)"),
    ("--axis", "an axis file (e.g. experiments/axes/belt.yaml): its plant, measures and "
     "train/test moves; the sweep tunes on its train moves"),
    ("--laws", "acceleration laws searched: rise, slew or rise,slew (default rise)"),
    ("--sampler", "compass (default: compass search in the problem's own coordinates with "
     "Gaussian-process checks), tpe, cmaes, gp, nsga2, grid or random"),
    ("--objective", "cost (default) or pareto (overshoot, move time, accel violation)"),
    ("--aggregate", "the cost minimised over the scenarios: mean (default), cvar (mean of the "
     "costliest --cvar-alpha share) or worst"),
    ("--cvar-alpha", "the share of the costliest scenarios cvar averages, in (0, 1] "
     "(default 0.25)"),
    ("--trials", "completed trials the study ends with, all workers together (default 100)"),
    ("--timeout", "seconds after which workers start no new trial"),
    ("--workers", "worker processes on the study (default 1: this process)"),
    ("--seed", "sampler seed (worker i uses seed+i; default 0)"),
    ("--storage", "sqlite (default, in the run folder), journal, sqlite:///FILE, "
     "journal:FILE or postgresql://USER:PASS@HOST:PORT/DB"),
    ("--study", "study name, also the run folder's (default: config name + time); "
     "the same name continues a study"),
    ("--runs-dir", "root of the run folders (default runs)"),
    ("--reference", "a grid reference.yaml (or grid run folder) to report the gap to "
     "(default: the best matching RUNS/grid/*/reference.yaml)"),
    ("--grid-points", "values per dimension for --sampler grid (default 5)"),
    ("--heartbeat", "seconds between a running trial's heartbeats (Optuna's heartbeat_interval, "
     "RDB storages; default 10)"),
    ("--grace", "seconds without a heartbeat before a trial is taken as dead and retried "
     "(Optuna's grace_period; default 2 x heartbeat)"),
)  # fmt: skip


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "sweep",
        help="tune the settings with Optuna (run folder, resumable, many workers)",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("--config", help="YAML file of these options (e.g. experiments/quick.yaml); "
                   "options on the command line override it")  # fmt: skip
    for flag, text in OPTIONS:
        p.add_argument(flag, help=text)
    p.add_argument("--scenario", dest="scenarios", help=argparse.SUPPRESS)
    p.add_argument(
        "--plots", action=argparse.BooleanOptionalAction, default=None, help="write PNG plots"
    )
    p.add_argument(
        "--progress", action=argparse.BooleanOptionalAction, default=None, help="progress bar"
    )
    p.set_defaults(func=run)


def _cli_values(args: argparse.Namespace) -> dict:
    keys = [f.lstrip("-").replace("-", "_") for f, _ in OPTIONS] + ["plots", "progress"]
    return {k: getattr(args, k) for k in keys}


def run(args: argparse.Namespace) -> int:
    from pathlib import Path

    from vfgym import tuning
    from vfgym.commands._common import Interrupted
    from vfgym.io.runs import read_yaml

    file_data = read_yaml(args.config) if args.config else None
    cfg = tuning.SweepConfig.resolve(file_data, _cli_values(args), source=str(args.config))
    bar = _Bar(cfg)
    try:
        result = tuning.sweep(
            cfg,
            stem=Path(args.config).stem if args.config else "sweep",
            argv=_argv(args),
            on_start=bar.start,
            on_progress=bar.update if cfg.progress else None,
        )
    finally:
        bar.close()
    print(result.text(), flush=True)
    if result.interrupted:
        raise Interrupted(
            f"completed trials are kept in {result.storage.display}; continue with the same "
            f"command and --study {result.study.study_name}"
        )
    return 1 if result.unfinished else 0


def _argv(args: argparse.Namespace) -> list[str]:
    """The command line to record: as given to ``vfgym``, else the options it resolved
    to (``run`` called as a function)."""
    import sys

    from vfgym.io.runs import command_args

    if command_args() is not None:  # run by vfgym.cli.main
        return command_args() or []
    if len(sys.argv) > 1 and "sweep" in sys.argv[1:]:
        return sys.argv[sys.argv.index("sweep") :]
    argv = ["sweep"] + [f"--{k.replace('_', '-')}={v}" for k, v in _cli_values(args).items()
                        if v is not None]  # fmt: skip
    return argv + ([f"--config={args.config}"] if args.config else [])


def _done(complete: int, budget: int) -> str:
    """How far the study is: ``3/10 trials done``, or that it already has its trials."""
    if complete < budget:
        return f"{complete}/{budget} trials done"
    return (
        f"{complete} trials done, --trials {budget} asked: nothing to run; give --trials "
        f"above {complete} to continue it"
    )


class _Bar:
    """The header once the study is open, then tqdm over completed trials with the best
    cost so far."""

    def __init__(self, cfg: SweepConfig) -> None:
        self.cfg = cfg
        self._bar: Any = None
        self._n = 0

    def start(self, s: SweepStart) -> None:
        from tqdm import tqdm

        cfg = self.cfg
        print(
            f"vfgym sweep: study {s.study} ({'new' if s.created else 'continued'}: "
            f"{_done(s.complete, s.budget)}) on {s.storage}\n"
            f"  {cfg.sampler} sampler, {cfg.objective} objective, {cfg.workers} worker(s), "
            f"laws {','.join(cfg.laws)}, scenarios {', '.join(s.scenarios)}\n"
            f"  run folder {s.run_dir}",
            flush=True,
        )
        initial = min(s.complete, s.budget)
        self._bar = tqdm(total=s.budget, initial=initial, desc=s.study, unit="trial",
                         disable=not cfg.progress, dynamic_ncols=True)  # fmt: skip
        self._n = initial

    def update(self, p: SweepProgress) -> None:
        if self._bar is None:
            return
        if p.best_cost is not None:
            feas = "" if p.best_feasible else " (infeasible)"
            self._bar.set_postfix_str(f"best {p.best_cost:.4f}{feas}", refresh=False)
        n = min(p.complete, self._bar.total)
        self._bar.update(n - self._n)
        self._n = n
        if p.final:
            self.close()

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()
            self._bar = None
