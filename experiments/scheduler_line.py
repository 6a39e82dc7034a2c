"""What the scheduler runs on plants along one design plant's load-torque line below the
axis's range, and where the base and that run come to rest: the end constraints
(overshoot and in-position, in in-position windows: feasible <= 0) of each.

The scheduler tells the plant from the hold's response (its residual from the told design
plant is printed), then runs that plant's continuation, its cheapest where the response
lies within the trusted radius, or holds the base.

    PYTHONPATH=src python experiments/scheduler_line.py \\
        --model runs/fit/loads-uncertain/settings_model.json --scenario test-8 \\
        --below 0.025,0.0296875,0.03,0.03125
"""

from __future__ import annotations

import argparse

import numpy as np

from vfgym.axis import PlantVariant, load_axis
from vfgym.permove import load_settings_model
from vfgym.permove._episodes import _episode, _ramp, _signature
from vfgym.permove.adaptive import AdaptiveOptions, EstimatingScheduler


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--axis", default="experiments/axes/loads-uncertain.yaml")
    ap.add_argument("--model", required=True, help="the axis's vfgym fit settings_model.json")
    ap.add_argument("--scenario", required=True, help="a test move's name")
    ap.add_argument("--below", required=True, help="shares of rated torque below the range")
    ap.add_argument("--count-margin", action="store_true")
    args = ap.parse_args()
    axis = load_axis(args.axis)
    opts = AdaptiveOptions(count_margin=args.count_margin)
    sched = EstimatingScheduler(axis, load_settings_model(args.model), opts)
    (sc,) = [s for s in axis.scenarios("test") if s.name == args.scenario]
    table = sched.table(sc)
    env = sched._tables[sc.name][0]
    lo = min(q.load_offset_nm for q in axis.design_plants())
    rated = axis.plant.motor.rated_torque_nm

    def ends(info: dict) -> str:
        return (f"overshoot {info['constraint_overshoot']:+.4f}, in-position "
                f"{info['constraint_arrival']:+.4f}")  # fmt: skip

    print(f"{args.scenario} on axis {axis.name}; {opts}")
    for f in (float(x) for x in args.below.split(",")):
        q = PlantVariant(load_offset_nm=lo - f * rated)
        told = table.tell(_signature(env, q, table.hold))
        c = told.continuation
        if told.residual < c.trusted:
            (a, r), runs = c.cheapest, "its cheapest"
        elif not told.fits or c.shadows:
            (a, r), runs = (np.zeros(4), 1), "the base held"
        else:
            (a, r), runs = (c.action, c.ramp), "its continuation"
        base = _episode(env, q, lambda t: np.zeros(4))[0]
        mine = _episode(env, q, lambda t, a=a, r=r: _ramp(a, r, table.hold, t))[0]
        print(f"{100 * f:.4g} % of rated below: told inertia {c.plant.inertia:.3f}, gain "
              f"{c.plant.torque_per_count:.3f}, load {c.plant.load_offset_nm:+.4f} N·m "
              f"(residual {told.residual:.3g}), runs {runs}")  # fmt: skip
        print(f"  base: {ends(base)}; feasible {base['feasible']}")
        print(f"  run:  {ends(mine)}; feasible {mine['feasible']}")


if __name__ == "__main__":
    main()
