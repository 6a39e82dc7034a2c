"""Per-move optima of random moves, cached as CSV (the reference of the amortised tuners
and the supervised model's training data):

    python experiments/move_optima.py --split test --count 64 --out experiments/optima/test.csv
    python experiments/move_optima.py --split train --count 320 --out experiments/optima/train.csv

Moves ``<split>-<first_seed>`` ... of the default distribution (``vfgym.random_scenario``,
the envs' default), each searched by :func:`vfgym.permove.optima.move_optima` (a 6⁴ grid
over the search space, then 8 rounds of local refinement around the 3 best points), all
through the batched kernel. About 1.7 s a move on the 2-core machine.
"""

from __future__ import annotations

import argparse
import time

from vfgym import scenario_set
from vfgym.moves import LOAD_DISTRIBUTION
from vfgym.permove.optima import OptimumSearch, move_optima, write_optima


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--split", choices=("train", "test"), required=True)
    ap.add_argument("--count", type=int, required=True)
    ap.add_argument("--first-seed", type=int, default=0)
    ap.add_argument("--out", required=True)
    args = ap.parse_args()
    search = OptimumSearch()
    scenarios = scenario_set(args.split, args.count, args.first_seed, LOAD_DISTRIBUTION)
    t0 = time.time()
    optima = move_optima(
        scenarios, search, progress=lambda s: print(f"{time.time() - t0:7.1f} s  {s}", flush=True)
    )
    write_optima(
        args.out,
        optima,
        header=(
            f"per-move optima of {args.split}-{args.first_seed} ... "
            f"{args.split}-{args.first_seed + args.count - 1}: {search}\n"
            f"python experiments/move_optima.py --split {args.split} --count {args.count} "
            f"--first-seed {args.first_seed} --out {args.out}"
        ),
    )
    print(f"{len(optima)} optima -> {args.out} ({time.time() - t0:.0f} s)")


if __name__ == "__main__":
    main()
