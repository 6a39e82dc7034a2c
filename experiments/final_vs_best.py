"""Where a training run's last policy stands against its best model (for a residual run
whose best model is its base: what the agent learnt and where it loses): both judged on
the first ``--moves`` held-out test moves as ``benchmarks/bench_agents.py`` judges an
agent, move by move.

    python experiments/final_vs_best.py RUN [RUN ...] [--moves 64]

RUN is a ``vfgym train`` run folder (``best_model.zip`` and ``final_model.zip``, each
with its ``VecNormalize`` statistics). Prints per run: both mean costs, their ratio, the
median of the per-move ratios, on how many moves the final policy is better or worse,
and its best and worst per-move ratio.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
import bench_agents

from vfgym.agents import agent_policy
from vfgym.report import Candidate, compare


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", nargs="+")
    ap.add_argument("--moves", type=int, default=64)
    args = ap.parse_args()
    scenarios, _, _ = bench_agents.baselines(args.moves)
    for run in map(Path, args.runs):
        cands = [
            Candidate(k, policy=agent_policy(run / f"{k}_model.zip")) for k in ("best", "final")
        ]
        rep = compare(cands, [], scenarios, resamples=1)
        best, final = rep.column("best").cost, rep.column("final").cost
        r = final / best
        print(f"{run}: best {best.mean():.4f}, final {final.mean():.4f} "
              f"({final.mean() / best.mean():.4f}x); median ratio {np.median(r):.4f}; final "
              f"better on {np.sum(r < 1 - 1e-9)}/{len(r)}, worse on {np.sum(r > 1 + 1e-9)}; "
              f"per move {r.min():.4f} to {r.max():.4f}", flush=True)  # fmt: skip


if __name__ == "__main__":
    main()
