"""Candidates (settings, baselines, per-scenario policies) run through the one scoring path
on a scenario set, gathered into a :class:`Report`.

Candidates are V-F :class:`~vfgym.Settings`, a baseline name, or a *policy*: a callable
``scenario -> Settings`` (a tuner: a settings model or an agent that picks settings per
move) or a :class:`~vfgym.scoring.Scheduler` (an agent that changes them during the
move). All of them are scored in one :func:`vfgym.evaluate` call.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from os import PathLike
from typing import Any

import numpy as np

from vfgym._validate import check_int
from vfgym.axis import PAPER_AXIS, Axis, PlantVariant, as_axis
from vfgym.moves.baselines import BASELINE_NAMES, Baseline, Controller, resolve
from vfgym.moves.distribution import scenario_set
from vfgym.moves.scenarios import Scenario
from vfgym.params import Plant, Settings
from vfgym.report._stats import DEFAULT_RESAMPLES, Spread, WinLoss, outcome, spread
from vfgym.scoring import (
    CONSTRAINTS,
    DEFAULT_BOUNDS,
    DEFAULT_WEIGHTS,
    AcrossPlants,
    Bounds,
    CostWeights,
    Scheduler,
    evaluate,
)

Policy = Callable[[Scenario], Settings] | Scheduler
"""A per-scenario controller: a tuner (the settings it picks for a move) or a scheduler."""
EXTRA_METRICS = ("ideal_time_s", "time_ratio", "window_rad", "arrived")
"""Measures :func:`vfgym.evaluate` adds to :data:`vfgym.plant.measures.NAMES`."""


@dataclass
class Column:
    """One candidate's results on every scenario (arrays indexed by scenario).

    Attributes
    ----------
    label : str
        The candidate's name in tables.
    role : str
        ``tuned`` or ``baseline``.
    source : str
        Where it came from: a settings file, a baseline name, a model file.
    controllers : list
        The controller as it ran on each scenario (baselines resolved per plant).
    cost : numpy.ndarray
        Cost per scenario (NaN where the candidate does not apply).
    constraints : numpy.ndarray
        Constraint values per scenario, (scenarios, len(CONSTRAINTS)), in the order of
        :data:`~vfgym.scoring.CONSTRAINTS`.
    metrics : list of dict
        The measures per scenario, as :func:`vfgym.evaluate` returns them.
    """

    label: str
    role: str
    source: str
    controllers: list[Controller | None]
    cost: np.ndarray
    constraints: np.ndarray
    metrics: list[dict[str, Any]]

    @property
    def feasible(self) -> np.ndarray:
        """All constraints ≤ 0 (NaN where the candidate does not apply)."""
        ok = np.all(self.constraints <= 0.0, axis=-1).astype(float)
        ok[np.isnan(self.cost)] = np.nan
        return ok

    @property
    def mean_cost(self) -> float:
        """The set's cost: the mean over the scenarios where the candidate applies (as
        :attr:`vfgym.Evaluation.mean_cost`)."""
        return float(np.nanmean(self.cost))

    def values(self, key: str) -> np.ndarray:
        """One measure per scenario as floats.

        Parameters
        ----------
        key : str
            ``cost``, ``feasible``, a constraint (``constraint_<name>``) or any measure
            :func:`vfgym.evaluate` returns.

        Returns
        -------
        numpy.ndarray
            float, one per scenario (NaN where not defined).
        """
        if key == "cost":
            return self.cost.astype(float)
        if key == "feasible":
            return self.feasible
        if key.startswith("constraint_"):
            return self.constraints[:, CONSTRAINTS.index(key.removeprefix("constraint_"))]
        return np.array([float(m.get(key, math.nan)) for m in self.metrics])


@dataclass(frozen=True)
class Candidate:
    """A controller to report on: fixed settings, a baseline, or a per-scenario policy.

    Parameters
    ----------
    label : str
        Its name in tables (unique within a report).
    controller : Settings, Baseline or None
        Fixed settings or a baseline; give this or ``policy``.
    policy : Policy or None
        A callable ``scenario -> Settings`` (an agent); give this or ``controller``.
    source : str
        Where it came from: a settings file, a baseline name, a model file.
    role : str
        ``tuned`` or ``baseline``.

    Raises
    ------
    ValueError
        If neither or both of ``controller`` and ``policy`` are given, or the role is
        not known.
    """

    label: str
    controller: Settings | Baseline | None = None
    policy: Policy | None = field(default=None, compare=False)
    source: str = ""
    role: str = "tuned"

    def __post_init__(self) -> None:
        if (self.controller is None) == (self.policy is None):
            raise ValueError(f"candidate {self.label!r}: give exactly one of controller, policy")
        if self.role not in ("tuned", "baseline"):
            raise ValueError(f"role={self.role!r} is not allowed: choose one of tuned, baseline")


def baseline_candidates(names: str | Sequence[str]) -> list[Candidate]:
    """Baselines by name, as candidates.

    Parameters
    ----------
    names : str or sequence of str
        Baseline names (:data:`vfgym.moves.baselines.BASELINE_NAMES`), as a
        comma-separated string or a list.

    Returns
    -------
    list of Candidate
        One baseline candidate per name.

    Raises
    ------
    ValueError
        If a name is not known.
    """
    if isinstance(names, str):
        names = [n.strip() for n in names.split(",") if n.strip()]
    out = []
    for name in names:
        if name not in BASELINE_NAMES:
            raise ValueError(
                f"baseline={name!r} is not known: choose one of {', '.join(BASELINE_NAMES)}"
            )
        out.append(Candidate(name, Baseline(name), source=name, role="baseline"))
    return out


@dataclass
class Report:
    """Candidates' results on a scenario set, with spreads and win/loss.

    What :func:`compare` returns.

    Attributes
    ----------
    scenarios : list of Scenario
        The scenarios, in order (the columns' arrays are indexed by them).
    columns : list of Column
        One per candidate, tuned ones first.
    axis : Axis
        The problem the candidates ran on: its plant (each scenario adds its load) and
        measures.
    resamples : int
        Bootstrap draws for the spreads.
    seed : int
        Seed of the bootstrap, so that a report is reproducible.
    scenario_spec : str
        The scenario set as given on the command line (empty for a list).
    across : AcrossPlants or None
        The columns' candidates on true plants, in their order, when :func:`compare` was
        given ``plants``.
    """

    scenarios: list[Scenario]
    columns: list[Column]
    axis: Axis
    resamples: int = DEFAULT_RESAMPLES
    seed: int = 0
    scenario_spec: str = ""
    across: AcrossPlants | None = None

    @property
    def tuned(self) -> list[Column]:
        """The tuned candidates' columns."""
        return [c for c in self.columns if c.role == "tuned"]

    @property
    def baselines(self) -> list[Column]:
        """The baselines' columns."""
        return [c for c in self.columns if c.role == "baseline"]

    def column(self, label: str) -> Column:
        """A candidate's column by label.

        Parameters
        ----------
        label : str
            The candidate's label.

        Returns
        -------
        Column
            Its results.

        Raises
        ------
        ValueError
            If no candidate has that label.
        """
        for c in self.columns:
            if c.label == label:
                return c
        raise ValueError(f"controller={label!r} is not in this report")

    def spread(self, label: str, key: str) -> Spread:
        """Spread of one measure of one candidate over the scenarios.

        Parameters
        ----------
        label : str
            The candidate's label.
        key : str
            The measure, as :meth:`Column.values` takes it.

        Returns
        -------
        Spread
            Over the scenarios where the measure is defined.
        """
        return spread(self.column(label).values(key), resamples=self.resamples, seed=self.seed)

    def win_loss(self, tuned: str, baseline: str) -> WinLoss:
        """Per-scenario outcomes and the paired cost difference of two candidates.

        Parameters
        ----------
        tuned : str
            The tuned candidate's label.
        baseline : str
            The baseline's label.

        Returns
        -------
        WinLoss
            Outcomes per scenario and the spread of tuned − baseline cost.
        """
        a, b = self.column(tuned).cost, self.column(baseline).cost
        outs = tuple(outcome(float(x), float(y)) for x, y in zip(a, b, strict=True))
        diff = spread(a - b, resamples=self.resamples, seed=self.seed)
        return WinLoss(tuned, baseline, outs, diff)

    def across_of(self, labels: Sequence[str]) -> AcrossPlants | None:
        """:attr:`across` for the candidates ``labels``, in that order (``None`` without).

        Parameters
        ----------
        labels : sequence of str
            Candidates' labels.

        Returns
        -------
        AcrossPlants or None
            Their rows of :attr:`across`.
        """
        if self.across is None:
            return None
        at = [self.columns.index(self.column(lab)) for lab in labels]
        a = self.across
        return AcrossPlants(a.plants, a.seed, a.cost[at], a.constraints[at])

    def win_losses(self) -> list[WinLoss]:
        """Every tuned candidate against every baseline.

        Returns
        -------
        list of WinLoss
            One per (tuned, baseline) pair.
        """
        return [self.win_loss(t.label, b.label) for t in self.tuned for b in self.baselines]


def _column_from_rows(
    cand: Candidate,
    scenarios: list[Scenario],
    plant: Plant,
    results: list[tuple[Controller | Baseline | None, float, np.ndarray, dict[str, Any]]],
) -> Column:
    ctrls = [
        None if c is None else resolve(c, sc.plant(plant))
        for (c, *_), sc in zip(results, scenarios, strict=True)
    ]
    return Column(
        label=cand.label,
        role=cand.role,
        source=cand.source,
        controllers=ctrls,
        cost=np.array([r[1] for r in results], dtype=float),
        constraints=np.array([r[2] for r in results], dtype=float).reshape(
            len(scenarios), len(CONSTRAINTS)
        ),
        metrics=[r[3] for r in results],
    )


def compare(
    candidates: Sequence[Candidate],
    baselines: str | Sequence[str] | Sequence[Candidate] = BASELINE_NAMES,
    scenarios: str | Scenario | Sequence[str | Scenario] = "test",
    *,
    axis: Axis | str | PathLike[str] = PAPER_AXIS,
    count: int | None = None,
    first_seed: int | None = None,
    weights: CostWeights = DEFAULT_WEIGHTS,
    bounds: Bounds = DEFAULT_BOUNDS,
    resamples: int = DEFAULT_RESAMPLES,
    seed: int = 0,
    plants: Sequence[PlantVariant] | int = (),
    plant_seed: int | None = None,
    progress: bool = False,
) -> Report:
    """Score tuned candidates and baselines on the same scenarios.

    One :func:`vfgym.evaluate` call for every candidate: fixed controllers, tuners and
    schedulers on the same moves and, with ``plants``, on the same true plants.

    Parameters
    ----------
    candidates : sequence of Candidate
        The tuned candidates.
    baselines : str, sequence of str, or sequence of Candidate
        Baseline names (a comma-separated string or a list) or candidates.
    scenarios : str, Scenario, or a sequence of these
        The scenario set, resolved on the axis (:meth:`vfgym.Axis.scenario_set`).
    axis : Axis, str or os.PathLike
        The problem: its plant, measures, moves and uncertainty, as :func:`vfgym.evaluate`
        takes it (default: the paper's axis).
    count : int or None
        ``train`` / ``test`` as that many random draws of the default distribution
        (:func:`vfgym.scenario_set`) instead of the axis's move sets.
    first_seed : int or None
        Seed of the first of those draws (default 0).
    weights : CostWeights
        Weights of the cost.
    bounds : Bounds
        Bounds of the constraints.
    resamples : int
        Bootstrap draws for the spreads, 1 to 1 000 000.
    seed : int
        Seed of the bootstrap, ≥ 0.
    plants : sequence of PlantVariant, or int
        True plants to judge every candidate on too (:attr:`Report.across`), or how many
        to draw within the axis's uncertainty, as :func:`vfgym.evaluate` takes them.
    plant_seed : int or None
        Their seed, as :func:`vfgym.evaluate` takes it.
    progress : bool
        A progress bar over the runs, as :func:`vfgym.evaluate` shows it.

    Returns
    -------
    Report
        Every candidate's results on every scenario.

    Raises
    ------
    ValueError
        If there is no candidate, two share a label, or an argument is out of range.
    """
    resamples = check_int("resamples", resamples, 1, 1_000_000)
    seed = check_int("seed", seed, 0)
    if isinstance(baselines, str) or (
        isinstance(baselines, Sequence) and all(isinstance(b, str) for b in baselines)
    ):
        base = baseline_candidates(baselines)  # type: ignore[arg-type]
    else:
        base = list(baselines)  # type: ignore[arg-type]
    cands = [*candidates, *base]
    if not cands:
        raise ValueError("candidates=[] is not allowed: give settings, a policy or baselines")
    labels = [c.label for c in cands]
    dup = sorted({x for x in labels if labels.count(x) > 1})
    if dup:
        raise ValueError(f"controller labels must differ: {', '.join(dup)} given twice")
    axis = as_axis(axis)
    spec = scenarios if isinstance(scenarios, str) else ""
    if count is None and first_seed is None:
        scens = axis.scenario_set(scenarios if isinstance(scenarios, str) else list(scenarios))
    else:  # random draws of the default distribution, as many as asked
        scens = scenario_set(scenarios, 16 if count is None else count, first_seed or 0)
    ev = evaluate(
        [c.controller if c.controller is not None else c.policy for c in cands],
        scens,
        axis=axis,
        weights=weights,
        bounds=bounds,
        plants=plants,
        plant_seed=plant_seed,
        progress=progress,
    )
    columns = [
        _column_from_rows(
            cand,
            scens,
            axis.plant,
            [
                (ev.chosen[ci][si], ev.cost[ci, si], ev.constraints[ci, si], ev.metrics[ci][si])
                for si in range(len(scens))
            ],
        )
        for ci, cand in enumerate(cands)
    ]
    return Report(
        scenarios=scens,
        columns=columns,
        axis=axis,
        resamples=resamples,
        seed=seed,
        scenario_spec=spec,
        across=ev.across,
    )
