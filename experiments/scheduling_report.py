"""Online gain scheduling report: a VFServo-v0 agent that changes the settings every
control interval, against the best fixed settings for the same moves.

    python experiments/scheduling_report.py --model runs/train/servo-ppo/best_model.zip \
        [--count 16] [--trials 150] [--seed 0]

On the first ``count`` test moves of the environments' distribution (new loads and moves,
never seen in training: :func:`vfgym.random_scenario`, the servo following its load) and
five named scenarios: the
cost of the agent's scheduled move (the scoring path's cost of the whole move, as
VFServo-v0 reports at the end of an episode), of the paper's fixed settings, and of the
best fixed settings a seeded per-scenario TPE sweep finds (``trials`` trials, the paper's
settings first), all from ``vfgym.evaluate``'s cost formula.
"""

from __future__ import annotations

import argparse

import numpy as np
from amortised_report import optuna_best

from vfgym import PAPER_SETTINGS, SCENARIOS, evaluate, random_scenario
from vfgym.agents import load_agent, make_env, rollout_info


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model", required=True)
    ap.add_argument("--count", type=int, default=16)
    ap.add_argument("--trials", type=int, default=150)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()

    pol = load_agent(args.model)  # behind its VecNormalize statistics, if trained so
    env = make_env("vfgym/VFServo-v0", pol.env_kwargs())
    names = ["paper-step", "short-move", "long-move", "heavy-load", "friction"]
    scenarios = [SCENARIOS[n] for n in names]
    scenarios += [random_scenario(seed, "test") for seed in range(args.count)]
    agent = np.array([float(rollout_info(pol, env, sc)["cost"]) for sc in scenarios])
    paper = evaluate(PAPER_SETTINGS, scenarios).cost[0]
    fixed = np.array(
        [optuna_best(sc, args.trials, args.seed + i) for i, sc in enumerate(scenarios)]
    )
    print(f"{'scenario':12s} {'scheduled':>10s} {'best fixed':>10s} {'paper':>8s}")
    for sc, a, f, p in zip(scenarios, agent, fixed, paper, strict=True):
        print(f"{sc.name:12s} {a:10.3f} {f:10.3f} {p:8.3f}")
    win = agent < fixed
    print(
        f"mean cost: scheduled {agent.mean():.3f}, best fixed {fixed.mean():.3f}, "
        f"paper {paper.mean():.3f}"
    )
    print(
        f"scheduling beats the best fixed settings on {win.sum()}/{len(win)} moves; "
        f"beats the paper on {np.sum(agent < paper)}/{len(win)}"
    )


if __name__ == "__main__":
    main()
