"""Which aggregate generalises best to held-out moves: mean, CVaR or worst.

For each axis, aggregate and seed this runs ``vfgym sweep`` itself (the command line, in
this process; a journal storage in a scratch runs folder, no plots) on the axis's train
moves, then judges the best setting on the axis's test moves, which the sweep never saw:
the held-out verdict the sweep printed (wins against the paper's settings and the rule of
thumb, feasible count) and the held-out cost's mean, CVaR (worst quarter) and worst.
Prints one row per run, then per axis and aggregate the median over the seeds.

    python experiments/aggregates.py --axes default experiments/axes/vertical.yaml \\
        --seeds 0 1 2 --trials 300 --sampler cmaes

``default`` is the paper's axis without ``--axis`` (its 16 train and 32 test moves).
"""

from __future__ import annotations

import argparse
import contextlib
import io
import statistics
import tempfile
import time
from pathlib import Path

import yaml

from vfgym import cli, evaluate, tuning
from vfgym.axis import PAPER_AXIS, load_axis
from vfgym.commands._common import load_settings


def one_run(axis: str, how: str, seed: int, args: argparse.Namespace, runs: str) -> dict:
    """Sweep once, return the held-out figures of its best setting."""
    study = f"{Path(axis).stem}-{how}-{seed}"
    argv = ["sweep", "--scenarios", "train", "--aggregate", how, "--seed", str(seed)]
    argv += ["--trials", str(args.trials), "--sampler", args.sampler, "--storage", "journal"]
    argv += ["--runs-dir", runs, "--study", study, "--no-plots", "--no-progress"]
    argv += [] if axis == "default" else ["--axis", axis]
    t0 = time.perf_counter()
    with contextlib.redirect_stdout(io.StringIO()):
        code = cli.main(argv)
    if code != 0:
        raise SystemExit(f"vfgym {' '.join(argv)} exited {code}")
    run = Path(runs) / "sweep" / study
    summary = yaml.safe_load((run / "summary.yaml").read_text())
    rows = {r["controller"]: r for r in summary["verdict"]["controllers"]}
    ax = PAPER_AXIS if axis == "default" else load_axis(axis)
    test = ax.scenarios("test")
    cost = evaluate(load_settings(str(run / "best.yaml"), ax), test, axis=ax).cost[0]
    return {
        "axis": ax.name,
        "aggregate": how,
        "seed": seed,
        "train": summary["best"]["cost"],
        "wins_paper": rows["paper"]["wins"],
        "wins_rot": rows["rule-of-thumb"]["wins"],
        "feasible": rows["tuned"]["feasible"],
        "n": len(test),
        "mean": float(tuning.aggregate_costs(cost, "mean")),
        "cvar": float(tuning.aggregate_costs(cost, "cvar", 0.25)),
        "worst": float(tuning.aggregate_costs(cost, "worst")),
        "rot_mean": rows["rule-of-thumb"]["cost"]["mean"],
        "s": time.perf_counter() - t0,
    }


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--axes", nargs="+", default=["default", "experiments/axes/vertical.yaml"])
    p.add_argument("--aggregates", nargs="+", default=list(tuning.AGGREGATES))
    p.add_argument("--seeds", nargs="+", type=int, default=[0, 1, 2])
    p.add_argument("--trials", type=int, default=300)
    p.add_argument("--sampler", default="cmaes")
    args = p.parse_args()
    head = (
        "axis       aggregate seed  train   wins/paper wins/rot feasible  held-out mean "
        "cvar0.25  worst  (rule of thumb mean)  s"
    )
    print(head, flush=True)
    results = []
    with tempfile.TemporaryDirectory() as runs:
        for axis in args.axes:
            for how in args.aggregates:
                for seed in args.seeds:
                    r = one_run(axis, how, seed, args, runs)
                    results.append(r)
                    print(
                        f"{r['axis']:10s} {how:9s} {seed:4d} {r['train']:6.3f}   "
                        f"{r['wins_paper']:3d}/{r['n']:<3d}    {r['wins_rot']:3d}/{r['n']:<3d} "
                        f"{r['feasible']:3d}/{r['n']:<3d}  {r['mean']:13.3f} {r['cvar']:8.3f} "
                        f"{r['worst']:6.2f}  ({r['rot_mean']:.3f})  {r['s']:5.0f}",
                        flush=True,
                    )
    print("\nmedian over the seeds (held out):")
    print("axis       aggregate  wins/paper  wins/rot  feasible   mean   cvar0.25  worst")
    for axis in dict.fromkeys(r["axis"] for r in results):
        for how in args.aggregates:
            rs = [r for r in results if r["axis"] == axis and r["aggregate"] == how]
            med = {
                k: statistics.median(r[k] for r in rs)
                for k in rs[0]
                if k not in ("axis", "aggregate")
            }
            print(
                f"{axis:10s} {how:9s}  {med['wins_paper']:6.1f}/{rs[0]['n']}  "
                f"{med['wins_rot']:5.1f}/{rs[0]['n']}  {med['feasible']:5.1f}/{rs[0]['n']}  "
                f"{med['mean']:6.3f}  "
                f"{med['cvar']:7.3f}  {med['worst']:6.2f}"
            )


if __name__ == "__main__":
    main()
