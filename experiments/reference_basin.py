"""How wide is each grid optimum: the share of settings near a grid reference that are
feasible and within 1 % and 2 % of its cost, in boxes of growing size around it.

A sampler that must get within 1 % of a reference in a few tens of trials (the goal that
``experiments/trials_to_reference.py`` measures) needs a basin around it in which a fair
share of the settings are that good. This script measures the basin: for each problem
(found in ``--refs`` as ``trials_to_reference.py`` does) and each half-width h, it scores
``--count`` settings drawn uniformly in the box ``[x·e^−h, x·e^h]`` of each of value, L, k
and Ts/Tf around the reference x (Ts/Tf capped at its bound, 1), through the one scoring
path, and prints

- ``feasible``: the share of them that meet every constraint;
- ``1 %``, ``2 %``: the share feasible and within 1 % (2 %) of the reference's cost;
- ``median``: the median gap (%) of the feasible ones; ``best``: the lowest gap (%);
- ``binds``: over the infeasible ones, the constraint with the largest value most often,
  and the median of its value (constraints are ≤ 0 when met).

    python experiments/reference_basin.py --refs REFS
"""

from __future__ import annotations

import argparse
import collections
import statistics
import sys
from pathlib import Path

import numpy as np

from vfgym import Settings, evaluate, tuning
from vfgym.scoring import CONSTRAINTS

sys.path.insert(0, str(Path(__file__).parent))
from trials_to_reference import PROBLEMS, problem_config, problem_reference

WIDTHS = (0.001, 0.003, 0.01, 0.03, 0.1)
"""Half-widths of the boxes, in natural-log units (0.01: ±1 % on each setting)."""


def box(ref: Settings, h: float, n: int, rng: np.random.Generator) -> list[Settings]:
    """``n`` settings uniform in log coordinates within ±h of ``ref`` (Ts/Tf ≤ 1)."""
    x0 = np.log([ref.value_rad, ref.error_limit_rad, ref.k, ref.ts_over_tf])
    x = np.exp(x0 + rng.uniform(-h, h, (n, 4)))
    x[:, 3] = np.minimum(x[:, 3], 1.0)
    return [
        Settings(value_rad=v, error_limit_rad=lim, k=k, ts_over_tf=a, accel_law=ref.accel_law)
        for v, lim, k, a in x.tolist()
    ]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--refs", default="runs", help="runs folder holding the grid references")
    ap.add_argument("--problems", default=";".join(PROBLEMS), help="';'-separated scenario sets")
    ap.add_argument("--count", type=int, default=400, help="settings per box")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    rng = np.random.default_rng(args.seed)
    for problem in args.problems.split(";"):
        cfg = problem_config(problem)
        scen = cfg.scenario_list()
        axis = cfg.axis
        data = problem_reference(args.refs, problem).record
        ref = Settings(**data["settings"])
        ref_cost = float(data["cost"])
        own = tuning.aggregate(evaluate(ref, scen, axis=axis))
        pairs = zip(CONSTRAINTS, own.constraints[0], strict=True)
        margins = ", ".join(f"{c} {v:+.3f}" for c, v in pairs)
        print(f"\n{problem}: reference cost {ref_cost:.5f} (re-scored {own.cost[0]:.5f}; "
              f"constraints {margins})")  # fmt: skip
        print(f"{'box':>7s} {'feasible':>9s} {'1 %':>7s} {'2 %':>7s} {'median':>8s} "
              f"{'best':>8s}  binds")  # fmt: skip
        for h in WIDTHS:
            agg = tuning.aggregate(evaluate(box(ref, h, args.count, rng), scen, axis=axis))
            gap = 100.0 * (agg.cost / ref_cost - 1.0)
            ok = agg.feasible
            bad = agg.constraints[~ok]
            worst = collections.Counter(CONSTRAINTS[i] for i in np.argmax(bad, axis=1))
            binds = "-"
            if len(bad):
                name = worst.most_common(1)[0][0]
                value = statistics.median(bad[:, CONSTRAINTS.index(name)])
                binds = f"{name} ({worst[name]}/{len(bad)}, median {value:+.3f})"
            med = f"{np.median(gap[ok]):+8.2f}" if ok.any() else f"{'-':>8s}"
            best = f"{gap[ok].min():+8.2f}" if ok.any() else f"{'-':>8s}"
            print(f"{'±' + format(100 * h, 'g') + ' %':>7s} {ok.mean():9.3f} "
                  f"{np.mean(ok & (gap <= 1.0)):7.3f} {np.mean(ok & (gap <= 2.0)):7.3f} "
                  f"{med} {best}  {binds}", flush=True)  # fmt: skip


if __name__ == "__main__":
    main()
