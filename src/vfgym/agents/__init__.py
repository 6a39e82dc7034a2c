"""stable-baselines3 agents for the vfgym environments (needs the ``agents`` extra:
``pip install -c constraints.txt -e ".[agents]"``).

:func:`load_tuner` makes any tuner (the shipped settings model, a fitted one, a
VFTune-v0 agent) a callable from a move to settings (:mod:`vfgym.agents.tuners`).
:func:`load_model` reads a saved model (its algorithm from the run folder's config, or
tried in turn); :func:`policy_settings` turns a VFTune-v0 agent into a function from a
scenario to the settings it picks in one forward pass, which ``vfgym predict`` uses;
:func:`agent_policy` also runs a VFServo-v0 agent as a scheduler on each move, which
``vfgym evaluate --model`` uses. A model trained with ``normalize`` acts behind the
``VecNormalize`` statistics saved beside it (:mod:`vfgym.agents.loaded`).
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
    from vfgym.agents.loaded import load_agent, settings_policy

    agent = load_agent(model_path)
    if agent.env_id != "vfgym/VFTune-v0":
        raise ValueError(
            f"--model {model_path}: an agent for {agent.env_id}; settings per move "
            "come from vfgym/VFTune-v0 agents"
        )
    return settings_policy(agent, axis)


def agent_policy(model_path: str | Path, axis: str | None = None) -> Callable[[Any], Any]:
    """Any trained agent as a policy :func:`vfgym.report.compare` scores: a VFTune-v0
    agent's settings per move (:func:`policy_settings`), or a VFServo-v0 agent that
    schedules each move interval by interval (a :class:`vfgym.scoring.Scheduler`)."""
    from vfgym.agents.loaded import load_agent, scheduler_policy, settings_policy

    agent = load_agent(model_path)
    if agent.env_id == "vfgym/VFServo-v0":
        return scheduler_policy(agent, axis)
    return settings_policy(agent, axis)


def servo_agent(model_path: str | Path) -> Any:
    """The VFServo-v0 agent saved at ``model_path`` (a ``.zip``, loaded with its saved
    normalisation, :func:`vfgym.agents.loaded.load_agent`), or None for any other model (a
    settings model, a VFTune-v0 agent), which :func:`load_tuner` reads."""
    if Path(model_path).suffix != ".zip":
        return None
    from vfgym.agents.loaded import load_agent

    agent = load_agent(model_path)
    return agent if agent.env_id == "vfgym/VFServo-v0" else None


def scheduler_policy(agent: Any, axis: Any = None, source: str = "agent") -> Any:
    """A VFServo-v0 agent (:func:`servo_agent`) as a policy :func:`vfgym.report.compare`
    scores: each move scheduled interval by interval (a :class:`vfgym.scoring.Scheduler`)."""
    from vfgym.agents import loaded

    return loaded.scheduler_policy(agent, axis, source)


__all__ = [
    "Tuner",
    "TunerWarning",
    "agent_policy",
    "load_model",
    "load_tuner",
    "policy_settings",
    "scheduler_policy",
    "servo_agent",
]
