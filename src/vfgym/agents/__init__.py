"""stable-baselines3 agents for the vfgym environments (needs the ``agents`` extra:
``pip install -c constraints.txt -e ".[agents]"``).

:func:`load_tuner` makes any tuner (the shipped settings model, a fitted one, a
VFTune-v0 agent) a callable from a move to settings (:mod:`vfgym.agents.tuners`).
:func:`load_model` reads a saved model (its algorithm from the run folder's config, or
tried in turn); :func:`policy_settings` turns a VFTune-v0 agent into a function from a
scenario to the settings it picks in one forward pass, which ``vfgym evaluate --model``
and ``vfgym predict`` use.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

from vfgym.agents.tuners import Tuner, TunerWarning, load_tuner
from vfgym.io.runs import read_yaml
from vfgym.moves.axis import Axis
from vfgym.moves.scenarios import Scenario
from vfgym.params import Settings


def _config(model_path: Path) -> dict[str, Any]:
    for folder in (model_path.parent, model_path.parent.parent):
        cfg = folder / "config.yaml"
        if cfg.is_file():
            data = read_yaml(cfg)
            if isinstance(data, dict) and "algo" in data:
                return data
    return {}


def load_model(model_path: str | Path) -> tuple[Any, dict[str, Any]]:
    """The saved model and its run config (algo, env, hyperparams; may be empty)."""
    from vfgym.agents.hyperparams import ALGOS, algo_class

    path = Path(model_path)
    if not path.is_file():
        raise ValueError(f"--model {path}: no such file")
    cfg = _config(path)
    algos = [cfg["algo"]] if cfg.get("algo") in ALGOS else list(ALGOS)
    for algo in algos:
        try:
            return algo_class(algo).load(path, device="cpu"), cfg
        except (KeyError, ValueError, TypeError, RuntimeError):
            continue
    raise ValueError(f"--model {path}: not a stable-baselines3 PPO, SAC or TD3 model")


def policy_settings(
    model_path: str | Path, axis: str | Axis | None = None
) -> Callable[[Scenario | str], Settings]:
    """A VFTune-v0 agent as a function: scenario → the settings it picks (deterministic).
    ``axis``: an axis file the moves belong to (default: the one the agent was trained
    on, if any), which the observations describe and names resolve on."""
    from vfgym.agents.training import make_env
    from vfgym.envs.tune import action_settings

    model, cfg = load_model(model_path)
    env_id = cfg.get("env", "vfgym/VFTune-v0")
    if env_id != "vfgym/VFTune-v0":
        raise ValueError(
            f"--model {model_path}: an agent for {env_id}; settings per move "
            "come from vfgym/VFTune-v0 agents"
        )
    env_kwargs = dict((cfg.get("hyperparams") or {}).get("env_kwargs") or {})
    if axis is not None:
        env_kwargs["axis"] = axis
    env = make_env(env_id, env_kwargs)
    law = env.unwrapped.accel_law

    def settings_for(scenario: Scenario | str) -> Settings:
        obs, _ = env.reset(options={"scenario": scenario})
        action, _ = model.predict(obs, deterministic=True)
        return action_settings(action, law)

    return settings_for


__all__ = ["Tuner", "TunerWarning", "load_model", "load_tuner", "policy_settings"]
