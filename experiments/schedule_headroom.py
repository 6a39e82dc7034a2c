"""Is there anything for a VFServo-v0 scheduler to gain over the per-move optimum? The
headroom measured without RL: for each of the first ``--moves`` held-out test moves, a
search over schedules that start from the move's optimum (experiments/optima/test.csv)
and change the settings once or twice during the move, scored by the scoring path (a
VFServo-v0 episode with a fixed action sequence, its end-of-episode cost).

    python experiments/schedule_headroom.py [--moves 16] [--evals 600] [--interval-ms 1]
        [--sigma 0.2] [--seed 0] [--show 3]

Each move is one VFServo-v0 env with residual actions on the move's optimum
(``residual_base``: its settings; L's offset of L/value, each action of ±1 moving a
coordinate of :class:`vfgym.space.Relative` an eighth of its range), so the zero action
is the optimum bit for bit. Schedules are piecewise constant: ``P`` pieces, the action
``a_j`` held over the control intervals [s_j, s_{j+1}) with s_0 = 0 and the switch
times s_j a share of the optimum's own episode length (its steps until it settles).
Three searches, each CMA-ES (``cmaes``, ``--evals`` episodes, started at the zero action
with σ ``--sigma`` in action units, the same seed), on the least cost, an infeasible move
paying 10 more:

* fixed: one piece (4 numbers), a fixed setting near the optimum: the control, the
  search's own gain over the optimum, which the optimum's grid (6⁴ points then 8 rounds
  of refinement) may have left;
* 1 switch: two pieces (9 numbers: two actions and a switch time);
* 2 switches: three pieces (14 numbers).

Scheduling's headroom is the schedules' gain over the fixed search's (same optimiser,
budget and start); goal (c) of issue 23 (a scheduler at most the per-move optima's mean
cost) is reachable in principle by the schedules' gain over the optima. ``--show N``
prints the best 2-switch schedule of the N moves where it gains most over the fixed
search: each piece's first interval and its settings.
"""

from __future__ import annotations

import argparse
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from cmaes import CMA

from vfgym import evaluate, random_scenario
from vfgym.envs.servo import VFServoEnv
from vfgym.envs.tune import VFTuneEnv
from vfgym.permove.optima import read_optima

OPTIMA = Path(__file__).resolve().parent / "optima" / "test.csv"
INFEASIBLE = 10.0
"""Added to an infeasible schedule's cost in the search (never in the reported cost)."""


@dataclass(frozen=True)
class Scored:
    """One schedule's scoring-path cost on its move."""

    cost: float
    feasible: bool


class Schedules:
    """Piecewise-constant action schedules on one move, residual on its optimum."""

    def __init__(self, scenario, base, interval_s: float) -> None:
        self.scenario = scenario
        self.base = base
        self.env = VFServoEnv(
            scenario,
            residual=True,
            residual_base=base,
            interval_s=interval_s,
        )
        self.steps = self.episode_steps()

    def run(self, actions: np.ndarray, switches: list[int]) -> Scored:
        """The cost of holding ``actions[j]`` from interval ``switches[j-1]`` on."""
        self.env.reset()
        t = 0
        while True:
            j = int(np.searchsorted(switches, t, side="right"))
            _, _, term, trunc, info = self.env.step(actions[j])
            t += 1
            if term or trunc:
                return Scored(float(info["cost"]), bool(info["feasible"]))

    def episode_steps(self) -> int:
        """The zero schedule's (the optimum's) episode length in intervals."""
        self.env.reset()
        t = 0
        while True:
            _, _, term, trunc, _ = self.env.step(np.zeros(4))
            t += 1
            if term or trunc:
                return t

    def decode(self, x: np.ndarray, pieces: int) -> tuple[np.ndarray, list[int]]:
        """A search point: the ``pieces`` actions, then the switch times' shares."""
        acts = np.clip(x[: 4 * pieces].reshape(pieces, 4), -1.0, 1.0)
        shares = np.sort(np.clip(x[4 * pieces :], 0.0, 1.0))
        return acts, [max(1, round(u * self.steps)) for u in shares]


def fmt(s) -> str:
    """Settings in one line."""
    return (f"value {s.value_rad:.4g} rad, L {s.error_limit_rad:.4g} rad, k {s.k:.4g}, "
            f"Ts/Tf {s.ts_over_tf:.3g}")  # fmt: skip


def search(
    sched: Schedules, pieces: int, evals: int, seed: int, sigma: float
) -> tuple[Scored, np.ndarray]:
    """CMA-ES over ``pieces``-piece schedules from the zero action; the best found."""
    n = 4 * pieces + (pieces - 1)
    mean = np.zeros(n)
    mean[4 * pieces :] = (np.arange(1, pieces) / pieces) if pieces > 1 else []
    lo = np.r_[-np.ones(4 * pieces), np.zeros(pieces - 1)]
    opt = CMA(mean=mean, sigma=sigma, bounds=np.c_[lo, np.ones(n)], seed=seed)
    best, best_x, done = sched.run(np.zeros((1, 4)), []), mean, 0
    while done < evals:
        told = []
        for _ in range(opt.population_size):
            x = opt.ask()
            s = sched.run(*sched.decode(x, pieces))
            told.append((x, s.cost + (0.0 if s.feasible else INFEASIBLE)))
            done += 1
            if (s.feasible, -s.cost) > (best.feasible, -best.cost):
                best, best_x = s, x
        opt.tell(told)
    return best, best_x


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--moves", type=int, default=16)
    ap.add_argument("--evals", type=int, default=600)
    ap.add_argument("--interval-ms", type=float, default=1.0)
    ap.add_argument("--sigma", type=float, default=0.2)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--show", type=int, default=3)
    args = ap.parse_args()
    optima = {o.scenario: o.settings for o in read_optima(OPTIMA)}
    arms = {"fixed": 1, "1 switch": 2, "2 switches": 3}
    rows = []
    shown = []
    t0 = time.perf_counter()
    print("| move | steps | optimum | " + " | ".join(arms) + " |")
    print("|---|---|---|" + "---|" * len(arms))
    for i in range(args.moves):
        sc = random_scenario(i, "test")
        base = optima[sc.name]
        sched = Schedules(sc, base, args.interval_ms * 1e-3)
        zero = sched.run(np.zeros((1, 4)), [])
        ref = evaluate(base, sc)
        assert zero.cost == ref.cost[0, 0], "the zero schedule is not the optimum's cost"
        found = [search(sched, p, args.evals, args.seed + i, args.sigma) for p in arms.values()]
        rows.append([zero, *(f[0] for f in found)])
        shown.append((sched, found[-1][1], len(arms)))
        cells = [f"{s.cost:.4f}{'' if s.feasible else ' (inf.)'}" for s in rows[-1]]
        print(f"| {sc.name} | {sched.steps} | " + " | ".join(cells) + " |", flush=True)
    cost = np.array([[s.cost for s in r] for r in rows])
    feas = np.array([[s.feasible for s in r] for r in rows])
    mean = cost.mean(axis=0)
    print("| mean | | " + " | ".join(f"{m:.4f}" for m in mean) + " |")
    print("| / optima's mean | | " + " | ".join(f"{m / mean[0]:.4f}" for m in mean) + " |")
    print("| / fixed search's mean | | | " + " | ".join(f"{m / mean[1]:.4f}" for m in mean[1:]))
    print("| feasible | | " + " | ".join(f"{int(f)}/{len(rows)}" for f in feas.sum(axis=0)))
    for j, name in enumerate(arms, start=1):
        gain = 1.0 - cost[:, j] / cost[:, 1]
        print(f"{name}: beats the fixed search on {np.sum(cost[:, j] < cost[:, 1] - 1e-12)}"
              f"/{len(rows)} moves (median gain {100 * np.median(gain):.2f} %), "
              f"the optimum on {np.sum(cost[:, j] < cost[:, 0] - 1e-12)}/{len(rows)}")  # fmt: skip
    for i in np.argsort(cost[:, -1] / cost[:, 1])[: args.show]:
        sched, x, pieces = shown[i]
        acts, switches = sched.decode(x, pieces)
        print(f"{sched.scenario.name}: optimum {cost[i, 0]:.4f}, fixed search {cost[i, 1]:.4f}, "
              f"2 switches {cost[i, -1]:.4f}; the optimum settles after {sched.steps} "
              f"intervals")  # fmt: skip
        tune = VFTuneEnv(sched.scenario, residual=True, residual_base=sched.base)
        tune.reset()
        print(f"  the optimum: {fmt(sched.base)}")
        ends = [*switches, None]
        for t, t1, a in zip([0, *switches], ends, acts, strict=True):
            if t != t1:  # an empty piece (two equal switch times) is not shown
                print(f"  from interval {t}: {fmt(tune.settings_of(a))}")
    print(f"{time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
