"""The cost of every train move's optimal settings on every train move: the table the
settings model picks from (:mod:`vfgym.permove.supervised`).

    python experiments/candidate_costs.py --optima experiments/optima/train.csv \
        --out experiments/optima/train_costs.npz

Candidate j = the optimum of train move j in the model's coordinates (its k relative to
the move's k_a, :func:`vfgym.permove.supervised.settings_targets`); entry [i, j] = the cost
on train move i of those coordinates made settings on move i's plant, all
pairs through the batched kernel (:func:`vfgym.permove.fit.candidate_costs`, what
``vfgym fit`` uses), with the feasibility of each pair.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from vfgym import get_scenario
from vfgym.moves import LOAD_DISTRIBUTION
from vfgym.permove.fit import candidate_costs
from vfgym.permove.optima import read_optima


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--optima", default="experiments/optima/train.csv")
    ap.add_argument("--out", default="experiments/optima/train_costs.npz")
    ap.add_argument("--batch", type=int, default=20_000)
    args = ap.parse_args()
    optima = read_optima(args.optima)
    scenarios = [get_scenario(o.scenario, LOAD_DISTRIBUTION) for o in optima]
    t0 = time.time()
    cost, feas = candidate_costs(
        scenarios,
        optima,
        batch=args.batch,
        progress=lambda done, n: print(f"{time.time() - t0:7.1f} s  {done}/{n} pairs", flush=True),
    )
    names = np.array([o.scenario for o in optima])
    np.savez_compressed(args.out, scenarios=names, cost=cost, feasible=feas)
    print(f"{len(optima)} x {len(optima)} costs -> {args.out}")


if __name__ == "__main__":
    main()
