"""A trained agent as it was trained, and the environment it acts on.

The environment of an agent is made of its hyperparameter file's env arguments
(:func:`env_options`), above all the residual base its actions are offsets from (the
paper's settings, a per-move settings model of :mod:`vfgym.permove`, a settings file or
another VFTune-v0 agent). A saved agent is its model, its run config and the observation
normalisation (SB3's ``VecNormalize``) saved beside it (:func:`load_agent`), ready to act
on that environment's observations; vfgym judges one by the settings a VFTune-v0 agent
picks for a move (:func:`policy_settings`) or the whole move a VFServo-v0 agent
schedules (:func:`scheduler_policy`).

Both the training (:mod:`vfgym.agents.training`) and the judging of a saved agent build
their envs here; an agent as a residual base makes this module call itself (the agent is
loaded with its own env), never another module back. stable-baselines3 is imported only
when a model is loaded.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from vfgym.axis import Axis, PlantVariant
from vfgym.io.runs import read_yaml
from vfgym.moves.scenarios import Scenario
from vfgym.params import Settings
from vfgym.plant.measures import NAMES as METRIC_NAMES
from vfgym.scoring import Scheduler

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


def run_config(model_path: str | Path) -> dict[str, Any]:
    """The run config (``config.yaml``: algo, env, hyperparams) of a saved model, read
    from its folder or the one above (a checkpoint's); empty if none is found."""
    model_path = Path(model_path)
    for folder in (model_path.parent, model_path.parent.parent):
        cfg = folder / "config.yaml"
        if cfg.is_file():
            data = read_yaml(cfg)
            if isinstance(data, dict) and "algo" in data:
                return _without_residual_ratio(data, model_path)
    return {}


def _without_residual_ratio(cfg: dict[str, Any], model_path: Path) -> dict[str, Any]:
    """A run saved when residual actions had the option ``residual_ratio`` (they are now
    always offsets of L/value, :class:`vfgym.space.Relative`): the option is dropped. Its
    actions mean what they meant with the ratio on and L/value held (its scale 0, as the
    shipped hyperparameters); otherwise one line says that L's actions changed meaning."""
    kw = (cfg.get("hyperparams") or {}).get("env_kwargs")
    if not isinstance(kw, dict) or "residual_ratio" not in kw:
        return cfg
    ratio = kw.pop("residual_ratio")
    scale = kw.get("residual_scale")
    held = isinstance(scale, (list, tuple)) and len(scale) == 4 and scale[1] == 0
    if kw.get("residual") and not (ratio and held):
        import warnings

        from vfgym.permove import TunerWarning

        was = "L/value over L's range" if ratio else "L alone"
        warnings.warn(
            f"{model_path}: trained with residual actions offsetting {was}; they now offset "
            "L/value over its own range: its L actions mean something else (train it again)",
            TunerWarning,
            stacklevel=3,
        )
    return cfg


SERVO_OBSERVATION = "drive"
"""What a VFServo-v0 run's ``config.yaml`` says its agent observes (``observation:``): what a
drive measures (encoder counts, its speed counter, the torque it commands). Runs without it
observed the simulator's continuous angle, speed and torque: their agents are refused."""


def check_observation(cfg: dict[str, Any], where: str) -> None:
    """Refuse, in one line, a VFServo-v0 run trained on the observation VFServo-v0 had
    before it became what a drive measures (:data:`SERVO_OBSERVATION`).

    Parameters
    ----------
    cfg : dict
        The run's ``config.yaml``.
    where : str
        Names the run or model in the message.

    Raises
    ------
    ValueError
        If the run is such a run.
    """
    if cfg.get("env") == "vfgym/VFServo-v0" and cfg.get("observation") != SERVO_OBSERVATION:
        raise ValueError(
            f"{where}: a VFServo-v0 agent trained when its observation held the simulator's "
            "continuous angle, speed and torque; it is now what a drive measures (encoder "
            "counts, speed counter, torque command): train it again"
        )


def load_model(model_path: str | Path) -> tuple[Any, dict[str, Any]]:
    """The saved model and its run config (algo, env, hyperparams; may be empty)."""
    from vfgym.agents.hyperparams import ALGOS, algo_class

    path = Path(model_path)
    if not path.is_file():
        raise ValueError(f"--model {path}: no such file")
    cfg = run_config(path)
    check_observation(cfg, f"--model {path}")
    algos = [cfg["algo"]] if cfg.get("algo") in ALGOS else list(ALGOS)
    for algo in algos:
        try:
            return algo_class(algo).load(path, device="cpu"), cfg
        except (KeyError, ValueError, TypeError, RuntimeError):
            continue
    raise ValueError(f"--model {path}: not a PPO, SAC, TD3 or RecurrentPPO model")


def env_options(env_kwargs: dict[str, Any] | None) -> dict[str, Any]:
    """The env arguments of a hyperparameter file made objects: ``residual_base`` written
    as ``paper`` (the paper's settings), ``model`` (the shipped per-move settings model as
    ``vfgym predict`` uses it: its best-ranked candidates simulated on the move, the best
    kept; :class:`CheckedBase`), ``model-lookup`` (its look-up alone, unsimulated: the
    best-ranked candidate), ``model:FILE.json`` / ``model-lookup:FILE.json`` or a bare
    ``FILE.json`` (the same of a settings model of ``vfgym fit``, e.g. an axis's own), a
    settings file (a mapping of the settings, or one under ``settings:`` as ``best.yaml``)
    or a trained VFTune-v0 agent (its ``.zip``: the settings it picks for each move). A
    model's check keeps the settings feasible on the axis's design plants."""
    from vfgym.axis import LOADS_AXIS, as_axis

    kw = dict(env_kwargs or {})
    axis = kw["axis"] = as_axis(kw.get("axis", LOADS_AXIS))  # the envs' default axis
    base = kw.get("residual_base")
    if isinstance(base, str):
        kw["residual_base"] = _residual_base(base, axis.measures, axis.design_plants())
    return kw


BASE_SPECS = ("paper", "model", "model-lookup")
"""The named bases a hyperparameter file's ``residual_base`` may be (or a file's path; a
settings model's as ``model:FILE.json`` or ``model-lookup:FILE.json``)."""


class CheckedBase:
    """A settings model's settings for each move, remembered per (move, plant): with its
    check on (:attr:`vfgym.permove.pick.PickModel.check`) each new move simulates its
    candidates once (a few ms), and the validation moves, scored again at every
    evaluation, only the first time.

    Parameters
    ----------
    model : PickModel or SettingsModel
        The model.
    measures : Measures
        What the check scores with (an axis's).
    size : int
        Moves remembered; the oldest are forgotten beyond it.
    plants : tuple of PlantVariant
        True plants the check keeps the settings feasible on (an axis's design).
    """

    def __init__(self, model: Any, measures: Any, size: int = 8192, plants: Any = ()) -> None:
        self.model, self.measures, self.size, self.plants = model, measures, size, plants
        self._seen: dict[tuple[Scenario, Any], Any] = {}

    def __call__(self, scenario: Scenario, plant: Any) -> Any:
        """The model's settings for ``scenario`` on the base plant ``plant``."""
        key = (scenario, plant)
        out = self._seen.get(key)
        if out is None:
            if len(self._seen) >= self.size:
                del self._seen[next(iter(self._seen))]
            out = self._seen[key] = self.model.settings(scenario, plant, self.measures, self.plants)
        return out


def _residual_base(spec: str, measures: Any = None, plants: Any = ()) -> Any:
    from vfgym.params import DEFAULT_MEASURES, PAPER_SETTINGS
    from vfgym.permove import PRETRAINED
    from vfgym.space import settings_from_dict

    if spec == "paper":
        return PAPER_SETTINGS
    kind, _, path = spec.partition(":")
    if spec.endswith(".json") and kind not in BASE_SPECS:
        kind, path = "model", spec
    if kind in ("model", "model-lookup"):
        from dataclasses import replace

        from vfgym.permove import PickModel, load_settings_model

        try:
            model = load_settings_model(path or PRETRAINED)
        except ValueError as exc:  # its message names --model; here the key is residual_base
            raise ValueError(f"residual_base={spec!r}: {exc}".replace("--model ", "")) from None
        if kind == "model-lookup" and isinstance(model, PickModel):
            model = replace(model, check=0)
        on = DEFAULT_MEASURES if measures is None else measures
        return CheckedBase(model, on, plants=tuple(plants))
    if spec.endswith(".zip") and Path(spec).is_file():
        pick = policy_settings(spec)
        return lambda scenario, plant: pick(scenario)
    if not Path(spec).is_file():
        raise ValueError(
            f"residual_base={spec!r} is not allowed: {', '.join(BASE_SPECS)} (the shipped "
            "settings model, checked on the move, or its look-up alone), model:FILE.json "
            "(a settings model of vfgym fit), a settings file or a VFTune-v0 agent's .zip"
        )
    data = read_yaml(spec)
    data = data["settings"] if isinstance(data, dict) and "settings" in data else data
    return settings_from_dict(data, source=spec)


def acting_kwargs(params: dict[str, Any]) -> dict[str, Any]:
    """The env arguments a trained agent acts with, validated and deployed: its training
    env's (``env_kwargs``) with ``eval_env_kwargs`` over them (e.g. a one-decision agent
    trained without the shield and judged with it).

    Parameters
    ----------
    params : dict
        The run's hyperparameters.

    Returns
    -------
    dict
        The env arguments.
    """
    return {**(params.get("env_kwargs") or {}), **(params.get("eval_env_kwargs") or {})}


def make_env(env_id: str, env_kwargs: dict[str, Any] | None = None, **kw: Any) -> Any:
    """One (non-vector) environment (``env_kwargs`` through :func:`env_options`)."""
    import gymnasium as gym

    import vfgym.envs  # noqa: F401  (registers the ids)

    return gym.make(env_id, **env_options(env_kwargs), **kw)


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
        return self.step(obs)[0]

    def step(
        self, obs: np.ndarray, state: Any = None, episode_start: bool = True
    ) -> tuple[np.ndarray, Any]:
        """The deterministic action for an observation, and the policy's memory after it
        (a recurrent policy's LSTM state; ``None`` for the others).

        Parameters
        ----------
        obs : numpy.ndarray
            An observation of the environment (normalised here as in training).
        state : Any
            The memory :meth:`step` returned for the episode's previous observation.
        episode_start : bool
            The first observation of an episode (the memory starts anew).

        Returns
        -------
        tuple of (numpy.ndarray, Any)
            The action and the memory to pass with the next observation.
        """
        if self.normalizer is not None:
            obs = self.normalizer.normalize_obs(obs)
        start = np.full(len(obs) if np.ndim(obs) > 1 else 1, episode_start)  # per env of a batch
        return self.model.predict(obs, state=state, episode_start=start, deterministic=True)

    def env_kwargs(self, axis: str | Axis | None = None) -> dict[str, Any]:
        """The env arguments it acts with (:func:`acting_kwargs`: its training env's with
        ``eval_env_kwargs`` over them; ``axis`` replacing the trained one)."""
        kw = acting_kwargs(self.config.get("hyperparams") or {})
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
        If the file is missing or not a PPO, SAC, TD3 or RecurrentPPO model, or the run trained with
        normalisation and its statistics are missing.
    """
    model, cfg = load_model(model_path)
    env_id = cfg.get("env", "vfgym/VFTune-v0")
    stats = vecnormalize_path(model_path)
    normalizer = None
    if stats.is_file():
        from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

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
    state, start = None, True
    while True:
        action, state = agent.step(obs, state, start)
        obs, _, terminated, truncated, info = env.step(action)
        start = False
        if terminated or truncated:
            return info


def settings_policy(agent: Agent, axis: str | Axis | None = None) -> Callable[[Any], Settings]:
    """A VFTune-v0 agent as a function: scenario → the settings it picks (with residual
    actions, its offset from the move's base)."""

    env = make_env(agent.env_id, agent.env_kwargs(axis))

    def settings_for(scenario: Scenario | str) -> Settings:
        obs, _ = env.reset(options={"scenario": scenario})
        return env.unwrapped.settings_of(agent.act(obs))

    return settings_for


@dataclass(frozen=True)
class AgentScheduler(Scheduler):
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

    return AgentScheduler(agent, make_env(agent.env_id, agent.env_kwargs(axis)), source)


def schedule_of(
    agent: Agent, scenario: Scenario | str, axis: str | Axis | None = None
) -> dict[str, Any]:
    """A VFServo-v0 agent's schedule on one move, as plain data: each control interval's
    start (ms) and the settings in force through it (read back from the observation's
    ``setting_*`` entries, float32), then the scored move's cost and feasibility. An agent
    of one decision a move (``decision="once"``) has its decision replayed interval by
    interval: the base over the hold, the ramp, the correction that ran (``info["correction"]``:
    gentler or the base's where shielded).

    Parameters
    ----------
    agent : Agent
        A VFServo-v0 agent.
    scenario : Scenario or str
        The move.
    axis : str, Axis or None
        The axis (or its file) the move belongs to (default: the agent's).

    Returns
    -------
    dict
        ``{"schedule": [{"from_ms": ..., "settings": {...}}, ...], "cost": ...,
        "feasible": ...}``, a row where the settings change.
    """
    from vfgym.envs.servo import SERVO_FEATURES
    from vfgym.space import from_action, settings_to_dict

    kw = agent.env_kwargs(axis)
    env = make_env(agent.env_id, kw)
    plan = None
    config = env.unwrapped.core.config
    if config.decision == "once":  # its one decision, replayed interval by interval
        obs, _ = env.reset(options={"scenario": scenario})
        action = np.asarray(agent.act(obs), dtype=np.float64)
        *_, info = env.step(action)
        act = info["correction"]  # the one run: the action, a gentler one or the base's 0
        hold, ramp = config.hold_intervals, info["ramp"]

        def plan(t: int) -> np.ndarray:
            return np.zeros(4) if t < hold else act * min(1.0, (t - hold + 1) / ramp)

        off = {"decision": "interval", "tell": False, "shield": False, "shield_gentler": 0}
        env = make_env(agent.env_id, {**kw, **off})
    law = env.unwrapped.accel_law
    interval_ms = env.unwrapped.core.config.interval_s * 1e3
    first = SERVO_FEATURES.index("setting_value")
    obs, _ = env.reset(options={"scenario": scenario})
    rows: list[dict[str, Any]] = []
    step = 0
    while True:
        a = agent.act(obs) if plan is None else plan(step)
        obs, _, terminated, truncated, info = env.step(a)
        s = settings_to_dict(from_action(obs[first : first + 4], law))
        if not rows or rows[-1]["settings"] != s:  # a change of settings starts a row
            rows.append({"from_ms": round(step * interval_ms, 6), "settings": s})
        step += 1
        if terminated or truncated:
            return {"schedule": rows, "cost": float(info["cost"]), "feasible": info["feasible"]}


def policy_settings(
    model_path: str | Path, axis: str | Axis | None = None
) -> Callable[[Scenario | str], Settings]:
    """A VFTune-v0 agent as a function: scenario → the settings it picks (deterministic).
    ``axis``: an axis file the moves belong to (default: the one the agent was trained
    on, if any), which the observations describe and names resolve on."""
    agent = load_agent(model_path)
    if agent.env_id != "vfgym/VFTune-v0":
        raise ValueError(
            f"--model {model_path}: an agent for {agent.env_id}; settings per move "
            "come from vfgym/VFTune-v0 agents"
        )
    return settings_policy(agent, axis)


def agent_policy(model_path: str | Path, axis: str | Axis | None = None) -> Any:
    """Any trained agent as a policy :func:`vfgym.report.compare` scores: a VFTune-v0
    agent's settings per move (:func:`policy_settings`), or a VFServo-v0 agent that
    schedules each move interval by interval (a :class:`vfgym.scoring.Scheduler`)."""
    agent = load_agent(model_path)
    if agent.env_id == "vfgym/VFServo-v0":
        return scheduler_policy(agent, axis)
    return settings_policy(agent, axis)


def servo_agent(model_path: str | Path) -> Any:
    """The VFServo-v0 agent saved at ``model_path`` (a ``.zip``, loaded with its saved
    normalisation, :func:`load_agent`), or None for any other model (a
    settings model, a VFTune-v0 agent), which :func:`vfgym.agents.tuners.load_tuner` reads."""
    if Path(model_path).suffix != ".zip":
        return None
    agent = load_agent(model_path)
    return agent if agent.env_id == "vfgym/VFServo-v0" else None


__all__ = [
    "BASE_SPECS",
    "SERVO_OBSERVATION",
    "VECNORMALIZE_FILE",
    "Agent",
    "CheckedBase",
    "acting_kwargs",
    "agent_policy",
    "check_observation",
    "env_options",
    "load_agent",
    "load_model",
    "make_env",
    "policy_settings",
    "rollout_info",
    "run_config",
    "schedule_of",
    "scheduler_policy",
    "servo_agent",
    "settings_policy",
    "vecnormalize_path",
]
