"""One way to use a per-move settings model: :func:`load_tuner` reads the settings model
vfgym ships or a settings model of ``vfgym fit`` (JSON) and returns a :class:`Tuner`, a
callable from a move to the settings it picks. A trained VFTune-v0 agent (``.zip``) is
made the same kind of :class:`Tuner` by :func:`vfgym.agents.load_tuner`, which needs
stable-baselines3; this module does not.

A tuner knows the machine it was learnt on (its axis's plant and measures). Used on an
axis with another machine, or on a move outside the ranges of its training moves'
features, it says so in one line (once for the axis, once for the first such move),
through ``warn`` (default: :func:`warnings.warn` with :class:`TunerWarning`).
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from dataclasses import dataclass, field
from os import PathLike
from pathlib import Path
from typing import Any

import numpy as np

from vfgym.axis import PAPER_AXIS, Axis, as_axis, machine_digest
from vfgym.moves.features import SCENARIO_FEATURES, scenario_features
from vfgym.moves.scenarios import Scenario
from vfgym.params import Settings

from .supervised import PRETRAINED, load_settings_model

RANGE_MARGIN = 0.02
"""A feature counts as outside the training moves' range beyond this share of the range."""
SHIPPED_SOURCE = "pretrained settings model"


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


def default_warn(message: str) -> None:
    """Issue a tuner's one-line warning as a :class:`TunerWarning` (the default ``warn``)."""
    warnings.warn(message, TunerWarning, stacklevel=3)


def _model_ranges(model: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    points = getattr(model, "points", None)
    if points is None:
        return None
    x = np.asarray(points) * model.scale + model.mean
    return x.min(axis=0), x.max(axis=0), np.asarray(model.weights) > 0


def outside_ranges(
    ranges: tuple[np.ndarray, np.ndarray, np.ndarray] | None, axis: Axis
) -> Callable[[Scenario], str | None]:
    """The check :attr:`Tuner.outside` runs: a move → the first feature outside the
    training moves' ranges (beyond :data:`RANGE_MARGIN`), as a phrase, or ``None``.

    Parameters
    ----------
    ranges : tuple of numpy.ndarray, or None
        The features' lows, highs and which of them count; ``None``: not known.
    axis : Axis
        The axis the moves are on (their features are computed on its plant).

    Returns
    -------
    callable
        Scenario → phrase or ``None``.
    """

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
    axis: Axis | str | PathLike[str] = PAPER_AXIS,
    warn: Callable[[str], None] | None = None,
) -> Tuner:
    """The tuner in a settings model's file (JSON): the shipped one or one of ``vfgym fit``.

    Parameters
    ----------
    path : str, Path or None
        The file; ``None``: the settings model vfgym ships (learnt on the paper's plant
        with varied loads). A VFTune-v0 agent (``.zip``) is read by
        :func:`vfgym.agents.load_tuner` instead.
    axis : Axis, str or os.PathLike
        The axis (or its file) of the moves (default: the paper's).
    warn : callable or None
        Gets each one-line warning (default: :func:`warnings.warn`, :class:`TunerWarning`).

    Returns
    -------
    Tuner
        The tuner, callable on moves.

    Raises
    ------
    ValueError
        If the file is missing, not a settings model, or an agent's ``.zip``.
    """
    warn = warn or default_warn
    if path is not None and str(path).endswith(".zip"):
        raise ValueError(
            f"--model {path}: a trained agent; vfgym.agents.load_tuner reads it "
            "(the agents extra: stable-baselines3)"
        )
    ax = as_axis(axis)
    model = load_settings_model(PRETRAINED if path is None else path)
    own = getattr(model, "trained_on", None) or trained_on(PAPER_AXIS)
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
        outside_ranges(_model_ranges(model), ax),
        warn,
    )


__all__ = [
    "RANGE_MARGIN",
    "SHIPPED_SOURCE",
    "Tuner",
    "TunerWarning",
    "default_warn",
    "load_tuner",
    "machine_digest",
    "outside_ranges",
    "trained_on",
]
