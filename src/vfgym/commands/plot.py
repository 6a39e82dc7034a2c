"""``vfgym plot KIND``: draw one figure as a PNG (matplotlib, headless).

Kinds:
  response   command, pulse train and motor on one scenario: position, error, speed,
             acceleration with the motor's limit (paper Fig. 4: --scenario paper-step,
             Fig. 5: --scenario paper-sine)
  scurve     S-curve speed profile of a short move with and without triangle form
             prevention, and of a long move reaching the drive speed (MCX514 Fig. 2.2-9)
  frequency  pulse frequency against time: the V-F controller against --against
             (default: fixed-frequency; paper when the controller is fixed-frequency)
  compare    the controller against --against on the same move, overlaid (default: paper;
             rule-of-thumb when the controller is the paper's)
  history    optimisation history of a sweep (--sweep RUN_DIR)
  pareto     Pareto front of a sweep (--sweep RUN_DIR)

The controller is --settings FILE.yaml or --baseline NAME (default: paper). Traces come
from vfgym.evaluate(..., keep_traces=True); the numbers in titles are its measures.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from optuna import Study

KINDS = ("response", "scurve", "frequency", "compare", "history", "pareto")


DEFAULT_AGAINST = {
    "compare": ("paper", "rule-of-thumb"),
    "frequency": ("fixed-frequency", "paper"),
}
"""Baselines compared with by default: the first that is not the controller itself."""


def add_parser(sub: argparse._SubParsersAction) -> None:
    from vfgym.commands._common import add_axis_option, real, whole

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
        help="baselines to compare with (default: compare: paper, frequency: fixed-frequency; "
        "the next one when that is the controller itself)",
    )
    p.add_argument("--sweep", metavar="RUN_DIR", help="sweep run folder (history, pareto)")
    p.add_argument(
        "--storage",
        help="history, pareto: the study's storage (sqlite:///FILE, journal:FILE, a database "
        "URL), if not the one in the folder's config.yaml",
    )
    p.add_argument("--x", help="pareto: objective on the x axis (default: the first)")
    p.add_argument("--y", help="pareto: objective on the y axis (default: the second)")
    p.add_argument(
        "--short-rad",
        type=real(0.0, lo_open=True),
        default=1.0,
        help="scurve: the short move, > 0 (default 1 rad)",
    )
    p.add_argument(
        "--long-rad",
        type=real(0.0, lo_open=True),
        default=10.0,
        help="scurve: the long move, > 0 (default 10 rad)",
    )
    p.add_argument("--out", metavar="PNG", help="output file (default: <kind>-<scenario>.png)")
    p.add_argument(
        "--dpi", type=whole(10, 1200), default=120, help="resolution, 10..1200 (default: 120)"
    )
    add_axis_option(p)
    p.set_defaults(func=run)


def load_study(run_dir: str, storage: str | None = None) -> Study:
    """The Optuna study of a sweep run folder. ``config.yaml`` names the study
    (``study_name`` or ``study``) and its ``storage``, found by
    :func:`vfgym.tuning.find_storage` (a file moved with the folder is found in
    it); a URL whose password was masked in the file needs ``storage`` given again. A
    ``storage`` given is used as it is: a file it names must exist (no fallback to the
    folder's own)."""
    import optuna

    from vfgym.io.runs import read_yaml
    from vfgym.tuning import find_storage, open_storage

    d = Path(run_dir)
    if not d.is_dir():
        raise ValueError(f"--sweep {run_dir}: no such folder")
    cfg = read_yaml(d / "config.yaml")
    name = cfg.get("study_name") or cfg.get("study") if isinstance(cfg, dict) else None
    if not name:
        raise ValueError(f"{d / 'config.yaml'}: no study name (is this a sweep folder?)")
    if storage is not None:
        return _load_given(str(name), storage, d)
    spec = find_storage(cfg.get("storage") or "sqlite", d)
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    try:
        return optuna.load_study(study_name=str(name), storage=open_storage(spec))
    except KeyError:
        raise ValueError(f"--sweep {run_dir}: no study named {name!r} in its storage") from None


def _load_given(name: str, storage: str, run_dir: Path) -> Any:
    """The study ``name`` in the storage given with --storage (a plain path: a journal)."""
    import optuna

    from vfgym.tuning import open_storage, resolve_storage

    text = storage.strip()
    plain = "://" not in text and not text.startswith("journal:")
    spec = resolve_storage(
        f"journal:{text}" if plain and text not in ("sqlite", "journal") else text, run_dir
    )
    if spec.path is not None and not Path(spec.path).is_file():
        raise ValueError(f"--storage {storage}: {spec.path}: no such file")
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    try:
        return optuna.load_study(study_name=name, storage=open_storage(spec))
    except KeyError:
        raise ValueError(f"--storage {spec.display}: no study named {name!r} in it") from None


def _controller(args: argparse.Namespace, axis: Any) -> tuple[Any, str]:
    """The controller and its label (a settings file's stem; its path if the stem is a
    baseline's name, so that the two never share a label), used on ``axis``."""
    from vfgym.commands._common import load_settings
    from vfgym.moves.baselines import BASELINE_NAMES, Baseline

    if args.settings:
        stem = Path(args.settings).stem
        label = args.settings if stem in BASELINE_NAMES else stem
        return load_settings(args.settings, axis), label
    name = args.baseline or "paper"
    return Baseline(name), name


def _against(args: argparse.Namespace, own: str) -> list[Any]:
    """The baselines to draw beside the controller: --against without the controller
    itself, or the kind's first default that is not the controller."""
    from vfgym.report import baseline_candidates

    if args.against is None:
        name = next(n for n in DEFAULT_AGAINST[args.kind] if n != own)
        return baseline_candidates(name)
    cands = [c for c in baseline_candidates(args.against) if c.label != own]
    if not cands:
        raise ValueError(
            f"--against={args.against!r} is not allowed: it names only the controller itself "
            f"({own}); give another baseline"
        )
    return cands


def build_figure(args: argparse.Namespace) -> Any:
    """The figure the arguments ask for."""
    from vfgym.commands._common import axis_from_args, scenario_from_args
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
    plant = scenario.plant(axis.plant)
    if args.kind == "scurve":
        return plots.scurve_figure(plant, short_rad=args.short_rad, long_rad=args.long_rad)
    ctrl, label = _controller(args, axis)
    if args.kind == "response":
        ev = evaluate(ctrl, [scenario], keep_traces=True, axis=axis)
        trace = own_trace(ev, scenario)
        title = f"{scenario.name}: {scenario.description}\n{ev.labels()[0]}"
        return plots.response_figure(
            trace, title=title, metrics=ev.metrics[0][0], tracking=scenario.tracking
        )
    others = _against(args, label)
    ev = evaluate([ctrl, *(c.controller for c in others)], [scenario], keep_traces=True, axis=axis)
    own_trace(ev, scenario)
    kept = ev.traces
    assert kept is not None  # keep_traces=True
    names = [label, *(c.label for c in others)]
    traces, skipped = {}, []
    for i, name in enumerate(names):
        tr = kept[i][0]
        if tr is None:  # a pulse source on a moving reference
            skipped.append(name)
            continue
        traces[f"{name} (cost {ev.cost[i, 0]:.3g})"] = tr
    if skipped:
        raise ValueError(
            f"scenario {scenario.name!r} is a moving reference: {', '.join(skipped)} (pulse "
            "sources) do not apply to it; choose a point-to-point scenario or --against "
            "paper,rule-of-thumb"
        )
    title = f"{scenario.name}: {scenario.description}"
    if args.kind == "frequency":
        return plots.frequency_figure(traces, title=title)
    return plots.compare_figure(traces, title=title, tracking=scenario.tracking)


def own_trace(ev: Any, scenario: Any) -> Any:
    """The first controller's trace on the scenario; a pulse source on a moving reference
    (it has none) raises ``ValueError``."""
    trace = ev.traces[0][0]
    if trace is None:
        raise ValueError(
            f"{ev.labels()[0]} does not apply to scenario {scenario.name!r} (a moving "
            "reference): choose a point-to-point scenario or V-F settings"
        )
    return trace


def run(args: argparse.Namespace) -> int:
    from vfgym._validate import check_output_path
    from vfgym.io.runs import write_atomically

    out = args.out
    if out is None:
        tail = "" if args.kind in ("scurve", "history", "pareto") else f"-{args.scenario}"
        out = f"{args.kind}{tail}.png"
    out_path = Path(out)
    if out_path.suffix.lower() != ".png":
        raise ValueError(f"--out={out!r} is not allowed: give a .png file")
    check_output_path("--out", out_path)
    fig = build_figure(args)
    write_atomically(out_path, lambda tmp: fig.savefig(tmp, dpi=args.dpi), suffix=".png")
    print(f"wrote {out_path}")
    return 0
