"""stable-baselines3 agents for the vfgym environments (needs the ``agents`` extra:
``pip install -c constraints.txt -e ".[agents]"``; importing this package does not,
stable-baselines3 is imported when a model is trained or loaded).

- :func:`train` trains PPO, SAC, TD3 or RecurrentPPO (``ppo_lstm``, sb3-contrib) on
  ``vfgym/VFTune-v0`` or ``vfgym/VFServo-v0`` into a run folder
  (:mod:`vfgym.agents.training`), with the hyperparameters of
  :mod:`vfgym.agents.hyperparams` (:func:`load_hyperparams`); its ``best_model.zip`` is
  chosen on validation (move, plant) pairs (:mod:`vfgym.agents.selection`).
- :func:`load_agent` reads a saved agent with its run config and observation
  normalisation; :func:`load_model` the bare model (:mod:`vfgym.agents.loaded`).
- :func:`policy_settings` turns a VFTune-v0 agent into a function from a move to the
  settings it picks, which ``vfgym predict`` uses; :func:`agent_policy` also runs a
  VFServo-v0 agent as a scheduler on each move (:func:`scheduler_policy`), which
  ``vfgym evaluate --model`` uses.
- :func:`load_tuner` makes any tuner (the shipped settings model, a fitted one, a
  VFTune-v0 agent) a :class:`vfgym.permove.Tuner`, move → settings
  (:mod:`vfgym.agents.tuners`); the per-move settings models themselves, which need no
  torch, are :mod:`vfgym.permove`'s.
- :func:`make_env` builds an agent's environment from its hyperparameter file's env
  arguments (:func:`env_options`: the residual base).
"""

from vfgym.agents.heldout import HeldOutResult, agent_verdict, heldout_result
from vfgym.agents.hyperparams import ALGOS, HYPERPARAMS_DIR, algo_class
from vfgym.agents.hyperparams import load as load_hyperparams
from vfgym.agents.loaded import (
    BASE_SPECS,
    Agent,
    CheckedBase,
    agent_policy,
    env_options,
    load_agent,
    load_model,
    make_env,
    policy_settings,
    rollout_info,
    run_config,
    schedule_of,
    scheduler_policy,
    servo_agent,
    settings_policy,
    vecnormalize_path,
)
from vfgym.agents.selection import validation_plants, validation_scenarios
from vfgym.agents.training import train
from vfgym.agents.tuners import load_tuner
from vfgym.permove import Tuner, TunerWarning

__all__ = [
    "ALGOS",
    "BASE_SPECS",
    "HYPERPARAMS_DIR",
    "Agent",
    "CheckedBase",
    "HeldOutResult",
    "Tuner",
    "TunerWarning",
    "agent_policy",
    "agent_verdict",
    "algo_class",
    "env_options",
    "heldout_result",
    "load_agent",
    "load_hyperparams",
    "load_model",
    "load_tuner",
    "make_env",
    "policy_settings",
    "rollout_info",
    "run_config",
    "schedule_of",
    "scheduler_policy",
    "servo_agent",
    "settings_policy",
    "train",
    "validation_plants",
    "validation_scenarios",
    "vecnormalize_path",
]
