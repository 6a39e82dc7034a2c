"""The sweep's objective: a trial's settings scored by the one scoring path, with its
constraints set on the trial for the samplers that learn them.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from contextlib import nullcontext
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np

from vfgym import space
from vfgym.moves.scenarios import Scenario
from vfgym.params import DEFAULT_MEASURES, PAPER_PLANT, Measures, Plant, Settings
from vfgym.scoring import CONSTRAINTS, Evaluation, evaluate
from vfgym.tuning._aggregate import DEFAULT_AGGREGATE, DEFAULT_CVAR_ALPHA, aggregate_costs
from vfgym.tuning._recovery import WORKER_ATTR, _worker_id

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
        Per controller: ``cost`` (the aggregate over the scenarios), ``constraints``
        (worst, max, over the scenarios), ``feasible`` (every constraint ≤ 0 on every scenario) and
        ``objectives`` (means).
    """
    cons = np.nanmax(ev.constraints, axis=1)
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
    ) -> None:
        self.scenarios = scenarios
        self.how = (aggregate, cvar_alpha)
        self.plant = plant
        self.measures = measures
        self.laws = laws
        self.form = form
        self.cache: dict[tuple, tuple[Any, dict[str, Any]]] = {}
        self.simulated = 0
        self.on_enter: Callable[[], None] | None = None
        self.guard: Callable[[], Any] = nullcontext
        self.current: int | None = None

    def __call__(self, trial: Trial) -> float | list[float]:
        self.current = trial.number
        # Before the claim lock goes: a retried trial inherits its dead worker's attribute,
        # and another worker's recovery must not see this one running under that name.
        trial.set_user_attr(WORKER_ATTR, _worker_id())
        if self.on_enter:
            self.on_enter()
        return self._run(trial)

    def _run(self, trial: Trial) -> float | list[float]:
        settings = space.suggest(trial, self.laws)
        key = settings_key(settings)
        hit = self.cache.get(key) or self._lookup(trial.study, settings)
        if hit is None:
            with self.guard():  # the only place a trial may be interrupted
                values, attrs = self.score(settings)
            self.simulated += 1
            self.cache[key] = (values, attrs | {"cached_from": trial.number})
        else:
            values, attrs = hit
        for k, v in attrs.items():
            trial.set_user_attr(k, v)
        # Optuna 5 reads constraints from the trial (its constraints_func is deprecated).
        # A retried trial carries its first run's (identical) constraints: those stay.
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            for name, v in zip(CONSTRAINTS, attrs["constraints"], strict=True):
                trial.set_constraint(name, v)
        return values

    def score(self, settings: Settings) -> tuple[Any, dict[str, Any]]:
        """Values and user attributes of one setting (one batched evaluation).

        Parameters
        ----------
        settings : Settings
            The setting.

        Returns
        -------
        tuple
            ``(values, attrs)``: the aggregate cost (``cost`` form) or the three
            objectives' means, and the trial's user attributes (settings, cost, constraints,
            feasible, objectives).
        """
        agg = aggregate(
            evaluate(settings, self.scenarios, plant=self.plant, measures=self.measures),
            *self.how,
        )
        attrs = {
            "settings": space.settings_to_dict(settings),
            "cost": float(agg.cost[0]),
            "constraints": [float(x) for x in agg.constraints[0]],
            "feasible": bool(agg.feasible[0]),
            "objectives": [float(x) for x in agg.objectives[0]],
        }
        values = attrs["cost"] if self.form == "cost" else list(attrs["objectives"])
        return values, attrs

    def _lookup(self, study: Study, settings: Settings) -> tuple[Any, dict[str, Any]] | None:
        import optuna

        want = space.settings_to_dict(settings)
        for t in study.get_trials(deepcopy=False, states=(optuna.trial.TrialState.COMPLETE,)):
            cons = t.user_attrs.get("constraints")
            if (
                t.user_attrs.get("settings") == want
                and "cost" in t.user_attrs
                and len(cons or ()) == len(CONSTRAINTS)  # not scored with other constraints
            ):
                attrs = {k: t.user_attrs[k] for k in _RESULT_ATTRS if k in t.user_attrs}
                attrs["cached_from"] = t.user_attrs.get("cached_from", t.number)
                values = t.value if self.form == "cost" else list(t.values)
                return values, attrs
        return None


_RESULT_ATTRS = ("settings", "cost", "constraints", "feasible", "objectives")
