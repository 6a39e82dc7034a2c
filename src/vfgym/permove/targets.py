"""The coordinates the settings models learn and predict in: :class:`vfgym.space.Relative`'s
log coordinates, with ``k_ref`` the move's k_a, the k that holds the pulse train to the
loaded motor's usable acceleration (:func:`vfgym.params.usable_k`). k_a carries most of a
load's effect on the best k (a step's optimal k sits at k_a, on the acceleration limit),
and L/value is 1 on the cost's ridge (L = value).
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

TARGETS = ("log_value_rad", "log_limit_over_value", "log_k_over_ka", "log_ts_over_tf")
"""What the models predict (module doc), natural logarithms."""
TARGETS_0_1 = ("value_rad", "error_limit_rad", "log10_k_over_ka", "ts_over_tf")
"""The targets of model files written by vfgym 0.1 (value, L and Ts/Tf as unit coordinates
of :data:`vfgym.space.SPACE` in [-1, 1], k as log10(k / k_a)): :func:`from_targets_0_1`."""

accel_k = usable_k
"""k_a: the k that holds the pulse train to the loaded motor's usable acceleration
(:func:`vfgym.params.usable_k`)."""


def settings_targets(settings: Settings, plant: Plant) -> np.ndarray:
    """The targets of settings on a move's plant (order of :data:`TARGETS`).

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
    return space.Relative(accel_k(plant)).to_log(settings)


def target_settings(t: np.ndarray, plant: Plant, accel_law: str = "rise") -> Settings:
    """Settings from targets (the inverse of :func:`settings_targets`, clipped to the
    coordinates' ranges and the search space).

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
    return space.Relative(accel_k(plant)).from_log(t, accel_law)


def from_targets_0_1(t: np.ndarray) -> np.ndarray:
    """Targets (:data:`TARGETS`) from rows of :data:`TARGETS_0_1`, the same settings: a
    pick model's library of an older file is read into today's coordinates.

    Parameters
    ----------
    t : numpy.ndarray
        (n, 4).

    Returns
    -------
    numpy.ndarray
        (n, 4).
    """
    v, lim, _, ts = space.SPACE
    rows = []
    for t0, t1, t2, t3 in np.asarray(t, dtype=np.float64).reshape(-1, 4):
        value = math.log(v.from_unit(t0))
        rows.append([value, math.log(lim.from_unit(t1)) - value, t2 * math.log(10.0),
                     math.log(ts.from_unit(t3))])  # fmt: skip
    return np.array(rows, dtype=np.float64).reshape(-1, 4)


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
    "TARGETS",
    "TARGETS_0_1",
    "TargetModel",
    "accel_k",
    "from_targets_0_1",
    "model_head",
    "settings_targets",
    "target_settings",
]
