"""Two per-move searches on an axis's first training moves (those ``vfgym fit`` draws): the
mean optimum of each, its ratio to the last search's per move (median, worst), the moves
where a search is more than 5 % above the last, and the seconds each took.

    PYTHONPATH=src python experiments/fit_search.py --axis experiments/axes/belt-compliant.yaml
    PYTHONPATH=src python experiments/fit_search.py --axis experiments/axes/belt.yaml \\
        --searches 4,5,2 6,8,3
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from vfgym.axis import load_axis
from vfgym.permove.fit import fit_moves
from vfgym.permove.optima import OptimumSearch, move_optima


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--axis", required=True)
    ap.add_argument("--moves", type=int, default=32, help="the first N of the fit's 160 moves")
    ap.add_argument("--searches", nargs="+", default=["4,5,2", "6,8,3"],
                    help="points,rounds,keep of each; the last is the yardstick")  # fmt: skip
    args = ap.parse_args()
    axis = load_axis(args.axis)
    moves = fit_moves(axis, 160)[: args.moves]
    plants = () if axis.uncertainty.exact else axis.design_plants()
    costs = []
    for spec in args.searches:
        points, rounds, keep = (int(x) for x in spec.split(","))
        search = OptimumSearch(points=points, rounds=rounds, keep=keep)
        t0 = time.perf_counter()
        found = move_optima(moves, search, plant=axis.plant, measures=axis.measures,
                            plants=plants)  # fmt: skip
        costs.append(np.array([o.cost for o in found]))
        print(f"search {spec} ({search.evaluations} settings a move): mean optimum "
              f"{costs[-1].mean():.4f}, {time.perf_counter() - t0:.0f} s")  # fmt: skip
    ref = costs[-1]
    print(f"{len(moves)} training moves of axis {axis.name}; / search {args.searches[-1]}:")
    print("| search | mean optimum / last's | median per move | worst |")
    print("| --- | --- | --- | --- |")
    for spec, c in zip(args.searches, costs, strict=True):
        r = c / ref
        print(f"| {spec} | {c.mean() / ref.mean():.3f} | {np.median(r):.3f} | {r.max():.2f} |")
    for spec, c in zip(args.searches[:-1], costs, strict=False):
        for sc, x, y in zip(moves, c, ref, strict=True):
            if x > 1.05 * y:
                print(f"  {spec}: {sc.name} {sc.profile} {sc.distance_rad:+.2f} rad: "
                      f"{x:.3f} against {y:.3f}")  # fmt: skip


if __name__ == "__main__":
    main()
