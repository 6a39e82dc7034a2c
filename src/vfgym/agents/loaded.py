"""A trained agent as it was trained: its model, its run config, and the observation
normalisation (SB3's ``VecNormalize``) saved beside it, ready to act on an environment's
observations; and the two ways vfgym judges one: the settings a VFTune-v0 agent picks
for a move, and the whole move a VFServo-v0 agent schedules.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from vfgym.moves.axis import Axis
from vfgym.moves.scenarios import Scenario
from vfgym.params import Settings
from vfgym.plant.measures import NAMES as METRIC_NAMES
from vfgym.plant.uncertainty import PlantVariant

VECNORMALIZE_FILE = "vecnormalize.pkl"
"""The normalisation statistics saved beside ``best_model.zip`` (rl-baselines3-zoo's name)."""


def vecnormalize_path(model_path: str | Path) -> Path:
    """Where the normalisation statistics of a saved model live: ``vecnormalize.pkl`` for
    ``best_model.zip``, ``<stem>_vecnormalize.pkl`` for any other model (``final_model``),
    and SB3's checkpoint name ``model_vecnormalize_<N>_steps.pkl`` for
    ``model_<N>_steps.zip``.

    Parameters
    ----------
    model_path : str or Path
        The model's ``.zip``.

    Returns
    -------
    Path
        The statistics' file (it may not exist: the agent was trained without them).
    """
    p = Path(model_path)
    if p.name == "best_model.zip":
        return p.with_name(VECNORMALIZE_FILE)
    if p.stem.startswith("model_") and p.stem.endswith("_steps"):
        return p.with_name(f"model_vecnormalize_{p.stem[len('model_') :]}.pkl")
    return p.with_name(f"{p.stem}_{VECNORMALIZE_FILE}")


@dataclass(frozen=True)
class Agent:
    """A loaded agent.

    Parameters
    ----------
    model : Any
        The stable-baselines3 model.
    config : dict
        Its run's ``config.yaml`` (algo, env, hyperparams; empty if none was found).
    normalizer : Any
        The ``VecNormalize`` it was trained behind (evaluation mode: statistics frozen,
        rewards not normalised), or None.
    env_id : str
        The environment it acts on.
    """

    model: Any
    config: dict[str, Any]
    normalizer: Any
    env_id: str

    def act(self, obs: np.ndarray) -> np.ndarray:
        """The deterministic action for an observation (normalised as in training).

        Parameters
        ----------
        obs : numpy.ndarray
            An observation of the environment.

        Returns
        -------
        numpy.ndarray
            The action.
        """
        if self.normalizer is not None:
            obs = self.normalizer.normalize_obs(obs)
        action, _ = self.model.predict(obs, deterministic=True)
        return action

    def env_kwargs(self, axis: str | Axis | None = None) -> dict[str, Any]:
        """The env arguments it was trained with (``axis`` replacing the trained one)."""
        kw = dict((self.config.get("hyperparams") or {}).get("env_kwargs") or {})
        if axis is not None:
            kw["axis"] = axis
        return kw


def load_agent(model_path: str | Path) -> Agent:
    """A saved model with its run config and, if it was trained with ``normalize``, its
    ``VecNormalize`` statistics (:func:`vecnormalize_path`), loaded with
    ``training=False, norm_reward=False``.

    Parameters
    ----------
    model_path : str or Path
        The model's ``.zip`` (``RUN/best_model.zip``).

    Returns
    -------
    Agent
        The agent.

    Raises
    ------
    ValueError
        If the file is missing or not a PPO, SAC or TD3 model, or the run trained with
        normalisation and its statistics are missing.
    """
    from vfgym.agents import load_model

    model, cfg = load_model(model_path)
    env_id = cfg.get("env", "vfgym/VFTune-v0")
    stats = vecnormalize_path(model_path)
    normalizer = None
    if stats.is_file():
        from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

        from vfgym.agents.bases import make_env

        kw = dict((cfg.get("hyperparams") or {}).get("env_kwargs") or {})
        normalizer = VecNormalize.load(str(stats), DummyVecEnv([lambda: make_env(env_id, kw)]))
        normalizer.training = False
        normalizer.norm_reward = False
    elif (cfg.get("hyperparams") or {}).get("normalize"):
        raise ValueError(
            f"--model {model_path}: trained with normalize but {stats.name} is missing beside it"
        )
    return Agent(model, cfg, normalizer, env_id)


def rollout_info(
    agent: Agent, env: Any, scenario: Scenario | str, plant: Any = None
) -> dict[str, Any]:
    """Run the agent (deterministic) through one episode on ``scenario`` (on the true
    ``plant``, if given); the scoring path's info of the move at the end.

    Parameters
    ----------
    agent : Agent
        The agent.
    env : gymnasium.Env
        Its environment.
    scenario : Scenario or str
        The move.
    plant : PlantVariant or None
        The episode's true plant (an axis with uncertainty); ``None``: as the env draws.

    Returns
    -------
    dict
        The info of the episode's last step (cost, constraints, measures).
    """
    opts: dict[str, Any] = {"scenario": scenario}
    if plant is not None:
        opts["plant"] = plant
    obs, _ = env.reset(options=opts)
    while True:
        obs, _, terminated, truncated, info = env.step(agent.act(obs))
        if terminated or truncated:
            return info


def settings_policy(agent: Agent, axis: str | Axis | None = None) -> Callable[[Any], Settings]:
    """A VFTune-v0 agent as a function: scenario → the settings it picks (with residual
    actions, its offset from the move's base)."""
    from vfgym.agents.bases import make_env

    env = make_env(agent.env_id, agent.env_kwargs(axis))

    def settings_for(scenario: Scenario | str) -> Settings:
        obs, _ = env.reset(options={"scenario": scenario})
        return env.unwrapped.settings_of(agent.act(obs))

    return settings_for


@dataclass(frozen=True)
class AgentScheduler:
    """A VFServo-v0 agent as a :class:`vfgym.scoring.Scheduler`: each move is one episode
    of VFServo-v0 with the agent's env arguments, on the true plant asked for, the settings
    changing every control interval; :func:`vfgym.evaluate` scores the measures it returns
    as it scores every controller.

    Parameters
    ----------
    agent : Agent
        The VFServo-v0 agent.
    env : gymnasium.Env
        Its environment, on the axis it is judged on.
    source : str
        Where it came from (its label in tables).
    """

    agent: Agent
    env: Any
    source: str = "agent"

    def run_move(self, scenario: Scenario, plant: PlantVariant) -> dict[str, Any]:
        """The measures of the move the agent schedules on ``plant``
        (:class:`vfgym.scoring.Scheduler`)."""
        info = rollout_info(self.agent, self.env, scenario, plant)
        return {k: info[k] for k in METRIC_NAMES}


def scheduler_policy(
    agent: Agent, axis: str | Axis | None = None, source: str = "agent"
) -> AgentScheduler:
    """A VFServo-v0 agent as a :class:`vfgym.scoring.Scheduler` (:class:`AgentScheduler`),
    which :func:`vfgym.evaluate` and :func:`vfgym.report.compare` run on every (move,
    plant) pair and score as every controller."""
    from vfgym.agents.bases import make_env

    return AgentScheduler(agent, make_env(agent.env_id, agent.env_kwargs(axis)), source)


def schedule_of(agent: Agent, scenario: Scenario | str, axis: str | None = None) -> dict[str, Any]:
    """A VFServo-v0 agent's schedule on one move, as plain data: each control interval's
    start (ms) and the settings in force through it (read back from the observation's
    ``setting_*`` entries, float32), then the scored move's cost and feasibility.

    Parameters
    ----------
    agent : Agent
        A VFServo-v0 agent.
    scenario : Scenario or str
        The move.
    axis : str or None
        An axis file the move belongs to (default: the agent's).

    Returns
    -------
    dict
        ``{"schedule": [{"from_ms": ..., "settings": {...}}, ...], "cost": ...,
        "feasible": ...}``, a row where the settings change.
    """
    from vfgym.agents.bases import make_env
    from vfgym.envs.servo import SERVO_FEATURES
    from vfgym.space import from_action, settings_to_dict

    env = make_env(agent.env_id, agent.env_kwargs(axis))
    law = env.unwrapped.accel_law
    interval_ms = env.unwrapped.core.config.interval_s * 1e3
    first = SERVO_FEATURES.index("setting_value")
    obs, _ = env.reset(options={"scenario": scenario})
    rows: list[dict[str, Any]] = []
    step = 0
    while True:
        obs, _, terminated, truncated, info = env.step(agent.act(obs))
        s = settings_to_dict(from_action(obs[first : first + 4], law))
        if not rows or rows[-1]["settings"] != s:  # a change of settings starts a row
            rows.append({"from_ms": round(step * interval_ms, 6), "settings": s})
        step += 1
        if terminated or truncated:
            return {"schedule": rows, "cost": float(info["cost"]), "feasible": info["feasible"]}
