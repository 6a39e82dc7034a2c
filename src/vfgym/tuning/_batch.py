"""A worker's batch of trials: claimed under the claim lock with their heartbeats (or,
for a sampler that plans its trials, made in one write each, and created while their
settings are simulated), simulated together, and told their results; given back when
interrupted.
"""

from __future__ import annotations

import copy
import math
import threading
import warnings
from collections.abc import Callable
from typing import Any, NamedTuple

from vfgym import space
from vfgym.params import Settings
from vfgym.tuning._objective import Objective, Result, trial_id_of
from vfgym.tuning._recovery import WORKER_ATTR, _fail_and_retry, _retry, _worker_id
from vfgym.tuning._stored import FORMAT


def claim(
    study: Any,
    objective: Objective,
    n: int,
    beats: Heartbeats,
    maker: OneWrite | None = None,
    waiting: int = 0,
    study_id: int | None = None,
) -> list[Claimed]:
    """Ask the study for ``n`` trials (waiting ones first), each with its heartbeat
    started, this worker's name and its settings stored (call under the claim lock: a
    retried trial inherits its dead worker's name, which must be gone when it goes).

    With ``maker`` (a sampler that plans its trials, :meth:`OneWrite.make`), the trials
    after the ``waiting`` ones are each created in one write instead of ``study.ask()``
    and a write per parameter and attribute. ``study_id``: the study's id in the trials'
    storage (default: the maker's, else read)."""
    sid = study_id if study_id is not None else maker.study_id if maker else None
    out = []
    for i in range(n):
        if maker is not None and i >= waiting:
            made, settings = maker.make(study, i == waiting, objective.laws)
            trial: Any = made
            trial_id = made.trial_id
            start(trial, trial_id, beats)
        else:
            with warnings.catch_warnings():  # heartbeats are ours (:class:`Heartbeats`)
                warnings.filterwarnings("ignore", message="Heartbeat of storage is supposed")
                trial = study.ask()
            trial_id = trial_id_of(trial, sid)
            start(trial, trial_id, beats)
            settings = space.suggest(trial, objective.laws)
        out.append(Claimed(trial, settings, trial_id, maker is not None and i >= waiting))
    if maker is not None and len(out) > waiting:
        maker.check([c.trial for c in out[waiting:]])
    return out


def start(trial: Any, trial_id: int, beats: Heartbeats) -> None:
    """Start a claimed trial's heartbeat, then write this worker's name on it.

    The name only once the heartbeat is recorded: recovery takes a running trial without
    a name for an orphan (its worker died before the heartbeat began), and one with a name
    for the heartbeat to judge, so a name written first would leave a death in between
    never retried."""
    beats.add(trial_id)
    trial.set_user_attr(WORKER_ATTR, _worker_id())


class OneWrite(NamedTuple):
    """Trials of a sampler that plans them (the compass: ``plan_trial``, ``created`` and
    ``replan``) made in one storage write each, and told through the storage: such a
    sampler learns nothing in ``after_trial``, and ``study.tell`` reads the trial twice
    before its one write (the same state and values)."""

    sampler: Any
    storage: Any
    study_id: int
    trial_format: int = FORMAT

    def make(self, study: Any, first: bool, laws: tuple[str, ...]) -> tuple[MadeTrial, Settings]:
        """The next planned trial, created running with its parameters and generation
        (and, in a study of trial format 1, its settings; from 2 they are stored with its
        result) (the worker's name is written after its heartbeat, :func:`claim`); and
        the settings. Its number is the one planned, which :meth:`check` confirms for a
        batch."""
        template, settings = self.plan(study, first, laws)
        made = self.create(template)
        self.sampler.created(template.number)
        return made, settings

    def plan(self, study: Any, first: bool, laws: tuple[str, ...]) -> tuple[Any, Settings]:
        """The next planned trial (an ``optuna.trial.FrozenTrial`` to create, numbered as
        planned) and its settings, without a write: a batch may be planned whole, then
        created (:meth:`create`) while it is simulated, and numbered by :meth:`check`."""
        template = self.sampler.plan_trial(study, first)
        settings = settings_of(template.params, laws)
        if self.trial_format < 2:
            # The settings' user attribute with them (the trial's result records it
            # again, which :meth:`Objective.record` skips as already there).
            template.user_attrs["settings"] = space.settings_to_dict(settings)
        return template, settings

    def create(self, template: Any) -> MadeTrial:
        """Create a planned trial (one write)."""
        trial_id = self.storage.create_new_trial(self.study_id, template)
        return MadeTrial(self.storage, trial_id, template.number, template.user_attrs)

    def check(self, made: list[MadeTrial]) -> None:
        """Confirm the numbers planned for trials made one after the other (by
        :meth:`make`, the first with ``first``): a trial's number counts the study's
        trials before it, so they are the planned ones unless a trial was made meanwhile
        (outside the claim lock), and then one numbered past the last planned exists.
        One read a batch; on a mismatch each trial's number is read and the sampler plans
        from the study again."""
        if not made:
            return
        try:
            self.storage.get_trial_id_from_study_id_trial_number(self.study_id, made[-1].number + 1)
        except KeyError:
            return
        for m in made:
            m.number = self.storage.get_trial(m.trial_id).number
        self.sampler.replan()

    def tell(self, trial_id: int, values: float | list[float]) -> None:
        """Complete the trial with its values (what ``study.tell`` writes)."""
        import optuna

        vals = [float(values)] if isinstance(values, (int, float)) else [float(v) for v in values]
        self.storage.set_trial_state_values(trial_id, optuna.trial.TrialState.COMPLETE, vals)


def settings_of(params: dict[str, Any], laws: tuple[str, ...]) -> Settings:
    """The settings of a trial's parameters (the law, if not among them, the one searched),
    as :func:`vfgym.space.suggest` gives them."""
    return Settings(
        **{d.name: params[d.name] for d in space.SPACE},
        accel_law=params.get("accel_law", laws[0]),
    )


def one_write(sampler: Any, storage: Any, study_id: int, fmt: int = FORMAT) -> OneWrite | None:
    """:class:`OneWrite` for a sampler that plans its trials (``fmt``: the study's trial
    format), else None."""
    if not all(hasattr(sampler, m) for m in ("plan_trial", "created", "replan")):
        return None
    return OneWrite(sampler, storage, study_id, fmt)


class MadeTrial:
    """A trial :class:`OneWrite` made, with what a worker uses of an
    :class:`optuna.trial.Trial` (its number, storage, user attributes) and its id in the
    storage, without reading the trial back from the storage."""

    def __init__(self, storage: Any, trial_id: int, number: int, user_attrs: dict) -> None:
        self.storage = storage
        self.trial_id = trial_id
        self.number = number
        self._user_attrs = dict(user_attrs)

    @property
    def user_attrs(self) -> dict[str, Any]:
        """The user attributes (the trial's as made, and those set since)."""
        return dict(self._user_attrs)

    def set_user_attr(self, key: str, value: Any) -> None:
        """Set a user attribute (one storage write)."""
        self.storage.set_trial_user_attr(self.trial_id, key, value)
        self._user_attrs[key] = value


class Claimed(NamedTuple):
    """A trial a worker claimed, the settings drawn for it, its id in the storage, and
    whether :class:`OneWrite` made it (then it is told through the storage)."""

    trial: Any
    settings: Settings
    trial_id: int
    made: bool = False


def run_batch(
    study: Any, objective: Objective, batch: list[Claimed], maker: OneWrite | None = None
) -> None:
    """Score the batch's settings together (one batched simulation; a setting a completed
    trial holds is copied from those ``objective`` read last, :meth:`Objective.learn`)
    and tell the study; a failing evaluation fails the batch's trials and raises."""
    numbers, settings = [c.trial.number for c in batch], [c.settings for c in batch]
    results = _results_or_fail(study, objective, batch, numbers, settings)
    tell_results(study, objective, batch, results, maker)


def _results_or_fail(
    study: Any,
    objective: Objective,
    batch: list[Claimed],
    numbers: Any,
    settings: list[Settings],
    while_running: Callable[[], None] | None = None,
) -> list[Result]:
    """:meth:`Objective.results`; a failing evaluation fails the ``batch``'s trials (those
    made by then) and raises."""
    import optuna

    try:
        return objective.results(None, numbers, settings, while_running)
    except KeyboardInterrupt:
        raise
    except Exception:
        for c in batch:
            study.tell(c.trial.number, state=optuna.trial.TrialState.FAIL)
        raise


def once(fn: Callable[[], None]) -> Callable[[], None]:
    """``fn`` to be called at most once (later calls do nothing)."""
    done = False

    def call() -> None:
        nonlocal done
        if not done:
            done = True
            fn()

    return call


def tell_results(
    study: Any,
    objective: Objective,
    batch: list[Claimed],
    results: list[Result],
    maker: OneWrite | None = None,
) -> None:
    """Record each result on its trial and complete the trial (through the storage for
    trials :class:`OneWrite` made)."""
    for c, res in zip(batch, results, strict=True):
        objective.record(c.trial, res, c.trial_id)
        values = res.values if isinstance(res.values, list) else [res.values]
        if maker is not None and c.made and all(map(math.isfinite, values)):
            maker.tell(c.trial_id, res.values)
        else:
            study.tell(c.trial.number, res.values)


def run_planned(
    study: Any,
    objective: Objective,
    maker: OneWrite,
    beats: Heartbeats,
    planned: list[tuple[Any, Settings]],
    claimed: list[Claimed],
    release: Callable[[], None],
    held: Callable[[], Any],
) -> None:
    """Simulate a planned batch (:meth:`OneWrite.plan`, under the claim lock) and create
    its trials meanwhile, then tell each its result.

    The trials are created and started as :func:`claim` does (:func:`start`) on this
    thread while the kernel simulates their settings on the others, with interrupts
    ``held`` back (a write is not cut short), and then the claim lock is
    released. The writes a batch needs before its results take the simulation's
    time instead of adding to it. ``claimed`` receives the trials as they are made (what
    an interrupt gives back); a failing simulation fails them and raises."""
    created = False

    def create() -> None:
        nonlocal created
        created = True
        with held():
            try:
                for template, settings in planned:
                    made = maker.create(template)
                    start(made, made.trial_id, beats)
                    claimed.append(Claimed(made, settings, made.trial_id, True))
                maker.check([c.trial for c in claimed])
            finally:
                release()

    def numbers() -> list[int]:  # read after create: checked
        return [c.trial.number for c in claimed]

    try:
        settings = [s for _, s in planned]
        results = _results_or_fail(study, objective, claimed, numbers, settings, create)
    finally:
        if not created:  # failed before any trial was made: none exists, plan again
            release()
            maker.sampler.replan()
    tell_results(study, objective, claimed, results, maker)


def give_back(study: Any, batch: list[Claimed]) -> None:
    """Mark the claimed trials that did not complete failed and enqueue them again."""
    import optuna

    for c in batch:
        t = copy.deepcopy(study.get_trials(deepcopy=False)[c.trial.number])
        if t.state == optuna.trial.TrialState.FAIL:
            _retry(study, t)
        elif t.state == optuna.trial.TrialState.RUNNING:
            _fail_and_retry(study, t)


class Heartbeats:
    """Heartbeats of the claimed trials on RDB storages (what ``study.optimize`` runs for
    one trial): one recorded when a trial is claimed, then every ``heartbeat`` seconds
    from a thread until :meth:`stop`. Without one, a dead worker's trial is never stale."""

    def __init__(self, storage: Any) -> None:
        interval = getattr(storage, "get_heartbeat_interval", lambda: None)()
        self._storage = storage if interval else None
        self._interval = float(interval or 0)
        self._ids: list[int] = []
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    def add(self, trial_id: int) -> None:
        """Record a heartbeat of the trial (by its id in the storage) now, and from now
        on every interval."""
        if self._storage is None:
            return
        self._storage.record_heartbeat(trial_id)
        self._ids.append(trial_id)
        if self._thread is None:
            self._stop.clear()
            self._thread = threading.Thread(target=self._beat, daemon=True)
            self._thread.start()

    def _beat(self) -> None:
        storage = self._storage
        while storage is not None and not self._stop.wait(self._interval):
            for trial_id in list(self._ids):
                storage.record_heartbeat(trial_id)

    def stop(self) -> None:
        if self._thread is not None:
            self._stop.set()
            self._thread.join()
            self._thread = None
        self._ids = []
