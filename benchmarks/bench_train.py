"""Training throughput: prints figures, asserts nothing (machines are noisy).

PPO with the shipped hyperparameters (vfgym/agents/hyperparams_files/ppo.yml: VFServo-v0 16 envs ×
128 steps, VFTune-v0 32 envs × 8 steps, a 64-64 tanh MLP, CPU), on one thread as
``vfgym train --threads 1`` runs it (``--threads N``: as ``vfgym train --threads N``,
torch's and numba's threads); each measurement in a fresh process, after one rollout and
update outside the timing (compiles, first allocations). Figures:

1. PPO steps/s on VFServo-v0 alone, then two such trainings side by side (started
   together): each one's steps/s and its ratio to alone (target ≥ 0.45x each).
2. The environment's share of PPO's wall time (the SB3 vector env's ``step_wait``) on
   VFServo-v0 and VFTune-v0 (target ≤ 10 % on both), and the compiled simulation's share
   within it (VFTune-v0: :func:`vfgym.plant._kernel.run_batch`).

With ``--compare SRC`` every measurement runs also on another source tree (its
``src`` folder, e.g. an older commit exported by ``git archive``), each measurement on
both trees before the next, so that before/after ratios come from one run.

    python benchmarks/bench_train.py [--steps-servo N] [--steps-tune N] [--threads N]
                                     [--compare SRC] [--share-only]

``--share-only`` skips the side-by-side runs (figure 1's second half).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

HYPERPARAMS = Path(__file__).resolve().parents[1] / "agents" / "hyperparams" / "ppo.yml"
PPO_KEYS = ("n_steps", "batch_size", "n_epochs", "learning_rate", "gamma", "gae_lambda")


def child(env_id: str, steps: int, threads: int = 1) -> dict:
    """PPO on ``env_id`` for ``steps`` steps in this process: steps/s, the env's share of
    the wall time, and the compiled simulation's share (VFTune-v0's batched kernel)."""
    import numba
    import torch
    from stable_baselines3 import PPO

    from vfgym.agents import hyperparams as hp
    from vfgym.envs.sb3 import SB3VecEnv, make_sb3_vec_env
    from vfgym.plant import _kernel as K
    from vfgym.plant._layout import A_TICKS

    torch.set_num_threads(threads)  # as vfgym train --threads N
    numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))
    params = hp.load("ppo", env_id, HYPERPARAMS, {})
    spent = {"env": 0.0, "kernel": 0.0, "ticks": 0.0}

    def timed(key, fn):
        def run(*a, **kw):
            t = time.perf_counter()
            try:
                return fn(*a, **kw)
            finally:
                spent[key] += time.perf_counter() - t

        return run

    SB3VecEnv.step_wait = timed("env", SB3VecEnv.step_wait)  # type: ignore[method-assign]
    run_batch = timed("kernel", K.run_batch)

    def counted(*args):  # the last argument: the accumulator rows, ticks among them
        run_batch(*args)
        spent["ticks"] += float(args[-1][:, A_TICKS].sum())

    K.run_batch = counted
    venv = make_sb3_vec_env(env_id, n_envs=params["n_envs"], seed=0)
    pk = dict(params["policy_kwargs"])
    pk["activation_fn"] = {"tanh": torch.nn.Tanh, "relu": torch.nn.ReLU}[pk["activation_fn"]]
    model = PPO(
        params["policy"],
        venv,
        policy_kwargs=pk,
        seed=0,
        device="cpu",
        verbose=0,
        ent_coef=params.get("ent_coef", 0.0),
        **{k: params[k] for k in PPO_KEYS},
    )
    model.learn(params["n_steps"] * params["n_envs"])  # compiles, allocations
    spent.update(env=0.0, kernel=0.0, ticks=0.0)
    t = time.perf_counter()
    model.learn(steps, reset_num_timesteps=False)
    wall = time.perf_counter() - t
    done = model.num_timesteps - params["n_steps"] * params["n_envs"]
    return {
        "steps_per_s": done / wall,
        "env_share": spent["env"] / wall,
        "kernel_share": spent["kernel"] / wall,
        "kernel_mticks_per_s": spent["ticks"] / spent["kernel"] / 1e6 if spent["ticks"] else 0.0,
    }


def spawn(env_id: str, steps: int, src: str | None, threads: int = 1) -> subprocess.Popen:
    env = dict(os.environ)
    if src is not None:
        env["PYTHONPATH"] = src
    return subprocess.Popen(
        [sys.executable, __file__, "--child", env_id, str(steps), str(threads)],
        env=env,
        stdout=subprocess.PIPE,
        text=True,
    )


def result(p: subprocess.Popen) -> dict:
    out, _ = p.communicate()
    if p.returncode != 0:
        raise SystemExit(f"a measurement failed (exit status {p.returncode})")
    return json.loads(out.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps-servo", type=int, default=32768, help="timed VFServo-v0 steps")
    ap.add_argument("--steps-tune", type=int, default=8192, help="timed VFTune-v0 steps")
    ap.add_argument("--threads", type=int, default=1, help="as vfgym train --threads")
    ap.add_argument("--compare", metavar="SRC", help="also measure this source tree's src")
    ap.add_argument("--share-only", action="store_true", help="skip the side-by-side runs")
    ap.add_argument("--child", nargs=3, metavar=("ENV", "STEPS", "N"), help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        print(json.dumps(child(args.child[0], int(args.child[1]), int(args.child[2]))))
        return
    if args.threads < 1:
        ap.error(f"--threads={args.threads} is out of range: allowed whole numbers >= 1")
    n = args.threads
    load = ", ".join(f"{x:.2f}" for x in os.getloadavg())
    print(
        f"{os.cpu_count()} CPUs, load average {load}; PPO, shipped hyperparameters, "
        f"{n} thread{'s' if n > 1 else ''}"
    )
    trees = [("this tree", None)]
    if args.compare:
        trees.append((f"--compare {args.compare}", str(Path(args.compare) / "src")))
    servo, tune = "vfgym/VFServo-v0", "vfgym/VFTune-v0"
    alone, both, t = {}, {}, {}
    for label, src in trees:  # each measurement on every tree before the next one
        alone[label] = result(spawn(servo, args.steps_servo, src, n))
    for label, src in trees:
        if args.share_only:
            both[label] = []
            continue
        pair = [spawn(servo, args.steps_servo, src, n) for _ in range(2)]
        both[label] = [result(p) for p in pair]
    for label, src in trees:
        t[label] = result(spawn(tune, args.steps_tune, src, n))
    for label, _ in trees:
        a = alone[label]["steps_per_s"]
        print(f"{label}:")
        print(f"  VFServo-v0 PPO alone        : {a:8.0f} steps/s")
        for i, r in enumerate(both[label]):
            s = r["steps_per_s"]
            print(
                f"  two side by side, run {i + 1}   : {s:8.0f} steps/s = {s / a:.2f}x alone"
                "   (target >= 0.45x)"
            )
        print(
            f"  env share of PPO wall time : VFServo-v0 {alone[label]['env_share']:.1%}, "
            f"VFTune-v0 {t[label]['env_share']:.1%} (target <= 10 %)"
        )
        print(
            f"  VFTune-v0 PPO              : {t[label]['steps_per_s']:8.0f} steps/s; its "
            f"compiled simulation {t[label]['kernel_share']:.1%} of the wall time, at "
            f"{t[label]['kernel_mticks_per_s']:.1f} M ticks/s"
        )
    if args.compare:
        this, other = (label for label, _ in trees)
        ratio = t[this]["steps_per_s"] / t[other]["steps_per_s"]
        print(f"VFTune-v0 PPO steps/s, this tree / {other}: {ratio:.2f}x")


if __name__ == "__main__":
    main()
