"""Samplers and studies: which sampler a sweep uses, its search space and trial budget, and
the study created or resumed with the paper's settings enqueued first.
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from vfgym import space
from vfgym.moves.baselines import rule_of_thumb, usable_accel
from vfgym.moves.scenarios import Scenario
from vfgym.params import PAPER_PLANT, PAPER_SETTINGS, Settings, paper_k
from vfgym.scoring import OBJECTIVES
from vfgym.tuning._config import SweepConfig

META_KEY = "vfgym"
"""Study user attribute recording what the study optimises (checked when resumed)."""

SAMPLER_NEEDS = {"cmaes": ("cmaes",), "gp": ("torch", "scipy"), "compass": ("scipy",)}
"""Packages a sampler needs beyond Optuna."""


def check_sampler(cfg: SweepConfig) -> None:
    """Raise ``ValueError`` naming ``sampler`` when a package it needs is missing."""
    import importlib.util

    missing = [m for m in SAMPLER_NEEDS.get(cfg.sampler, ()) if not importlib.util.find_spec(m)]
    if missing:
        raise ValueError(
            f"sampler={cfg.sampler!r} needs {', '.join(missing)}: pip install {' '.join(missing)}"
        )


def make_sampler(
    cfg: SweepConfig, seed: int | None, scenarios: list[Scenario] | None = None
) -> Any:
    """The Optuna sampler named by ``cfg.sampler``, seeded. The constraints reach TPE, GP
    and NSGA-II through the trials (``trial.set_constraint``, Optuna 5's way; its
    ``constraints_func`` is deprecated); CMA-ES and the grid ignore them."""
    import optuna

    s = optuna.samplers
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", optuna.exceptions.ExperimentalWarning)
        if cfg.sampler == "compass":
            from vfgym.tuning._compass import CompassSampler

            return CompassSampler(relative_space(scenarios or cfg.scenario_list()), cfg.laws, seed)
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
            return s.GridSampler(grid_space(cfg), seed=seed)
        return s.RandomSampler(seed=seed)


def relative_space(scenarios: list[Scenario]) -> space.Relative:
    """The compass sampler's coordinates: ``k`` relative to the acceleration limit's k
    (:func:`vfgym.params.paper_k`) of the scenarios' plants (their geometric mean: the
    limit is the motor's, the same for every load)."""
    ks = [paper_k(sc.plant(PAPER_PLANT)) for sc in scenarios] or [paper_k(PAPER_PLANT)]
    return space.Relative(float(np.exp(np.mean(np.log(ks)))))


BATCH = {"tpe": 1, "gp": 1, "cmaes": 8, "nsga2": 8, "grid": 16, "random": 16}
"""Trials a worker claims and simulates at once, by sampler: one for the samplers that
learn from every trial (TPE, GP: a batch would be asked blind), CMA-ES's population (4 +
3 ln 4 = 8 in four dimensions), a share of NSGA-II's generation, and more for the grid
and random sampling, which never look at results."""


def batch_size(cfg: SweepConfig, sampler: Any = None, study: Any = None) -> int:
    """Trials to claim next: ``cfg.batch``, else the sampler's own — what its
    ``batch_hint(study)`` asks for (the compass sampler: one generation), else
    :data:`BATCH`'s."""
    if cfg.batch:
        return cfg.batch
    hint = getattr(sampler, "batch_hint", None)
    if hint is not None and study is not None:
        return int(hint(study))
    return BATCH.get(cfg.sampler, 1)


def grid_space(cfg: SweepConfig) -> dict[str, list[Any]]:
    """The grid sampler's values per parameter, from :func:`vfgym.space.grid`."""
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
    """Trials the study ends with: ``trials``, but at most the grid (plus the baseline)."""
    if cfg.sampler == "grid":
        return min(cfg.trials, cfg.grid_points ** len(space.SPACE) * len(cfg.laws) + 1)
    return cfg.trials


def baseline_params(laws: tuple[str, ...], settings: Settings = PAPER_SETTINGS) -> dict[str, Any]:
    """Settings (the paper's by default) as trial parameters: clipped to the search space,
    with their law if it is searched, else the fixed one."""
    d = space.settings_to_dict(settings)
    law = d.pop("accel_law")
    for dim in space.SPACE:
        d[dim.name] = min(max(d[dim.name], dim.low), dim.high)
    if len(laws) > 1:
        d["accel_law"] = law if law in laws else laws[0]
    return d


def warm_starts(scenarios: list[Scenario]) -> list[tuple[str, Settings]]:
    """The settings a study tries first: the paper's, then the rule of thumb
    (:func:`vfgym.moves.baselines.rule_of_thumb`) for the scenarios' most loaded plant
    (the one with the least usable acceleration, whose limits bind the set), if it
    differs. Returned as (baseline name, settings)."""
    plants = [sc.plant(PAPER_PLANT) for sc in scenarios]
    loaded = min(plants, key=usable_accel) if plants else PAPER_PLANT
    out = [("paper", PAPER_SETTINGS)]
    rot = rule_of_thumb(loaded)
    if rot != PAPER_SETTINGS:
        out.append(("rule-of-thumb", rot))
    return out


def study_meta(cfg: SweepConfig, scenarios: list[Scenario]) -> dict[str, Any]:
    return {
        "scenarios": [s.name for s in scenarios],
        "laws": list(cfg.laws),
        "objective": cfg.objective,
    }


def create_or_load(
    storage: Any, name: str, cfg: SweepConfig, scenarios: list[Scenario], sampler: Any = None
) -> tuple[Any, bool]:
    """The study ``name``: created with the baseline enqueued first, or loaded (and
    checked to optimise the same thing). Returns (study, created)."""
    import optuna

    optuna.logging.set_verbosity(optuna.logging.WARNING)
    directions = ["minimize"] if cfg.objective == "cost" else ["minimize"] * len(OBJECTIVES)
    meta = study_meta(cfg, scenarios)
    try:
        study = optuna.create_study(
            storage=storage, study_name=name, directions=directions, sampler=sampler
        )
        created = True
    except optuna.exceptions.DuplicatedStudyError:
        study = optuna.load_study(study_name=name, storage=storage, sampler=sampler)
        created = False
    if created:
        study.set_user_attr(META_KEY, meta)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", optuna.exceptions.ExperimentalWarning)
            study.set_metric_names(["cost"] if cfg.objective == "cost" else list(OBJECTIVES))
        for label, settings in warm_starts(scenarios):
            study.enqueue_trial(baseline_params(cfg.laws, settings), user_attrs={"baseline": label})
        return study, True
    old = study.user_attrs.get(META_KEY)
    if old is not None:
        for key in ("scenarios", "laws", "objective"):
            if old.get(key) != meta[key]:
                raise ValueError(
                    f"study={name!r} already optimises {key}={old.get(key)!r}, not "
                    f"{meta[key]!r}: give another --study, or the same {key}"
                )
    if len(study.directions) != len(directions):
        raise ValueError(
            f"study={name!r} has {len(study.directions)} objective(s), not "
            f"{len(directions)}: give another --study"
        )
    return study, False
