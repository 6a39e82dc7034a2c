"""``vfgym grid``: the exhaustive reference — a dense grid over the settings on a scenario
set, through the batched kernel, refined around its best points.

The run folder (``RUNS/grid/NAME/``) holds every evaluated setting (``grid.csv``) and the
best as ``reference.yaml`` (Settings-YAML), which ``vfgym sweep`` on the same scenarios
reports its best against.
"""

from __future__ import annotations

import argparse

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
    import time
    from pathlib import Path

    from tqdm import tqdm

    from vfgym import tuning
    from vfgym._validate import check_output_path
    from vfgym.axis import AXIS_FILE, write_axis
    from vfgym.io.runs import read_yaml, record_command, write_text, write_yaml
    from vfgym.report import format_compact
    from vfgym.tuning._grid import grid_reference, write_grid_csv
    from vfgym.tuning._results import against_paper

    keys = [f.lstrip("-").replace("-", "_") for f, _ in OPTIONS] + ["progress"]
    file_data = read_yaml(args.config) if args.config else None
    cfg = tuning.GridConfig.resolve(
        file_data, {k: getattr(args, k) for k in keys}, source=str(args.config)
    )
    scenarios = cfg.scenario_list()
    name = cfg.name or _default_name(cfg)
    run_dir = Path(cfg.runs_dir) / "grid" / name
    check_output_path("runs_dir", run_dir, folder=True, shown=cfg.runs_dir, root=cfg.runs_dir)
    run_dir.mkdir(parents=True, exist_ok=True)
    write_yaml(run_dir / "config.yaml", {"command": "grid", **cfg.to_dict(), "name": name})
    axis = cfg.load_axis()
    if axis is not None:
        write_axis(axis, run_dir / AXIS_FILE)
    record_command(run_dir)
    n0 = cfg.points**4 * len(cfg.laws)
    print(
        f"vfgym grid: {n0} settings ({cfg.points}/dimension, laws {','.join(cfg.laws)}) "
        f"+ {cfg.refine} refinement round(s) around {cfg.keep} point(s), on "
        f"{', '.join(s.name for s in scenarios)}\n  run folder {run_dir}",
        flush=True,
    )
    bar = tqdm(total=n0, unit="setting", desc=name, disable=not cfg.progress, dynamic_ncols=True)

    def progress(done: int, total: int, best: float) -> None:
        bar.total = total
        bar.set_postfix_str(f"best {best:.4f}", refresh=False)
        bar.update(done - bar.n)

    t0 = time.monotonic()
    try:
        result = tuning.run_grid(cfg, progress)
        bar.total = bar.n  # the estimate counted refinement points already on the grid
        bar.refresh()
    finally:
        bar.close()
    elapsed = time.monotonic() - t0
    write_grid_csv(result.rows, run_dir / "grid.csv")
    ref = grid_reference(cfg, result)
    ref["elapsed_s"] = round(elapsed, 3)
    write_yaml(run_dir / "reference.yaml", ref)
    cmp = against_paper(result.best.settings, scenarios, "grid", cfg.axis_or_paper())
    s = ref["settings"]
    n = len(result.rows)
    text = "\n".join(
        [
            f"{n} settings evaluated in {elapsed:.1f} s ({n * len(scenarios) / elapsed:.0f} "
            "runs/s)",
            f"reference: cost {ref['cost']:.4f} ({'feasible' if ref['feasible'] else 'INFEASIBLE'})"
            f" against the paper's {cmp.column('paper').mean_cost:.4f}",
            f"settings: value {s['value_rad']:.6g} rad, error limit {s['error_limit_rad']:.6g} "
            f"rad, k {s['k']:.6g}, Ts/Tf {s['ts_over_tf']:.4g}, law {s['accel_law']}",
            "",
            format_compact(cmp),
        ]
    )
    write_text(run_dir / "report.txt", text + "\n")
    print(text, flush=True)
    return 0


def _default_name(cfg) -> str:
    slug = "".join(c if c.isalnum() or c in "._-" else "_" for c in cfg.scenarios)[:60]
    if cfg.axis is not None:
        slug = f"{cfg.load_axis().name}-{slug}"[:60]
    elif cfg.scenarios in ("train", "test"):
        slug += f"{cfg.scenario_count}s{cfg.first_seed}"
    laws = "" if cfg.laws == ("rise",) else "-" + "_".join(cfg.laws)
    return f"{slug}{laws}-p{cfg.points}-r{cfg.refine}k{cfg.keep}"
