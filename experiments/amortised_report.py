"""Amortised tuning report: a VFTune-v0 agent against the paper's baseline and a
per-scenario Optuna best, on held-out test moves (never seen in training).

    python experiments/amortised_report.py --model runs/train/amortised-ppo/best_model.zip \
        [--count 48] [--trials 150] [--seed 0] [--out runs/amortised-report.yaml]

For each of the first ``count`` test scenarios: the settings the agent picks in one
forward pass, the paper's settings, and the best of a small TPE sweep on that scenario
alone (``trials`` trials, the paper's settings enqueued first, seeded), all scored by
``vfgym.evaluate``. Prints mean cost, the agent's win rate against the paper and its gap
to the per-scenario optimum.
"""

from __future__ import annotations

import argparse

import numpy as np
import optuna

from vfgym import PAPER_SETTINGS, evaluate, scenario_set
from vfgym.agents import policy_settings
from vfgym.io.runs import write_yaml
from vfgym.space import NAMES, suggest


def optuna_best(scenario, trials: int, seed: int) -> float:
    """The lowest cost a seeded TPE sweep finds on this one scenario."""
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    study = optuna.create_study(sampler=optuna.samplers.TPESampler(seed=seed))
    study.enqueue_trial({k: getattr(PAPER_SETTINGS, k) for k in NAMES})
    study.optimize(lambda t: float(evaluate(suggest(t), [scenario]).cost[0, 0]), n_trials=trials)
    return float(study.best_value)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model", required=True)
    ap.add_argument("--count", type=int, default=48)
    ap.add_argument("--first-seed", type=int, default=0)
    ap.add_argument("--trials", type=int, default=150)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", help="write the per-scenario figures as YAML")
    args = ap.parse_args()

    scenarios = scenario_set("test", args.count, args.first_seed)
    pick = policy_settings(args.model)
    agent = np.array([float(evaluate(pick(sc), [sc]).cost[0, 0]) for sc in scenarios])
    paper = evaluate(PAPER_SETTINGS, scenarios).cost[0]
    best = np.array(
        [
            min(optuna_best(sc, args.trials, args.seed + i), a)
            for i, (sc, a) in enumerate(zip(scenarios, agent, strict=True))
        ]
    )
    gap = agent / best - 1.0
    win = agent < paper
    print(
        f"held-out test moves: {len(scenarios)} (test-{args.first_seed} ... "
        f"test-{args.first_seed + len(scenarios) - 1}); model {args.model}"
    )
    print(
        f"mean cost   agent {agent.mean():.3f}   paper {paper.mean():.3f}   "
        f"per-scenario Optuna ({args.trials} TPE trials) {best.mean():.3f}"
    )
    print(
        f"median cost agent {np.median(agent):.3f}   paper {np.median(paper):.3f}   "
        f"Optuna {np.median(best):.3f}"
    )
    print(f"agent beats the paper on {win.sum()}/{len(win)} moves ({100 * win.mean():.0f} %)")
    print(
        f"agent / Optuna mean cost: {agent.mean() / best.mean():.3f}; per move, median gap "
        f"{100 * np.median(gap):.1f} %, within 10 % on {np.sum(gap <= 0.10)}/{len(gap)}"
    )
    if args.out:
        write_yaml(
            args.out,
            {
                "model": args.model,
                "trials": args.trials,
                "scenarios": [s.name for s in scenarios],
                "agent_cost": agent.tolist(),
                "paper_cost": paper.tolist(),
                "optuna_cost": best.tolist(),
            },
        )


if __name__ == "__main__":
    main()
