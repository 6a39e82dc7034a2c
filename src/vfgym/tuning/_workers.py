"""Workers that share a study: claiming trials, recovering those of dead workers, and a
Ctrl-C that never cuts a storage write in half.

A worker that dies mid-trial leaves a running trial behind: on RDB storages Optuna's
heartbeat marks it failed after the grace period, on the journal the other workers see
that its process is gone; either way it is marked failed and enqueued again with the
settings it had drawn. Ctrl-C is only acted on inside a trial's evaluation or while
waiting, so the interrupted trial is marked failed and enqueued again, and running the
same command with the same ``--study`` continues where it stopped.
"""

from __future__ import annotations

import copy
import json
import math
import signal
import subprocess
import sys
import threading
import time
import warnings
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import asdict, dataclass, field
from typing import TYPE_CHECKING, Any, NamedTuple

from vfgym import space
from vfgym.moves.axis import axis_kwargs
from vfgym.params import PAPER_SETTINGS, Settings
from vfgym.scoring import evaluate
from vfgym.tuning._config import SweepConfig
from vfgym.tuning._objective import Objective, trial_id_of
from vfgym.tuning._recovery import (
    WORKER_ATTR,
    RetryStale,
    _fail_and_retry,
    _retry,
    _worker_id,
    counts,
    recover,
)
from vfgym.tuning._storage import StorageSpec, _claim_lock, open_storage
from vfgym.tuning._stored import FORMAT, study_format
from vfgym.tuning._study import batch_size, make_sampler, trial_budget

if TYPE_CHECKING:
    from optuna import Study


class DeferredInterrupt:
    """SIGINT raises KeyboardInterrupt only inside :meth:`allowed` blocks (a trial's
    simulation, a wait); anywhere else it is held until the next such block or the end of
    the ``with``, so a storage write or a lock is never cut in half.

    The decision is taken by the Python-level handler, which runs in the main thread
    between bytecodes, so there is no window between "the signal arrived" and "the block
    closed" in which an interrupt can escape into Optuna's bookkeeping. Off the main thread
    (where handlers cannot be installed) the process's handler is left as it is.

    Raises
    ------
    KeyboardInterrupt
        On leaving the ``with`` normally while an interrupt is held back.
    """

    def __init__(self) -> None:
        self.open = False
        self.pending = False
        self._old: Any = None
        self._installed = False

    def __enter__(self) -> DeferredInterrupt:
        if threading.current_thread() is threading.main_thread():
            self._old = signal.signal(signal.SIGINT, self._handle)
            self._installed = True
        return self

    def __exit__(self, kind: Any, exc: Any, tb: Any) -> None:
        if self._installed:
            signal.signal(signal.SIGINT, self._old)
            self._installed = False
        if self.pending and kind is None:
            self.pending = False
            raise KeyboardInterrupt

    def _handle(self, signum: int, frame: Any) -> None:
        if self.open:
            self.open = False
            raise KeyboardInterrupt
        self.pending = True

    def check(self) -> None:
        """Raise an interrupt that was held back.

        Raises
        ------
        KeyboardInterrupt
            If one was held back.
        """
        if self.pending:
            self.pending = False
            raise KeyboardInterrupt

    @contextmanager
    def allowed(self) -> Iterator[None]:
        """Let an interrupt through here (raising at once one that was held back).

        Yields
        ------
        None
            Inside the block, SIGINT raises KeyboardInterrupt.
        """
        self.check()
        self.open = True
        try:
            yield
        finally:
            self.open = False


@dataclass
class WorkerReport:
    """What one worker did.

    Attributes
    ----------
    trials : list of int
        Numbers of the trials it ran.
    simulated : int
        Settings it simulated (the others were copied from equal settings).
    recovered : list of int
        Trials of dead workers it marked failed and enqueued again.
    stopped : str
        Why it stopped: ``done``, ``timeout`` or ``interrupted``.
    """

    trials: list[int] = field(default_factory=list)
    simulated: int = 0
    recovered: list[int] = field(default_factory=list)
    stopped: str = ""


def run_worker(
    cfg: SweepConfig,
    spec: StorageSpec,
    study_name: str,
    index: int = 0,
    on_trial: Callable[[Study], object] | None = None,
    poll_s: float = 0.25,
) -> WorkerReport:
    """Run trials of ``study_name`` until it holds the trials asked for (or the timeout).

    Each round claims a batch of trials under the claim lock (asked of the sampler, their
    settings stored, heartbeats started), simulates their settings in one batched call,
    then tells the study each result. SIGINT is held back (:class:`DeferredInterrupt`)
    except inside that simulation and while waiting; the trials of an interrupted batch
    are marked failed and enqueued again before KeyboardInterrupt propagates.

    Parameters
    ----------
    cfg : SweepConfig
        The sweep's configuration.
    spec : StorageSpec
        Where the study lives.
    study_name : str
        The study.
    index : int
        The worker's index, added to the sampler's seed.
    on_trial : callable or None
        Called with the study after each trial the worker ran.
    poll_s : float
        Seconds between looks at the study while every trial is claimed.

    Returns
    -------
    WorkerReport
        What the worker did.
    """
    import optuna

    # ERROR: an interrupted trial is reported by the sweep, not as Optuna's warning with a
    # traceback; a failing objective still raises.
    optuna.logging.set_verbosity(optuna.logging.ERROR)
    warnings.filterwarnings("ignore", category=optuna.exceptions.ExperimentalWarning)
    warnings.filterwarnings("ignore", message="Constraints have been set, but CmaEsSampler")
    rep = WorkerReport()
    scenarios = cfg.scenario_list()
    budget = trial_budget(cfg)
    grace = cfg.grace or 2 * cfg.heartbeat
    orphan_s = max(30.0, 3.0 * grace)
    seed = None if cfg.seed is None else cfg.seed + index
    deadline = math.inf if cfg.timeout is None else time.monotonic() + cfg.timeout
    with DeferredInterrupt() as interrupts:
        storage = open_storage(spec, cfg.heartbeat, cfg.grace)
        sampler = make_sampler(cfg, seed, scenarios, storage)
        study = optuna.load_study(study_name=study_name, storage=storage, sampler=sampler)
        on_axis = axis_kwargs(cfg.load_axis())
        objective = Objective(
            scenarios,
            cfg.laws,
            str(cfg.objective),
            **on_axis,  # type: ignore[arg-type]
            aggregate=cfg.aggregate,
            cvar_alpha=cfg.cvar_alpha,
        )
        objective.trial_format = study_format(study)
        # First call compiles/loads the kernel before any trial is claimed.
        evaluate(PAPER_SETTINGS, scenarios[:1], **on_axis)
        lock = _claim_lock(spec, study_name)
        beats = Heartbeats(storage)
        study_id = storage.get_study_id_from_name(study_name)
        maker = one_write(sampler, storage, study_id, objective.trial_format)
        objective.guard = interrupts.allowed
        claimed: list[Claimed] = []
        try:
            while True:
                interrupts.check()
                lock.acquire()
                try:
                    rep.recovered += recover(study, storage, spec, orphan_s)
                    n = counts(study)
                    if n["complete"] >= budget:
                        rep.stopped = "done"
                        break
                    if time.monotonic() >= deadline:
                        rep.stopped = "timeout"
                        break
                    objective.learn(study)  # (the batch's results read nothing more)
                    free = budget - n["complete"] - n["running"]
                    size = batch_size(cfg, sampler, study)
                    take = min(size, free) if free > 0 else min(1, n["waiting"])
                    claimed = claim(study, objective, take, beats, maker, n["waiting"], study_id)
                finally:
                    lock.release()
                if not claimed:
                    with interrupts.allowed():
                        time.sleep(poll_s)
                    continue
                run_batch(study, objective, claimed, maker)
                beats.stop()
                rep.trials += [c.trial.number for c in claimed]
                claimed = []
                if on_trial is not None:
                    on_trial(study)
        except KeyboardInterrupt:
            rep.stopped = "interrupted"
            beats.stop()
            give_back(study, claimed)
            raise
        finally:
            beats.stop()
            rep.simulated = objective.simulated
            cb = getattr(storage, "heartbeat_stale_trial_callback", None)
            if isinstance(cb, RetryStale):  # also those failed while claiming
                rep.recovered = sorted(set(rep.recovered) | set(cb.failed))
            lock.close()
    return rep


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
            beats.add(trial_id)
            # The worker's name only once its heartbeat is recorded, as below: recovery
            # takes a running trial without one for an orphan (its worker died before
            # the heartbeat began), and one with a name for the heartbeat to judge, so a
            # name written with the trial would leave a death in between never retried.
            trial.set_user_attr(WORKER_ATTR, _worker_id())
        else:
            with warnings.catch_warnings():  # heartbeats are ours (:class:`Heartbeats`)
                warnings.filterwarnings("ignore", message="Heartbeat of storage is supposed")
                trial = study.ask()
            trial_id = trial_id_of(trial, sid)
            beats.add(trial_id)
            trial.set_user_attr(WORKER_ATTR, _worker_id())
            settings = space.suggest(trial, objective.laws)
        objective.current = trial.number
        out.append(Claimed(trial, settings, trial_id, maker is not None and i >= waiting))
    if maker is not None and len(out) > waiting:
        maker.check([c.trial for c in out[waiting:]])
        objective.current = out[-1].trial.number
    return out


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
        template = self.sampler.plan_trial(study, first)
        settings = settings_of(template.params, laws)
        if self.trial_format < 2:
            # The settings' user attribute with them (the trial's result records it
            # again, which :meth:`Objective.record` skips as already there).
            template.user_attrs["settings"] = space.settings_to_dict(settings)
        trial_id = self.storage.create_new_trial(self.study_id, template)
        self.sampler.created(template.number)
        return MadeTrial(self.storage, trial_id, template.number, template.user_attrs), settings

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
    import optuna

    try:
        results = objective.results(
            None, [c.trial.number for c in batch], [c.settings for c in batch]
        )
    except KeyboardInterrupt:
        raise
    except Exception:
        for c in batch:
            study.tell(c.trial.number, state=optuna.trial.TrialState.FAIL)
        raise
    for c, res in zip(batch, results, strict=True):
        objective.record(c.trial, res, c.trial_id)
        values = res.values if isinstance(res.values, list) else [res.values]
        if maker is not None and c.made and all(map(math.isfinite, values)):
            maker.tell(c.trial_id, res.values)
        else:
            study.tell(c.trial.number, res.values)


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


def spawn_workers(
    cfg: SweepConfig, spec: StorageSpec, study: str, n: int
) -> list[subprocess.Popen[str]]:
    """Start worker processes on the study (``python -m vfgym.tuning``).

    Their job goes through stdin, so the storage password never shows on a command line.

    Parameters
    ----------
    cfg : SweepConfig
        The sweep's configuration.
    spec : StorageSpec
        Where the study lives.
    study : str
        The study's name.
    n : int
        Processes to start.

    Returns
    -------
    list of subprocess.Popen
        The processes; each prints its :class:`WorkerReport` as JSON on stdout.
    """
    procs = []
    for i in range(n):
        p = subprocess.Popen(
            [sys.executable, "-m", "vfgym.tuning"],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
        )
        job = {"config": cfg.to_dict(), "storage": asdict(spec), "study": study, "index": i}
        assert p.stdin is not None
        p.stdin.write(json.dumps(job))
        p.stdin.close()
        procs.append(p)
    return procs
