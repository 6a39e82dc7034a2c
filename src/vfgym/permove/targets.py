"""The coordinates the settings models learn and predict in.

Value, L and Ts/Tf as unit coordinates of :data:`vfgym.space.SPACE` (log scales), and k
as log10(k / k_a), k_a the k that holds the pulse train to the loaded motor's usable
acceleration (:func:`vfgym.params.usable_k`), which carries most of a load's effect on
the best k: a step's optimal k sits at k_a, on the acceleration limit.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from vfgym import space
from vfgym.io.runs import write_text
from vfgym.moves.features import SCENARIO_FEATURES, scenario_features
from vfgym.moves.scenarios import Scenario
from vfgym.params import DEFAULT_MEASURES, PAPER_PLANT, Measures, Plant, Settings, usable_k

TARGETS = ("value_rad", "error_limit_rad", "log10_k_over_ka", "ts_over_tf")
"""What the regression predicts (module doc)."""
K_LOG_RANGE = 4.0
"""log10(k / k_a) is clipped to ±this before k is clipped to the search space."""


accel_k = usable_k
"""k_a: the k that holds the pulse train to the loaded motor's usable acceleration
(:func:`vfgym.params.usable_k`)."""


def settings_targets(settings: Settings, plant: Plant) -> np.ndarray:
    """The regression targets of settings on a move's plant (order of :data:`TARGETS`).

    Parameters
    ----------
    settings : Settings
        The settings.
    plant : Plant
        The plant with the move's load.

    Returns
    -------
    numpy.ndarray
        float64, (4,).
    """
    u = np.array([d.to_unit(getattr(settings, d.name)) for d in space.SPACE])  # float64
    u[2] = math.log10(settings.k / accel_k(plant))
    return u


def target_settings(t: np.ndarray, plant: Plant, accel_law: str = "rise") -> Settings:
    """Settings from regression targets (the inverse of :func:`settings_targets`, clipped
    to the search space).

    Parameters
    ----------
    t : numpy.ndarray
        (4,), in the order of :data:`TARGETS`.
    plant : Plant
        The plant with the move's load.
    accel_law : str
        The acceleration law.

    Returns
    -------
    Settings
        Inside :data:`vfgym.space.SPACE`.
    """
    u = np.clip(np.asarray(t, dtype=np.float64), -1.0, 1.0)
    kd = space.SPACE[2]
    k = accel_k(plant) * 10.0 ** float(np.clip(t[2], -K_LOG_RANGE, K_LOG_RANGE))
    u[2] = kd.to_unit(min(max(k, kd.low), kd.high))
    return space.from_action(u, accel_law)


class TargetModel:
    """What both settings models share: settings from the targets a model gives for a
    move's features (:meth:`targets_of`, each model's own), and writing it as JSON."""

    accel_law: str

    def targets_of(self, features: np.ndarray) -> np.ndarray:
        """The targets (:data:`TARGETS`) for one move's features; each model's own.

        Parameters
        ----------
        features : numpy.ndarray
            (len(SCENARIO_FEATURES),).

        Returns
        -------
        numpy.ndarray
            (4,).
        """
        raise NotImplementedError

    def to_dict(self) -> dict[str, Any]:
        """The model as plain data (what :meth:`save` writes); each model's own."""
        raise NotImplementedError

    def settings(
        self,
        scenario: Scenario,
        plant: Plant = PAPER_PLANT,
        measures: Measures = DEFAULT_MEASURES,
        plants: Sequence[Any] = (),
    ) -> Settings:
        """The settings the model picks for a move.

        Parameters
        ----------
        scenario : Scenario
            The move.
        plant : Plant
            The base plant (an axis's), before the move's load.
        measures : Measures
            The axis's measures (for a model that scores candidates on the move).
        plants : sequence of PlantVariant
            True plants a model that scores candidates keeps them feasible on (unused by
            a model that does not).

        Returns
        -------
        Settings
            Inside the search space.
        """
        loaded = scenario.plant(plant)
        t = self.targets_of(scenario_features(scenario, plant, loaded))
        return target_settings(t, loaded, self.accel_law)

    def save(self, path: str | Path) -> None:
        """Write the model as JSON.

        Parameters
        ----------
        path : str or Path
            The file.
        """
        write_text(path, json.dumps(self.to_dict()) + "\n")


def model_head(kind: str, accel_law: str) -> dict[str, Any]:
    """The keys every model file starts with: its kind, features, targets and law.

    Parameters
    ----------
    kind : str
        The model's kind.
    accel_law : str
        The law of its settings.

    Returns
    -------
    dict
        ``kind``, ``features``, ``targets``, ``accel_law``.
    """
    return {
        "kind": kind,
        "features": list(SCENARIO_FEATURES),
        "targets": list(TARGETS),
        "accel_law": accel_law,
    }


__all__ = [
    "K_LOG_RANGE",
    "TARGETS",
    "TargetModel",
    "accel_k",
    "model_head",
    "settings_targets",
    "target_settings",
]
