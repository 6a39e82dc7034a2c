"""The supervised settings models: learnt from per-move optima (:mod:`vfgym.permove.optima`)
of training moves, they map a move's features (the ones the envs observe,
:func:`vfgym.moves.features.scenario_features`) to settings in one plain-numpy look-up, no
torch needed. Both work in the coordinates of :mod:`vfgym.permove.targets`.

- ``pick`` (:class:`vfgym.permove.pick.PickModel`, the shipped one): the library candidate
  of least mean cost ratio over the move's nearest training moves.
- ``ridge`` (:class:`SettingsModel`, the baseline it beats): a ridge regression straight to
  the optimal settings; inputs the features, their squares and pairwise products
  (``degree`` 2), standardised.

A model is a JSON file (``save``, :func:`load_settings_model`); the pretrained one ships in
``vfgym/permove/pretrained/`` with the config and the command that made it
(:data:`PRETRAINED`), and :func:`train_settings_model` remakes it from its config.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from vfgym._validate import check_choice, check_int
from vfgym.moves.features import SCENARIO_FEATURES, scenario_features
from vfgym.moves.scenarios import Scenario
from vfgym.params import PAPER_PLANT, Plant

from .optima import MoveOptimum
from .pick import PICK_KIND, PickModel, fit_pick_model, greedy_library, ratio_table
from .targets import (
    TARGETS,
    TARGETS_0_1,
    TargetModel,
    accel_k,
    from_targets_0_1,
    model_head,
    settings_targets,
    target_settings,
)

PRETRAINED = Path(__file__).parent / "pretrained" / "settings_model.json"
"""The shipped model (its ``config.yaml`` and ``command.txt`` beside it)."""

MODEL_KIND = "vfgym-settings-regression"


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
class SettingsModel(TargetModel):
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

    def targets_of(self, features: np.ndarray) -> np.ndarray:
        """The regression's targets for one move's features.

        Parameters
        ----------
        features : numpy.ndarray
            (len(SCENARIO_FEATURES),).

        Returns
        -------
        numpy.ndarray
            (4,).
        """
        return self.predict_targets(features)[0]

    def to_dict(self) -> dict[str, Any]:
        """The model as plain data (what :meth:`save` writes)."""
        return model_head(MODEL_KIND, self.accel_law) | {
            "degree": self.degree,
            "ridge": self.ridge,
            "mean": self.mean.tolist(),
            "scale": self.scale.tolist(),
            "coef": self.coef.tolist(),
        }


def load_settings_model(path: str | Path = PRETRAINED) -> PickModel | SettingsModel:
    """A model written by :meth:`SettingsModel.save` (default: the shipped one).

    Parameters
    ----------
    path : str or Path
        The JSON file.

    Returns
    -------
    PickModel or SettingsModel
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
    if not isinstance(d, dict) or d.get("kind") not in (MODEL_KIND, PICK_KIND):
        raise ValueError(f"--model {p}: not a vfgym settings model ({PICK_KIND} JSON)")
    old = d.get("targets") == list(TARGETS_0_1)  # a library reads into today's targets
    if d.get("features") != list(SCENARIO_FEATURES) or not (
        d.get("targets") == list(TARGETS) or (old and d["kind"] == PICK_KIND)
    ):
        again = " (an older vfgym's regression: fit it again)" if old else ""
        raise ValueError(
            f"--model {p}: made for other features or targets than this vfgym's{again}"
        )
    if d["kind"] == PICK_KIND:
        library = np.array(d["library"], dtype=np.float64)
        return PickModel(
            neighbours=int(d["neighbours"]),
            mean=np.array(d["mean"], dtype=np.float64),
            scale=np.array(d["scale"], dtype=np.float64),
            points=np.array(d["points"], dtype=np.float64),
            library=from_targets_0_1(library) if old else library,
            ratios=np.array(d["ratios"], dtype=np.float64),
            weights=np.array(d["weights"], dtype=np.float64),
            accel_law=str(d["accel_law"]),
            trained_on=d.get("trained_on"),
            check=int(d.get("check", 0)),
        )
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


KINDS = ("pick", "ridge")
"""The model kinds: :class:`PickModel` and the ridge regression :class:`SettingsModel`."""


@dataclass(frozen=True)
class TrainConfig:
    """How a settings model is trained: what its ``config.yaml`` holds.

    Parameters
    ----------
    kind : str
        ``pick`` (:func:`fit_pick_model`) or ``ridge`` (:func:`fit_settings_model`).
    optima : str
        The optima CSV of the training moves (:func:`vfgym.permove.optima.read_optima`),
        relative to the repository's root.
    costs : str
        The candidates' cost table (``experiments/candidate_costs.py``; ``pick`` only).
    neighbours, library : int
        The pick model's neighbours and library size.
    ignore : tuple of str
        Features the pick model's distance leaves out.
    degree, ridge : int, float
        The ridge regression's degree (1 or 2) and penalty (≥ 0).
    check : int
        The pick model's candidates simulated on each new move
        (:attr:`PickModel.check`), 0 to ``library``.

    Raises
    ------
    ValueError
        If ``kind`` is not one of :data:`KINDS`.
    """

    kind: str = "pick"
    optima: str = "experiments/optima/train.csv"
    costs: str = "experiments/optima/train_costs.npz"
    neighbours: int = 6
    library: int = 64
    ignore: tuple[str, ...] = ("direction",)
    degree: int = 2
    ridge: float = 1.0
    check: int = 0

    def __post_init__(self) -> None:
        check_choice("kind", self.kind, KINDS)
        object.__setattr__(self, "ignore", tuple(self.ignore))
        object.__setattr__(self, "check", check_int("check", self.check, 0, self.library))


def train_settings_model(cfg: TrainConfig, root: str | Path = ".") -> PickModel | SettingsModel:
    """Fit a model as its config says, on the paper's plant (the random moves' base).

    Parameters
    ----------
    cfg : TrainConfig
        The training config.
    root : str or Path
        The folder the config's files are relative to.

    Returns
    -------
    PickModel or SettingsModel
        The fitted model.
    """
    from vfgym.moves import LOAD_DISTRIBUTION, get_scenario

    from .optima import read_optima

    optima = read_optima(Path(root) / cfg.optima)
    scenarios = [get_scenario(o.scenario, LOAD_DISTRIBUTION) for o in optima]
    if cfg.kind == "ridge":
        return fit_settings_model(scenarios, optima, degree=cfg.degree, ridge=cfg.ridge)
    table = np.load(Path(root) / cfg.costs)
    if list(table["scenarios"]) != [o.scenario for o in optima]:
        raise ValueError(f"{cfg.costs}: a cost table of other moves than {cfg.optima}'s")
    model = fit_pick_model(
        scenarios,
        optima,
        table["cost"],
        table["feasible"],
        neighbours=cfg.neighbours,
        library=cfg.library,
        ignore=cfg.ignore,
    )
    return replace(model, check=cfg.check)


__all__ = [
    "KINDS",
    "PRETRAINED",
    "TARGETS",
    "PickModel",
    "SettingsModel",
    "TrainConfig",
    "accel_k",
    "expand",
    "fit_pick_model",
    "fit_settings_model",
    "greedy_library",
    "load_settings_model",
    "ratio_table",
    "settings_targets",
    "target_settings",
    "train_settings_model",
]
