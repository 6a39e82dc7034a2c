"""On a compliant axis's test moves: on how many the tuned side beats both the paper's
settings and the S-curve source on cost, and on how many its load's residual vibration is
no larger than the S-curve source's; per move and in aggregate, every number
``vfgym.evaluate``'s.

The tuned side is a settings file (``best.yaml`` of a sweep: one setting for every move)
or a settings model (``settings_model.json`` of ``vfgym fit``: settings per move).

    PYTHONPATH=src python experiments/compliant_goal.py \\
        --axis experiments/axes/belt-compliant.yaml \\
        --model runs/fit/belt-compliant/settings_model.json
    PYTHONPATH=src python experiments/compliant_goal.py \\
        --axis experiments/axes/belt-compliant.yaml --settings runs/sweep/belt-compliant/best.yaml
"""

from __future__ import annotations

import argparse

import numpy as np
import yaml

from vfgym import Settings, evaluate
from vfgym.axis import load_axis
from vfgym.permove import load_tuner


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--axis", required=True)
    side = ap.add_mutually_exclusive_group(required=True)
    side.add_argument("--model", help="a settings model (vfgym fit's settings_model.json)")
    side.add_argument("--settings", help="a settings file (a sweep's best.yaml)")
    ap.add_argument("--per-move", action="store_true", help="print every move's row")
    args = ap.parse_args()
    axis = load_axis(args.axis)
    if args.model:
        tuned = load_tuner(args.model, axis)
    else:
        with open(args.settings, encoding="utf-8") as f:
            tuned = Settings(**yaml.safe_load(f)["settings"])
    moves = axis.scenarios("test")
    ev = evaluate([tuned, "paper", "scurve"], moves, axis=axis)
    if axis.plant.transmission is None:
        raise SystemExit(f"--axis {args.axis}: states no transmission (no load measures)")
    unit = "um" if axis.plant.transmission.travel_mm_per_rad is not None else "counts"
    key = f"load_residual_vibration_{unit}"
    cost = ev.cost
    resid = np.array([[m[key] for m in row] for row in ev.metrics])
    both = (cost[0] < cost[1]) & (cost[0] < cost[2])
    quiet = resid[0] <= resid[2]
    n = len(moves)
    if args.per_move:
        print(f"{'move':10s} {'tuned':>7s} {'paper':>7s} {'scurve':>7s}  residual {unit}: "
              f"{'tuned':>7s} {'scurve':>7s}")  # fmt: skip
        for j, sc in enumerate(moves):
            print(f"{sc.name:10s} {cost[0, j]:7.3f} {cost[1, j]:7.3f} {cost[2, j]:7.3f}  "
                  f"{'':>{9 + len(unit)}s} {resid[0, j]:7.2f} {resid[2, j]:7.2f}")  # fmt: skip
    print(f"{n} test moves of axis {axis.name}")
    print(f"  tuned beats the paper's settings on {(cost[0] < cost[1]).sum()}/{n}, the S-curve "
          f"source on {(cost[0] < cost[2]).sum()}/{n}, both on {both.sum()}/{n} "
          f"({100 * both.mean():.0f} %)")  # fmt: skip
    print(f"  feasible: tuned {ev.feasible[0].sum()}/{n}, paper {ev.feasible[1].sum()}/{n}, "
          f"S-curve {ev.feasible[2].sum()}/{n}")  # fmt: skip
    print(f"  mean cost: tuned {cost[0].mean():.3f}, paper {cost[1].mean():.3f}, "
          f"S-curve {cost[2].mean():.3f}")  # fmt: skip
    print(f"  residual vibration ({unit}): tuned's no larger than the S-curve's on "
          f"{quiet.sum()}/{n} ({100 * quiet.mean():.0f} %); mean {resid[0].mean():.2f} "
          f"against {resid[2].mean():.2f}, median {np.median(resid[0]):.2f} against "
          f"{np.median(resid[2]):.2f}, largest {resid[0].max():.2f} against "
          f"{resid[2].max():.2f}")  # fmt: skip
    print(f"  both goals on one move (beats both, residual no larger): "
          f"{(both & quiet).sum()}/{n}")  # fmt: skip


if __name__ == "__main__":
    main()
