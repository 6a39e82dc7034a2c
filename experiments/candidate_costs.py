"""The cost of every train move's optimal settings on every train move: the table the
settings model picks from (:mod:`vfgym.agents.supervised`).

    python experiments/candidate_costs.py --optima experiments/optima/train.csv \
        --out experiments/optima/train_costs.npz

Candidate j = the optimum of train move j in the model's coordinates (its k relative to
the move's k_a, :func:`vfgym.agents.supervised.settings_targets`); entry [i, j] = the cost
on train move i of those coordinates made settings on move i's plant, all
pairs through the batched kernel (:func:`vfgym.scoring.score_pairs`, the scoring path),
with the feasibility of each pair.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from vfgym import get_scenario
from vfgym.agents.optima import read_optima
from vfgym.agents.supervised import settings_targets, target_settings
from vfgym.moves import LOAD_DISTRIBUTION
from vfgym.scoring import Move, score_pairs


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--optima", default="experiments/optima/train.csv")
    ap.add_argument("--out", default="experiments/optima/train_costs.npz")
    ap.add_argument("--batch", type=int, default=20_000)
    args = ap.parse_args()
    optima = read_optima(args.optima)
    moves = [Move.of(get_scenario(o.scenario, LOAD_DISTRIBUTION)) for o in optima]
    cand = [settings_targets(o.settings, mv.plant) for o, mv in zip(optima, moves, strict=True)]
    n = len(optima)
    pairs = [(i, j) for i in range(n) for j in range(n)]
    cost = np.empty((n, n))
    feas = np.empty((n, n), dtype=bool)
    t0 = time.time()
    for a in range(0, len(pairs), args.batch):
        chunk = pairs[a : a + args.batch]
        ctrls = [target_settings(cand[j], moves[i].plant) for i, j in chunk]
        res = score_pairs(ctrls, [moves[i] for i, _ in chunk])
        for (i, j), r in zip(chunk, res, strict=True):
            assert r is not None
            cost[i, j] = r.cost
            feas[i, j] = bool(np.all(r.constraints <= 0.0))
        print(f"{time.time() - t0:7.1f} s  {a + len(chunk)}/{len(pairs)} pairs", flush=True)
    names = np.array([o.scenario for o in optima])
    np.savez_compressed(args.out, scenarios=names, cost=cost, feasible=feas)
    print(f"{n} x {n} costs -> {args.out}")


if __name__ == "__main__":
    main()
