"""Amortised tuning report: the supervised settings model (default: the one vfgym ships)
and, if given, a VFTune-v0 agent, against the per-move optima and the paper's settings,
on held-out test moves (never seen in training):

    python experiments/amortised_report.py --optima experiments/optima/test.csv --count 48 \
        [--model settings_model.json] [--agent runs/train/NAME/best_model.zip] \
        [--refine 40] [--out runs/amortised-report.yaml]

The optima come from ``python experiments/move_optima.py --split test --count 64 --out
experiments/optima/test.csv`` (a batched grid with local refinement per move). Every cost
is the scoring path's (``vfgym.evaluate``) on the same moves. Per tuner: mean cost, its
ratio to the optima's mean cost, the mean and median per-move gap, moves within 10 %, wins
against the paper's settings, feasible moves. With ``--refine N``: ``vfgym predict
--refine``'s sweep from the model's settings on each move, and the trials it takes to get
within 1 % of the move's optimum (median over the moves; a move never within counts as
more than N).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from vfgym import PAPER_SETTINGS, evaluate, get_scenario
from vfgym.io.runs import write_yaml
from vfgym.moves import LOAD_DISTRIBUTION
from vfgym.permove.optima import read_optima
from vfgym.permove.refine import refine
from vfgym.permove.supervised import PRETRAINED, load_settings_model


def optuna_best(scenario, trials: int, seed: int) -> float:
    """The lowest cost a seeded TPE sweep finds on this one scenario (the paper's settings
    enqueued first); ``scheduling_report.py``'s best fixed settings per move."""
    import optuna

    from vfgym.space import NAMES, suggest

    optuna.logging.set_verbosity(optuna.logging.WARNING)
    study = optuna.create_study(sampler=optuna.samplers.TPESampler(seed=seed))
    study.enqueue_trial({k: getattr(PAPER_SETTINGS, k) for k in NAMES})
    study.optimize(lambda t: float(evaluate(suggest(t), [scenario]).cost[0, 0]), n_trials=trials)
    return float(study.best_value)


def score(settings, scenarios) -> tuple[np.ndarray, np.ndarray]:
    """Cost and feasibility of ``settings[i]`` on ``scenarios[i]`` (vfgym.evaluate)."""
    evs = [evaluate(s, sc) for s, sc in zip(settings, scenarios, strict=True)]
    return np.array([e.cost[0, 0] for e in evs]), np.array([e.feasible[0, 0] for e in evs])


def row(name: str, cost, feas, best, paper) -> dict:
    gap = cost / best - 1.0
    return {
        "tuner": name,
        "mean_cost": float(cost.mean()),
        "ratio_of_means": float(cost.mean() / best.mean()),
        "mean_ratio": float(np.mean(cost / best)),
        "median_gap_pct": float(100 * np.median(gap)),
        "within_10pct": int(np.sum(gap <= 0.10)),
        "beats_paper": int(np.sum(cost < paper)),
        "feasible": int(np.sum(feas)),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--optima", default="experiments/optima/test.csv")
    ap.add_argument("--count", type=int, default=48)
    ap.add_argument("--model", default=str(PRETRAINED), help="a settings model (JSON)")
    ap.add_argument("--also", action="append", default=[], help="another settings model")
    ap.add_argument("--agent", help="a VFTune-v0 agent (stable-baselines3 .zip)")
    ap.add_argument("--refine", type=int, default=0, help="trials of the refinement sweep")
    ap.add_argument("--out", help="write the per-move figures as YAML")
    args = ap.parse_args()

    optima = read_optima(args.optima)[: args.count]
    scenarios = [get_scenario(o.scenario, LOAD_DISTRIBUTION) for o in optima]
    n = len(scenarios)
    best = np.array([o.cost for o in optima])
    paper, paper_feas = score([PAPER_SETTINGS] * n, scenarios)
    model = load_settings_model(args.model)
    t0 = time.perf_counter()
    picks = [model.settings(sc) for sc in scenarios]
    dt = (time.perf_counter() - t0) / n
    sup, sup_feas = score(picks, scenarios)
    rows = [row(f"{type(model).__name__} {Path(args.model).name}", sup, sup_feas, best, paper)]
    per_move = {"scenarios": [o.scenario for o in optima], "optimum_cost": best.tolist()}
    per_move |= {"paper_cost": paper.tolist(), "model_cost": sup.tolist()}
    for path in args.also:
        other = load_settings_model(path)
        c, f = score([other.settings(sc) for sc in scenarios], scenarios)
        rows.append(row(f"{type(other).__name__} {path}", c, f, best, paper))
        per_move[f"cost {path}"] = c.tolist()
    if args.agent:
        from vfgym.agents import policy_settings

        pick = policy_settings(args.agent)
        agent, agent_feas = score([pick(sc) for sc in scenarios], scenarios)
        rows.append(row("agent", agent, agent_feas, best, paper))
        per_move["agent_cost"] = agent.tolist()
    rows.append(row("paper", paper, paper_feas, best, paper))
    reached: list[float] = []
    if args.refine:
        refined, refined_feas = [], []
        for sc, s, b in zip(scenarios, picks, best, strict=True):
            r = refine(sc, s, args.refine)
            refined.append(r.cost)
            refined_feas.append(r.feasible)
            run = np.minimum.accumulate(np.array(r.costs))
            hit = np.flatnonzero(run <= 1.01 * b)
            reached.append(float(hit[0] + 1) if hit.size else np.inf)
        rows.append(
            row(
                f"refined ({args.refine} trials)",
                np.array(refined),
                np.array(refined_feas),
                best,
                paper,
            )
        )
        per_move["refined_cost"] = refined
        per_move["trials_to_1pct"] = reached

    print(f"held-out test moves: {n} ({optima[0].scenario} ... {optima[-1].scenario}); "
          f"optima from {args.optima}; model {args.model} ({1e3 * dt:.2f} ms a move)")  # fmt: skip
    print(f"optimum mean cost {best.mean():.3f}, {int(sum(o.feasible for o in optima))}/{n} "
          "feasible")  # fmt: skip
    head = ("tuner", "mean cost", "/ optimum", "mean ratio", "median gap", "within 10 %",
            "beats paper", "feasible")  # fmt: skip
    print("| " + " | ".join(head) + " |")
    print("|" + " --- |" * len(head))
    for r in rows:
        print(
            f"| {r['tuner']} | {r['mean_cost']:.3f} | {r['ratio_of_means']:.3f}x | "
            f"{r['mean_ratio']:.3f}x | {r['median_gap_pct']:.1f} % | {r['within_10pct']}/{n} | "
            f"{r['beats_paper']}/{n} | {r['feasible']}/{n} |"
        )
    if reached:
        hits = np.array(reached)
        print(
            f"refinement: trials to within 1 % of the optimum: median {np.median(hits):g} "
            f"(within {args.refine} trials on {np.sum(np.isfinite(hits))}/{n} moves; already "
            f"at the prediction on {np.sum(hits == 1)}/{n}; upper quartile "
            f"{np.percentile(hits, 75, method='lower'):g})"
        )
    if args.out:
        write_yaml(args.out, {"summary": rows, "per_move": per_move})


if __name__ == "__main__":
    main()
