"""The scheduler that watches the response (:class:`vfgym.permove.adaptive.EstimatingScheduler`)
against the robust per-move base it starts from, on the held-out (move, plant) pairs of
``bench_adaptive.py`` (the axis's first ``--moves`` test moves × ``--plants`` true plants
from ``--plant-seed``), in one :func:`vfgym.evaluate` call, and against the oracle if
``bench_adaptive.py`` cached it in ``--oracle``'s folder.

    python benchmarks/bench_estimating.py --model FIT/settings_model.json
        [--axis experiments/axes/loads-uncertain.yaml] [--moves 32] [--plants 16]
        [--hold-ms 2] [--evals 150] [--neighbours 2] [--probes 2] [--oracle runs/bench-adaptive]
    python benchmarks/bench_estimating.py --model FIT/settings_model.json --outside
        [--levels 0.02,0.05,0.1] [--moves 8] [--plants 8]

Prints the mean cost, the pairs feasible, the ratio to the base, the pairs cheaper / dearer
than the base, the pairs where it breaks a limit the base holds, and the seconds taken
(the tables of continuations are computed once per move, within the call).

``--outside``: the scheduler outside what the axis states. Besides the ``--plants`` drawn
within the ranges, true plants with one quantity outside its range, each side, by each of
``--levels`` (inertia and drive gain ``torque_per_count``: a share of the range's edge;
load torque: of the motor's rated torque). The scheduler with its fallback, the same
without it (its tables shared) and the base, in one :func:`vfgym.evaluate` call; per
group of plants: pairs feasible, pairs breaking a limit the base holds (goal 0), the mean
cost over the base's, and the moves on which the scheduler held its base (the response fit
no design plant / a shadow plant broke the told continuation). Last, the goals: no break
where the base holds outside; in range at most 0.93× the base.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))


def main(argv: list[str] | None = None) -> int:
    from bench_adaptive import judge, pairs

    from vfgym import load_axis
    from vfgym.axis import VERDICT_PLANT_SEED
    from vfgym.permove import load_settings_model, load_tuner
    from vfgym.permove.adaptive import AdaptiveOptions, EstimatingScheduler

    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--axis", default="experiments/axes/loads-uncertain.yaml")
    p.add_argument("--model", required=True, help="the axis's vfgym fit settings_model.json")
    p.add_argument("--moves", type=int, default=32)
    p.add_argument("--plants", type=int, default=16)
    p.add_argument("--plant-seed", type=int, default=VERDICT_PLANT_SEED)
    p.add_argument("--hold-ms", type=float, default=2.0)
    p.add_argument("--interval-ms", type=float, default=1.0)
    p.add_argument("--evals", type=int, default=150)
    p.add_argument("--neighbours", type=int, default=2)
    p.add_argument("--probes", type=int, default=2)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--oracle", default=None, help="a bench_adaptive.py --out folder")
    p.add_argument("--outside", action="store_true", help="also plants outside the ranges")
    p.add_argument("--levels", default="0.02,0.05,0.1", help="how far outside (--outside)")
    p.add_argument("--count-margin", action="store_true",
                   help="AdaptiveOptions.count_margin: a count inside the window")  # fmt: skip
    args = p.parse_args(argv)
    axis = load_axis(args.axis)
    test, variants = pairs(axis, args.moves, args.plants, args.plant_seed)
    opts = AdaptiveOptions(
        hold_ms=args.hold_ms,
        interval_ms=args.interval_ms,
        evals=args.evals,
        neighbours=args.neighbours,
        probes=args.probes,
        seed=args.seed,
        count_margin=args.count_margin,
    )
    sched = EstimatingScheduler(axis, load_settings_model(args.model), opts)
    base = load_tuner(args.model, axis, warn=print)
    if args.outside:
        levels = [float(x) for x in args.levels.split(",")]
        return outside(axis, base, sched, test, list(variants), levels, args.plant_seed)
    t0 = time.perf_counter()
    (c0, ok0), (c, ok) = judge([base, sched], axis, test, variants)
    took = time.perf_counter() - t0
    n = len(c0)
    print(f"axis {axis.name}: {len(test)} test moves x {len(variants)} plants (plant seed "
          f"{args.plant_seed}) = {n} pairs; {opts}")  # fmt: skip
    print("| tuner | mean cost | feasible | / base | cheaper / dearer | breaks where base holds |")
    print("| --- | --- | --- | --- | --- | --- |")
    print(f"| base (the fit's model) | {c0.mean():.4f} | {int(ok0.sum())}/{n} | 1.0000 | | |")
    print(f"| estimating scheduler | {c.mean():.4f} | {int(ok.sum())}/{n} | "
          f"{c.mean() / c0.mean():.4f} | {int(np.sum(c < c0 - 1e-9))} / "
          f"{int(np.sum(c > c0 + 1e-9))} | {int(np.sum(ok0 & ~ok))} |")  # fmt: skip
    cache = Path(args.oracle or "") / "oracle.json"
    if args.oracle and cache.is_file():
        orc = np.array(json.loads(cache.read_text())["cost"])
        if orc.shape == c0.shape:
            print(f"| oracle (cached) | {orc.mean():.4f} | | {orc.mean() / c0.mean():.4f} | | |")
    print(f"{took:.0f} s for both, tables included")
    return 0


def outside_plants(axis, levels: list[float]) -> list[tuple[str, object]]:
    """(label, plant) with one quantity outside the axis's range, each side, each level."""
    from vfgym.axis import PlantVariant

    design = axis.design_plants()
    rated = axis.plant.motor.rated_torque_nm
    out = []
    for k, short in (("inertia", "inertia"), ("torque_per_count", "gain"),
                     ("load_offset_nm", "load torque")):  # fmt: skip
        lo, hi = min(getattr(q, k) for q in design), max(getattr(q, k) for q in design)
        for f in levels:
            if k == "load_offset_nm":
                sides = ((f"{short} {lo:+.3g} - {f:g} rated", lo - f * rated),
                         (f"{short} {hi:+.3g} + {f:g} rated", hi + f * rated))  # fmt: skip
            else:
                sides = ((f"{short} {lo:g} x {1 - f:g}", lo * (1 - f)),
                         (f"{short} {hi:g} x {1 + f:g}", hi * (1 + f)))  # fmt: skip
            out += [(lab, PlantVariant(**{k: v})) for lab, v in sides]
    return out


def outside(axis, base, sched, test, inside: list, levels: list[float], seed: int) -> int:
    """The ``--outside`` table (module doc)."""
    from vfgym import evaluate

    outs = outside_plants(axis, levels)
    plants = inside + [q for _, q in outs]
    without = sched.without_fallback()
    t0 = time.perf_counter()
    a = evaluate([base, without, sched], test, axis=axis, plants=plants).across
    took = time.perf_counter() - t0
    cost, ok = a.cost, a.feasible  # (controllers, plants, moves)
    groups = [(f"in range ({len(inside)} plants, seed {seed})", list(range(len(inside))))]
    groups += [(lab, [len(inside) + j]) for j, (lab, _) in enumerate(outs)]
    groups += [(f"outside, all {len(outs)}", list(range(len(inside), len(plants))))]
    print(f"axis {axis.name}: {len(test)} test moves x ({len(inside)} plants in range + "
          f"{len(outs)} outside); {sched.options}")  # fmt: skip
    print("| true plants | pairs | base feasible | without fallback: feasible, breaks where "
          "base holds, / base | with fallback: feasible, breaks, / base | held (response / "
          "shadow) |")  # fmt: skip
    print("| --- | --- | --- | --- | --- | --- |")
    rows = {}
    for lab, idx in groups:
        c, f = cost[:, idx].reshape(3, -1), ok[:, idx].reshape(3, -1)
        n = c.shape[1]
        brk = [int(np.sum(f[0] & ~f[i])) for i in (1, 2)]
        ratio = [c[i].mean() / c[0].mean() for i in (1, 2)]
        on = {plants[i] for i in idx}
        runs = [r for r in sched.runs if r.plant in on]
        resp = sum(r.held == "response" for r in runs)
        shad = sum(r.held == "shadow" for r in runs)
        rows[lab] = (brk, ratio)
        print(f"| {lab} | {n} | {int(f[0].sum())}/{n} | {int(f[1].sum())}/{n}, {brk[0]}, "
              f"{ratio[0]:.4f} | {int(f[2].sum())}/{n}, {brk[1]}, {ratio[1]:.4f} | "
              f"{resp + shad}/{len(runs)} ({resp} / {shad}) |")  # fmt: skip
    safer = sum(c.safer for sc in test for c in sched.table(sc).continuations)
    held = sum(bool(c.shadows) for sc in test for c in sched.table(sc).continuations)
    total = sum(len(sched.table(sc).continuations) for sc in test)
    print(f"continuations: {total}; {safer} replaced by a searched one no shadow plant breaks, "
          f"{held} held at the base (every candidate broken by a shadow)")  # fmt: skip
    (brk_out, _), (_, r_in) = rows[groups[-1][0]], rows[groups[0][0]]
    print(f"goals: breaks where the base holds, outside: {brk_out[1]} (goal 0; without the "
          f"fallback {brk_out[0]}); in range {r_in[1]:.4f}x the base (goal <= 0.93; without "
          f"{r_in[0]:.4f})")  # fmt: skip
    print(f"{took:.0f} s for the three, tables included")
    return 0


if __name__ == "__main__":
    sys.exit(main())
