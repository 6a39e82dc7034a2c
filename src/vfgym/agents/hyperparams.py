"""Hyperparameters in YAML, rl-baselines3-zoo style: one file per algorithm, one section
per environment id, overridable from the command line. The default files ship with vfgym
(:data:`HYPERPARAMS_DIR`); a file ``agents/hyperparams/<algo>.yml`` in the working folder
is read instead when there is one (:func:`default_file`).

Everything is checked before any training starts: unknown keys, values of the wrong type
or outside the range stable-baselines3 documents for them (:data:`RANGES`: a discount in
[0, 1], a learning rate > 0, ...), unknown algorithms and environments raise
``ValueError`` naming the file, the key and what is allowed. Numbers may be written in any
notation (``n_timesteps: 1e5``); a whole-valued float is taken where a count is expected.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable
from pathlib import Path
from typing import Any

from vfgym._validate import check_choice, check_int, check_real
from vfgym.io.runs import parse_yaml, read_yaml

ALGOS = ("ppo", "sac", "td3", "ppo_lstm")
"""Algorithm names (rl-baselines3-zoo's): ``ppo_lstm`` is sb3-contrib's RecurrentPPO."""
ENV_IDS = ("vfgym/VFTune-v0", "vfgym/VFServo-v0")

# keys that are not constructor arguments of the algorithm
RUN_KEYS: dict[str, tuple[type, ...]] = {
    "n_envs": (int,),
    "n_timesteps": (int,),
    "policy": (str,),
    "policy_kwargs": (dict,),
    "env_kwargs": (dict,),
    "eval_env_kwargs": (dict,),
    "action_noise_std": (int, float),
    "eval_freq": (int,),
    "n_eval_scenarios": (int,),
    "n_eval_scenarios_uncertain": (int,),
    "checkpoint_freq": (int,),
    "normalize": (bool, dict),
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
    "rollout_buffer_class",  # classes cannot be written in YAML
    "replay_buffer_class",
}
POLICY_KWARGS = {
    "net_arch": (list, dict),
    "activation_fn": (str,),
    "log_std_init": (int, float),
    "ortho_init": (bool,),
    "squash_output": (bool,),
    "n_critics": (int,),
    # RecurrentPPO's (sb3-contrib's MlpLstmPolicy)
    "lstm_hidden_size": (int,),
    "n_lstm_layers": (int,),
    "shared_lstm": (bool,),
    "enable_critic_lstm": (bool,),
}
ACTIVATIONS = ("tanh", "relu", "elu", "leaky_relu")
MIXED_TYPES = {"ent_coef", "target_entropy", "train_freq"}
"""Keys that take a number or a string/list (SAC's ``ent_coef='auto'``, ``train_freq=[4,
'episode']``); their check in :data:`RANGES` decides, not the type of the default."""
POLICIES = {"ppo": "MlpPolicy", "sac": "MlpPolicy", "td3": "MlpPolicy", "ppo_lstm": "MlpLstmPolicy"}
"""Each algorithm's policy for the vfgym environments (flat Box observations)."""


def _count(lo: int, hi: int | None = None) -> Callable[[str, Any], int]:
    return lambda name, v: check_int(name, v, lo, hi)


def _real(
    lo: float | None = None, hi: float | None = None, lo_open: bool = False, none: bool = False
) -> Callable[[str, Any], Any]:
    def check(name: str, v: Any) -> Any:
        return None if (none and v is None) else check_real(name, v, lo, hi, lo_open=lo_open)

    return check


def _minus_one_or_count(name: str, v: Any) -> int:
    n = check_int(name, v, -1)
    if n == 0:
        raise ValueError(f"{name}=0 is not allowed: -1 (as many as collected) or >= 1")
    return n


def _train_freq(name: str, v: Any) -> Any:
    if isinstance(v, (list, tuple)):
        if len(v) != 2:
            raise ValueError(f"{name}={v!r} is not allowed: N or [N, step|episode]")
        return [check_int(name, v[0], 1), check_choice(name, v[1], ("step", "episode"))]
    return check_int(name, v, 1)


def _entropy(name: str, v: Any) -> Any:
    """SAC's ent_coef: a number >= 0, 'auto', or 'auto_X' (X > 0: the initial value)."""
    if isinstance(v, str):
        if v == "auto":
            return v
        if v.startswith("auto_"):
            check_real(f"{name} initial value", v[5:], 0.0, lo_open=True, text=True)
            return v
        raise ValueError(f"{name}={v!r} is not allowed: a number >= 0, 'auto' or 'auto_X'")
    return check_real(name, v, 0.0)


NORMALIZE_KEYS = ("norm_obs", "norm_reward", "clip_obs", "clip_reward", "epsilon")
"""What ``normalize`` may set of SB3's ``VecNormalize`` (rl-baselines3-zoo's option); its
``gamma`` is always the agent's."""


def _normalize(name: str, v: Any) -> Any:
    """``normalize``: true/false, or a mapping of :data:`NORMALIZE_KEYS`."""
    if isinstance(v, bool):
        return v
    out: dict[str, Any] = {}
    for key, x in v.items():
        if key not in NORMALIZE_KEYS:
            raise ValueError(f"{name}.{key} is not known: allowed {', '.join(NORMALIZE_KEYS)}")
        if key.startswith("norm_"):
            if not isinstance(x, bool):
                raise ValueError(f"{name}.{key}={x!r} must be true or false")
            out[key] = x
        else:
            out[key] = check_real(f"{name}.{key}", x, 0.0, lo_open=True)
    return out


def _target_entropy(name: str, v: Any) -> Any:
    return v if v == "auto" else check_real(name, v)


RANGES: dict[str, Callable[[str, Any], Any]] = {
    # run keys
    "n_envs": _count(1, 1024),
    "n_timesteps": _count(1),
    "eval_freq": _count(1),
    "n_eval_scenarios": _count(1),
    "n_eval_scenarios_uncertain": _count(1),
    "checkpoint_freq": _count(1),
    "action_noise_std": _real(0.0),
    "policy": lambda name, v: check_choice(name, v, tuple(sorted(set(POLICIES.values())))),
    "normalize": lambda name, v: _normalize(name, v),
    # constructor arguments (stable-baselines3's documentation of PPO, SAC and TD3)
    "learning_rate": _real(0.0, lo_open=True),
    "n_steps": _count(1),
    "batch_size": _count(1),
    "n_epochs": _count(1),
    "gamma": _real(0.0, 1.0),
    "gae_lambda": _real(0.0, 1.0),
    "clip_range": _real(0.0, lo_open=True),
    "clip_range_vf": _real(0.0, lo_open=True, none=True),
    "ent_coef": _entropy,
    "vf_coef": _real(0.0),
    "max_grad_norm": _real(0.0, lo_open=True),
    "sde_sample_freq": _count(-1),
    "target_kl": _real(0.0, lo_open=True, none=True),
    "stats_window_size": _count(1),
    "buffer_size": _count(1),
    "learning_starts": _count(0),
    "tau": _real(0.0, 1.0, lo_open=True),
    "train_freq": _train_freq,
    "gradient_steps": _minus_one_or_count,
    "target_update_interval": _count(1),
    "target_entropy": _target_entropy,
    "policy_delay": _count(1),
    "target_policy_noise": _real(0.0),
    "target_noise_clip": _real(0.0),
    "log_std_init": _real(),
    "n_critics": _count(1, 16),
}
"""The allowed values of each hyperparameter, as stable-baselines3 documents them: a
discount ``gamma`` and GAE's ``gae_lambda`` in [0, 1], ``tau`` (Polyak) in (0, 1], rates,
clip ranges and gradient norms > 0, coefficients and noises >= 0, counts >= 1
(``learning_starts`` >= 0; ``gradient_steps`` -1 for "as many as collected";
``sde_sample_freq`` -1 for "once per rollout"). Each check returns the value normalised
(a whole float as an int)."""
HYPERPARAMS_DIR = Path(__file__).resolve().parent / "hyperparams_files"
"""The shipped hyperparameter files, ``<algo>.yml`` (package data)."""
LOCAL_DIR = Path("agents") / "hyperparams"
"""Where a working folder's own hyperparameter files are looked for first."""


def default_file(algo: str) -> Path:
    """The hyperparameter file of ``algo`` when none is given: the working folder's
    ``agents/hyperparams/<algo>.yml`` if there is one, else the shipped file.

    Parameters
    ----------
    algo : str
        ``ppo``, ``sac`` or ``td3``.

    Returns
    -------
    Path
        The file.
    """
    algo_class(algo)
    local = LOCAL_DIR / f"{algo}.yml"
    return local if local.is_file() else HYPERPARAMS_DIR / f"{algo}.yml"


def algo_class(algo: str) -> Any:
    """The stable-baselines3 (or sb3-contrib) class of an algorithm name."""
    if algo not in ALGOS:
        raise ValueError(f"algo={algo!r} is not known: choose one of {', '.join(ALGOS)}")
    if algo == "ppo_lstm":
        try:
            from sb3_contrib import RecurrentPPO
        except ImportError:
            raise ValueError(
                "algo='ppo_lstm' needs sb3-contrib: pip install -c constraints.txt -e \".[agents]\""
            ) from None
        return RecurrentPPO
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


def validate(
    algo: str, params: dict[str, Any], where: str, env_id: str | None = None
) -> dict[str, Any]:
    """Check the keys, value types and ranges (:data:`RANGES`) of one environment's
    hyperparameters; returns them normalised (``n_timesteps: 1e5`` as the int 100000).

    Parameters
    ----------
    algo
        ``ppo``, ``sac`` or ``td3``.
    params
        The hyperparameters (run keys, constructor arguments, ``policy_kwargs``,
        ``env_kwargs``).
    where
        Names the source in messages (file, section).
    env_id
        The environment whose constructor ``env_kwargs`` must fit (default: either).

    Returns
    -------
    dict
        The checked hyperparameters.
    """
    cls = algo_class(algo)
    sig = inspect.signature(cls.__init__).parameters
    out: dict[str, Any] = {}
    for key, value in params.items():
        types: tuple[type, ...] | None
        if key in RUN_KEYS:
            types = RUN_KEYS[key]
        elif key in sig and key not in RESERVED:
            default = sig[key].default
            mixed = key in MIXED_TYPES and not isinstance(default, float)
            types = None if mixed else _allowed_types(default)
        else:
            allowed = sorted(set(RUN_KEYS) | (set(sig) - RESERVED))
            raise ValueError(
                f"{where}: unknown key {key!r} for {algo}; allowed: {', '.join(allowed)}"
            )
        out[key] = _checked(where, key, value, types)
    if "policy_kwargs" in out:
        out["policy_kwargs"] = _policy_kwargs(where, out["policy_kwargs"] or {})
    for key in ("env_kwargs", "eval_env_kwargs"):
        if key in out:
            _env_kwargs(where, out[key] or {}, env_id)
    if out.get("policy", POLICIES[algo]) != POLICIES[algo]:
        raise ValueError(
            f"{where}: policy={out['policy']!r} is not allowed for {algo}: give {POLICIES[algo]}"
        )
    if algo == "ppo" and out.get("normalize_advantage", True) and out.get("batch_size", 2) < 2:
        raise ValueError(
            f"{where}: batch_size={out['batch_size']!r} is out of range for ppo with "
            "normalize_advantage: allowed >= 2"
        )
    return out


def _checked(
    where: str, key: str, value: Any, types: tuple[type, ...] | None, prefix: str = ""
) -> Any:
    """``value`` of the right type (a whole float taken as an int) and in its range."""
    if types is not None and int in types and float not in types and isinstance(value, float):
        types = (*types, float)  # 1e5, 2.0: check_int takes whole floats and refuses 2.5
    _check_type(where, prefix + key, value, types)
    check = RANGES.get(key)
    if check is None:
        return value
    try:
        return check(prefix + key, value)
    except ValueError as exc:
        raise ValueError(f"{where}: {exc}") from None


def _policy_kwargs(where: str, kwargs: dict[str, Any]) -> dict[str, Any]:
    out = {}
    for key, value in kwargs.items():
        if key not in POLICY_KWARGS:
            raise ValueError(
                f"{where}: unknown policy_kwargs key {key!r}; allowed: {', '.join(POLICY_KWARGS)}"
            )
        out[key] = _checked(where, key, value, POLICY_KWARGS[key], prefix="policy_kwargs.")
        if key == "activation_fn" and value not in ACTIVATIONS:
            raise ValueError(
                f"{where}: policy_kwargs.activation_fn={value!r} is not known: "
                f"choose one of {', '.join(ACTIVATIONS)}"
            )
        if key == "net_arch":
            _net_arch(where, value)
    return out


def _net_arch(where: str, arch: Any) -> None:
    """A list of layer widths, or a mapping of such lists per network (pi, vf, qf)."""
    lists = arch.items() if isinstance(arch, dict) else [("", arch)]
    for part, widths in lists:
        name = f"policy_kwargs.net_arch{'.' + str(part) if part else ''}"
        ok = isinstance(widths, list) and all(
            isinstance(w, int) and not isinstance(w, bool) and 1 <= w <= 65536 for w in widths
        )
        if not ok or (part and part not in ("pi", "vf", "qf")):
            raise ValueError(
                f"{where}: {name}={widths!r} is not allowed: a list of layer widths "
                "(whole numbers >= 1), or a mapping of such lists under pi, vf, qf"
            )


def _env_kwargs(where: str, kwargs: dict[str, Any], env_id: str | None) -> None:
    """Keys of the env's constructor that YAML can give (numbers, strings, booleans)."""
    import dataclasses

    from vfgym.envs.servo import ServoConfig, VFServoEnv
    from vfgym.envs.tune import TuneConfig, VFTuneEnv

    # the env's own arguments, then its options: the fields of its frozen config
    classes = {
        "vfgym/VFTune-v0": (VFTuneEnv, TuneConfig),
        "vfgym/VFServo-v0": (VFServoEnv, ServoConfig),
    }
    plain = (str, int, float, bool, tuple)
    allowed: set[str] = set()
    for cls, config in [classes[env_id]] if env_id in classes else classes.values():
        for name, par in inspect.signature(cls.__init__).parameters.items():
            named = par.kind in (par.KEYWORD_ONLY, par.POSITIONAL_OR_KEYWORD) and name != "self"
            if named and (par.default is None or isinstance(par.default, plain)):
                allowed.add(name)
        for f in dataclasses.fields(config):
            if f.default is None or isinstance(f.default, plain):
                allowed.add(f.name)
    allowed.add("axis")  # an axis file's path (the envs' default is an Axis object)
    unknown = sorted(set(kwargs) - allowed)
    if unknown:
        raise ValueError(
            f"{where}: unknown env_kwargs key(s) {', '.join(map(str, unknown))}; "
            f"allowed: {', '.join(sorted(allowed))}"
        )


def parse_overrides(items: list[str] | None) -> dict[str, Any]:
    """``key=value`` pairs from the command line, values parsed as YAML."""
    out: dict[str, Any] = {}
    for item in items or []:
        key, sep, text = item.partition("=")
        if not sep or not key:
            raise ValueError(f"--hyperparams {item!r} is not allowed: give key=value")
        out[key.strip()] = parse_yaml(text, f"--hyperparams {item!r}")
    return out


def load(
    algo: str, env_id: str, path: str | Path | None = None, overrides: dict[str, Any] | None = None
) -> dict[str, Any]:
    """The resolved hyperparameters of ``algo`` on ``env_id``: the file's section for the
    env, then the overrides; validated."""
    algo_class(algo)
    if env_id not in ENV_IDS:
        raise ValueError(f"env={env_id!r} is not known: choose one of {', '.join(ENV_IDS)}")
    file = Path(path) if path else default_file(algo)
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
    params = data[env_id] or {}
    if not isinstance(params, dict):
        raise ValueError(f"{file} [{env_id}]: expected a mapping of hyperparameters")
    params = validate(algo, dict(params), f"{file} [{env_id}]", env_id)
    params |= overrides or {}
    return validate(algo, params, f"{file} [{env_id}] with --hyperparams", env_id)
