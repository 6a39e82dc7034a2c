"""How much of the oracle's gain can a VFServo-v0 scheduler still reach on an uncertain axis,
once it has held the robust base for the first milliseconds? Measured without RL, by a
scheduler that knows the true plant (clairvoyant): an estimate of what online adaptation
could gain on the axis, against which trained agents are read.

    python experiments/adaptive_headroom.py --model FIT/settings_model.json
        [--axis experiments/axes/loads-uncertain.yaml] [--moves 8] [--plants 4]
        [--plant-seed S] [--evals 300] [--interval-ms 1] [--hold-ms 2] [--sigma 0.3]
        [--seed 0]

Pairs: the axis's first ``--moves`` test moves × ``--plants`` true plants drawn within its
uncertainty from ``--plant-seed`` (the verdicts' default seed). Each pair is one VFServo-v0
env on its true plant with residual actions on the move's robust base (``--model``, the
axis's ``vfgym fit`` model, checked across the axis's design plants, as the agents' base),
L/value held at the base's (as the shipped hyperparameters) and each action of ±1 moving a
coordinate of :class:`vfgym.space.Relative` half its range. Schedules are piecewise linear
in the action between knots, scored by the scoring path (the episode's end-of-move cost);
CMA-ES (``cmaes``, ``--evals`` episodes from the zero action, the same seed), an
infeasible episode paying 10 more in the search:

* held: one action from the start (4 numbers): a fixed setting near the base chosen
  knowing the plant, the oracle's kind of gain;
* base, then a ramp: the base until ``--hold-ms`` (the earliest the response can have
  told the plant), then a linear ramp to an action, held after (5 numbers: the action and
  the ramp's length);
* base, then two ramps: the same with a second ramp to a second action (10 numbers).

The schedules' costs are what a scheduler that watches the response could reach at best on
these pairs (a clairvoyant one, starting from the base: an agent's first action need not be
zero, so this is an estimate, not a bound).
"""

from __future__ import annotations

import argparse
import time
from dataclasses import dataclass

import numpy as np
from cmaes import CMA

from vfgym import evaluate
from vfgym.axis import VERDICT_PLANT_SEED, draw_plants, load_axis
from vfgym.envs.servo import VFServoEnv
from vfgym.permove import load_settings_model

INFEASIBLE = 10.0
"""Added to an infeasible schedule's cost in the search (never in the reported cost)."""
SCALE = (1.0, 0.0, 1.0, 1.0)
"""Residual scales: value, L/value (held), k, Ts/Tf; ±1 moves a coordinate half its range."""


@dataclass(frozen=True)
class Scored:
    """One schedule's scoring-path cost on its pair."""

    cost: float
    feasible: bool

    def key(self) -> tuple[bool, float]:
        return (self.feasible, -self.cost)


class Pair:
    """One (move, true plant): a VFServo-v0 env with residual actions on the move's base."""

    def __init__(self, axis, scenario, variant, base, interval_s: float, hold_ms: float):
        self.scenario, self.variant, self.base = scenario, variant, base
        self.env = VFServoEnv(scenario, axis=axis, residual=True, residual_base=base,
                              residual_scale=SCALE, interval_s=interval_s)  # fmt: skip
        self.hold = max(1, round(hold_ms * 1e-3 / interval_s))
        self.steps = self.run(lambda t: np.zeros(4), count=True)

    def run(self, act, count: bool = False):
        """The episode under ``act(t)`` (interval t): its Scored, or its length."""
        self.env.reset(options={"plant": self.variant})
        t = 0
        while True:
            _, _, term, trunc, info = self.env.step(np.clip(act(t), -1.0, 1.0))
            t += 1
            if term or trunc:
                return t if count else Scored(float(info["cost"]), bool(info["feasible"]))

    def schedule(self, x: np.ndarray, ramps: int):
        """``act(t)`` of a search point: ``ramps`` = 0, one held action; else the zero
        action until the hold, then ``ramps`` linear ramps, each an action and a length
        (a share of the base's episode)."""
        if ramps == 0:
            return lambda t: x[:4]
        acts = [np.zeros(4), *x[: 4 * ramps].reshape(ramps, 4)]
        lengths = [max(1.0, u * self.steps) for u in np.clip(x[4 * ramps :], 0.0, 1.0)]
        knots = np.cumsum([float(self.hold), *lengths])

        def act(t: int) -> np.ndarray:
            if t < knots[0]:
                return acts[0]
            for j in range(1, len(knots)):
                if t < knots[j]:
                    w = (t - knots[j - 1]) / (knots[j] - knots[j - 1])
                    return acts[j - 1] + w * (acts[j] - acts[j - 1])
            return acts[-1]

        return act


def search(pair: Pair, ramps: int, evals: int, seed: int, sigma: float) -> Scored:
    """CMA-ES over the schedules from the zero action; the best found (feasible first)."""
    n = 4 * max(ramps, 1) + ramps
    mean = np.r_[np.zeros(4 * max(ramps, 1)), np.full(ramps, 0.2)]
    lo = np.r_[-np.ones(4 * max(ramps, 1)), np.zeros(ramps)]
    opt = CMA(mean=mean, sigma=sigma, bounds=np.c_[lo, np.ones(n)], seed=seed)
    best, done = pair.run(lambda t: np.zeros(4)), 0
    while done < evals:
        told = []
        for _ in range(opt.population_size):
            x = opt.ask()
            s = pair.run(pair.schedule(x, ramps))
            told.append((x, s.cost + (0.0 if s.feasible else INFEASIBLE)))
            done += 1
            best = max(best, s, key=Scored.key)
        opt.tell(told)
    return best


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--axis", default="experiments/axes/loads-uncertain.yaml")
    ap.add_argument("--model", required=True, help="the axis's vfgym fit settings_model.json")
    ap.add_argument("--moves", type=int, default=8)
    ap.add_argument("--plants", type=int, default=4)
    ap.add_argument("--plant-seed", type=int, default=VERDICT_PLANT_SEED)
    ap.add_argument("--evals", type=int, default=300)
    ap.add_argument("--interval-ms", type=float, default=1.0)
    ap.add_argument("--hold-ms", type=float, default=2.0)
    ap.add_argument("--sigma", type=float, default=0.3)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    axis = load_axis(args.axis)
    model = load_settings_model(args.model)
    design = axis.design_plants()
    variants = draw_plants(axis.uncertainty, axis.plant, args.plants, args.plant_seed)
    arms = {"held": 0, "base, ramp": 1, "base, 2 ramps": 2}
    t0 = time.perf_counter()
    print(f"axis {axis.name}, {args.moves} test moves x {args.plants} plants "
          f"(seed {args.plant_seed}), hold {args.hold_ms:g} ms, {args.evals} episodes a "
          "search")  # fmt: skip
    print("| move | plant | steps | base | " + " | ".join(arms) + " |")
    print("|---|---|---|---|" + "---|" * len(arms))
    rows = []
    for sc in axis.scenarios("test")[: args.moves]:
        base = model.settings(sc, axis.plant, axis.measures, design)
        for p, v in enumerate(variants):
            pair = Pair(axis, sc, v, base, args.interval_ms * 1e-3, args.hold_ms)
            zero = pair.run(lambda t: np.zeros(4))
            ref = evaluate(base, [sc], axis=axis, plants=[v]).across
            assert zero.cost == ref.cost[0, 0, 0], "the zero schedule is not the base's cost"
            found = [search(pair, r, args.evals, args.seed, args.sigma) for r in arms.values()]
            rows.append([zero, *found])
            cells = [f"{s.cost:.4f}{'' if s.feasible else ' (inf.)'}" for s in rows[-1]]
            print(f"| {sc.name} | {p} | {pair.steps} | " + " | ".join(cells) + " |", flush=True)
    cost = np.array([[s.cost for s in r] for r in rows])
    feas = np.array([[s.feasible for s in r] for r in rows])
    mean = cost.mean(axis=0)
    print("| mean | | | " + " | ".join(f"{m:.4f}" for m in mean) + " |")
    print("| / base | | | " + " | ".join(f"{m / mean[0]:.4f}" for m in mean) + " |")
    print("| feasible | | | " + " | ".join(f"{int(f)}/{len(rows)}" for f in feas.sum(axis=0)))
    print(f"{time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
