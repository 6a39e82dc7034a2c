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
    ("--sampler", "tpe (default), cmaes, gp, nsga2, grid or random"),
    ("--objective", "cost (default) or pareto (overshoot, move time, accel violation)"),
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
    ("--heartbeat", "seconds between a running trial's heartbeats (RDB storages; default 10)"),
    ("--grace", "seconds without a heartbeat before a trial is taken as dead "
     "(default 2 x heartbeat)"),
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
    import signal
    import sys
    import time
    from pathlib import Path

    from vfgym import tuning
    from vfgym.io.runs import read_yaml
    from vfgym.moves.axis import axis_digest

    file_data = read_yaml(args.config) if args.config else None
    cfg = tuning.SweepConfig.resolve(file_data, _cli_values(args), source=str(args.config))
    scenarios = cfg.scenario_list()
    tuning.check_sampler(cfg)
    name = cfg.study or _default_name(args.config, cfg.runs_dir)
    run_dir = Path(cfg.runs_dir) / "sweep" / name
    spec = tuning.resolve_storage(cfg.storage, run_dir)
    axis = cfg.load_axis()
    reference = tuning.find_reference(
        cfg.reference, cfg.runs_dir, scenarios, cfg.laws, axis_digest(axis)
    )
    storage = None
    if spec.kind == "postgresql":  # reach the server before making a run folder
        storage = tuning.open_storage(spec, cfg.heartbeat, cfg.grace)
    run_dir.mkdir(parents=True, exist_ok=True)
    _record(run_dir, args, cfg, name, spec)
    if storage is None:
        storage = tuning.open_storage(spec, cfg.heartbeat, cfg.grace)
    study, created = tuning.create_or_load(storage, name, cfg, scenarios)
    budget = tuning.trial_budget(cfg)
    n0 = tuning.counts(study)
    print(
        f"vfgym sweep: study {name} ({'new' if created else 'continued'}: "
        f"{n0['complete']}/{budget} trials done) on {spec.display}\n"
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
            reports.append(
                {
                    "stopped": rep.stopped,
                    "trials": rep.trials,
                    "simulated": rep.simulated,
                    "recovered": rep.recovered,
                    "exit": 0,
                }
            )
        else:
            reports = _run_workers(cfg, spec, name, study, bar)
    except KeyboardInterrupt:
        interrupted = True
        signal.signal(signal.SIGINT, signal.SIG_IGN)
    finally:
        bar.update(study)
        bar.close()
    elapsed = time.monotonic() - t0
    code = _finish(study, cfg, spec, scenarios, run_dir, reference, interrupted, elapsed, reports)
    if interrupted:
        print(
            f"interrupted: completed trials are kept in {spec.display}; continue with the "
            f"same command and --study {name}",
            file=sys.stderr,
        )
        signal.signal(signal.SIGINT, signal.default_int_handler)
        raise KeyboardInterrupt
    return code


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
    """config.yaml (resolved, password masked) and command.txt (every invocation)."""
    import shlex
    import sys

    from vfgym.io.runs import write_text, write_yaml
    from vfgym.tuning import mask_url

    conf = cfg.to_dict() | {"study": name, "storage": spec.display}
    write_yaml(run_dir / "config.yaml", {"command": "sweep", **conf})
    axis = cfg.load_axis()
    if axis is not None:  # the axis as tuned on, beside the config that names its file
        from vfgym.moves.axis import AXIS_FILE, write_axis

        write_axis(axis, run_dir / AXIS_FILE)
    if len(sys.argv) > 1 and "sweep" in sys.argv[1:]:
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
    """tqdm over completed trials, with the best cost so far."""

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

    def update(self, study) -> None:
        from vfgym.tuning import best_trial, counts

        n = min(counts(study)["complete"], self._bar.total)
        best = best_trial(study)
        if best is not None:
            feas = "" if best.user_attrs.get("feasible") else " (infeasible)"
            self._bar.set_postfix_str(f"best {best.user_attrs['cost']:.4f}{feas}", refresh=False)
        self._bar.update(n - self._n)
        self._n = n

    def close(self) -> None:
        self._bar.close()


def _run_workers(cfg, spec, name, study, bar) -> list[dict]:
    """Start the worker processes and follow the study until they end. On Ctrl-C they
    finish or give back their trial; the interrupt is raised again afterwards."""
    import json
    import signal
    import time

    from vfgym.tuning import spawn_workers

    procs = spawn_workers(cfg, spec, name, cfg.workers)
    interrupted = False
    try:
        while any(p.poll() is None for p in procs):
            bar.update(study)
            time.sleep(0.5)
    except KeyboardInterrupt:
        interrupted = True
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        deadline = time.monotonic() + 2.0
        while time.monotonic() < deadline and any(p.poll() is None for p in procs):
            time.sleep(0.05)
        for p in procs:
            if p.poll() is None:
                p.send_signal(signal.SIGINT)
        for p in procs:
            try:
                p.wait(timeout=60)
            except Exception:
                p.kill()
                p.wait()
    reports = []
    for p in procs:
        out = ""
        if p.stdout is not None:
            out = p.stdout.read()
            p.stdout.close()
        try:
            rep = json.loads(out.strip().splitlines()[-1])
        except (ValueError, IndexError):
            rep = {"stopped": "interrupted" if p.returncode == 130 else "died", "trials": []}
        rep["exit"] = p.returncode
        reports.append(rep)
    if interrupted:
        raise KeyboardInterrupt
    return reports


def _finish(study, cfg, spec, scenarios, run_dir, reference, interrupted, elapsed, reports) -> int:
    """Trials CSV, best.yaml, plots, the tuned-vs-paper table (printed and in report.txt)
    and summary.yaml. Returns the exit status."""
    from vfgym import tuning
    from vfgym.io.runs import write_text, write_yaml
    from vfgym.moves.axis import axis_kwargs

    tuning.write_trials_csv(study, run_dir / "trials.csv")
    n = tuning.counts(study)
    budget = tuning.trial_budget(cfg)
    stops = sorted({r.get("stopped", "") for r in reports})
    lines = [
        f"study {study.study_name}: {n['complete']}/{budget} completed trials "
        f"({n['fail']} failed, {n['running']} running, {n['waiting']} waiting) "
        f"in {elapsed:.1f} s"
    ]
    if reports:
        sims = sum(int(r.get("simulated", 0)) for r in reports)
        ran = sum(len(r.get("trials", [])) for r in reports)
        rec = sorted({x for r in reports for x in r.get("recovered", [])})
        lines.append(
            f"this run: {ran} trials by {len(reports)} worker(s), {sims} simulated "
            f"({ran - sims} repeated settings copied)"
            + (f", dead workers' trials retried: {rec}" if rec else "")
            + (f"; worker exits {[r['exit'] for r in reports]}" if len(reports) > 1 else "")
        )
    summary: dict = {
        "study": study.study_name,
        "storage": spec.display,
        "trials": n,
        "budget": budget,
        "elapsed_s": round(elapsed, 3),
        "workers": reports,
    }
    best = tuning.best_trial(study)
    code = 0
    if best is None:
        lines.append("no completed trial yet")
    else:
        settings = tuning.trial_settings(best)
        rec = tuning.best_record(study, best, cfg, spec, scenarios)
        cmp = tuning.compare(settings, scenarios, **axis_kwargs(cfg.load_axis()))
        paper_cost = cmp["set"][0]["cost"]
        rec["paper_cost"] = paper_cost
        lines.append(
            f"best: trial {best.number}, cost {rec['cost']:.4f} "
            f"({'feasible' if rec['feasible'] else 'INFEASIBLE'}) against the paper's "
            f"{paper_cost:.4f} ({tuning.gap_pct(rec['cost'], paper_cost):+.1f} %)"
        )
        if reference is not None:
            ref, ref_path = reference
            gap = tuning.gap_pct(rec["cost"], float(ref["cost"]))
            rec["reference"] = {"path": str(ref_path), "cost": ref["cost"], "gap_pct": gap}
            lines.append(
                f"gap to the grid reference {ref_path} (cost {float(ref['cost']):.4f}): "
                f"{gap:+.2f} %"
            )
        s = rec["settings"]
        lines.append(
            f"settings: value {s['value_rad']:.6g} rad, error limit {s['error_limit_rad']:.6g} "
            f"rad, k {s['k']:.6g}, Ts/Tf {s['ts_over_tf']:.4g}, law {s['accel_law']}"
        )
        write_yaml(run_dir / "best.yaml", rec)
        summary["best"] = rec
        summary["comparison"] = cmp
        lines += ["", tuning.format_comparison(cmp)]
    if cfg.plots and not interrupted and best is not None:
        plots = tuning.write_plots(study, run_dir, cfg.objective)
        summary["plots"] = plots
        lines.append("plots: " + ", ".join(f"{k} {v}" for k, v in plots.items()))
    if not interrupted and n["complete"] < budget and "timeout" not in stops:
        lines.append(
            f"the study is not finished ({n['complete']}/{budget}): the workers ended "
            f"({', '.join(stops) or 'no report'}); run the same command again to continue"
        )
        code = 1
    text = "\n".join(lines)
    write_text(run_dir / "report.txt", text + "\n")
    write_yaml(run_dir / "summary.yaml", summary)
    print(text, flush=True)
    return code
