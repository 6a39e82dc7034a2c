"""Hyperparameters in YAML, rl-baselines3-zoo style: one file per algorithm under
``agents/hyperparams/``, one section per environment id, overridable from the command line.

Everything is checked before any training starts: unknown keys, values of the wrong type,
unknown algorithms and environments raise ``ValueError`` naming the file, the key and what
is allowed.
"""

from __future__ import annotations

import inspect
from pathlib import Path
from typing import Any

import yaml

from vfgym.io.runs import read_yaml

ALGOS = ("ppo", "sac", "td3")
ENV_IDS = ("vfgym/VFTune-v0", "vfgym/VFServo-v0")

# keys that are not constructor arguments of the algorithm
RUN_KEYS: dict[str, tuple[type, ...]] = {
    "n_envs": (int,),
    "n_timesteps": (int, float),
    "policy": (str,),
    "policy_kwargs": (dict,),
    "env_kwargs": (dict,),
    "action_noise_std": (int, float),
    "eval_freq": (int,),
    "n_eval_scenarios": (int,),
    "checkpoint_freq": (int,),
}
# constructor arguments the run sets itself
RESERVED = {
    "self",
    "policy",
    "env",
    "tensorboard_log",
    "verbose",
    "seed",
    "device",
    "_init_setup_model",
    "action_noise",
    "policy_kwargs",
}
POLICY_KWARGS = {
    "net_arch": (list, dict),
    "activation_fn": (str,),
    "log_std_init": (int, float),
    "ortho_init": (bool,),
    "squash_output": (bool,),
    "n_critics": (int,),
}
ACTIVATIONS = ("tanh", "relu", "elu", "leaky_relu")
HYPERPARAMS_DIR = Path(__file__).resolve().parents[3] / "agents" / "hyperparams"


def algo_class(algo: str) -> Any:
    """The stable-baselines3 class of an algorithm name."""
    if algo not in ALGOS:
        raise ValueError(f"algo={algo!r} is not known: choose one of {', '.join(ALGOS)}")
    import stable_baselines3 as sb3

    return {"ppo": sb3.PPO, "sac": sb3.SAC, "td3": sb3.TD3}[algo]


def _allowed_types(default: Any) -> tuple[type, ...] | None:
    if default is inspect.Parameter.empty or default is None:
        return None
    if isinstance(default, bool):
        return (bool,)
    if isinstance(default, int):
        return (int,)
    if isinstance(default, float):
        return (int, float)
    if isinstance(default, str):
        return (str,)
    if isinstance(default, tuple):
        return (tuple, list, int)
    return None


def _check_type(where: str, key: str, value: Any, types: tuple[type, ...] | None) -> None:
    if types is None:
        return
    ok = isinstance(value, types) and not (isinstance(value, bool) and bool not in types)
    if not ok:
        names = " or ".join(t.__name__ for t in types)
        raise ValueError(f"{where}: {key}={value!r} has the wrong type: expected {names}")


def validate(algo: str, params: dict[str, Any], where: str) -> dict[str, Any]:
    """Check keys and value types of one environment's hyperparameters."""
    cls = algo_class(algo)
    sig = inspect.signature(cls.__init__).parameters
    for key, value in params.items():
        if key in RUN_KEYS:
            _check_type(where, key, value, RUN_KEYS[key])
        elif key in sig and key not in RESERVED:
            _check_type(where, key, value, _allowed_types(sig[key].default))
        else:
            allowed = sorted(set(RUN_KEYS) | (set(sig) - RESERVED))
            raise ValueError(
                f"{where}: unknown key {key!r} for {algo}; allowed: {', '.join(allowed)}"
            )
    for key, value in (params.get("policy_kwargs") or {}).items():
        if key not in POLICY_KWARGS:
            raise ValueError(
                f"{where}: unknown policy_kwargs key {key!r}; allowed: {', '.join(POLICY_KWARGS)}"
            )
        _check_type(where, f"policy_kwargs.{key}", value, POLICY_KWARGS[key])
        if key == "activation_fn" and value not in ACTIVATIONS:
            raise ValueError(
                f"{where}: policy_kwargs.activation_fn={value!r} is not known: "
                f"choose one of {', '.join(ACTIVATIONS)}"
            )
    for key in ("n_envs", "n_timesteps", "eval_freq", "n_eval_scenarios", "checkpoint_freq"):
        if key in params and params[key] < 1:
            raise ValueError(f"{where}: {key}={params[key]!r} is out of range: allowed >= 1")
    return params


def parse_overrides(items: list[str] | None) -> dict[str, Any]:
    """``key=value`` pairs from the command line, values parsed as YAML."""
    out: dict[str, Any] = {}
    for item in items or []:
        key, sep, text = item.partition("=")
        if not sep or not key:
            raise ValueError(f"--hyperparams {item!r} is not allowed: give key=value")
        try:
            out[key.strip()] = yaml.safe_load(text)
        except yaml.YAMLError:
            raise ValueError(f"--hyperparams {item!r}: the value is not valid YAML") from None
    return out


def load(
    algo: str, env_id: str, path: str | Path | None = None, overrides: dict[str, Any] | None = None
) -> dict[str, Any]:
    """The resolved hyperparameters of ``algo`` on ``env_id``: the file's section for the
    env, then the overrides; validated."""
    algo_class(algo)
    if env_id not in ENV_IDS:
        raise ValueError(f"env={env_id!r} is not known: choose one of {', '.join(ENV_IDS)}")
    file = Path(path) if path else HYPERPARAMS_DIR / f"{algo}.yml"
    data = read_yaml(file)
    if not isinstance(data, dict):
        raise ValueError(f"{file}: expected a mapping of environment ids to hyperparameters")
    unknown_envs = sorted(set(data) - set(ENV_IDS))
    if unknown_envs:
        raise ValueError(
            f"{file}: unknown environment id(s) {', '.join(unknown_envs)}; "
            f"allowed: {', '.join(ENV_IDS)}"
        )
    if env_id not in data:
        raise ValueError(f"{file}: no hyperparameters for {env_id}")
    params = dict(data[env_id] or {})
    validate(algo, params, f"{file} [{env_id}]")
    params |= overrides or {}
    return validate(algo, params, f"{file} [{env_id}] with --hyperparams")
