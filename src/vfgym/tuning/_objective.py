"""The sweep's objective: a trial's settings scored by the one scoring path, with its
constraints set on the trial for the samplers that learn them.

Trials are scored one at a time (:meth:`Objective.__call__`, what ``study.optimize``
calls); :meth:`Objective.results` also scores several settings in ONE batched kernel call.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from contextlib import nullcontext
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np

from vfgym import space
from vfgym.moves.scenarios import Scenario
from vfgym.params import DEFAULT_MEASURES, PAPER_PLANT, Measures, Plant, Settings
from vfgym.plant.uncertainty import PlantVariant
from vfgym.scoring import CONSTRAINTS, Evaluation, evaluate
from vfgym.tuning._aggregate import DEFAULT_AGGREGATE, DEFAULT_CVAR_ALPHA, aggregate_costs
from vfgym.tuning._stored import CONSTRAINTS_KEY, RESULT_ATTR, result_attr, stored_result

if TYPE_CHECKING:
    from optuna import Study, Trial


class Aggregate(NamedTuple):
    """Each controller's scores over a scenario set (arrays indexed by controller).

    What :func:`aggregate` returns.

    Attributes
    ----------
    cost : numpy.ndarray
        The cost's aggregate over the scenarios (the mean by default), (C,).
    constraints : numpy.ndarray
        Worst (max) of each constraint over the scenarios, (C, 3).
    feasible : numpy.ndarray
        Every constraint ≤ 0 on every scenario, (C,) bool.
    objectives : numpy.ndarray
        The objectives' means over the scenarios, (C, 3).
    """

    cost: np.ndarray
    constraints: np.ndarray
    feasible: np.ndarray
    objectives: np.ndarray


def aggregate(
    ev: Evaluation, how: str = DEFAULT_AGGREGATE, cvar_alpha: float = DEFAULT_CVAR_ALPHA
) -> Aggregate:
    """Each controller's results over the scenarios, as a sweep scores a setting.

    Parameters
    ----------
    ev : Evaluation
        What :func:`vfgym.evaluate` returned.
    how : str
        The cost's aggregate over the scenarios: ``mean``, ``cvar`` or ``worst``
        (:mod:`vfgym.tuning._aggregate`).
    cvar_alpha : float
        The share of the costliest scenarios ``cvar`` averages.

    Returns
    -------
    Aggregate
        Per controller: ``cost`` (the aggregate over the scenarios, on the modelled plant),
        ``constraints`` (worst, max, over the scenarios and any true plants the evaluation
        holds, :attr:`vfgym.Evaluation.across`), ``feasible`` (every constraint ≤ 0 on
        every scenario and plant) and ``objectives`` (means).
    """
    cons = np.nanmax(ev.constraints, axis=1)
    if ev.across is not None:  # robust: the worst over the true plants of the design too
        cons = np.fmax(cons, np.nanmax(ev.across.constraints, axis=(1, 2)))
    return Aggregate(
        cost=aggregate_costs(ev.cost, how, cvar_alpha),
        constraints=cons,
        feasible=np.all(cons <= 0.0, axis=1),
        objectives=np.nanmean(ev.objectives, axis=1),
    )


def settings_key(s: Settings) -> tuple:
    """A hashable key of settings, equal for equal settings.

    Parameters
    ----------
    s : Settings
        The settings.

    Returns
    -------
    tuple
        (value_rad, error_limit_rad, k, ts_over_tf, accel_law).
    """
    return (s.value_rad, s.error_limit_rad, s.k, s.ts_over_tf, s.accel_law)


class Result(NamedTuple):
    """A trial's objective value(s) and the user attributes it records."""

    values: float | list[float]
    attrs: dict[str, Any]


class Objective:
    """Settings from the trial → :func:`vfgym.evaluate` on the scenarios (on ``plant``
    with ``measures``: an axis's) → cost (or the three objectives), with the worst
    constraints and the settings as user attributes.

    A setting already scored (in this process, or by a completed trial of the study) is
    not simulated again: the trial copies that result and records ``cached_from``.

    Parameters
    ----------
    scenarios : list of Scenario
        The scenarios each setting is scored on.
    laws : tuple of str
        The acceleration laws searched.
    form : str
        ``cost`` (one objective) or ``pareto`` (the three objectives).
    plant : Plant
        The plant the settings run on (an axis's, see :class:`vfgym.moves.axis.Axis`).
    measures : Measures
        Windows and bands of the measures (an axis's).
    aggregate, cvar_alpha : str, float
        The cost's aggregate over the scenarios (:func:`aggregate`).
    plants : sequence of PlantVariant
        True plants a setting must also be feasible on (an axis's
        :meth:`~vfgym.moves.axis.Axis.design_plants`); its cost is the modelled plant's.
    """

    def __init__(
        self,
        scenarios: list[Scenario],
        laws: tuple[str, ...],
        form: str,
        *,
        plant: Plant = PAPER_PLANT,
        measures: Measures = DEFAULT_MEASURES,
        aggregate: str = DEFAULT_AGGREGATE,
        cvar_alpha: float = DEFAULT_CVAR_ALPHA,
        plants: Sequence[PlantVariant] = (),
    ) -> None:
        self.scenarios = scenarios
        self.plants = tuple(plants)
        self.how = (aggregate, cvar_alpha)
        self.plant = plant
        self.measures = measures
        self.laws = laws
        self.form = form
        self.cache: dict[tuple, Result] = {}
        self.simulated = 0
        self.guard: Callable[[], Any] = nullcontext
        self._found: dict[tuple, Result] = {}
        self._seen: set[int] = set()
        self._found_in: tuple | None = None

    def __call__(self, trial: Trial) -> float | list[float]:
        settings = space.suggest(trial, self.laws)
        (res,) = self.results(trial.study, [trial.number], [settings])
        self.record(trial, res)
        return res.values

    def results(
        self, study: Study | None, numbers: Sequence[int], settings: list[Settings]
    ) -> list[Result]:
        """The result of each setting, simulating only those never scored.

        A setting is copied from this process's cache or from a completed trial of
        ``study``; the others are simulated together in one batched call (the only place a
        trial may be interrupted); repeats within the batch copy the first.

        Parameters
        ----------
        study : optuna.Study or None
            The study whose completed trials may already hold a setting's result.
        numbers : sequence of int
            The trials' numbers (recorded as ``cached_from`` of the results they create).
        settings : list of Settings
            The settings, one per trial.

        Returns
        -------
        list of Result
            One per setting, in order.
        """
        out: list[Result | None] = [self.cache.get(settings_key(s)) for s in settings]
        if any(r is None for r in out) and study is not None:
            found = self._completed(study)
            for i, s in enumerate(settings):
                if out[i] is None:
                    out[i] = found.get(settings_key(s))
        todo: dict[tuple, int] = {}
        for i, s in enumerate(settings):
            if out[i] is None:
                todo.setdefault(settings_key(s), i)
        if todo:
            with self.guard():
                scored = self.score_many([settings[i] for i in todo.values()])
            self.simulated += len(todo)
            for (key, i), res in zip(todo.items(), scored, strict=True):
                self.cache[key] = Result(res.values, res.attrs | {"cached_from": numbers[i]})
                out[i] = res
            for i, s in enumerate(settings):
                if out[i] is None:
                    out[i] = self.cache[settings_key(s)]
        return [r for r in out if r is not None]

    def record(self, trial: Trial, res: Result, trial_id: int | None = None) -> None:
        """Store a result on the trial: its user attribute, unless the trial holds it
        already (a retried trial), and its constraints (:mod:`vfgym.tuning._stored`: one
        write each).

        Parameters
        ----------
        trial : optuna.Trial
            The trial.
        res : Result
            Its result.
        trial_id : int or None
            The trial's id in ``trial.storage`` (default: looked up, :func:`trial_id_of`).
        """
        have = trial.user_attrs  # (the trial's own copy: no read)
        result = result_attr(res.attrs)
        if have.get(RESULT_ATTR) != result:
            trial.set_user_attr(RESULT_ATTR, result)
        values = dict(zip(CONSTRAINTS, res.attrs["constraints"], strict=True))
        set_constraints(trial, values, trial_id)

    def score(self, settings: Settings) -> Result:
        """Values and user attributes of one setting (one batched evaluation).

        Parameters
        ----------
        settings : Settings
            The setting.

        Returns
        -------
        Result
            ``(values, attrs)``: the aggregate cost (``cost`` form) or the three
            objectives' means, and the trial's user attributes (settings, cost, constraints,
            feasible, objectives).
        """
        return self.score_many([settings])[0]

    def score_many(self, settings: list[Settings]) -> list[Result]:
        """Values and user attributes of each setting, all in one batched evaluation.

        Parameters
        ----------
        settings : list of Settings
            The settings.

        Returns
        -------
        list of Result
            One per setting, as :meth:`score` gives it.
        """
        agg = aggregate(
            evaluate(
                settings,
                self.scenarios,
                plant=self.plant,
                measures=self.measures,
                plants=self.plants,
            ),
            *self.how,
        )
        out = []
        for i, s in enumerate(settings):
            cost = float(agg.cost[i])
            objectives = [float(x) for x in agg.objectives[i]]
            attrs: dict[str, Any] = {
                "settings": space.settings_to_dict(s),
                "cost": cost,
                "constraints": [float(x) for x in agg.constraints[i]],
                "feasible": bool(agg.feasible[i]),
                "objectives": objectives,
            }
            out.append(Result(cost if self.form == "cost" else objectives, attrs))
        return out

    def _completed(self, study: Study) -> dict[tuple, Result]:
        """Results of the study's completed trials, by settings (the lowest-numbered of each).

        A completed trial never changes: each is read once (per study), so a batch costs
        the trials completed since the last, not the whole study."""
        import optuna

        if self._found_in != (id(study), study.study_name):
            self._found, self._seen, self._found_in = {}, set(), (id(study), study.study_name)
        found, seen = self._found, self._seen
        for t in study.get_trials(deepcopy=False, states=(optuna.trial.TrialState.COMPLETE,)):
            if t.number in seen:
                continue
            seen.add(t.number)
            stored = stored_result(t)
            if stored is None or stored.settings is None:
                continue
            if len(stored.constraints) != len(CONSTRAINTS):  # scored with other constraints
                continue
            key = settings_key(space.settings_from_dict(stored.settings))
            if key in found and found[key].attrs["cached_from"] <= t.number:
                continue  # (a lower-numbered one may complete later, on another worker)
            parts = stored._asdict()
            attrs = {k: list(v) if isinstance(v, tuple) else v for k, v in parts.items()}
            attrs["cached_from"] = t.number if stored.cached_from is None else stored.cached_from
            values = float(t.value) if self.form == "cost" else [float(v) for v in t.values]
            found[key] = Result(values, attrs)
        return found


def trial_id_of(trial: Any, study_id: int | None = None) -> int:
    """A trial's id in its storage, by Optuna's public API (``trial.storage``, the
    number): where the study's storage caches its trials (RDB, in memory), no read.

    Parameters
    ----------
    trial : optuna.Trial
        The trial.
    study_id : int or None
        Its study's id in ``trial.storage`` (default: looked up by the study's name).

    Returns
    -------
    int
        The id the storage's trial methods take.
    """
    storage = trial.storage
    if study_id is None:
        study_id = storage.get_study_id_from_name(trial.study.study_name)
    return int(storage.get_trial_id_from_study_id_trial_number(study_id, trial.number))


def set_constraints(trial: Any, values: dict[str, float], trial_id: int | None = None) -> None:
    """Set the trial's constraints, as ``trial.set_constraint`` does (Optuna 5 reads them
    from the trial; its ``constraints_func`` is deprecated), without reading the trial
    first: on an RDB storage each read rebuilds the whole trial. A retried trial carries
    its first run's constraints, which are written again with the same values (the same
    settings, so the same result).

    Parameters
    ----------
    trial : optuna.Trial
        The trial (or what a worker made in its place: ``storage`` and ``number``).
    values : dict of str to float
        The constraints by name (≤ 0: met).
    trial_id : int or None
        The trial's id in ``trial.storage`` (default: :func:`trial_id_of`).
    Raises
    ------
    ValueError
        If a value is NaN.
    """
    tid = trial_id_of(trial) if trial_id is None else trial_id
    for name, v in values.items():
        if math.isnan(float(v)):
            raise ValueError(f"constraint {name!r} of trial {trial.number} is NaN")
    trial.storage.set_trial_system_attr(tid, CONSTRAINTS_KEY, [float(v) for v in values.values()])
