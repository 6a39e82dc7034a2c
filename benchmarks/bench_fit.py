"""``vfgym fit`` on each shipped axis file: on the axis's held-out test moves, the fitted
model's mean cost against the per-move optima (the full search,
:class:`vfgym.permove.optima.OptimumSearch`'s defaults, checked against ``vfgym grid``),
its wins against the best fixed setting, the paper's settings and the S-curve source
(and in brackets the optima's own wins against it: the most any per-move setting got),
its feasible moves, and the fit's wall time (the goal: within 5 min on 2 cores). A test
move's optimum is the best known: its own search's, or another move's optimum (test or
training) where that is better on it and feasible.

    python benchmarks/bench_fit.py [--axes experiments/axes/*.yaml] [--moves N] [--out DIR]

Each fit runs in a fresh folder ``DIR/<axis>/`` (default ``runs/bench-fit``), kept for
inspection; the test moves' optima are kept there too (``test-optima.csv``) and reused by
a later run with the same search and axis. It asserts nothing (the machine is shared);
the goals are 1.05x the optima's mean cost or less, beating the paper's settings on 95 %
and the S-curve source on 85 % of the moves, feasible on all.
"""

from __future__ import annotations

import argparse
import os
import shutil
import time
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path

import numpy as np

from vfgym.axis import Axis, load_axis
from vfgym.moves.scenarios import Scenario
from vfgym.permove.fit import FitConfig, checkpointed_optima, fit_axis
from vfgym.permove.optima import MoveOptimum, OptimumSearch
from vfgym.scoring import Move, score_pairs

ROOT = Path(__file__).resolve().parents[1]
AXES = [str(p.relative_to(ROOT)) for p in sorted((ROOT / "experiments/axes").glob("*.yaml"))]


def best_known(
    test: Sequence[Scenario],
    ref: Sequence[MoveOptimum],
    candidates: Sequence[MoveOptimum],
    axis: Axis,
) -> tuple[np.ndarray, int]:
    """Each test move's best known cost: its own search's optimum, or a better feasible
    one among ``candidates`` (other moves' optima, scored on it); and how many bettered."""
    moves = [Move.of(sc, axis.plant) for sc in test]
    pairs = [(i, o.settings) for i in range(len(moves)) for o in candidates]
    scores = score_pairs([c for _, c in pairs], [moves[i] for i, _ in pairs],
                         measures=axis.measures)  # fmt: skip
    best = np.array([o.cost for o in ref])
    own = best.copy()
    for (i, _), r in zip(pairs, scores, strict=True):
        if r is not None and r.feasible:
            best[i] = min(best[i], r.cost)
    return best, int(np.sum(best < own))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--axes", nargs="+", default=AXES)
    ap.add_argument("--moves", type=int, default=FitConfig().moves, help="training moves")
    ap.add_argument("--reference-points", type=int, default=OptimumSearch().points,
                    help="grid points per dimension of the test moves' optima")  # fmt: skip
    ap.add_argument("--reference-rounds", type=int, default=OptimumSearch().rounds,
                    help="refinement rounds of the test moves' optima")  # fmt: skip
    ap.add_argument("--out", default="runs/bench-fit", help="folder of the fits' run folders")
    args = ap.parse_args()
    d = FitConfig()
    library = min(d.library, args.moves)
    cfg = replace(d, moves=args.moves, library=library, check=min(d.check, library))
    ref_search = OptimumSearch(points=args.reference_points, rounds=args.reference_rounds)
    print("| axis | test moves | fitted mean cost | / per-move optima | beats best fixed "
          "| beats paper | beats S-curve (optima) | feasible | fit wall time |")  # fmt: skip
    print("|" + " --- |" * 9)
    for path in args.axes:
        axis = load_axis(ROOT / path)
        folder = Path(args.out) / axis.name
        run = folder / "fit"
        shutil.rmtree(run, ignore_errors=True)
        run.mkdir(parents=True)
        t0 = time.perf_counter()
        res = fit_axis(axis, run, cfg, progress=False)
        wall = time.perf_counter() - t0
        test = axis.scenarios("test")
        ref = checkpointed_optima(test, ref_search, folder / "test-optima.csv",
                                  plant=axis.plant, measures=axis.measures)  # fmt: skip
        best, improved = best_known(test, ref, [*ref, *res.optima], axis)
        v = res.verdict
        fitted = v.row("fitted")
        cost = np.asarray(v.report.column("fitted").cost, dtype=float)
        n = len(test)
        wins = {r.label: r.versus.wins for r in v.rows if r.versus is not None}
        ceiling = int(np.sum(best < np.asarray(v.report.column("scurve").cost, dtype=float)))
        print(
            f"| {axis.name} | {n} | {np.mean(cost):.3f} | {np.mean(cost) / np.mean(best):.3f}x | "
            f"{wins['best-fixed']}/{n} | {wins['paper']}/{n} | {wins['scurve']}/{n} "
            f"({ceiling}/{n}) | {fitted.feasible}/{n} | {wall:.0f} s |",
            flush=True,
        )
        stages = ", ".join(f"{k} {v:.0f} s" for k, v in res.seconds.items())
        print(f"<!-- {axis.name}: {stages}; load average {os.getloadavg()[0]:.1f}; "
              f"{improved} test optima bettered by another move's -->", flush=True)  # fmt: skip


if __name__ == "__main__":
    main()
