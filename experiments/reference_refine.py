"""Is a grid reference the optimum near it: finer grids around it, each round around the
best so far.

A sampler's goal, within 1 % of the grid's optimum, means little if that optimum is
loose. For each problem (found in ``--refs`` as ``experiments/trials_to_reference.py``
finds it), this script scores ``7⁴`` settings on a grid in the compass's coordinates
(:class:`vfgym.space.Relative`: log value, log L/value, log k, log Ts/Tf) of half-width
h around the best setting so far, for h in ``--widths`` (natural-log units; each round
around the previous round's best), through the one scoring path, and prints the best
feasible cost against the reference's and where it lies.

    python experiments/reference_refine.py --refs REFS --problems multi-move
"""

from __future__ import annotations

import argparse
import itertools
import sys
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from trials_to_reference import problem_config, problem_reference

from vfgym import space, tuning
from vfgym.tuning._study import relative_space

POINTS = 7
"""Grid points per coordinate in each round."""


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--refs", default="runs", help="runs folder holding the grid references")
    ap.add_argument("--problems", required=True, help="';'-separated scenario sets")
    ap.add_argument("--widths", default="0.2,0.05,0.0125", help="half-widths, log units")
    args = ap.parse_args()
    warnings.filterwarnings("ignore")
    for problem in [p for p in args.problems.split(";") if p]:
        found = problem_reference(args.refs, problem)
        ref = float(found[0]["cost"])
        cfg = problem_config(problem, objective="cost")
        scenarios = cfg.scenario_list()
        rel = relative_space(scenarios, cfg.axis.plant)
        objective = tuning.Objective(
            scenarios, cfg.laws, "cost", axis=cfg.axis,
            aggregate=cfg.aggregate, cvar_alpha=cfg.cvar_alpha,
        )  # fmt: skip
        b = rel.bounds()
        lo, hi = b[:, 0], b[:, 1]
        x_ref = lo + rel.to_unit(space.settings_from_dict(found[0]["settings"])) * (hi - lo)
        best, x_best = ref, x_ref
        print(f"{problem}: reference {ref:.5f} at {np.round(x_ref, 3)}")
        for h in (float(w) for w in args.widths.split(",")):
            offsets = itertools.product(np.linspace(-h, h, POINTS), repeat=4)
            points = [np.clip(x_best + np.array(d), lo, hi) for d in offsets]
            results = objective.score_many([rel.settings((p - lo) / (hi - lo)) for p in points])
            for p, r in zip(points, results, strict=True):
                if r.attrs["feasible"] and float(r.values) < best:
                    best, x_best = float(r.values), p
            print(f"  half-width {h}: best {best:.5f} ({100 * (best / ref - 1):+.2f} %) "
                  f"at {np.round(x_best, 3)}", flush=True)  # fmt: skip


if __name__ == "__main__":
    main()
