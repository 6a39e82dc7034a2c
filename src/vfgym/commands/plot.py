"""``vfgym plot KIND``: draw one figure as a PNG (matplotlib, headless).

Kinds:
  response   command, pulse train and motor on one scenario: position, error, speed,
             acceleration with the motor's limit (paper Fig. 4: --scenario paper-step,
             Fig. 5: --scenario paper-sine)
  scurve     S-curve speed profile of a short move with and without triangle form
             prevention, and of a long move reaching the drive speed (MCX514 Fig. 2.2-9)
  frequency  pulse frequency against time: the V-F controller against --against
             (default: fixed-frequency)
  compare    the settings against --against (default: paper) on the same move, overlaid
  history    optimisation history of a sweep (--sweep RUN_DIR)
  pareto     Pareto front of a sweep (--sweep RUN_DIR)

The controller is --settings FILE.yaml or --baseline NAME (default: paper). Traces come
from vfgym.evaluate(..., keep_traces=True); the numbers in titles are its measures.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

KINDS = ("response", "scurve", "frequency", "compare", "history", "pareto")


def add_parser(sub: argparse._SubParsersAction) -> None:
    from vfgym.commands._common import add_axis_option

    p = sub.add_parser(
        "plot",
        help="draw a figure (response, scurve, frequency, compare, history, pareto) as PNG",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("kind", choices=KINDS, metavar="KIND", help=", ".join(KINDS))
    p.add_argument("--scenario", default="paper-step", help="scenario (default: paper-step)")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--settings", metavar="FILE.yaml", help="settings file of the V-F controller")
    g.add_argument("--baseline", help="a baseline instead: paper (default), rule-of-thumb, ...")
    p.add_argument(
        "--against",
        metavar="NAMES",
        help="baselines to compare with (compare: paper; frequency: fixed-frequency)",
    )
    p.add_argument("--sweep", metavar="RUN_DIR", help="sweep run folder (history, pareto)")
    p.add_argument(
        "--storage",
        help="history, pareto: the study's storage URL, if not the one in the folder's config.yaml",
    )
    p.add_argument("--x", help="pareto: objective on the x axis (default: the first)")
    p.add_argument("--y", help="pareto: objective on the y axis (default: the second)")
    p.add_argument(
        "--short-rad", type=float, default=1.0, help="scurve: the short move (default 1 rad)"
    )
    p.add_argument(
        "--long-rad", type=float, default=10.0, help="scurve: the long move (default 10 rad)"
    )
    p.add_argument("--out", metavar="PNG", help="output file (default: <kind>-<scenario>.png)")
    p.add_argument("--dpi", type=int, default=120, help="resolution (default: 120)")
    add_axis_option(p)
    p.set_defaults(func=run)


def load_study(run_dir: str, storage: str | None = None) -> Any:
    """The Optuna study of a sweep run folder. ``config.yaml`` names the study
    (``study_name`` or ``study``) and its ``storage``: ``sqlite:///FILE`` (if the file has
    moved, the folder's own ``study.db``), a journal file, or a database URL. A URL whose
    password was masked in the file needs ``storage`` given again."""
    import optuna

    from vfgym.io.runs import read_yaml

    d = Path(run_dir)
    if not d.is_dir():
        raise ValueError(f"--sweep {run_dir}: no such folder")
    cfg = read_yaml(d / "config.yaml")
    name = cfg.get("study_name") or cfg.get("study") if isinstance(cfg, dict) else None
    if not name:
        raise ValueError(f"{d / 'config.yaml'}: no study name (is this a sweep folder?)")
    url = str(storage or cfg.get("storage") or f"sqlite:///{d / 'study.db'}")
    if "***" in url:
        raise ValueError(f"--sweep {run_dir}: the storage password is masked; give --storage URL")
    if url.startswith("sqlite:///"):
        path = Path(url.removeprefix("sqlite:///"))
        if not path.is_file() and (d / "study.db").is_file():
            path = d / "study.db"
        if not path.is_file():
            raise ValueError(f"--sweep {run_dir}: study storage {path} not found")
        store: Any = f"sqlite:///{path}"
    elif "://" in url:
        store = url
    else:  # a journal file
        path = Path(url)
        if not path.is_file() and (d / path.name).is_file():
            path = d / path.name
        if not path.is_file():
            raise ValueError(f"--sweep {run_dir}: study journal {path} not found")
        from optuna.storages.journal import JournalFileBackend, JournalStorage

        store = JournalStorage(JournalFileBackend(str(path)))
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    try:
        return optuna.load_study(study_name=str(name), storage=store)
    except KeyError:
        raise ValueError(f"--sweep {run_dir}: no study named {name!r} in its storage") from None


def _controller(args: argparse.Namespace) -> tuple[Any, str]:
    from vfgym.commands.evaluate import load_settings_file
    from vfgym.moves.baselines import Baseline

    if args.settings:
        return load_settings_file(args.settings), Path(args.settings).stem
    name = args.baseline or "paper"
    return Baseline(name), name


def _against(args: argparse.Namespace, default: str, own: str) -> list[Any]:
    from vfgym.report import baseline_candidates

    cands = baseline_candidates(args.against or default)
    return [c for c in cands if c.label != own] or cands


def build_figure(args: argparse.Namespace) -> Any:
    """The figure the arguments ask for."""
    from vfgym.commands._common import axis_from_args, scenario_from_args
    from vfgym.moves.axis import axis_kwargs
    from vfgym.params import PAPER_PLANT
    from vfgym.report import figures as plots
    from vfgym.scoring import evaluate

    if args.kind in ("history", "pareto"):
        if not args.sweep:
            raise ValueError(f"plot {args.kind} needs --sweep RUN_DIR (a sweep run folder)")
        study = load_study(args.sweep, args.storage)
        if args.kind == "history":
            return plots.history_figure(study)
        return plots.pareto_figure(study, x=args.x, y=args.y)
    axis = axis_from_args(args)
    scenario = scenario_from_args(args, axis)
    plant = scenario.plant(PAPER_PLANT if axis is None else axis.plant)
    if args.kind == "scurve":
        return plots.scurve_figure(plant, short_rad=args.short_rad, long_rad=args.long_rad)
    ctrl, label = _controller(args)
    on_axis = axis_kwargs(axis)
    if args.kind == "response":
        ev = evaluate(ctrl, [scenario], keep_traces=True, **on_axis)
        title = f"{scenario.name}: {scenario.description}\n{ev.labels()[0]}"
        return plots.response_figure(
            ev.traces[0][0], title=title, metrics=ev.metrics[0][0], tracking=scenario.tracking
        )
    default = "fixed-frequency" if args.kind == "frequency" else "paper"
    others = _against(args, default, label)
    ev = evaluate([ctrl, *(c.controller for c in others)], [scenario], keep_traces=True, **on_axis)
    names = [label, *(c.label for c in others)]
    traces = {}
    for i, name in enumerate(names):
        tr = ev.traces[i][0]
        if tr is None:  # a pulse source on a moving reference
            continue
        cost = ev.cost[i, 0]
        traces[f"{name} (cost {cost:.3g})"] = tr
    if len(traces) < 2:
        raise ValueError(
            f"scenario {scenario.name!r} is a moving reference: the pulse-source baselines "
            "do not apply; choose a point-to-point scenario or other baselines"
        )
    title = f"{scenario.name}: {scenario.description}"
    if args.kind == "frequency":
        return plots.frequency_figure(traces, title=title)
    return plots.compare_figure(traces, title=title, tracking=scenario.tracking)


def run(args: argparse.Namespace) -> int:
    if args.dpi < 10 or args.dpi > 1200:
        raise ValueError(f"--dpi={args.dpi} is out of range: allowed 10..1200")
    fig = build_figure(args)
    out = args.out
    if not out:
        tail = "" if args.kind in ("scurve", "history", "pareto") else f"-{args.scenario}"
        out = f"{args.kind}{tail}.png"
    out_path = Path(out)
    if out_path.suffix.lower() != ".png":
        raise ValueError(f"--out={out}: give a .png file")
    out_path.parent.mkdir(parents=True, exist_ok=True)
    tmp = out_path.with_name(f".{out_path.name}.tmp.png")
    fig.savefig(tmp, dpi=args.dpi)
    tmp.replace(out_path)
    print(f"wrote {out_path}")
    return 0
