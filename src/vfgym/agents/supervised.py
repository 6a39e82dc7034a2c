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
from vfgym._validate import check_choice, check_int
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
    if d.get("features") != list(SCENARIO_FEATURES) or d.get("targets") != list(TARGETS):
        raise ValueError(f"--model {p}: made for other features or targets than this vfgym's")
    if d["kind"] == PICK_KIND:
        return PickModel(
            neighbours=int(d["neighbours"]),
            mean=np.array(d["mean"], dtype=np.float64),
            scale=np.array(d["scale"], dtype=np.float64),
            points=np.array(d["points"], dtype=np.float64),
            library=np.array(d["library"], dtype=np.float64),
            ratios=np.array(d["ratios"], dtype=np.float64),
            weights=np.array(d["weights"], dtype=np.float64),
            accel_law=str(d["accel_law"]),
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


PICK_KIND = "vfgym-settings-pick"
INFEASIBLE_PENALTY = 1.0
"""Added to a candidate's cost ratio on a move where it breaks a constraint."""
RATIO_CAP = 10.0
"""Cost ratios are capped here, so one disastrous move does not outweigh its neighbours."""


def ratio_table(cost: np.ndarray, feasible: np.ndarray, best: np.ndarray) -> np.ndarray:
    """What the pick model averages: cost / the move's optimum, plus
    :data:`INFEASIBLE_PENALTY` where infeasible, capped at :data:`RATIO_CAP`.

    Parameters
    ----------
    cost : numpy.ndarray
        (moves, candidates): each candidate's cost on each move.
    feasible : numpy.ndarray
        bool, the same shape.
    best : numpy.ndarray
        (moves,): each move's optimum cost.

    Returns
    -------
    numpy.ndarray
        (moves, candidates).
    """
    r = cost / best[:, None] + np.where(feasible, 0.0, INFEASIBLE_PENALTY)
    return np.minimum(np.nan_to_num(r, nan=RATIO_CAP), RATIO_CAP)


def greedy_library(ratios: np.ndarray, size: int) -> np.ndarray:
    """Columns of ``ratios`` chosen one by one, each lowering most the sum over the moves
    of the best chosen candidate's ratio (ties: the lower index).

    Parameters
    ----------
    ratios : numpy.ndarray
        (moves, candidates), from :func:`ratio_table`.
    size : int
        Candidates to choose (at most all).

    Returns
    -------
    numpy.ndarray
        int, the chosen columns in the order chosen.
    """
    chosen: list[int] = []
    cur = np.full(ratios.shape[0], np.inf)
    for _ in range(min(size, ratios.shape[1])):
        gain = np.minimum(cur[:, None], ratios).sum(axis=0)
        gain[chosen] = np.inf
        j = int(np.argmin(gain))
        chosen.append(j)
        cur = np.minimum(cur, ratios[:, j])
    return np.array(chosen, dtype=np.int64)


@dataclass(frozen=True, eq=False)
class PickModel:
    """Settings picked from a library of candidates by the moves most like this one.

    Candidates are optimal settings of training moves in the regression's coordinates
    (:data:`TARGETS`, k relative to the move's k_a). For a new move: its ``neighbours``
    nearest training moves in standardised feature space, the candidate whose mean
    cost ratio over them (:func:`ratio_table`) is least, made settings on the move's plant.

    Attributes
    ----------
    neighbours : int
        Training moves averaged over.
    mean, scale : numpy.ndarray
        Standardisation of the features.
    points : numpy.ndarray
        (moves, features): the training moves' standardised features.
    library : numpy.ndarray
        (candidates, 4): the candidates' targets.
    ratios : numpy.ndarray
        (moves, candidates): each candidate's cost ratio on each training move.
    weights : numpy.ndarray
        (features,): each standardised feature's weight in the distance (0: ignored).
    accel_law : str
        The law of the picked settings.
    """

    neighbours: int
    mean: np.ndarray
    scale: np.ndarray
    points: np.ndarray
    library: np.ndarray
    ratios: np.ndarray
    weights: np.ndarray
    accel_law: str = "rise"

    def pick(self, features: np.ndarray) -> int:
        """The library row picked for one move's features.

        Parameters
        ----------
        features : numpy.ndarray
            (len(SCENARIO_FEATURES),).

        Returns
        -------
        int
            The candidate's row.
        """
        z = (np.asarray(features, dtype=np.float64) - self.mean) / self.scale
        d = np.sum(((self.points - z) * self.weights) ** 2, axis=1)
        near = np.argsort(d, kind="stable")[: self.neighbours]
        return int(np.argmin(self.ratios[near].mean(axis=0)))

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
        j = self.pick(scenario_features(scenario, plant, loaded))
        return target_settings(self.library[j], loaded, self.accel_law)

    def to_dict(self) -> dict[str, Any]:
        """The model as plain data (what :meth:`save` writes)."""
        return {
            "kind": PICK_KIND,
            "features": list(SCENARIO_FEATURES),
            "targets": list(TARGETS),
            "neighbours": self.neighbours,
            "accel_law": self.accel_law,
            "mean": self.mean.tolist(),
            "scale": self.scale.tolist(),
            "weights": self.weights.tolist(),
            "library": self.library.tolist(),
            "points": self.points.tolist(),
            "ratios": self.ratios.tolist(),
        }

    def save(self, path: str | Path) -> None:
        """Write the model as JSON.

        Parameters
        ----------
        path : str or Path
            The file.
        """
        write_text(path, json.dumps(self.to_dict()) + "\n")


def fit_pick_model(
    scenarios: Sequence[Scenario],
    optima: Sequence[MoveOptimum],
    cost: np.ndarray,
    feasible: np.ndarray,
    *,
    neighbours: int = 6,
    library: int = 64,
    ignore: Sequence[str] = ("direction",),
    plant: Plant = PAPER_PLANT,
) -> PickModel:
    """Fit the pick model: a greedy library of candidates and the training moves' table.

    Parameters
    ----------
    scenarios : sequence of Scenario
        The training moves.
    optima : sequence of MoveOptimum
        Their optima, in the same order.
    cost, feasible : numpy.ndarray
        (moves, moves): the cost (and feasibility) on move i of move j's optimum made
        settings on move i's plant (``experiments/candidate_costs.py``).
    neighbours : int
        Training moves averaged over, ≥ 1.
    library : int
        Candidates kept, ≥ 1.
    ignore : sequence of str
        Features left out of the distance (names of :data:`SCENARIO_FEATURES`).
    plant : Plant
        The base plant the optima were found on.

    Returns
    -------
    PickModel
        The fitted model.

    Raises
    ------
    ValueError
        If the inputs do not match or an argument is out of range.
    """
    n = len(scenarios)
    if [s.name for s in scenarios] != [o.scenario for o in optima]:
        raise ValueError("scenarios and optima differ: give the optima of these moves, in order")
    if np.shape(cost) != (n, n) or np.shape(feasible) != (n, n):
        raise ValueError(f"cost and feasible must be ({n}, {n}), one row and column per move")
    neighbours = check_int("neighbours", neighbours, 1, n)
    library = check_int("library", library, 1, n)
    for name in ignore:
        check_choice("ignore", name, SCENARIO_FEATURES)
    weights = np.array([0.0 if f in ignore else 1.0 for f in SCENARIO_FEATURES])
    loaded = [sc.plant(plant) for sc in scenarios]
    x = np.array([scenario_features(sc, plant, p) for sc, p in zip(scenarios, loaded, strict=True)])
    t = np.array([settings_targets(o.settings, p) for o, p in zip(optima, loaded, strict=True)])
    mean, scale = x.mean(axis=0), x.std(axis=0)
    scale[scale < 1e-12] = 1.0
    # 6 decimals: the shipped file stays small (a ratio's 1e-6 is far below the gaps)
    r = ratio_table(np.asarray(cost), np.asarray(feasible), np.array([o.cost for o in optima]))
    r = np.round(r, 6)
    cols = greedy_library(r, library)
    law = optima[0].settings.accel_law
    z = np.round((x - mean) / scale, 6)
    return PickModel(neighbours, mean, scale, z, t[cols], r[:, cols], weights, law)


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
        The optima CSV of the training moves (:func:`vfgym.agents.optima.read_optima`),
        relative to the repository's root.
    costs : str
        The candidates' cost table (``experiments/candidate_costs.py``; ``pick`` only).
    neighbours, library : int
        The pick model's neighbours and library size.
    ignore : tuple of str
        Features the pick model's distance leaves out.
    degree, ridge : int, float
        The ridge regression's degree (1 or 2) and penalty (≥ 0).

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

    def __post_init__(self) -> None:
        check_choice("kind", self.kind, KINDS)
        object.__setattr__(self, "ignore", tuple(self.ignore))


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
    from vfgym.agents.optima import read_optima
    from vfgym.moves.scenarios import get_scenario

    optima = read_optima(Path(root) / cfg.optima)
    scenarios = [get_scenario(o.scenario) for o in optima]
    if cfg.kind == "ridge":
        return fit_settings_model(scenarios, optima, degree=cfg.degree, ridge=cfg.ridge)
    table = np.load(Path(root) / cfg.costs)
    if list(table["scenarios"]) != [o.scenario for o in optima]:
        raise ValueError(f"{cfg.costs}: a cost table of other moves than {cfg.optima}'s")
    return fit_pick_model(
        scenarios,
        optima,
        table["cost"],
        table["feasible"],
        neighbours=cfg.neighbours,
        library=cfg.library,
        ignore=cfg.ignore,
    )


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
