"""``vfgym fit``: a per-move settings model for one axis, learnt from per-move optima of moves
drawn from the axis's move distribution (its ``random:`` train set, or one spanning the
moves it lists) on its plant and measures. For a new move the model picks, among the
training moves' optimal settings, the one of least cost on the training moves most like it,
of its 64 candidates the best when simulated on the move itself. Writes
``runs/fit/<name>/``: ``settings_model.json`` (for ``vfgym predict --model`` and ``vfgym
evaluate --model``), ``optima.csv`` and ``costs.npz`` (what it learnt from), ``verdict.txt``
and ``summary.yaml`` (the held-out verdict on the axis's test moves against the best fixed
setting of a short sweep, the paper's settings and the S-curve source), ``config.yaml`` and
``command.txt``. The optima are saved as they are found: after an interrupt the same command
continues."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from vfgym.axis import Axis


def add_parser(sub: argparse._SubParsersAction) -> None:
    from vfgym.commands._common import whole
    from vfgym.permove import FitConfig

    d = FitConfig()
    p = sub.add_parser(
        "fit",
        help="learn per-move settings for an axis (a settings model)",
        description=__doc__,
    )
    p.add_argument("--axis", metavar="FILE.yaml", required=True, help="the axis file")
    p.add_argument("--runs-dir", default="runs", help="root of run folders (default: runs)")
    p.add_argument(
        "--name", help="run folder name (default: the axis's name); an existing one is continued"
    )
    p.add_argument(
        "--moves",
        type=whole(8, 5000),
        default=d.moves,
        help=f"training moves, 8 to 5000 (default {d.moves}: about 7 min on 2 cores)",
    )
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from dataclasses import replace

    from vfgym._validate import check_name, check_output_path
    from vfgym.axis import AXIS_FILE, write_axis
    from vfgym.commands._common import Interrupted, axis_from_args
    from vfgym.io.runs import new_run_dir, record_command, write_text, write_yaml
    from vfgym.permove.fit import FitConfig, config_dict, fit_axis
    from vfgym.report import format_verdict
    from vfgym.space import settings_to_dict

    axis = axis_from_args(args)
    name = args.name if args.name is not None else axis.name
    check_name("--name", name)
    check_output_path(
        "--runs-dir", Path(args.runs_dir) / "fit" / name, folder=True, shown=args.runs_dir
    )
    d = FitConfig()
    library = min(d.library, args.moves)
    cfg = replace(d, moves=args.moves, library=library, check=min(d.check, library))
    _check_same_axis(Path(args.runs_dir) / "fit" / name, axis, args.axis)
    run_dir = new_run_dir(args.runs_dir, "fit", name)
    write_yaml(run_dir / "config.yaml", {"kind": "fit", "axis": args.axis} | config_dict(cfg))
    record_command(run_dir)
    write_axis(axis, run_dir / AXIS_FILE)
    print(f"run folder: {run_dir}")
    try:
        res = fit_axis(axis, run_dir, cfg, progress=not args.no_progress)
    except KeyboardInterrupt:
        raise Interrupted(
            f"the optima found so far are saved in {run_dir / 'optima.csv'}; the same "
            "command continues from them"
        ) from None
    text = format_verdict(res.verdict, per_move=True)
    write_text(run_dir / "verdict.txt", text + "\n")
    write_yaml(
        run_dir / "summary.yaml",
        {
            "best_fixed": settings_to_dict(res.fixed),
            "verdict": res.verdict.to_dict(),
            "seconds": {k: round(v, 2) for k, v in res.seconds.items()},
        },
    )
    print(text)
    total = sum(res.seconds.values())
    print(f"\nsettings model: {run_dir / 'settings_model.json'} ({total:.0f} s)")
    return 0


def _check_same_axis(run_dir: Path, axis: Axis, axis_file: str) -> None:
    """A fit continues only on the axis it was started on: an edited axis under the same
    name would silently replace the earlier fit's optima and model."""
    from vfgym.axis import AXIS_FILE, axis_digest, load_axis

    old = run_dir / AXIS_FILE
    if not old.is_file():
        return
    if axis_digest(load_axis(old)) != axis_digest(axis):
        raise ValueError(
            f"--name {run_dir.name}: {run_dir} holds a fit of another axis (its {AXIS_FILE} "
            f"differs from {axis_file}): give another --name, or remove that folder to fit "
            "again"
        )
