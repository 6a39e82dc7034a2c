"""Every amortised tuner as one callable: :func:`load_tuner` reads a settings model (the
shipped one or one of ``vfgym fit``, through :func:`vfgym.permove.load_tuner`) or a
trained VFTune-v0 agent (``.zip``), and returns a :class:`vfgym.permove.Tuner`, move →
settings.

An agent's tuner, like a settings model's, knows the machine it was learnt on (its
training axis) and the ranges of its training moves' features (drawn as its training
env drew them), and says in one line when it is used outside them.
"""

from __future__ import annotations

from collections.abc import Callable
from os import PathLike
from pathlib import Path
from typing import Any

import numpy as np

from vfgym.axis import LOADS_AXIS, Axis, as_axis, load_axis, machine_digest
from vfgym.moves.features import scenario_features
from vfgym.permove import Tuner, default_warn, outside_ranges
from vfgym.permove import load_tuner as load_settings_tuner

from .loaded import policy_settings, run_config, scheduler_policy, servo_agent

AGENT_DRAWS = 512
"""Training moves drawn to know an agent's training ranges (its env's own draws)."""


def agent_ranges(
    env_kwargs: dict[str, Any], draws: int = AGENT_DRAWS
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The feature ranges of an agent's training moves: ``draws`` moves drawn as its
    training env drew them (its split, seed range and axis).

    Parameters
    ----------
    env_kwargs : dict
        The agent's env arguments (``scenario``, ``split``, ``seed_range``, ``axis``).
    draws : int
        Moves drawn.

    Returns
    -------
    tuple of numpy.ndarray
        The features' lows, highs, and which count (all), for
        :func:`vfgym.permove.outside_ranges`.
    """
    from vfgym.envs import EnvConfig

    keys = ("scenario", "split", "seed_range", "axis")
    kw = {k: env_kwargs[k] for k in keys if k in env_kwargs}
    src = EnvConfig(**kw).scenario_source()
    lo, _ = src.seed_range
    moves = [src.fixed] if src.fixed is not None else [src.seeded(lo + i) for i in range(draws)]
    x = np.array([scenario_features(sc, src.base, sc.plant(src.base)) for sc in moves])
    return x.min(axis=0), x.max(axis=0), np.ones(x.shape[1], dtype=bool)


def load_tuner(
    path: str | Path | None,
    axis: Axis | str | PathLike[str],
    warn: Callable[[str], None] | None = None,
) -> Any:
    """The controller in a model file, the one loader of every kind: a settings model
    (JSON, :func:`vfgym.permove.load_tuner`, no torch needed) or a VFTune-v0 agent
    (``.zip``), each a :class:`Tuner`; or a VFServo-v0 agent (``.zip``), a
    :class:`vfgym.scoring.Scheduler` (:class:`vfgym.agents.loaded.AgentScheduler`) that
    changes the settings during the move. :func:`vfgym.evaluate` takes any of them.

    Parameters
    ----------
    path : str, Path or None
        The file; ``None``: the settings model vfgym ships (learnt on the paper's plant
        with varied loads).
    axis : Axis, str or os.PathLike
        The axis (or its file) the moves belong to and the controller runs on; a model
        learnt on another machine says so in a warning.
    warn : callable or None
        Gets each one-line warning (default: :func:`warnings.warn`,
        :class:`vfgym.permove.TunerWarning`).

    Returns
    -------
    Tuner or AgentScheduler
        The tuner: callable on moves, or a scheduler.

    Raises
    ------
    ValueError
        If the file is missing or neither kind of tuner.
    """
    ax = as_axis(axis)
    if path is None or not str(path).endswith(".zip"):
        return load_settings_tuner(path, ax, warn)
    return _agent_tuner(Path(path), ax, warn or default_warn)


def _agent_tuner(path: Path, ax: Axis, warn: Callable[[str], None]) -> Any:
    if not path.is_file():
        raise ValueError(f"--model {path}: no such file")
    env_kwargs = (run_config(path).get("hyperparams") or {}).get("env_kwargs") or {}
    own_file = env_kwargs.get("axis")
    own = load_axis(own_file) if own_file and Path(own_file).is_file() else LOADS_AXIS
    source = f"agent {path}"
    if machine_digest(own) != machine_digest(ax):
        warn(
            f"{source}: trained on axis {own.name!r}, used on axis {ax.name!r} with another "
            "plant or measures; its observations describe moves it never saw"
        )
    agent = servo_agent(path)
    if agent is not None:  # a VFServo-v0 agent schedules each move itself
        return scheduler_policy(agent, ax, source)
    policy = policy_settings(path, ax)
    ranges = agent_ranges(env_kwargs)
    return Tuner(source, ax, own.name, policy, outside_ranges(ranges, ax), warn)


__all__ = ["AGENT_DRAWS", "agent_ranges", "load_tuner"]
