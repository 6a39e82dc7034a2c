"""One way to use any amortised tuner: :func:`load_tuner` reads the settings model vfgym
ships, a settings model of ``vfgym fit`` (JSON) or a VFTune-v0 agent (``.zip``), and
returns a :class:`Tuner`, a callable from a move to the settings it picks.

A tuner knows the machine it was learnt on (its axis's plant and measures). Used on an
axis with another machine, or on a move outside the ranges of its training moves'
features, it says so in one line (once for the axis, once for the first such move),
through ``warn`` (default: :func:`warnings.warn` with :class:`TunerWarning`).
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from vfgym.moves.axis import PAPER_AXIS, Axis, load_axis, machine_digest
from vfgym.moves.features import SCENARIO_FEATURES, scenario_features
from vfgym.moves.scenarios import Scenario
from vfgym.params import Settings

RANGE_MARGIN = 0.02
"""A feature counts as outside the training moves' range beyond this share of the range."""
SHIPPED_SOURCE = "pretrained settings model"
AGENT_DRAWS = 512
"""Training moves drawn to know an agent's training ranges (its env's own draws)."""


class TunerWarning(UserWarning):
    """A tuner used on another machine than its own, or on moves unlike its training's."""


def trained_on(axis: Axis) -> dict[str, str]:
    """The record a settings model keeps of its axis (``trained_on`` in its JSON).

    Parameters
    ----------
    axis : Axis
        The axis it was fitted on.

    Returns
    -------
    dict
        ``axis`` (the name) and ``machine`` (:func:`machine_digest`).
    """
    return {"axis": axis.name, "machine": machine_digest(axis)}


@dataclass(frozen=True, eq=False)
class Tuner:
    """An amortised tuner as a function: move (or its name on the axis) → settings.

    Attributes
    ----------
    source : str
        What it is, as the outputs name it (``pretrained settings model``, ``model
        FILE``, ``agent FILE``).
    axis : Axis
        The axis the moves are on (names resolve on it, settings are made for its plant).
    own_axis : str
        The name of the axis it was learnt on.
    pick : callable
        Scenario → Settings, the tuner itself.
    outside : callable
        Scenario → a phrase saying how the move is outside the training moves' ranges,
        or ``None`` (inside, or not known for this kind of tuner).
    warn : callable
        Called with each one-line warning.
    """

    source: str
    axis: Axis
    own_axis: str
    pick: Callable[[Scenario], Settings]
    outside: Callable[[Scenario], str | None]
    warn: Callable[[str], None]
    _warned: list[bool] = field(default_factory=list, repr=False)

    def __call__(self, scenario: Scenario | str) -> Settings:
        """The settings the tuner picks for a move.

        Parameters
        ----------
        scenario : Scenario or str
            The move, or its name on :attr:`axis`.

        Returns
        -------
        Settings
            The settings.
        """
        sc = self.axis.scenario(scenario)
        if not self._warned:
            why = self.outside(sc)
            if why is not None:
                self._warned.append(True)
                self.warn(
                    f"{self.source}: move {sc.name!r} is outside its training moves ({why}); "
                    "its settings there are an extrapolation (later such moves not reported)"
                )
        return self.pick(sc)


def _default_warn(message: str) -> None:
    warnings.warn(message, TunerWarning, stacklevel=3)


def _model_ranges(model: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    points = getattr(model, "points", None)
    if points is None:
        return None
    x = np.asarray(points) * model.scale + model.mean
    return x.min(axis=0), x.max(axis=0), np.asarray(model.weights) > 0


def _agent_ranges(
    env_kwargs: dict[str, Any], own: Axis | None, draws: int = AGENT_DRAWS
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The feature ranges of an agent's training moves: ``draws`` moves drawn as its
    training env drew them (its split, seed range and axis)."""
    from vfgym.envs import EnvConfig

    keys = ("scenario", "split", "seed_range", "plant")
    kw = {k: env_kwargs[k] for k in keys if k in env_kwargs}
    src = EnvConfig(axis=own, **kw).scenario_source()
    lo, _ = src.seed_range
    moves = [src.fixed] if src.fixed is not None else [src.seeded(lo + i) for i in range(draws)]
    x = np.array([scenario_features(sc, src.base, sc.plant(src.base)) for sc in moves])
    return x.min(axis=0), x.max(axis=0), np.ones(x.shape[1], dtype=bool)


def _outside_ranges(
    ranges: tuple[np.ndarray, np.ndarray, np.ndarray] | None, axis: Axis
) -> Callable[[Scenario], str | None]:
    def outside(sc: Scenario) -> str | None:
        if ranges is None:
            return None
        lo, hi, used = ranges
        f = scenario_features(sc, axis.plant, sc.plant(axis.plant))
        pad = RANGE_MARGIN * (hi - lo) + 1e-9
        for j, name in enumerate(SCENARIO_FEATURES):
            if used[j] and not lo[j] - pad[j] <= f[j] <= hi[j] + pad[j]:
                return f"{name} {f[j]:.3g}, trained on {lo[j]:.3g} to {hi[j]:.3g}"
        return None

    return outside


def load_tuner(
    path: str | Path | None = None,
    axis: str | Path | Axis | None = None,
    warn: Callable[[str], None] | None = None,
) -> Any:
    """The tuner in a file: a settings model (JSON) or a VFTune-v0 agent (``.zip``), each
    a :class:`Tuner`; or a VFServo-v0 agent (``.zip``), a :class:`vfgym.scoring.Scheduler`
    (:class:`vfgym.agents.loaded.AgentScheduler`) that changes the settings during the move.
    :func:`vfgym.evaluate` takes any of them.

    Parameters
    ----------
    path : str, Path or None
        The file; ``None``: the settings model vfgym ships (learnt on the paper's plant
        with varied loads).
    axis : str, Path, Axis or None
        The axis (file) of the moves; ``None``: the tuner's own (an agent's training
        axis, the paper's for a settings model).
    warn : callable or None
        Gets each one-line warning (default: :func:`warnings.warn`, :class:`TunerWarning`).

    Returns
    -------
    Tuner or AgentScheduler
        The tuner: callable on moves, or a scheduler.

    Raises
    ------
    ValueError
        If the file is missing or neither kind of tuner.
    """
    warn = warn or _default_warn
    ax = load_axis(axis) if isinstance(axis, (str, Path)) else axis
    if path is not None and str(path).endswith(".zip"):
        return _agent_tuner(Path(path), ax, warn)
    from vfgym.agents.supervised import PRETRAINED, load_settings_model

    model = load_settings_model(PRETRAINED if path is None else path)
    own = getattr(model, "trained_on", None) or trained_on(PAPER_AXIS)
    ax = ax or PAPER_AXIS
    source = SHIPPED_SOURCE if path is None else f"model {path}"
    if own.get("machine") != machine_digest(ax):
        warn(
            f"{source}: learnt on axis {own.get('axis')!r}, used on axis {ax.name!r} with "
            f"another plant or measures; fit one for it: vfgym fit --axis FILE"
        )
    plant, design = ax.plant, ax.design_plants()
    return Tuner(
        source,
        ax,
        str(own.get("axis")),
        lambda sc: model.settings(sc, plant, ax.measures, design),
        _outside_ranges(_model_ranges(model), ax),
        warn,
    )


def _agent_tuner(path: Path, ax: Axis | None, warn: Callable[[str], None]) -> Any:
    from vfgym.agents import _config, policy_settings, scheduler_policy, servo_agent

    if not path.is_file():
        raise ValueError(f"--model {path}: no such file")
    env_kwargs = (_config(path).get("hyperparams") or {}).get("env_kwargs") or {}
    own_file = env_kwargs.get("axis")
    own = load_axis(own_file) if own_file and Path(own_file).is_file() else PAPER_AXIS
    source = f"agent {path}"
    if ax is not None and machine_digest(own) != machine_digest(ax):
        warn(
            f"{source}: trained on axis {own.name!r}, used on axis {ax.name!r} with another "
            "plant or measures; its observations describe moves it never saw"
        )
    axis = ax or own
    agent = servo_agent(path)
    if agent is not None:  # a VFServo-v0 agent schedules each move itself
        return scheduler_policy(agent, axis, source)
    policy = policy_settings(path, ax)
    ranges = _agent_ranges(env_kwargs, None if own is PAPER_AXIS else own)
    return Tuner(source, axis, own.name, policy, _outside_ranges(ranges, axis), warn)


__all__ = [
    "AGENT_DRAWS",
    "RANGE_MARGIN",
    "Tuner",
    "TunerWarning",
    "load_tuner",
    "machine_digest",
    "trained_on",
]
