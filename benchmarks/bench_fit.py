"""``vfgym fit`` on each shipped axis file: on the axis's held-out test moves, the fitted
model's mean cost against the per-move optima (the full search,
:class:`vfgym.agents.optima.OptimumSearch`'s defaults, checked against ``vfgym grid``),
its wins against the best fixed setting, the paper's settings and the S-curve source,
its feasible moves, and the fit's wall time (the goal: within 5 min on 2 cores).

    python benchmarks/bench_fit.py [--axes experiments/axes/*.yaml] [--moves N]

It asserts nothing (the machine is shared); the goals are 1.05x the optima's mean cost
or less, beating the paper's settings on 95 % and the S-curve source on 85 % of the
moves, feasible on all.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from vfgym.agents.fit import FitConfig, fit_axis
from vfgym.agents.optima import OptimumSearch, move_optima
from vfgym.moves.axis import load_axis

ROOT = Path(__file__).resolve().parents[1]
AXES = [str(p.relative_to(ROOT)) for p in sorted((ROOT / "experiments/axes").glob("*.yaml"))]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--axes", nargs="+", default=AXES)
    ap.add_argument("--moves", type=int, default=FitConfig().moves, help="training moves")
    ap.add_argument("--reference-points", type=int, default=OptimumSearch().points,
                    help="grid points per dimension of the test moves' optima")  # fmt: skip
    ap.add_argument("--reference-rounds", type=int, default=OptimumSearch().rounds,
                    help="refinement rounds of the test moves' optima")  # fmt: skip
    args = ap.parse_args()
    d = FitConfig()
    cfg = replace(d, moves=args.moves, library=min(d.library, args.moves))
    ref_search = OptimumSearch(points=args.reference_points, rounds=args.reference_rounds)
    print("| axis | test moves | fitted mean cost | / per-move optima | beats best fixed "
          "| beats paper | beats S-curve | feasible | fit wall time |")  # fmt: skip
    print("|" + " --- |" * 9)
    for path in args.axes:
        axis = load_axis(ROOT / path)
        with tempfile.TemporaryDirectory() as run:
            t0 = time.perf_counter()
            res = fit_axis(axis, run, cfg, progress=False)
            wall = time.perf_counter() - t0
        test = axis.scenarios("test")
        best = np.array([o.cost for o in move_optima(test, ref_search, plant=axis.plant,
                                                      measures=axis.measures)])  # fmt: skip
        v = res.verdict
        fitted = v.row("fitted")
        cost = np.asarray(v.report.column("fitted").cost, dtype=float)
        n = len(test)
        wins = {r.label: r.versus.wins for r in v.rows if r.versus is not None}
        print(
            f"| {axis.name} | {n} | {np.mean(cost):.3f} | {np.mean(cost) / np.mean(best):.3f}x | "
            f"{wins['best-fixed']}/{n} | {wins['paper']}/{n} | {wins['scurve']}/{n} | "
            f"{fitted.feasible}/{n} | {wall:.0f} s |",
            flush=True,
        )


if __name__ == "__main__":
    main()
