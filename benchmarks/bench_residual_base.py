"""What the ``model`` residual base (the shipped settings model with its check on the move)
costs against ``model-lookup`` (its look-up alone): prints figures, asserts nothing.

    python benchmarks/bench_residual_base.py [--moves 200] [--steps 20000] [--repeat 2]
        [--envs VFServo-v0,VFTune-v0] [--batched]

1. The base alone: ms per new move (train-split moves never seen before, so nothing is
   remembered), each spelling through :func:`vfgym.agents.env_options`.
2. PPO with the shipped VFServo-v0 and VFTune-v0 hyperparameters, their ``residual_base``
   set to each spelling: steps/s over ``--steps`` steps after one rollout and update
   outside the timing (compiles), one thread; the two bases alternate ``--repeat`` times
   in this one process, so their ratio is measured under the same load.
3. With ``--batched`` (only): the check of 64 new moves done as the model does it, one
   compiled call per move, against calls of 4, 16 and 64 moves' candidates together
   (:func:`vfgym.scoring.score_pairs`), ms per move: what batching the check across the
   vector env's resets could save.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

SPELLINGS = ("model-lookup", "model")


def per_move_ms(spec: str, moves: int) -> float:
    """ms per new move of the base ``spec``."""
    from vfgym import random_scenario
    from vfgym.agents import env_options
    from vfgym.params import PAPER_PLANT

    base = env_options({"residual_base": spec})["residual_base"]
    base(random_scenario(0, "train"), PAPER_PLANT)  # compiles
    scs = [random_scenario(10_000 + i, "train") for i in range(moves)]
    t = time.perf_counter()
    for sc in scs:
        base(sc, PAPER_PLANT)
    return (time.perf_counter() - t) / moves * 1e3


def batched_ms(moves: int = 64) -> dict[int, float]:
    """ms per move of the check done ``size`` moves to a compiled call (0: the model's own
    call, one move at a time), on ``moves`` new moves."""
    from vfgym import random_scenario
    from vfgym.moves.features import scenario_features
    from vfgym.params import PAPER_PLANT
    from vfgym.permove.supervised import load_settings_model
    from vfgym.permove.targets import target_settings
    from vfgym.scoring import Move, score_pairs

    model = load_settings_model()
    scs = [random_scenario(20_000 + i, "train") for i in range(moves)]
    model.settings(scs[0], PAPER_PLANT)  # compiles

    def candidates(sc):
        loaded = sc.plant(PAPER_PLANT)
        order = model.ranked(scenario_features(sc, PAPER_PLANT, loaded))
        return [target_settings(model.library[j], loaded, model.accel_law)
                for j in order[: model.check]]  # fmt: skip

    out = {}
    t = time.perf_counter()
    for sc in scs:
        model.settings(sc, PAPER_PLANT)
    out[0] = (time.perf_counter() - t) / moves * 1e3
    for size in (4, 16, 64):
        t = time.perf_counter()
        for i in range(0, moves, size):
            cands, pairs = [], []
            for sc in scs[i : i + size]:
                c = candidates(sc)
                cands += c
                pairs += [Move.of(sc, PAPER_PLANT)] * len(c)
            score_pairs(cands, pairs)
        out[size] = (time.perf_counter() - t) / moves * 1e3
    return out


def ppo_steps_per_s(env_id: str, spec: str, steps: int, seed: int) -> float:
    """PPO steps/s with the shipped hyperparameters on ``env_id``, base ``spec``."""
    import torch
    from stable_baselines3 import PPO

    from vfgym.agents import env_options
    from vfgym.agents import hyperparams as hp
    from vfgym.envs.sb3 import make_sb3_vec_env

    torch.set_num_threads(1)
    p = hp.load("ppo", env_id, hp.HYPERPARAMS_DIR / "ppo.yml", {})
    kw = env_options({**p["env_kwargs"], "residual_base": spec})
    venv = make_sb3_vec_env(env_id, n_envs=p["n_envs"], seed=seed, **kw)
    pk = dict(p["policy_kwargs"])
    pk["activation_fn"] = {"tanh": torch.nn.Tanh, "relu": torch.nn.ReLU}[pk["activation_fn"]]
    keys = ("n_steps", "batch_size", "n_epochs", "learning_rate", "gamma", "gae_lambda")
    model = PPO("MlpPolicy", venv, policy_kwargs=pk, seed=seed, device="cpu", verbose=0,
                **{k: p[k] for k in keys})  # fmt: skip
    first = p["n_steps"] * p["n_envs"]
    model.learn(first)
    t = time.perf_counter()
    model.learn(steps, reset_num_timesteps=False)
    return (model.num_timesteps - first) / (time.perf_counter() - t)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--moves", type=int, default=200)
    ap.add_argument("--steps", type=int, default=20_000)
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--envs", default="VFServo-v0,VFTune-v0")
    ap.add_argument("--batched", action="store_true", help="only figure 3")
    args = ap.parse_args()
    if args.batched:
        for size, ms in batched_ms().items():
            how = f"{size} moves a call" if size else "the model's own call, one move"
            print(f"check, {how}: {ms:.2f} ms per move")
        return
    for spec in SPELLINGS:
        print(f"base {spec}: {per_move_ms(spec, args.moves):.2f} ms per new move", flush=True)
    for env_id in (f"vfgym/{e}" for e in args.envs.split(",")):
        rates: dict[str, list[float]] = {s: [] for s in SPELLINGS}
        for r in range(args.repeat):
            for spec in SPELLINGS:
                rates[spec].append(ppo_steps_per_s(env_id, spec, args.steps, r))
                print(f"{env_id} {spec}: {rates[spec][-1]:.0f} steps/s", flush=True)
        a, b = (float(np.mean(rates[s])) for s in SPELLINGS)
        print(f"{env_id}: PPO {a:.0f} steps/s with model-lookup, {b:.0f} with model "
              f"({b / a:.2f}x)")  # fmt: skip


if __name__ == "__main__":
    main()
