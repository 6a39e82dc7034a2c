"""How VFServo-v0's cost answers small residual actions: the mean cost of the first
``--moves`` validation moves (train split, never drawn in training) under constant
offsets on one setting at a time and under per-interval Gaussian noise, with the shipped
model's look-up (``model-lookup``) as base, with L/value free and held at the base's
(``residual_scale`` 0 for it, as the shipped hyperparameters).

    python experiments/residual_ridge.py [--moves 8] [--offset 0.02] [--noise 0.05]

The cost has a ridge along L = value (docs/model.md §1; docs/results/agents.md, residual
actions): an offset of L/value leaves it. (Residual actions were once offsets of L alone
as an option; they are now always of L/value, :class:`vfgym.space.Relative`.)
"""

from __future__ import annotations

import argparse

import numpy as np

from vfgym.agents import make_env, validation_scenarios

BASE = {"residual": True, "residual_base": "model-lookup", "interval_s": 0.005}
VARIANTS = {
    "L/value free": BASE,
    "L/value held": {**BASE, "residual_scale": [0.25, 0, 0.25, 0.25]},
}


def episode_cost(env, scenario, act) -> float:
    """The scoring path's cost of one episode whose action at step t is ``act(t)``."""
    env.reset(options={"scenario": scenario})
    t = 0
    while True:
        _, _, term, trunc, info = env.step(act(t))
        t += 1
        if term or trunc:
            return float(info["cost"])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--moves", type=int, default=8)
    ap.add_argument("--offset", type=float, default=0.02)
    ap.add_argument("--noise", type=float, default=0.05)
    args = ap.parse_args()
    moves = validation_scenarios(args.moves)
    print(f"mean cost of {args.moves} validation moves, residual on the shipped model")
    print("| action | " + " | ".join(VARIANTS) + " |")
    print("|---|" + "---|" * len(VARIANTS))
    rows: dict[str, list[float]] = {}
    for kw in VARIANTS.values():
        env = make_env("vfgym/VFServo-v0", kw)
        cases = {"zero": lambda t: np.zeros(4)}
        for j, name in enumerate(("value", "L", "k", "Ts/Tf")):
            a = np.zeros(4)
            a[j] = args.offset
            cases[f"{name} {args.offset:+g}"] = lambda t, a=a: a
        rng = np.random.default_rng(0)
        cases[f"noise {args.noise:g}"] = lambda t, rng=rng: np.clip(
            rng.normal(0.0, args.noise, 4), -1.0, 1.0
        )
        for case, act in cases.items():
            cost = np.mean([episode_cost(env, sc, act) for sc in moves])
            rows.setdefault(case, []).append(float(cost))
    for case, costs in rows.items():
        print(f"| {case} | " + " | ".join(f"{c:.3f}" for c in costs) + " |")


if __name__ == "__main__":
    main()
