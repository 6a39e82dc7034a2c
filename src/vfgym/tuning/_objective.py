"""The sweep's objective: a trial's settings scored by the one scoring path, and the one
format its result is stored in.

Each attribute written is one transaction of Optuna's RDB storage, so a trial writes two:
its result as one user attribute, ``result`` (:data:`PARTS`), and its constraints as one
system attribute, the list Optuna reads into ``trial.constraints`` (Optuna's
``set_constraint`` reads the whole trial before each of its one-key writes).

A sampler that plans its next points (the compass: the rest of a generation) lets the
objective score them ahead (:attr:`Objective.ahead`), in one batched call on a thread of
its own while this process writes the trial and asks for the next: the compiled kernel
releases the GIL. A point scored ahead gives the bits of one scored alone (each move of
each setting is simulated and scored on its own), and counts as simulated by the trial
that asks for it.
"""

from __future__ import annotations

import math
import threading
from collections.abc import Callable, Mapping
from contextlib import nullcontext
from typing import TYPE_CHECKING, Any, NamedTuple

from vfgym import space
from vfgym.axis import Axis
from vfgym.moves.scenarios import Scenario
from vfgym.params import Settings
from vfgym.scoring import CONSTRAINTS, evaluate
from vfgym.tuning._aggregate import DEFAULT_AGGREGATE, DEFAULT_CVAR_ALPHA, aggregate

if TYPE_CHECKING:
    from optuna import Trial

RESULT_ATTR = "result"
"""The user attribute of a trial's result."""
PARTS = ("settings", "cost", "constraints", "feasible", "objectives", "cached_from")
"""A result's parts (:class:`StoredResult`; ``cached_from`` only on a copied result)."""


class Result(NamedTuple):
    """A setting's objective value(s) and the parts of its stored result."""

    values: float | list[float]
    attrs: dict[str, Any]


class Objective:
    """Settings from the trial → :func:`vfgym.evaluate` on the scenarios (on the axis)
    → cost (or the three objectives), with the result stored on the trial.

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
    axis : Axis
        The problem: the settings run on its plant, are scored with its measures, and
        must also be feasible on its :meth:`~vfgym.axis.Axis.design_plants` (the
        cost is the modelled plant's); :data:`vfgym.axis.PAPER_AXIS` for the paper's.
    aggregate : str
        The cost's aggregate over the scenarios (:func:`vfgym.tuning.aggregate`).
    cvar_alpha : float
        The share of the costliest scenarios ``cvar`` averages.
    """

    def __init__(
        self,
        scenarios: list[Scenario],
        laws: tuple[str, ...],
        form: str,
        *,
        axis: Axis,
        aggregate: str = DEFAULT_AGGREGATE,
        cvar_alpha: float = DEFAULT_CVAR_ALPHA,
    ) -> None:
        self.scenarios = scenarios
        self.laws = laws
        self.form = form
        self.axis, self.plants = axis, tuple(axis.design_plants())
        self.how = (aggregate, cvar_alpha)
        self.cache: dict[Settings, Result] = {}
        self.simulated = 0
        self.guard: Callable[[], Any] = nullcontext  # around a simulation (interrupts)
        # The settings the sampler will ask for next, scored ahead (None: none planned).
        self.ahead: Callable[[], list[Settings]] | None = None
        self._batch: _Batch | None = None  # the last batch scored ahead
        self._ready: dict[Settings, Result] = {}  # its results not asked for yet
        self._study: tuple | None = None  # the study the fields below are of
        self._study_id = 0
        self._found: dict[Settings, Result] = {}  # its completed trials' results
        self._known: set[int] = set()  # its trials seen finished, or run here
        self._below = 0  # every trial numbered below this is known

    def __call__(self, trial: Trial) -> float | list[float]:
        settings = space.suggest(trial, self.laws)
        self._seen(trial)
        res = self.cache.get(settings) or self._completed(trial).get(settings)
        if res is None:
            with self.guard():
                res = self._scored_ahead(settings) or self.score_many([settings])[0]
            self.simulated += 1
            self.cache[settings] = Result(res.values, res.attrs | {"cached_from": trial.number})
        self._score_ahead()
        result = {k: res.attrs[k] for k in PARTS if k in res.attrs}
        if trial.user_attrs.get(RESULT_ATTR) != result:  # (a retry may hold it already)
            trial.set_user_attr(RESULT_ATTR, result)
        values = dict(zip(CONSTRAINTS, res.attrs["constraints"], strict=True))
        set_constraints(trial, values, self._study_id)
        return res.values

    def score_many(self, settings: list[Settings]) -> list[Result]:
        """Values and result parts of each setting, all in one batched evaluation.

        Parameters
        ----------
        settings : list of Settings
            The settings.

        Returns
        -------
        list of Result
            One per setting: the aggregate cost (``cost`` form) or the objectives' means,
            and the parts of its stored result.
        """
        ev = evaluate(settings, self.scenarios, axis=self.axis, plants=self.plants)
        agg = aggregate(ev, *self.how)
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

    def close(self) -> None:
        """Wait for the settings being scored ahead, if any (a compiled call cannot be
        stopped: the process's next one waits for it)."""
        if self._batch is not None:
            self._batch.thread.join()

    def _scored_ahead(self, settings: Settings) -> Result | None:
        """The settings' result if scored ahead (waiting for its batch), else None; any
        other batch still running is waited for too (one kernel call at a time)."""
        batch = self._batch
        if batch is not None:
            batch.thread.join()
            self._ready.update(batch.results)  # (none if it failed: scored here again)
            self._batch = None
        return self._ready.pop(settings, None)

    def _score_ahead(self) -> None:
        """Start scoring the planned settings not scored yet, unless a batch runs."""
        if self.ahead is None or (self._batch is not None and self._batch.thread.is_alive()):
            return
        if self._batch is not None:
            self._ready.update(self._batch.results)
            self._batch = None
        plan = [s for s in dict.fromkeys(self.ahead()) if s not in self.cache]
        self._ready = {s: r for s, r in self._ready.items() if s in plan}
        todo = [s for s in plan if s not in self._ready and s not in self._found]
        if todo:
            self._batch = _Batch.start(self, todo)

    def _seen(self, trial: Trial) -> None:
        """Note the trial as run here (a new study: forget the last one's)."""
        study = trial.study
        if self._study != (id(study), study.study_name):
            self._study = (id(study), study.study_name)
            self._study_id = trial.storage.get_study_id_from_name(study.study_name)
            self._found, self._known, self._below = {}, set(), 0
        self._known.add(trial.number)

    def _completed(self, trial: Trial) -> dict[Settings, Result]:
        """Results of the study's completed trials, by settings (the lowest-numbered of
        each), read while a trial numbered below this one finished unseen here (another
        process's: a resumed or shared study); each read once."""
        import optuna

        while self._below in self._known:
            self._below += 1
        if self._below >= trial.number:
            return self._found
        found = self._found
        for t in trial.study.get_trials(deepcopy=False):
            if t.number in self._known or not t.state.is_finished():
                continue
            self._known.add(t.number)
            stored = stored_result(t)
            if t.state != optuna.trial.TrialState.COMPLETE or stored is None:
                continue
            if stored.settings is None or len(stored.constraints) != len(CONSTRAINTS):
                continue  # (scored with other constraints)
            key = space.settings_from_dict(stored.settings)
            if key in found and found[key].attrs["cached_from"] <= t.number:
                continue  # (a lower-numbered one may complete later, on another worker)
            attrs = {k: list(v) if isinstance(v, tuple) else v for k, v in stored._asdict().items()}
            attrs["cached_from"] = t.number if stored.cached_from is None else stored.cached_from
            values = float(t.value) if self.form == "cost" else [float(v) for v in t.values]
            found[key] = Result(values, attrs)
        return found


class _Batch(NamedTuple):
    """Settings scored ahead on a thread of its own, and their results once it ends
    (empty if it failed)."""

    thread: threading.Thread
    results: dict[Settings, Result]

    @classmethod
    def start(cls, objective: Objective, settings: list[Settings]) -> _Batch:
        results: dict[Settings, Result] = {}

        def score() -> None:
            import numba

            numba.set_num_threads(max(1, numba.get_num_threads() - 1))  # (this thread's)
            try:
                scored = objective.score_many(settings)
            except Exception:  # (scored again when asked for, where it raises as it will)
                return
            results.update(zip(settings, scored, strict=True))

        thread = threading.Thread(target=score, name="vfgym-ahead", daemon=True)
        thread.start()
        return cls(thread, results)


def set_constraints(trial: Any, values: dict[str, float], study_id: int | None = None) -> None:
    """Set the trial's constraints (by name, in order; ≤ 0: met) in one write, without
    reading the trial first as ``trial.set_constraint`` does; ``study_id``: the trial's
    study's in ``trial.storage`` (default: looked up). ValueError for a NaN."""
    for name, v in values.items():
        if math.isnan(float(v)):
            raise ValueError(f"constraint {name!r} of trial {trial.number} is NaN")
    storage = trial.storage
    if study_id is None:
        study_id = storage.get_study_id_from_name(trial.study.study_name)
    tid = storage.get_trial_id_from_study_id_trial_number(study_id, trial.number)
    storage.set_trial_system_attr(tid, "constraints", [float(v) for v in values.values()])


class StoredResult(NamedTuple):
    """A completed trial's result as a sweep stored it.

    Attributes
    ----------
    settings : dict or None
        The settings scored (:func:`vfgym.space.settings_to_dict`).
    cost : float
        The cost's aggregate over the scenarios.
    constraints : tuple of float
        The worst of each constraint over the scenarios, in ``CONSTRAINTS``' order
        (≤ 0: met).
    feasible : bool
        Every constraint met on every scenario.
    objectives : tuple of float
        The objectives' means over the scenarios.
    cached_from : int or None
        The trial whose simulation it copies (None: its own).
    """

    settings: dict[str, Any] | None
    cost: float
    constraints: tuple[float, ...]
    feasible: bool
    objectives: tuple[float, ...]
    cached_from: int | None

    @property
    def arrives(self) -> bool:
        """Whether the move arrived on every scenario (worst ``arrival`` ≤ 0)."""
        if len(self.constraints) != len(CONSTRAINTS):
            return False
        return self.constraints[CONSTRAINTS.index("arrival")] <= 0.0


def stored_result(trial: Any) -> StoredResult | None:
    """A trial's stored result.

    Parameters
    ----------
    trial : optuna.trial.FrozenTrial
        The trial (anything with ``user_attrs``).

    Returns
    -------
    StoredResult or None
        Its result; None if it holds no cost (not scored by a sweep, or not yet).
    """
    parts = trial.user_attrs.get(RESULT_ATTR)
    if not isinstance(parts, Mapping) or "cost" not in parts:
        return None
    cached = parts.get("cached_from")
    settings = parts.get("settings")
    return StoredResult(
        settings=dict(settings) if isinstance(settings, Mapping) else None,
        cost=float(parts["cost"]),
        constraints=tuple(float(c) for c in parts.get("constraints") or ()),
        feasible=bool(parts.get("feasible", False)),
        objectives=tuple(float(o) for o in parts.get("objectives") or ()),
        cached_from=None if cached is None else int(cached),
    )
