"""The scheduler that watches the response (:class:`vfgym.permove.adaptive.EstimatingScheduler`)
against the robust per-move base it starts from, on the held-out (move, plant) pairs of
``bench_adaptive.py`` (the axis's first ``--moves`` test moves × ``--plants`` true plants
from ``--plant-seed``), in one :func:`vfgym.evaluate` call, and against the oracle if
``bench_adaptive.py`` cached it in ``--oracle``'s folder.

    python benchmarks/bench_estimating.py --model FIT/settings_model.json
        [--axis experiments/axes/loads-uncertain.yaml] [--moves 32] [--plants 16]
        [--hold-ms 2] [--evals 150] [--neighbours 2] [--probes 2] [--oracle runs/bench-adaptive]

Prints the mean cost, the pairs feasible, the ratio to the base, the pairs cheaper / dearer
than the base, the pairs where it breaks a limit the base holds, and the seconds taken
(the tables of continuations are computed once per move, within the call).
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
    )
    sched = EstimatingScheduler(axis, load_settings_model(args.model), opts)
    base = load_tuner(args.model, axis, warn=print)
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


if __name__ == "__main__":
    sys.exit(main())
