"""``vfgym grid``: the exhaustive reference — a dense grid over the settings on a scenario
set, through the batched kernel, refined around its best points.

The run folder (``RUNS/grid/NAME/``) holds every evaluated setting (``grid.csv``) and the
best as ``reference.yaml`` (Settings-YAML), which ``vfgym sweep`` on the same scenarios
reports its best against.
"""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from vfgym.tuning import GridStart

OPTIONS = (
    ("--scenarios", "scenario set (default paper-step; with --axis, its train moves): a "
     "name, 'named', 'train', 'test' or a comma-separated list"),
    ("--scenario-count", "number of scenarios in a 'train'/'test' set (default 16; not with "
     "--axis)"),
    ("--first-seed", "first seed of a 'train'/'test' set (default 0; not with --axis)"),
    ("--axis", "an axis file (e.g. experiments/axes/belt.yaml): its plant, measures and "
     "train/test moves"),
    ("--laws", "acceleration laws: rise, slew or rise,slew (default rise)"),
    ("--points", "values per dimension, over the whole space and in each refinement "
     "(default 12)"),
    ("--refine", "refinement rounds around the best points (default 2)"),
    ("--keep", "best distinct points refined in each round (default 4)"),
    ("--batch", "settings per compiled call (default 4096)"),
    ("--name", "run folder name (default: scenarios, points and rounds)"),
    ("--runs-dir", "root of the run folders (default runs)"),
)  # fmt: skip


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "grid",
        help="exhaustive grid over the settings: the reference optimum for sweeps",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("--config", help="YAML file of these options; the command line overrides it")
    for flag, text in OPTIONS:
        p.add_argument(flag, help=text)
    p.add_argument("--scenario", dest="scenarios", help=argparse.SUPPRESS)
    p.add_argument(
        "--progress", action=argparse.BooleanOptionalAction, default=None, help="progress bar"
    )
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from tqdm import tqdm

    from vfgym import tuning
    from vfgym.io.runs import command_args, read_yaml

    keys = [f.lstrip("-").replace("-", "_") for f, _ in OPTIONS] + ["progress"]
    file_data = read_yaml(args.config) if args.config else None
    cfg = tuning.GridConfig.resolve(
        file_data, {k: getattr(args, k) for k in keys}, source=str(args.config)
    )
    bars = []

    def start(s: GridStart) -> None:
        print(
            f"vfgym grid: {s.settings} settings ({cfg.points}/dimension, laws "
            f"{','.join(cfg.laws)}) + {cfg.refine} refinement round(s) around {cfg.keep} "
            f"point(s), on {', '.join(s.scenarios)}\n  run folder {s.run_dir}",
            flush=True,
        )
        bars.append(tqdm(total=s.settings, unit="setting", desc=s.name,
                         disable=not cfg.progress, dynamic_ncols=True))  # fmt: skip

    def progress(done: int, total: int, best: float) -> None:
        (bar,) = bars
        bar.total = total
        bar.set_postfix_str(f"best {best:.4f}", refresh=False)
        bar.update(done - bar.n)

    try:
        done = tuning.grid(cfg, argv=command_args(), on_start=start, on_progress=progress)
        for bar in bars:  # the estimate counted refinement points already on the grid
            bar.total = bar.n
            bar.refresh()
    finally:
        for bar in bars:
            bar.close()
    print(done.text(), flush=True)
    return 0
