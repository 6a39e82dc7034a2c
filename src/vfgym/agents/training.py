"""Training stable-baselines3 agents on the vfgym environments, one run folder per run.

A run folder (``runs/train/<name>/``) holds ``config.yaml`` (the resolved
hyperparameters, algorithm, env, seed), ``command.txt``, TensorBoard logs (``tb/``),
checkpoints (``checkpoints/model_<steps>_steps.zip`` and, for off-policy algorithms, the
replay buffer), ``best_model.zip`` chosen on held-out scenarios by
:class:`HeldOutEval` (``evaluations.csv`` logs every evaluation; ``best_model_costs.json``
holds the best's cost on each validation scenario) and ``final_model.zip``.
Starting the same run again continues from its last checkpoint; an interrupt (Ctrl-C)
saves a checkpoint first, so nothing trained is lost.

Held-out scenarios and the rule that picks the best model: :mod:`vfgym.agents.selection`.
"""

from __future__ import annotations

import json
import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from vfgym._validate import check_int
from vfgym.axis import Axis
from vfgym.io.runs import read_yaml, write_text, write_yaml
from vfgym.moves.scenarios import Scenario

from .hyperparams import POLICIES, algo_class
from .loaded import (
    SERVO_OBSERVATION,
    Agent,
    acting_kwargs,
    check_observation,
    env_options,
    make_env,
    rollout_info,
    vecnormalize_path,
)
from .selection import (
    BEST_COSTS,
    MIN_GAIN,
    SIGNIFICANCE,
    append_eval,
    beats,
    best_is_start,
    best_so_far,
    validation_plants,
    validation_scenarios,
    validation_size,
)


def _activation(name: str) -> Any:
    import torch

    return {
        "tanh": torch.nn.Tanh,
        "relu": torch.nn.ReLU,
        "elu": torch.nn.ELU,
        "leaky_relu": torch.nn.LeakyReLU,
    }[name]


def rollout_cost(
    model: Any, env: Any, scenario: Scenario, normalizer: Any = None, plant: Any = None
) -> dict[str, Any]:
    """Run the policy (deterministic) on one scenario (on the true ``plant``, if given),
    its observations through ``normalizer`` (a ``VecNormalize``) if given; the scoring
    path's info at the end."""
    return rollout_info(Agent(model, {}, normalizer, ""), env, scenario, plant)


def evaluate_policy_costs(
    model: Any,
    env: Any,
    scenarios: list[Scenario],
    normalizer: Any = None,
    plants: list[Any] | None = None,
) -> np.ndarray:
    """The scoring path's cost of the policy on each scenario (each on its true plant of
    ``plants``, if given), and whether the move was feasible: a (2, scenarios) array."""
    on = plants or [None] * len(scenarios)
    infos = [
        rollout_cost(model, env, sc, normalizer, p) for sc, p in zip(scenarios, on, strict=True)
    ]
    return np.array([[float(i["cost"]) for i in infos], [float(i["feasible"]) for i in infos]])


def _callbacks(
    run: Path,
    params: dict[str, Any],
    env_id: str,
    n_envs: int,
    progress: bool,
    total: int,
    axis: Axis,
    normalizer: Any,
) -> list[Any]:
    from stable_baselines3.common.callbacks import BaseCallback, CheckpointCallback

    class HeldOutEval(BaseCallback):
        """Every ``eval_freq`` steps: mean cost on the held-out scenarios; the best model
        is saved as ``best_model.zip``, every evaluation logged to ``evaluations.csv``."""

        def __init__(self, freq: int, scenarios: list[Scenario], plants: list[Any]) -> None:
            super().__init__()
            self.freq, self.scenarios, self.plants = freq, scenarios, plants
            self.env = make_env(env_id, acting_kwargs(params))
            self.best, self.best_costs, self.best_ok = best_so_far(run)
            self.next_at = 0

        def _on_step(self) -> bool:
            if self.num_timesteps >= self.next_at:
                self.next_at = self.num_timesteps + self.freq
                costs, feasible = evaluate_policy_costs(
                    self.model, self.env, self.scenarios, normalizer, self.plants
                )
                mean = float(np.mean(costs))
                self.logger.record("eval/mean_cost", mean)
                # written now, at this step: the next dump (a rollout's end) comes later
                # and TensorBoard would give the cost that step, not evaluations.csv's
                self.logger.dump(self.num_timesteps)
                if self.best_costs is None and np.isfinite(self.best):
                    new = mean < self.best  # (a run continued from before the costs were kept)
                else:
                    new = beats(costs, self.best_costs, SIGNIFICANCE, feasible, self.best_ok)
                if new:
                    self.best, self.best_costs, self.best_ok = mean, costs, feasible
                    self.model.save(run / "best_model.zip")
                    doc = {"cost": costs.tolist(), "feasible": [bool(f) for f in feasible]}
                    write_text(run / BEST_COSTS, json.dumps(doc))
                    if normalizer is not None:
                        normalizer.save(str(vecnormalize_path(run / "best_model.zip")))
                append_eval(run, self.num_timesteps, mean, float(np.median(costs)), new)
            return True

    class Progress(BaseCallback):
        """A tqdm bar over the timesteps, with the best held-out cost so far."""

        def __init__(self, evaluator: Any) -> None:
            super().__init__()
            self.evaluator = evaluator

        def _on_training_start(self) -> None:
            from tqdm.auto import tqdm

            self.bar = tqdm(
                total=_final_steps(self.model, total),
                initial=self.model.num_timesteps,
                unit="step",
                desc="train",
                dynamic_ncols=True,
            )

        def _on_step(self) -> bool:
            if np.isfinite(self.evaluator.best):
                self.bar.set_postfix(best_cost=f"{self.evaluator.best:.3f}", refresh=False)
            if self.model.num_timesteps > self.bar.total:  # an off-policy run's last steps
                self.bar.total = self.model.num_timesteps
            self.bar.update(self.model.num_timesteps - self.bar.n)  # redraws at most 10/s
            return True

        def _on_training_end(self) -> None:
            self.bar.close()

    n_eval = validation_size(params, axis)
    evaluator = HeldOutEval(
        params.get("eval_freq", 10_000),
        validation_scenarios(n_eval, axis),
        validation_plants(n_eval, axis),
    )
    ckpt = CheckpointCallback(
        save_freq=max(1, params.get("checkpoint_freq", 20_000) // n_envs),
        save_path=str(run / "checkpoints"),
        name_prefix="model",
        save_replay_buffer=True,
        save_vecnormalize=True,
    )
    cbs = [ckpt, evaluator]
    if progress:
        cbs.append(Progress(evaluator))
    return cbs


def _final_steps(model: Any, total: int) -> int:
    """The step count ``model.learn`` ends at for ``total`` timesteps: an on-policy
    algorithm collects whole rollouts of ``n_steps`` steps on each env, so it ends at the
    first multiple of a rollout at or past ``total`` (20 224 for 20 000 with 8 steps on 32
    envs); otherwise ``total``, which the bar grows past if a last step overruns it."""
    start = model.num_timesteps
    rollout = getattr(model, "n_steps", 0) * getattr(model, "n_envs", 1)
    if rollout <= 0 or total <= start:
        return max(total, start)
    return start + -(-(total - start) // rollout) * rollout


def latest_checkpoint(run: Path) -> tuple[Path, int] | None:
    """The newest ``checkpoints/model_<steps>_steps.zip`` and its step count."""
    best = None
    for p in (run / "checkpoints").glob("model_*_steps.zip"):
        m = re.fullmatch(r"model_(\d+)_steps\.zip", p.name)
        if m and (best is None or int(m.group(1)) > best[1]):
            best = (p, int(m.group(1)))
    return best


def _save_checkpoint(model: Any, run: Path, normalizer: Any) -> None:

    steps = model.num_timesteps
    path = run / "checkpoints" / f"model_{steps}_steps.zip"
    path.parent.mkdir(parents=True, exist_ok=True)
    model.save(path)
    if normalizer is not None:
        normalizer.save(str(vecnormalize_path(path)))
    if hasattr(model, "save_replay_buffer") and getattr(model, "replay_buffer", None):
        model.save_replay_buffer(run / "checkpoints" / f"model_replay_buffer_{steps}_steps.pkl")


def check_same_run(
    run: Path, algo: str, env_id: str, seed: int, env_kwargs: dict[str, Any] | None = None
) -> None:
    """A run folder that already holds a run must hold one of the same algorithm, env,
    seed and env arguments (the problem: axis, base, intervals), which is then continued;
    otherwise ``ValueError`` (a run on another problem is never continued as this one)."""
    old = Path(run) / "config.yaml"
    if not old.is_file():
        return
    prev = read_yaml(old)
    prev = prev if isinstance(prev, dict) else {}
    for key, value in (("algo", algo), ("env", env_id), ("seed", seed)):
        if prev.get(key) != value:
            raise ValueError(
                f"{run}: holds a run with {key}={prev.get(key)!r}, not {value!r}; "
                "choose another --name"
            )
    check_observation(prev, str(run))
    old_kw = (prev.get("hyperparams") or {}).get("env_kwargs") or {}
    if env_kwargs is not None and "hyperparams" in prev and old_kw != env_kwargs:
        keys = sorted(
            k for k in set(old_kw) | set(env_kwargs) if old_kw.get(k) != env_kwargs.get(k)
        )
        raise ValueError(
            f"{run}: holds a run with other env_kwargs ({', '.join(keys)}: "
            f"{', '.join(f'{k}={old_kw.get(k)!r}' for k in keys)}); choose another --name"
        )


def use_threads(n: int) -> None:
    """Run this process's training on ``n`` threads: torch's intra-op threads
    (``torch.set_num_threads``) and numba's threads of the calling thread
    (``numba.set_num_threads``, at most the ``NUMBA_NUM_THREADS`` numba started with),
    which simulate VFTune-v0's moves and vector envs from 512 envs. torch's inter-op
    threads are left alone (as rl-zoo3's ``--num-threads``).

    Parameters
    ----------
    n : int
        Threads, ≥ 1.
    """
    import numba
    import torch

    torch.set_num_threads(n)
    numba.set_num_threads(min(n, numba.config.NUMBA_NUM_THREADS))


def train(
    algo: str,
    env_id: str,
    params: dict[str, Any],
    run: Path,
    *,
    seed: int = 0,
    device: str = "cpu",
    progress: bool = True,
    log: Callable[[str], None] = print,
    threads: int | None = None,
) -> Any:
    """Train (or continue) the run in ``run``; returns the trained model.

    ``params`` are validated hyperparameters (:func:`vfgym.agents.hyperparams.load`). A
    run folder that already holds a config must hold the same algorithm, env and seed.
    ``threads``: :func:`use_threads` first (``vfgym train --threads``, default 1 there);
    ``None`` keeps the thread counts the caller set. The run's ``config.yaml`` records
    the threads it trained on.
    """
    from stable_baselines3.common.noise import NormalActionNoise

    from vfgym.envs.sb3 import make_sb3_vec_env

    cls = algo_class(algo)
    if threads is not None:
        use_threads(check_int("threads", threads, 1))
    import torch

    config = {
        "algo": algo,
        "env": env_id,
        "seed": seed,
        "device": device,
        "threads": torch.get_num_threads(),
        "hyperparams": params,
    }
    if env_id == "vfgym/VFServo-v0":
        config["observation"] = SERVO_OBSERVATION
    check_same_run(run, algo, env_id, seed, params.get("env_kwargs") or {})
    write_yaml(run / "config.yaml", config)

    n_envs = int(params.get("n_envs", 1))
    total = int(params.get("n_timesteps", 10_000))
    env_kwargs = dict(params.get("env_kwargs") or {})
    options = env_options(env_kwargs)  # the axis resolved here, once
    venv = make_sb3_vec_env(env_id, n_envs=n_envs, seed=seed, **options)
    venv, normalizer = _wrap(venv, params, cls, latest_checkpoint(run))
    kwargs = {
        k: v
        for k, v in params.items()
        if k
        not in (
            "n_envs",
            "n_timesteps",
            "policy",
            "policy_kwargs",
            "env_kwargs",
            "eval_env_kwargs",
            "action_noise_std",
            "eval_freq",
            "n_eval_scenarios",
            "n_eval_scenarios_uncertain",
            "checkpoint_freq",
            "normalize",
        )
    }
    pk = dict(params.get("policy_kwargs") or {})
    if "activation_fn" in pk:
        pk["activation_fn"] = _activation(pk["activation_fn"])
    if "action_noise_std" in params:
        dim = venv.action_space.shape[0]
        kwargs["action_noise"] = NormalActionNoise(
            np.zeros(dim), params["action_noise_std"] * np.ones(dim)
        )
    ckpt = latest_checkpoint(run)
    if ckpt is not None:
        path, steps = ckpt
        log(f"continuing {run} from {path.name} ({steps} steps)")
        model = cls.load(
            path,
            env=venv,
            device=device,
            tensorboard_log=str(run / "tb"),
            **({"action_noise": kwargs["action_noise"]} if "action_noise" in kwargs else {}),
        )
        buf = run / "checkpoints" / f"model_replay_buffer_{steps}_steps.pkl"
        if buf.is_file() and hasattr(model, "load_replay_buffer"):
            model.load_replay_buffer(buf)
    else:
        model = cls(
            params.get("policy", POLICIES[algo]),
            venv,
            policy_kwargs=pk or None,
            tensorboard_log=str(run / "tb"),
            seed=seed,
            device=device,
            verbose=0,
            **kwargs,
        )
        if env_kwargs.get("residual"):
            start_at_base(model)
    remaining = total - model.num_timesteps
    if remaining > 0:
        cbs = _callbacks(run, params, env_id, n_envs, progress, total, options["axis"], normalizer)
        try:
            model.learn(
                remaining, callback=cbs, reset_num_timesteps=ckpt is None, tb_log_name="run"
            )
        except KeyboardInterrupt:
            _save_checkpoint(model, run, normalizer)
            raise
        _save_checkpoint(model, run, normalizer)

    for name in ("final_model.zip", "best_model.zip"):
        if name == "best_model.zip" and (run / name).is_file():
            continue
        model.save(run / name)
        if normalizer is not None:
            normalizer.save(str(vecnormalize_path(run / name)))
    venv.close()
    if best_is_start(run):
        start = "its residual base itself" if env_kwargs.get("residual") else "the untrained policy"
        log(
            "no later model beat the start on the validation pairs (feasible wherever it is, "
            f"cheaper by {SIGNIFICANCE:g} standard errors and {100 * MIN_GAIN:g} %): "
            f"best_model.zip is the start, {start}"
        )
    from .heldout import heldout_result

    result = heldout_result(run / "best_model.zip", params)
    log(result.text())
    write_yaml(run / "heldout.yaml", result.as_dict())
    if env_kwargs.get("axis"):  # an axis file: the verdict vfgym fit gives
        _agent_verdict(run, options["axis"], log)
    return model


def _agent_verdict(run: Path, axis: Axis, log: Callable[[str], None]) -> None:
    """On an axis, the verdict ``vfgym fit`` gives a settings model, for the run's best
    model: printed, and written to ``verdict.txt`` and ``summary.yaml`` as fit writes them."""
    from vfgym.report import format_verdict
    from vfgym.space import settings_to_dict

    from .heldout import agent_verdict

    v, fixed = agent_verdict(run / "best_model.zip", axis)
    text = format_verdict(v, per_move=True)
    write_text(run / "verdict.txt", text + "\n")
    write_yaml(
        run / "summary.yaml", {"best_fixed": settings_to_dict(fixed), "verdict": v.to_dict()}
    )
    log(text)


def start_at_base(model: Any) -> None:
    """Zero the last layer of the policy's action output (PPO's ``action_net``, SAC's and
    TD3's ``actor.mu``), so that the untrained policy's deterministic action is 0: with
    residual actions, exactly the base setting (residual policy learning, Silver et al.
    2018). The layer still learns: its gradient is the hidden activations'.

    Parameters
    ----------
    model : PPO, SAC, TD3 or RecurrentPPO
        A freshly made model.
    """
    import torch

    policy = model.policy
    head = policy.action_net if hasattr(policy, "action_net") else model.actor.mu
    linear = [m for m in head.modules() if isinstance(m, torch.nn.Linear)][-1]
    with torch.no_grad():
        linear.weight.zero_()
        linear.bias.zero_()
    if getattr(model, "actor_target", None) is not None:
        model.actor_target.load_state_dict(model.actor.state_dict())


def _wrap(venv: Any, params: dict[str, Any], cls: Any, ckpt: tuple[Path, int] | None) -> Any:
    """The training env in ``VecMonitor`` (episode returns and lengths for TensorBoard's
    ``rollout/ep_rew_mean``) and, with ``normalize``, in ``VecNormalize`` (its gamma the
    agent's; continued from the checkpoint's statistics): (env, the VecNormalize or None)."""
    import inspect

    from stable_baselines3.common.vec_env import VecMonitor, VecNormalize

    venv = VecMonitor(venv)
    norm = params.get("normalize", False)
    if not norm:
        return venv, None

    if ckpt is not None and vecnormalize_path(ckpt[0]).is_file():
        normalizer = VecNormalize.load(str(vecnormalize_path(ckpt[0])), venv)
        normalizer.training = True
        return normalizer, normalizer
    gamma = params.get("gamma", inspect.signature(cls.__init__).parameters["gamma"].default)
    kw = norm if isinstance(norm, dict) else {}
    normalizer = VecNormalize(venv, gamma=gamma, **kw)
    return normalizer, normalizer
