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


def _check_ignored(file_data: object, cli: dict) -> None:
    """A command-line option the axis overrides is refused rather than ignored without a
    word (a config file's move-set keys stay its default for runs without an axis)."""
    axis = cli.get("axis") or (file_data.get("axis") if isinstance(file_data, dict) else None)
    if axis is None:
        return
    for key in ("scenario_count", "first_seed"):
        if cli.get(key) is not None:
            flag = "--" + key.replace("_", "-")
            raise ValueError(
                f"{flag}={cli[key]!r} is ignored with --axis {axis}: the axis file sets its "
                "move sets (moves.train, moves.test); leave it out"
            )


def run(args: argparse.Namespace) -> int:
    import dataclasses
    import signal
    import time
    from pathlib import Path

    from vfgym import tuning
    from vfgym._validate import check_output_path
    from vfgym.axis import axis_digest
    from vfgym.commands._common import Interrupted
    from vfgym.io.runs import read_yaml
    from vfgym.tuning._results import find_reference
    from vfgym.tuning._study import check_sampler, trial_budget

    file_data = read_yaml(args.config) if args.config else None
    _check_ignored(file_data, _cli_values(args))
    cfg = tuning.SweepConfig.resolve(file_data, _cli_values(args), source=str(args.config))
    scenarios = cfg.scenario_list()
    check_sampler(cfg)
    name = cfg.study or _default_name(args.config, cfg.runs_dir)
    run_dir = Path(cfg.runs_dir) / "sweep" / name
    check_output_path("runs_dir", run_dir, folder=True, shown=cfg.runs_dir, root=cfg.runs_dir)
    spec = tuning.resolve_storage(cfg.storage, run_dir)
    _check_storage_file(cfg.storage, spec)
    _check_same_storage(run_dir, spec.display)
    axis = cfg.load_axis()
    reference = (
        find_reference(cfg.reference, cfg.runs_dir, scenarios, cfg.laws, axis_digest(axis))
        if cfg.aggregate == "mean"
        else None
    )  # a grid's reference is a mean cost
    study, created = _open_study(cfg, spec, name, run_dir, scenarios)
    _record(run_dir, args, cfg, name, spec)
    budget = trial_budget(cfg)
    n0 = _counts(study)
    print(
        f"vfgym sweep: study {name} ({'new' if created else 'continued'}: "
        f"{_done(n0['complete'], budget)}) on {spec.display}\n"
        f"  {cfg.sampler} sampler, {cfg.objective} objective, {cfg.workers} worker(s), "
        f"laws {','.join(cfg.laws)}, scenarios {', '.join(s.name for s in scenarios)}\n"
        f"  run folder {run_dir}",
        flush=True,
    )
    bar = _Bar(cfg, budget, n0["complete"], name)
    t0 = time.monotonic()
    interrupted = False
    reports: list[dict] = []
    try:
        if cfg.workers == 1:
            rep = tuning.run_worker(cfg, spec, name, 0, on_trial=bar.update)
            reports.append(dataclasses.asdict(rep) | {"exit": 0})
        else:
            reports = _run_workers(cfg, spec, name, study, bar)
    except KeyboardInterrupt:
        interrupted = True
        signal.signal(signal.SIGINT, signal.SIG_IGN)
    finally:
        bar.update(study, force=True)
        bar.close()
    elapsed = time.monotonic() - t0
    made = sum(n0.values())  # the trials before this run's
    code = _finish(study, cfg, spec, scenarios, run_dir, reference, interrupted, elapsed, reports,
                   made)  # fmt: skip
    if interrupted:
        signal.signal(signal.SIGINT, signal.default_int_handler)
        raise Interrupted(
            f"completed trials are kept in {spec.display}; continue with the same command "
            f"and --study {name}"
        )
    return code


def _counts(study) -> dict[str, int]:
    """Trials of the study by state: ``complete``, ``running``, ``waiting``, ``fail``,
    ``pruned``."""
    out = {"complete": 0, "running": 0, "waiting": 0, "fail": 0, "pruned": 0}
    for t in study.get_trials(deepcopy=False):
        out[t.state.name.lower()] += 1
    return out


def _done(complete: int, budget: int) -> str:
    """How far the study is: ``3/10 trials done``, or that it already has its trials."""
    if complete < budget:
        return f"{complete}/{budget} trials done"
    return (
        f"{complete} trials done, --trials {budget} asked: nothing to run; give --trials "
        f"above {complete} to continue it"
    )


def _check_same_storage(run_dir, display: str) -> None:
    """A run folder's study continues only in the storage it lives in: another storage
    would start a second study beside it without a word."""
    from vfgym.io.runs import read_yaml

    conf = run_dir / "config.yaml"
    if not conf.is_file():
        return
    old = read_yaml(conf)
    old = old.get("storage") if isinstance(old, dict) else None
    if not isinstance(old, str):
        return

    def kind(s: str) -> str | None:  # a file may have moved with its folder: same kind
        if s.startswith("sqlite:"):
            return "sqlite"
        if s.endswith(".log"):
            return "journal"
        return s if s.startswith("postgresql") else None

    if kind(old) is not None and kind(old) != kind(display):
        raise ValueError(
            f"--storage={display!r} is not allowed for run folder {run_dir}: its study "
            f"lives in {old}; continue it there (leave --storage out, or give the same), "
            "or give another --study"
        )


def _check_storage_file(text: str, spec) -> None:
    """A storage file named by the user (sqlite:///FILE, journal:FILE) must go in an
    existing folder: a typo must not make folders silently. The defaults ``sqlite`` and
    ``journal`` live in the run folder, which the sweep makes."""
    from vfgym._validate import check_output_path

    if spec.path is None or str(text).strip() in ("sqlite", "journal"):
        return
    check_output_path("storage", spec.path, shown=text)  # a missing folder, a file in the way


def _open_study(cfg, spec, name, run_dir, scenarios):
    """Open the storage and create or load the study; a run folder made here is removed
    again if that fails (a refused sweep leaves nothing behind)."""
    import json
    import shutil

    from vfgym import tuning

    storage = None
    if spec.kind == "postgresql":  # reach the server before making a run folder
        storage = tuning.open_storage(spec, cfg.heartbeat, cfg.grace)
    made = not run_dir.exists()
    run_dir.mkdir(parents=True, exist_ok=True)
    try:
        if storage is None:
            storage = tuning.open_storage(spec, cfg.heartbeat, cfg.grace)
        try:
            return tuning.create_or_load(storage, name, cfg, scenarios)
        except (UnicodeDecodeError, json.JSONDecodeError) as exc:  # a file, not a journal
            raise ValueError(f"storage={spec.display!r} cannot be opened: {exc}") from None
    except BaseException:
        if made:
            shutil.rmtree(run_dir, ignore_errors=True)
        raise


def _default_name(config: str | None, runs_dir: str) -> str:
    import time
    from pathlib import Path

    stem = Path(config).stem if config else "sweep"
    stem = "".join(c if c.isalnum() or c in "._-" else "-" for c in stem) or "sweep"
    base = f"{stem}-{time.strftime('%Y%m%d-%H%M%S')}"
    name, i = base, 1
    while (Path(runs_dir) / "sweep" / name).exists():
        name, i = f"{base}-{i}", i + 1
    return name


def _record(run_dir, args, cfg, name, spec) -> None:
    """config.yaml (resolved, password masked) and command.txt (every invocation that
    opened the study: a refused one is not recorded)."""
    import shlex
    import sys

    from vfgym.io.runs import command_args, write_text, write_yaml
    from vfgym.tuning._storage import mask_url

    conf = cfg.to_dict() | {"study": name, "storage": spec.display}
    write_yaml(run_dir / "config.yaml", {"command": "sweep", **conf})
    axis = cfg.load_axis()
    if axis is not None:  # the axis as tuned on, beside the config that names its file
        from vfgym.axis import AXIS_FILE, write_axis

        write_axis(axis, run_dir / AXIS_FILE)
    if command_args() is not None:  # run by vfgym.cli.main
        argv = command_args() or []
    elif len(sys.argv) > 1 and "sweep" in sys.argv[1:]:
        argv = sys.argv[sys.argv.index("sweep") :]
    else:  # called as a function: the options it resolved to
        argv = ["sweep"] + [f"--{k.replace('_', '-')}={v}" for k, v in _cli_values(args).items()
                            if v is not None]  # fmt: skip
        argv += [f"--config={args.config}"] if args.config else []
    line = "vfgym " + " ".join(shlex.quote(mask_url(a)) for a in argv)
    path = run_dir / "command.txt"
    old = path.read_text(encoding="utf-8") if path.exists() else ""
    write_text(path, old + line + "\n")


class _Bar:
    """tqdm over completed trials, with the best cost so far (read at most twice a second:
    each read is the study's, a storage query a trial would otherwise add)."""

    def __init__(self, cfg, total: int, initial: int, name: str) -> None:
        from tqdm import tqdm

        self._bar = tqdm(
            total=total,
            initial=min(initial, total),
            desc=name,
            unit="trial",
            disable=not cfg.progress,
            dynamic_ncols=True,
        )
        self._n = min(initial, total)
        self._at = 0.0

    def update(self, study, force: bool = False) -> None:
        import time

        from vfgym.tuning import best_trial, stored_result

        if not force and time.monotonic() - self._at < 0.5:
            return
        self._at = time.monotonic()
        n = min(_counts(study)["complete"], self._bar.total)
        best = best_trial(study)
        res = None if best is None else stored_result(best)
        if res is not None:
            feas = "" if res.feasible else " (infeasible)"
            self._bar.set_postfix_str(f"best {res.cost:.4f}{feas}", refresh=False)
        self._bar.update(n - self._n)
        self._n = n

    def close(self) -> None:
        self._bar.close()


def _run_workers(cfg, spec, name, study, bar) -> list[dict]:
    """Start the worker processes and follow the study until they end. On Ctrl-C they
    finish or give back their trial; the interrupt is raised again afterwards."""
    import os
    import signal
    import time
    from dataclasses import asdict

    from vfgym.tuning._workers import spawn_workers

    workers = spawn_workers(cfg, spec, name, cfg.workers)
    reports: list[dict | None] = [None] * len(workers)

    def collect() -> None:  # (read as they come: a report may exceed a pipe's buffer)
        for i, w in enumerate(workers):
            if reports[i] is None and w.report.poll():
                try:
                    reports[i] = asdict(w.report.recv())
                except (EOFError, OSError):  # died before sending it
                    reports[i] = {}

    interrupted = False
    try:
        while any(w.process.is_alive() for w in workers):
            bar.update(study)
            collect()
            time.sleep(0.5)
    except KeyboardInterrupt:
        interrupted = True
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        deadline = time.monotonic() + 2.0
        while time.monotonic() < deadline and any(w.process.is_alive() for w in workers):
            time.sleep(0.05)
        for w in workers:
            if w.process.is_alive() and w.process.pid is not None:
                os.kill(w.process.pid, signal.SIGINT)
        for w in workers:
            w.process.join(timeout=60)
            if w.process.is_alive():
                w.process.kill()
                w.process.join()
    collect()
    out = []
    for w, rep in zip(workers, reports, strict=True):
        code = w.process.exitcode
        rep = rep or {"stopped": "interrupted" if code == 130 else "died", "trials": []}
        out.append(rep | {"exit": code})
    if interrupted:
        raise KeyboardInterrupt
    return out


def _finish(study, cfg, spec, scenarios, run_dir, reference, interrupted, elapsed, reports,
            made) -> int:  # fmt: skip
    """Trials CSV, best.yaml, plots, the tuned-vs-paper table (printed and in report.txt)
    and summary.yaml; ``made``: the study's trials before this run. Returns the exit
    status."""
    from vfgym import tuning
    from vfgym.axis import PAPER_AXIS
    from vfgym.io.runs import write_text, write_yaml
    from vfgym.params import PAPER_SETTINGS
    from vfgym.report import axis_verdict, compact_rows, format_compact, format_verdict
    from vfgym.tuning._aggregate import describe, set_cost
    from vfgym.tuning._results import (
        against_paper,
        best_record,
        gap_pct,
        write_plots,
        write_trials_csv,
    )
    from vfgym.tuning._study import trial_budget
    from vfgym.tuning._workers import RETRY

    write_trials_csv(study, run_dir / "trials.csv")
    n = _counts(study)
    budget = trial_budget(cfg)
    stops = sorted({r.get("stopped", "") for r in reports})
    done = (
        f"{n['complete']}/{budget} completed trials"
        if n["complete"] <= budget
        else f"{n['complete']} completed trials (--trials {budget} asked)"
    )
    lines = [
        f"study {study.study_name}: {done} "
        f"({n['fail']} failed, {n['running']} running, {n['waiting']} waiting"
        + (f", {n['pruned']} pruned: over the budget" if n["pruned"] else "")
        + f") in {elapsed:.1f} s"
    ]
    # A dead worker's trial, or one interrupted, is failed and enqueued again (Optuna's
    # retry names the trial it repeats): the study says which, whichever worker did it.
    retried = sorted(t.system_attrs[RETRY] for t in study.get_trials(deepcopy=False)[made:]
                     if RETRY in t.system_attrs)  # fmt: skip
    if reports:
        sims = sum(int(r.get("simulated", 0)) for r in reports)
        ran = sum(len(r.get("trials", [])) for r in reports)
        lines.append(
            f"this run: {ran} trials by {len(reports)} worker(s), {sims} simulated "
            f"({ran - sims} repeated settings copied)"
            + (f", failed trials retried: {retried}" if retried else "")
            + (f"; worker exits {[r['exit'] for r in reports]}" if len(reports) > 1 else "")
        )
    summary: dict = {
        "study": study.study_name,
        "storage": spec.display,
        "trials": n,
        "budget": budget,
        "elapsed_s": round(elapsed, 3),
        "workers": reports,
        "retried": retried,
    }
    best = tuning.best_trial(study)
    code = 0
    if best is None:
        lines.append("no completed trial yet")
    else:
        settings = tuning.trial_settings(best)
        cmp = against_paper(settings, scenarios, "tuned", cfg.axis_or_paper())
        paper_cost = set_cost(PAPER_SETTINGS, scenarios, cfg)  # as the sweep scores
        record = best_record(study, best, cfg, spec, scenarios, paper_cost, reference)
        lines.append(
            f"best: trial {best.number}, {describe(cfg)} cost {record.cost:.4f} "
            f"({'feasible' if record.feasible else 'INFEASIBLE'}) against the paper's "
            f"{paper_cost:.4f} ({gap_pct(record.cost, paper_cost):+.1f} %)"
        )
        if record.reference is not None:
            lines.append(
                f"gap to the grid reference {record.reference.path} (cost "
                f"{record.reference.cost:.4f}): {record.reference.gap_pct:+.2f} %"
            )
        s = record.settings
        lines.append(
            f"settings: value {s['value_rad']:.6g} rad, error limit {s['error_limit_rad']:.6g} "
            f"rad, k {s['k']:.6g}, Ts/Tf {s['ts_over_tf']:.4g}, law {s['accel_law']}"
        )
        write_yaml(run_dir / "best.yaml", record.as_dict())
        summary["best"] = record.as_dict()
        summary["comparison"] = compact_rows(cmp).as_dict()
        lines += ["", format_compact(cmp)]
    if cfg.plots and not interrupted and best is not None:
        plots = write_plots(study, run_dir, cfg.objective)
        summary["plots"] = plots
        lines.append("plots: " + ", ".join(f"{k} {v}" for k, v in plots.items()))
    if not interrupted and n["complete"] < budget and "timeout" not in stops:
        lines.append(
            f"the study is not finished ({n['complete']}/{budget}): the workers ended "
            f"({', '.join(stops) or 'no report'}); run the same command again to continue"
        )
        code = 1
    if best is not None and not interrupted:  # the report ends with the held-out verdict
        v = axis_verdict(
            tuning.trial_settings(best), cfg.load_axis() or PAPER_AXIS, tuned_on=scenarios
        )
        summary["verdict"] = v.to_dict()
        lines += ["", format_verdict(v, axis_file=cfg.axis)]
    text = "\n".join(lines)
    write_text(run_dir / "report.txt", text + "\n")
    write_yaml(run_dir / "summary.yaml", summary)
    print(text, flush=True)
    return code
