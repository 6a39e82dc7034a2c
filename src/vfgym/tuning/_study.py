"""Samplers and studies: the sweep's sampler, search space and trial budget, and its study
created with the warm starts enqueued first, or resumed."""

from __future__ import annotations

import time
import warnings
from typing import TYPE_CHECKING, Any

import numpy as np

from vfgym import space
from vfgym.moves.baselines import rule_of_thumb, usable_accel
from vfgym.moves.scenarios import Scenario
from vfgym.params import PAPER_PLANT, PAPER_SETTINGS, Plant, Settings, usable_k
from vfgym.scoring import OBJECTIVES
from vfgym.tuning._config import SweepConfig

if TYPE_CHECKING:
    from optuna import Study
    from optuna.samplers import BaseSampler
    from optuna.storages import BaseStorage

META_KEY = "vfgym"
"""Study user attribute recording what the study optimises (checked when resumed)."""

SAMPLER_NEEDS = {"gp": ("torch",)}
"""Packages a sampler needs beyond vfgym's dependencies (Optuna's GPSampler: torch)."""


def check_sampler(cfg: SweepConfig) -> None:
    """Raise ValueError naming ``sampler`` if a package it needs is not installed."""
    import importlib.util

    missing = [m for m in SAMPLER_NEEDS.get(cfg.sampler, ()) if not importlib.util.find_spec(m)]
    if missing:
        raise ValueError(
            f"sampler={cfg.sampler!r} needs {', '.join(missing)}: pip install {' '.join(missing)}"
        )


def make_sampler(
    cfg: SweepConfig,
    seed: int | None,
    scenarios: list[Scenario] | None = None,
    storage: BaseStorage | None = None,
) -> BaseSampler:
    """The Optuna sampler named by ``cfg.sampler``, seeded.

    The constraints reach TPE, GP and NSGA-II through ``trial.constraints``; CMA-ES and
    the grid ignore them.

    Parameters
    ----------
    cfg : SweepConfig
        The sweep's configuration.
    seed : int or None
        The sampler's seed (``None``: unseeded).
    scenarios : list of Scenario or None
        The sweep's scenarios, on whose plants the compass's coordinates depend (default:
        ``cfg``'s).
    storage : optuna.storages.BaseStorage or None
        The study's storage, where the compass records each trial's generation (needed
        by the compass only).

    Returns
    -------
    optuna.samplers.BaseSampler
        Compass, TPE (multivariate), CMA-ES, GP, NSGA-II, grid or random.

    Raises
    ------
    ValueError
        For the compass without a storage.
    """
    import optuna

    s = optuna.samplers
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", optuna.exceptions.ExperimentalWarning)
        if cfg.sampler == "compass":
            from vfgym.tuning._compass import CompassSampler

            if storage is None:
                raise ValueError("sampler='compass' records its search in the study's storage")

            base = cfg.axis.plant
            rel = relative_space(scenarios or cfg.scenario_list(), base)
            return CompassSampler(rel, cfg.laws, seed, storage=storage)
        if cfg.sampler == "tpe":
            return s.TPESampler(seed=seed, multivariate=True)
        if cfg.sampler == "cmaes":
            return s.CmaEsSampler(seed=seed, warn_independent_sampling=False)
        if cfg.sampler == "gp":
            return s.GPSampler(
                seed=seed, deterministic_objective=True, warn_independent_sampling=False
            )
        if cfg.sampler == "nsga2":
            return s.NSGAIISampler(seed=seed)
        if cfg.sampler == "grid":
            return _grid_sampler(grid_space(cfg), seed=seed)
        return s.RandomSampler(seed=seed)


def _grid_sampler(search_space: dict[str, list[Any]], seed: int | None) -> BaseSampler:
    """Optuna's grid sampler without its ``after_trial`` stop: the study's trial budget
    (:func:`trial_budget`) ends the grid for every worker sharing it (Optuna's stop ends
    only the worker that drew the last point)."""
    import optuna

    class GridSampler(optuna.samplers.GridSampler):
        def after_trial(self, study: Study, trial: object, state: object, values: object) -> None:
            return None

    return GridSampler(search_space, seed=seed)


def relative_space(scenarios: list[Scenario], base: Plant = PAPER_PLANT) -> space.Relative:
    """The compass sampler's coordinates for a scenario set on ``base``: ``k`` relative to
    the geometric mean, over the scenarios' plants, of :func:`vfgym.params.usable_k`."""
    ks = [usable_k(sc.plant(base)) for sc in scenarios] or [usable_k(base)]
    return space.Relative(float(np.exp(np.mean(np.log(ks)))))


def grid_space(cfg: SweepConfig) -> dict[str, list[Any]]:
    """The grid sampler's values per parameter (:func:`vfgym.space.grid`'s)."""
    pts = space.grid(cfg.grid_points, cfg.laws[:1])
    # Clipped to the distributions: exp(log(high)) may round one ulp above ``high``.
    out: dict[str, list[Any]] = {
        d.name: sorted({min(max(getattr(p, d.name), d.low), d.high) for p in pts})
        for d in space.SPACE
    }
    if len(cfg.laws) > 1:
        out["accel_law"] = list(cfg.laws)
    return out


def trial_budget(cfg: SweepConfig) -> int:
    """Trials the study ends with: ``cfg.trials``, for the grid at most the grid and the
    paper's settings."""
    if cfg.sampler == "grid":
        return min(cfg.trials, cfg.grid_points ** len(space.SPACE) * len(cfg.laws) + 1)
    return cfg.trials


def baseline_params(laws: tuple[str, ...], settings: Settings = PAPER_SETTINGS) -> dict[str, Any]:
    """Settings as trial parameters clipped to the search space, as the study's warm starts
    are enqueued.

    Parameters
    ----------
    laws : tuple of str
        The laws searched.
    settings : Settings
        The settings.

    Returns
    -------
    dict
        The parameters; ``accel_law`` only when several laws are searched (the paper's,
        if among them, else the first).
    """
    d = space.settings_to_dict(settings)
    law = d.pop("accel_law")
    for dim in space.SPACE:
        d[dim.name] = min(max(d[dim.name], dim.low), dim.high)
    if len(laws) > 1:
        d["accel_law"] = law if law in laws else laws[0]
    return d


def warm_starts(scenarios: list[Scenario], base: Plant = PAPER_PLANT) -> list[tuple[str, Settings]]:
    """The settings a study tries first.

    Parameters
    ----------
    scenarios : list of Scenario
        The sweep's scenarios.
    base : Plant
        The plant their loads are added to (an axis's).

    Returns
    -------
    list of (str, Settings)
        ``paper``: the paper's settings; ``rule-of-thumb``
        (:func:`vfgym.moves.baselines.rule_of_thumb`) for the most loaded plant, whose
        limits bind the set, if it differs.
    """
    plants = [sc.plant(base) for sc in scenarios]
    loaded = min(plants, key=usable_accel) if plants else base
    out = [("paper", PAPER_SETTINGS)]
    rot = rule_of_thumb(loaded)
    if rot != PAPER_SETTINGS:
        out.append(("rule-of-thumb", rot))
    return out


def create_or_load(
    storage: BaseStorage,
    name: str,
    cfg: SweepConfig,
    scenarios: list[Scenario],
    sampler: BaseSampler | None = None,
) -> tuple[Study, bool]:
    """The study ``name``: created with the warm starts enqueued first, or loaded.

    A new study records what it optimises as its ``vfgym`` user attribute, last; a study
    loaded must optimise the same.

    Parameters
    ----------
    storage : optuna.storages.BaseStorage
        Where it lives (:func:`open_storage`).
    name : str
        The study's name.
    cfg : SweepConfig
        The sweep's configuration.
    scenarios : list of Scenario
        The sweep's scenarios.
    sampler : optuna.samplers.BaseSampler or None
        The sampler to attach.

    Returns
    -------
    tuple of (optuna.Study, bool)
        The study, and whether it was created.

    Raises
    ------
    ValueError
        If a study of that name optimises something else.
    """
    import optuna

    optuna.logging.set_verbosity(optuna.logging.WARNING)
    directions = ["minimize"] if cfg.objective == "cost" else ["minimize"] * len(OBJECTIVES)
    meta = {
        "scenarios": [s.name for s in scenarios],
        "laws": list(cfg.laws),
        "objective": cfg.objective,
        "axis": cfg.axis_key(),  # None: the default axis
        "aggregate": cfg.aggregate_label(),
    }
    try:
        study = optuna.create_study(
            storage=storage, study_name=name, directions=directions, sampler=sampler
        )
    except optuna.exceptions.DuplicatedStudyError:
        study = optuna.load_study(study_name=name, storage=storage, sampler=sampler)
    else:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", optuna.exceptions.ExperimentalWarning)
            study.set_metric_names(["cost"] if cfg.objective == "cost" else list(OBJECTIVES))
        starts = warm_starts(scenarios, cfg.axis.plant)
        for label, settings in starts[:1] if cfg.sampler == "grid" else starts:  # grid: exhaustive
            study.enqueue_trial(baseline_params(cfg.laws, settings), user_attrs={"baseline": label})
        study.set_user_attr(META_KEY, meta)  # last: the study is ready
        return study, True
    # Another process that has just created the study records what it optimises last.
    deadline = time.monotonic() + 30.0
    while META_KEY not in study.user_attrs and time.monotonic() < deadline:
        time.sleep(0.1)
    old = study.user_attrs.get(META_KEY)
    if old is not None:
        old = {"aggregate": "mean"} | old  # a study made before the aggregate was recorded
        for key, want in meta.items():
            if old.get(key) != want:
                raise ValueError(
                    f"study={name!r} already optimises {key}={old.get(key)!r}, not "
                    f"{want!r}: give another --study, or the same {key}"
                )
    if len(study.directions) != len(directions):
        raise ValueError(
            f"study={name!r} has {len(study.directions)} objective(s), not "
            f"{len(directions)}: give another --study"
        )
    return study, False
