"""How far a residual VFServo-v0 agent's deterministic action has moved from zero (its
base) at each checkpoint of a training run: the mean and the largest magnitude, per
action coordinate (value, L, k, Ts/Tf), over every control interval of the first
``--moves`` held-out test moves, with the mean cost of those moves. A drift that grows on
a coordinate whose ``residual_scale`` is 0 (L with ``[0.25, 0, 0.25, 0.25]``: its action
changes nothing) is the critic's gradient on an action it cannot have learnt, followed by
the actor.

    python experiments/action_drift.py RUN [RUN ...] [--moves 8]

RUN is a ``vfgym train`` run folder with checkpoints (``checkpoints/model_<N>_steps.zip``
and their ``VecNormalize`` statistics).
"""

from __future__ import annotations

import argparse
import re
from pathlib import Path

import numpy as np

from vfgym import random_scenario
from vfgym.agents import load_agent, make_env


def drift(model: Path, moves: int) -> tuple[np.ndarray, np.ndarray, float]:
    """(mean action, largest |action| per coordinate, mean cost) of the agent saved at
    ``model`` over every interval of the held-out moves ``test-0`` … ``test-<moves-1>``."""
    agent = load_agent(model)
    env = make_env(agent.env_id, agent.env_kwargs())
    actions, costs = [], []
    for i in range(moves):
        obs, _ = env.reset(options={"scenario": random_scenario(i, "test")})
        while True:
            a = agent.act(obs)
            actions.append(a)
            obs, _, terminated, truncated, info = env.step(a)
            if terminated or truncated:
                costs.append(float(info["cost"]))
                break
    env.close()
    acts = np.asarray(actions)
    return acts.mean(axis=0), np.abs(acts).max(axis=0), float(np.mean(costs))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", nargs="+")
    ap.add_argument("--moves", type=int, default=8)
    args = ap.parse_args()
    for run in map(Path, args.runs):
        ckpts = sorted(
            (run / "checkpoints").glob("model_*_steps.zip"),
            key=lambda p: int(re.findall(r"\d+", p.stem)[0]),
        )
        print(f"{run} (mean action value, L, k, Ts/Tf | largest |action| | mean cost):")
        for path in ckpts:
            mean, peak, cost = drift(path, args.moves)
            steps = int(re.findall(r"\d+", path.stem)[0])
            print(f"  {steps:>7}: {np.array2string(mean, precision=3, sign=' ')} | "
                  f"{np.array2string(peak, precision=3)} | {cost:.4f}", flush=True)  # fmt: skip


if __name__ == "__main__":
    main()
