"""The supervised amortised tuner: a ridge regression from a move's features (the ones the
envs observe, :func:`vfgym.envs._common.scenario_features`) to its optimal settings,
trained on per-move optima (:mod:`vfgym.agents.optima`).

Targets, in the search space's coordinates: value, L and Ts/Tf as unit coordinates of
:data:`vfgym.space.SPACE` (log scales), and k as log10(k / k_a), k_a the k that holds the
pulse train to the loaded motor's usable acceleration (:func:`vfgym.params.paper_k`),
which carries most of the load's effect on k. Inputs: the features, their squares and
pairwise products (``degree`` 2), standardised; a ridge penalty keeps the few hundred
moves from being over-fitted. Prediction is plain numpy: no torch is needed.

A model is a JSON file (:meth:`SettingsModel.save`, :func:`load_settings_model`); the
pretrained one ships in ``vfgym/agents/pretrained/`` with the config and the command that
made it (:data:`PRETRAINED`).
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from vfgym import space
from vfgym.envs._common import SCENARIO_FEATURES, scenario_features
from vfgym.io.runs import write_text
from vfgym.moves.scenarios import Scenario
from vfgym.params import PAPER_PLANT, Plant, Settings, paper_k

from .optima import MoveOptimum

PRETRAINED = Path(__file__).parent / "pretrained" / "settings_model.json"
"""The shipped model (its ``config.yaml`` and ``command.txt`` beside it)."""

MODEL_KIND = "vfgym-settings-regression"
TARGETS = ("value_rad", "error_limit_rad", "log10_k_over_ka", "ts_over_tf")
"""What the regression predicts (module doc)."""
K_LOG_RANGE = 4.0
"""log10(k / k_a) is clipped to ±this before k is clipped to the search space."""


def accel_k(plant: Plant) -> float:
    """k_a: the k that holds the pulse train to the loaded motor's usable acceleration.

    Parameters
    ----------
    plant : Plant
        The plant with the move's load.

    Returns
    -------
    float
        :func:`vfgym.params.paper_k` at ``plant.motor.usable_accel_rad_s2``.
    """
    return paper_k(plant, plant.motor.usable_accel_rad_s2)


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


def expand(x: np.ndarray, degree: int) -> np.ndarray:
    """Model inputs of feature rows: the features and, for ``degree`` 2, every product of
    two of them (squares included).

    Parameters
    ----------
    x : numpy.ndarray
        (n, features).
    degree : int
        1 or 2.

    Returns
    -------
    numpy.ndarray
        (n, inputs).
    """
    x = np.atleast_2d(np.asarray(x, dtype=np.float64))
    if degree == 1:
        return x
    i, j = np.triu_indices(x.shape[1])
    return np.hstack([x, x[:, i] * x[:, j]])


@dataclass(frozen=True, eq=False)
class SettingsModel:
    """A fitted ridge regression from move features to settings (module doc).

    Attributes
    ----------
    degree : int
        1 (linear in the features) or 2 (with their products).
    ridge : float
        The ridge penalty it was fitted with (on standardised inputs).
    mean, scale : numpy.ndarray
        Standardisation of the expanded inputs.
    coef : numpy.ndarray
        (inputs + 1, 4): intercept row first.
    accel_law : str
        The law of the predicted settings.
    """

    degree: int
    ridge: float
    mean: np.ndarray
    scale: np.ndarray
    coef: np.ndarray
    accel_law: str = "rise"

    def predict_targets(self, features: np.ndarray) -> np.ndarray:
        """Targets (:data:`TARGETS`) for feature rows.

        Parameters
        ----------
        features : numpy.ndarray
            (n, len(SCENARIO_FEATURES)) or one row.

        Returns
        -------
        numpy.ndarray
            (n, 4).
        """
        z = (expand(features, self.degree) - self.mean) / self.scale
        return self.coef[0] + z @ self.coef[1:]

    def settings(self, scenario: Scenario, plant: Plant = PAPER_PLANT) -> Settings:
        """The settings the model picks for a move.

        Parameters
        ----------
        scenario : Scenario
            The move.
        plant : Plant
            The base plant (an axis's), before the move's load.

        Returns
        -------
        Settings
            Inside the search space.
        """
        loaded = scenario.plant(plant)
        t = self.predict_targets(scenario_features(scenario, plant, loaded))[0]
        return target_settings(t, loaded, self.accel_law)

    def to_dict(self) -> dict[str, Any]:
        """The model as plain data (what :meth:`save` writes)."""
        return {
            "kind": MODEL_KIND,
            "features": list(SCENARIO_FEATURES),
            "targets": list(TARGETS),
            "degree": self.degree,
            "ridge": self.ridge,
            "accel_law": self.accel_law,
            "mean": self.mean.tolist(),
            "scale": self.scale.tolist(),
            "coef": self.coef.tolist(),
        }

    def save(self, path: str | Path) -> None:
        """Write the model as JSON.

        Parameters
        ----------
        path : str or Path
            The file.
        """
        write_text(path, json.dumps(self.to_dict(), indent=1) + "\n")


def load_settings_model(path: str | Path = PRETRAINED) -> SettingsModel:
    """A model written by :meth:`SettingsModel.save` (default: the shipped one).

    Parameters
    ----------
    path : str or Path
        The JSON file.

    Returns
    -------
    SettingsModel
        The model.

    Raises
    ------
    ValueError
        If the file is missing, not such a model, or made for other features.
    """
    p = Path(path)
    if not p.is_file():
        raise ValueError(f"--model {p}: no such file")
    try:
        d = json.loads(p.read_text())
    except (UnicodeDecodeError, json.JSONDecodeError):
        d = None
    if not isinstance(d, dict) or d.get("kind") != MODEL_KIND:
        raise ValueError(f"--model {p}: not a vfgym settings model ({MODEL_KIND} JSON)")
    if d.get("features") != list(SCENARIO_FEATURES) or d.get("targets") != list(TARGETS):
        raise ValueError(f"--model {p}: made for other features or targets than this vfgym's")
    return SettingsModel(
        degree=int(d["degree"]),
        ridge=float(d["ridge"]),
        mean=np.array(d["mean"], dtype=np.float64),
        scale=np.array(d["scale"], dtype=np.float64),
        coef=np.array(d["coef"], dtype=np.float64),
        accel_law=str(d["accel_law"]),
    )


def fit_settings_model(
    scenarios: Sequence[Scenario],
    optima: Sequence[MoveOptimum],
    *,
    degree: int = 2,
    ridge: float = 1.0,
    plant: Plant = PAPER_PLANT,
) -> SettingsModel:
    """Fit the ridge regression to per-move optima (closed form, deterministic).

    Parameters
    ----------
    scenarios : sequence of Scenario
        The training moves.
    optima : sequence of MoveOptimum
        Their optima, in the same order (same scenario names).
    degree : int
        1 or 2 (:func:`expand`).
    ridge : float
        The penalty on the standardised inputs' coefficients, ≥ 0.
    plant : Plant
        The base plant the optima were found on.

    Returns
    -------
    SettingsModel
        The fitted model.

    Raises
    ------
    ValueError
        If the two sequences do not match or an argument is out of range.
    """
    if [s.name for s in scenarios] != [o.scenario for o in optima]:
        raise ValueError("scenarios and optima differ: give the optima of these moves, in order")
    if degree not in (1, 2):
        raise ValueError(f"degree={degree!r} is not allowed: 1 or 2")
    if not (ridge >= 0.0 and math.isfinite(ridge)):
        raise ValueError(f"ridge={ridge!r} is not allowed: a finite number >= 0")
    laws = {o.settings.accel_law for o in optima}
    if len(laws) != 1:
        raise ValueError(f"optima of several acceleration laws ({sorted(laws)}): give one")
    loaded = [sc.plant(plant) for sc in scenarios]
    x = expand(
        np.array(
            [scenario_features(sc, plant, p) for sc, p in zip(scenarios, loaded, strict=True)]
        ),
        degree,
    )
    y = np.array([settings_targets(o.settings, p) for o, p in zip(optima, loaded, strict=True)])
    mean = x.mean(axis=0)
    scale = x.std(axis=0)
    scale[scale < 1e-12] = 1.0  # a constant input: its coefficient stays 0
    z = (x - mean) / scale
    a = np.hstack([np.ones((len(z), 1)), z])
    # ridge as least squares on rows sqrt(ridge)·I appended (the intercept not penalised);
    # lstsq's minimum-norm answer keeps collinear inputs (the one-hot profiles) harmless
    pen = math.sqrt(ridge) * np.eye(a.shape[1])[1:]
    coef = np.linalg.lstsq(np.vstack([a, pen]), np.vstack([y, np.zeros((len(pen), 4))]))[0]
    return SettingsModel(degree, float(ridge), mean, scale, coef, laws.pop())


@dataclass(frozen=True)
class TrainConfig:
    """How a settings model is trained: what its ``config.yaml`` holds.

    Parameters
    ----------
    optima : str
        The optima CSV of the training moves (:func:`vfgym.agents.optima.read_optima`),
        relative to the repository's root.
    degree : int
        1 or 2 (:func:`expand`).
    ridge : float
        The ridge penalty, ≥ 0.
    """

    optima: str = "experiments/optima/train.csv"
    degree: int = 2
    ridge: float = 1.0


def train_settings_model(cfg: TrainConfig, root: str | Path = ".") -> SettingsModel:
    """Fit a model as its config says, on the paper's plant (the random moves' base).

    Parameters
    ----------
    cfg : TrainConfig
        The training config.
    root : str or Path
        The folder ``cfg.optima`` is relative to.

    Returns
    -------
    SettingsModel
        The fitted model.
    """
    from vfgym.agents.optima import read_optima
    from vfgym.moves.scenarios import get_scenario

    optima = read_optima(Path(root) / cfg.optima)
    scenarios = [get_scenario(o.scenario) for o in optima]
    return fit_settings_model(scenarios, optima, degree=cfg.degree, ridge=cfg.ridge)


__all__ = [
    "PRETRAINED",
    "TARGETS",
    "SettingsModel",
    "TrainConfig",
    "accel_k",
    "expand",
    "fit_settings_model",
    "load_settings_model",
    "settings_targets",
    "target_settings",
    "train_settings_model",
]
