"""How often a run counted feasible reports a pulse-train peak above its acceleration
limit (docs/model.md §5.1): random settings and the baselines on random test moves of the
paper's axis and of a 25 krad/s² axis, through the scoring path (``vfgym.evaluate``).

    python experiments/accel_feasibility.py [--controllers 60] [--moves 12] [--seed 0]

Prints, per axis, the feasible runs, the largest peak any of them reports (× the limit)
and how many report more than the limit plus the tolerance (``Measures.accel_tolerance_pct``).
"""

from __future__ import annotations

import argparse
from dataclasses import replace

import numpy as np

from vfgym import DEFAULT_MEASURES, PAPER_AXIS, PAPER_PLANT, evaluate, scenario_set
from vfgym.space import from_action


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--controllers", type=int, default=60, help="random settings (default 60)")
    ap.add_argument("--moves", type=int, default=12, help="test moves per axis (default 12)")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    rng = np.random.default_rng(args.seed)
    ctrls = [from_action(rng.uniform(-1.0, 1.0, 4)) for _ in range(args.controllers)]
    ctrls += ["paper", "rule-of-thumb", "scurve"]
    tol = DEFAULT_MEASURES.accel_tolerance_pct / 100.0
    slow = replace(PAPER_AXIS, plant=PAPER_PLANT.with_motor(accel_limit_rad_s2=25e3))
    for name, axis in (("paper", PAPER_AXIS), ("25 krad/s2", slow)):
        ev = evaluate(ctrls, scenario_set("test", args.moves, 0), axis=axis)
        ratio = np.array([[m["accel_ratio_pulse"] for m in row] for row in ev.metrics])
        ok = ev.feasible
        top = ratio[ok].max() if ok.any() else float("nan")
        print(
            f"{name}: {int(ok.sum())} of {ok.size} runs feasible; largest reported peak "
            f"{top:.4f}x the limit; above {1.0 + tol:.2f}x: {int((ratio[ok] > 1.0 + tol).sum())}"
        )


if __name__ == "__main__":
    main()
