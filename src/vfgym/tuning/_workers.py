"""Workers on a study, run as Optuna runs them: each worker is ``study.optimize`` in its
own process, on one machine or on many sharing one RDB storage.

Optuna does the heartbeat, the retry of dead workers' trials (RDB storages), the timeout
and the bookkeeping. Kept here, each for what Optuna does not do: the whole study's trial
budget, the dead workers of a journal and a trial killed before its first heartbeat, and
a Ctrl-C that lands only inside a simulation. ``optimize`` gets no callback: Optuna reads
each finished trial back for its callbacks, so what follows a trial is done at the end of
the objective and at the start of the next trial.
"""

from __future__ import annotations

import copy
import datetime
import multiprocessing
import os
import signal
import socket
import sys
import threading
import time
import warnings
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from multiprocessing.connection import Connection
from multiprocessing.process import BaseProcess
from typing import TYPE_CHECKING, Any, NamedTuple

import psutil

from vfgym.axis import AxisNote
from vfgym.params import PAPER_SETTINGS
from vfgym.scoring import evaluate
from vfgym.tuning._config import SweepConfig
from vfgym.tuning._model import prepare
from vfgym.tuning._objective import Objective
from vfgym.tuning._storage import MAX_RETRY, StorageSpec, open_storage, retry
from vfgym.tuning._study import make_sampler, trial_budget

if TYPE_CHECKING:
    from optuna import Study, Trial
    from optuna.storages import BaseStorage
    from optuna.trial import FrozenTrial

RETRY = "failed_trial"
"""System attribute of a retried trial (Optuna's ``RetryHeartbeatStaleTrialCallback``)."""
WORKER_ATTR = "worker"
"""User attribute of a trial: ``host/pid/start-time`` of the process that ran it."""


class DeferredInterrupt:
    """SIGINT raises KeyboardInterrupt only inside :meth:`allowed` blocks (a simulation, a
    wait), else is held until the next one, :meth:`check` or the end of the ``with``:
    Optuna lets a Ctrl-C land anywhere, inside a storage write too. Off the main thread
    the process's handler is left as it is."""

    def __init__(self) -> None:
        self.open = False
        self.pending = False
        self._old: Any = None

    def __enter__(self) -> DeferredInterrupt:
        if threading.current_thread() is threading.main_thread():
            self._old = signal.signal(signal.SIGINT, self._handle)
        return self

    def __exit__(self, kind: Any, exc: Any, tb: Any) -> None:
        if self._old is not None:
            signal.signal(signal.SIGINT, self._old)
            self._old = None
        if kind is None:
            self.check()

    def _handle(self, signum: int, frame: Any) -> None:
        if self.open:
            self.open = False
            raise KeyboardInterrupt
        self.pending = True

    def check(self) -> None:
        """Raise KeyboardInterrupt if one was held back."""
        if self.pending:
            self.pending = False
            raise KeyboardInterrupt

    @contextmanager
    def allowed(self) -> Iterator[None]:
        """Let an interrupt through in the block (one held back is raised at once)."""
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
        The trials it completed.
    simulated : int
        Settings it simulated (the others were copied from equal settings).
    stopped : str
        ``done`` or ``timeout`` (an interrupted worker raises KeyboardInterrupt); for a
        worker process that sent no report, ``interrupted`` or ``died``.
    exit : int or None
        A worker process's exit status (0 for the one in the calling process); None
        while it runs.
    """

    trials: list[int] = field(default_factory=list)
    simulated: int = 0
    stopped: str = ""
    exit: int | None = None


def run_worker(
    cfg: SweepConfig,
    spec: StorageSpec,
    study_name: str,
    index: int = 0,
    on_trial: Callable[[Study], object] | None = None,
    storage: BaseStorage | None = None,
) -> WorkerReport:
    """Run trials of ``study_name`` (``study.optimize``) until it holds the trials asked
    for, however many workers share it, or the timeout. An interrupted trial is failed
    and enqueued again with its settings.

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
    storage : optuna.storages.BaseStorage or None
        ``spec`` opened already (:func:`open_storage`; default: opened here).

    Returns
    -------
    WorkerReport
        What the worker did.
    """
    import optuna

    from vfgym.tuning._compass import CompassSampler

    # ERROR: an interrupted trial is reported by the sweep, not as Optuna's warning with a
    # traceback; a failing objective still raises.
    optuna.logging.set_verbosity(optuna.logging.ERROR)
    warnings.filterwarnings("ignore", category=optuna.exceptions.ExperimentalWarning)
    warnings.filterwarnings("ignore", message="Constraints have been set, but CmaEsSampler")
    rep = WorkerReport()
    prepare_model(cfg)
    scenarios = cfg.scenario_list()
    seed = None if cfg.seed is None else cfg.seed + index
    axis = cfg.axis
    me = worker_id()
    with DeferredInterrupt() as interrupts:
        if storage is None:
            storage = open_storage(spec, cfg.heartbeat, cfg.grace)
        sampler = make_sampler(cfg, seed, scenarios, storage)
        study = optuna.load_study(study_name=study_name, storage=storage, sampler=sampler)
        objective = Objective(scenarios, cfg.laws, str(cfg.objective), axis=axis,
                              aggregate=cfg.aggregate, cvar_alpha=cfg.cvar_alpha)  # fmt: skip
        objective.guard = interrupts.allowed
        evaluate(PAPER_SETTINGS, scenarios[:1], axis=axis)  # the kernel compiled first
        gate = _Budget(study, cfg, spec, interrupts)
        current: list[int] = []  # the trial in a simulation here
        planned = getattr(sampler, "planned", None)  # (the compass plans ahead)
        if planned is not None:  # as many as the trials after this one may ask for
            objective.ahead = lambda: planned()[: max(0, gate.budget - 1 - current[0])]
        ran: list[int] = []
        paused: list[int] = []  # optimize stopped here, to wait outside it (or an interrupt)

        def run_trial(trial: Trial) -> float | list[float]:
            if ran and on_trial is not None:
                on_trial(study)  # (the last trial has completed)
            if isinstance(sampler, CompassSampler) and sampler.storage is storage:
                # it records its generations through the study's own storage, which knows
                # the ids of the trials it made
                sampler.storage = trial.storage
            trial.set_user_attr(WORKER_ATTR, me)
            go = gate.wait(trial.number)
            if go is None:
                raise optuna.TrialPruned("a retried trial takes the last place")
            if not go:
                study.stop()
                raise optuna.TrialPruned("the study already holds the trials asked for")
            current[:] = [trial.number]
            values = objective(trial)
            current.clear()
            ran.append(trial.number)
            if interrupts.pending or gate.full(trial.number):
                paused.append(trial.number)
                study.stop()  # optimize returns once the trial is told
            return values

        deadline = None if cfg.timeout is None else time.monotonic() + cfg.timeout
        try:
            while gate.wait():
                left = None if deadline is None else deadline - time.monotonic()
                if left is not None and left <= 0:
                    break
                paused.clear()
                try:
                    study.optimize(run_trial, timeout=left)
                except optuna.exceptions.UpdateFinishedTrialError:
                    # Another worker took this one's trial as dead (its heartbeat late past
                    # the grace period) and retried it: go on with the next.
                    current.clear()
                    continue
                interrupts.check()
                if not paused:  # the timeout
                    break
            rep.stopped = "done" if gate.done() else "timeout"
        except KeyboardInterrupt:
            for n in current:
                _fail_and_retry(study, copy.deepcopy(study.get_trials(deepcopy=False)[n]))
            raise
        finally:
            objective.close()
            rep.simulated = objective.simulated
            if ran:
                trials = study.get_trials(deepcopy=False)
                complete = optuna.trial.TrialState.COMPLETE
                rep.trials = [n for n in ran if trials[n].state == complete]
                if on_trial is not None:
                    on_trial(study)
    return rep


def prepare_model(cfg: SweepConfig) -> None:
    """Start importing the compass's model beside the first trials (:func:`prepare`) of a
    sweep long enough to reach a model batch (its compass's budget spent); a shorter one
    imports it only if a batch comes."""
    from vfgym.tuning._compass import CompassOptions

    if cfg.sampler == "compass" and trial_budget(cfg) >= CompassOptions().compass_trials:
        prepare()


class _Budget:
    """The study's trial budget across workers (``MaxTrialsCallback`` counts after a trial,
    so several workers overshoot it): :meth:`wait` says whether a trial may run, waiting
    while the running ones could fill the budget, and meanwhile fails and retries dead
    workers' trials (``fail_stale_trials``, which ``optimize`` runs only when a trial
    starts; by process on this host, as a journal has no heartbeat and a worker killed
    before its first heartbeat leaves none; by age, a trial whose worker died before it
    began)."""

    def __init__(self, study: Study, cfg: SweepConfig, spec: StorageSpec, interrupts: Any) -> None:
        self.study, self.budget, self.every = study, trial_budget(cfg), cfg.heartbeat
        self.workers = cfg.workers  # (this command's; other commands on the study: rare)
        self.journal = spec.kind == "journal"
        self.interrupts = interrupts
        self.orphan_s = max(30.0, 6.0 * self.every)
        self.retry_s = max(5.0, 2.0 * self.every)  # a failed trial's retry is awaited this long
        self._due = 0.0
        # The trials made, and those completed, running or waiting, at the last read: no
        # read is needed while they leave room for every trial made since.
        self._last = (0, self.budget)

    def _trials(self) -> list[FrozenTrial]:
        import optuna

        trials = self.study.get_trials(deepcopy=False)
        fail, pruned = optuna.trial.TrialState.FAIL, optuna.trial.TrialState.PRUNED
        self._last = (len(trials), sum(t.state not in (fail, pruned) for t in trials))
        return trials

    def done(self) -> bool:
        """Whether the study holds the trials asked for."""
        import optuna

        complete = (optuna.trial.TrialState.COMPLETE,)
        return len(self.study.get_trials(deepcopy=False, states=complete)) >= self.budget

    def full(self, number: int) -> bool:
        """Whether, once trial ``number`` completes, the completed and running trials fill
        the budget: this worker's next trial would only wait, so it waits outside
        ``optimize``."""
        import optuna

        made_then, busy = self._last
        if busy + (number + 1 - made_then) + (self.workers - 1) < self.budget:
            return False
        state = optuna.trial.TrialState
        taken = [t.state == state.COMPLETE or t.state == state.RUNNING for t in self._trials()]
        return sum(taken) >= self.budget  # (this trial, running, counted once)

    def wait(self, number: int | None = None, poll_s: float = 0.2) -> bool | None:
        """Wait until a trial may run: False once the study holds its trials, True when the
        completed and running trials (numbered below ``number``) are fewer than asked,
        None when trial ``number`` must give its place to a dead worker's retried one."""
        import optuna

        state = optuna.trial.TrialState
        self._recover()
        made_then, busy = self._last
        known = number if number is not None else made_then + self.workers
        if busy + (known - made_then) < self.budget:
            return True
        while True:
            trials = self._trials()
            n = sum(t.state == state.COMPLETE for t in trials)
            if n >= self.budget:
                return False
            lower = trials if number is None else trials[:number]
            taken = n + sum(t.state == state.RUNNING for t in lower)
            due = self._retries_due(trials)
            if number is None:
                taken += due  # a retry about to be enqueued: asked for next, it will run
            elif RETRY not in trials[number].system_attrs:
                waiting = sum(t.state == state.WAITING and RETRY in t.system_attrs for t in trials)
                if taken < self.budget <= taken + waiting + due:
                    return None  # a dead worker's retried trial takes the place first
            if taken < self.budget:
                return True
            with self.interrupts.allowed():
                time.sleep(poll_s)
            self._recover()

    def _retries_due(self, trials: list[FrozenTrial]) -> int:
        """Trials just failed whose retry is not enqueued yet: Optuna fails a dead worker's
        trial and enqueues its retry in two writes; a worker reading between them must not
        take the retry's place."""
        import optuna

        fail = optuna.trial.TrialState.FAIL
        retried = {
            t.system_attrs["retry_history"][-1]
            for t in trials
            if t.system_attrs.get("retry_history")
        }
        now = datetime.datetime.now()
        return sum(
            t.state == fail
            and t.number not in retried
            and len(t.system_attrs.get("retry_history", [])) < MAX_RETRY
            and t.datetime_complete is not None
            and (now - t.datetime_complete).total_seconds() < self.retry_s
            for t in trials
        )

    def _recover(self) -> None:
        import optuna

        if time.monotonic() < self._due:
            return
        self._due = time.monotonic() + self.every
        if not self.journal:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", optuna.exceptions.ExperimentalWarning)
                optuna.storages.fail_stale_trials(self.study)
        now = datetime.datetime.now()
        running = (optuna.trial.TrialState.RUNNING,)
        for t in self.study.get_trials(deepcopy=False, states=running):
            worker = t.user_attrs.get(WORKER_ATTR)
            age = (now - t.datetime_start).total_seconds() if t.datetime_start else 0.0
            if worker is None:  # its worker died before it began (Optuna: no heartbeat)
                dead = age > self.orphan_s
            else:  # a dead process on this host: a journal has no heartbeat, and an RDB's
                # misses a worker killed before its first one (the trial stays running)
                # (a retry holds its dead worker's name until its new worker writes its own)
                dead = age > self.every and _worker_alive(worker) is False
            if dead:
                _fail_and_retry(self.study, copy.deepcopy(t))


def _fail_and_retry(study: Study, trial: FrozenTrial) -> bool:
    """Fail a running trial (or take one failed) and enqueue it again; False if it had
    completed, or another worker failed it first (the storage lets one only)."""
    import optuna

    state = optuna.trial.TrialState
    if trial.state == state.RUNNING:
        try:
            study.tell(trial.number, state=state.FAIL)
        except (RuntimeError, ValueError, optuna.exceptions.UpdateFinishedTrialError):
            return False
    elif trial.state != state.FAIL:
        return False
    retry(study, trial)
    return True


def worker_id() -> str:
    """``host/pid/start-time`` of this process (the start time guards against pid reuse)."""
    me = psutil.Process()
    return f"{socket.gethostname()}/{me.pid}/{me.create_time()!r}"


def _worker_alive(worker: str) -> bool | None:
    """Whether the process that ran a trial is alive; None when it is on another host."""
    host, _, rest = worker.partition("/")
    pid, _, start = rest.partition("/")
    if host != socket.gethostname() or not pid.isdigit():
        return None
    try:
        p = psutil.Process(int(pid))
        return p.status() != psutil.STATUS_ZOMBIE and repr(p.create_time()) == start
    except psutil.NoSuchProcess:
        return False


class Worker(NamedTuple):
    """A worker process (:func:`spawn_workers`) and the pipe its :class:`WorkerReport` comes
    back through."""

    process: BaseProcess
    report: Connection


def spawn_workers(cfg: SweepConfig, spec: StorageSpec, study: str, n: int) -> list[Worker]:
    """Start ``n`` worker processes on the study: ``multiprocessing``'s spawn, a fresh
    interpreter each, the job passed to it (the storage's password on no command line)."""
    ctx = multiprocessing.get_context("spawn")
    workers = []
    for i in range(n):
        report, send = ctx.Pipe(duplex=False)
        process = ctx.Process(target=_worker_process, args=(cfg, spec, study, i, send))
        process.start()
        send.close()
        workers.append(Worker(process, report))
    return workers


def run_processes(
    cfg: SweepConfig, spec: StorageSpec, study: str, poll: Callable[[], object]
) -> list[WorkerReport]:
    """Run ``cfg.workers`` worker processes on the study and follow it until they end
    (``poll`` called twice a second). On Ctrl-C they finish or give back their trial and
    the interrupt is raised again once they have ended.

    Parameters
    ----------
    cfg : SweepConfig
        The sweep's configuration.
    spec : StorageSpec
        Where the study lives.
    study : str
        The study.
    poll : callable
        Called while the workers run.

    Returns
    -------
    list of WorkerReport
        Each worker's report with its exit status.
    """
    workers = spawn_workers(cfg, spec, study, cfg.workers)
    reports: list[WorkerReport | None] = [None] * len(workers)

    def collect() -> None:  # (read as they come: a report may exceed a pipe's buffer)
        for i, w in enumerate(workers):
            if reports[i] is None and w.report.poll():
                try:
                    reports[i] = w.report.recv()
                except (EOFError, OSError):  # died before sending it
                    reports[i] = WorkerReport()

    interrupted = False
    try:
        # Ctrl-C is let through in the wait only: ``poll`` reads the study through Optuna's
        # storage, where an interrupt could land in a finaliser and be lost
        with DeferredInterrupt() as interrupts:
            while any(w.process.is_alive() for w in workers):
                poll()
                collect()
                with interrupts.allowed():
                    time.sleep(0.5)
    except KeyboardInterrupt:
        interrupted = True
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        _stop(workers)
    collect()
    out = []
    for w, rep in zip(workers, reports, strict=True):
        code = w.process.exitcode
        if rep is None or not rep.stopped:
            rep = WorkerReport(stopped="interrupted" if code == 130 else "died")
        out.append(replace(rep, exit=code))
    if interrupted:
        raise KeyboardInterrupt
    return out


def _stop(workers: list[Worker]) -> None:
    """After a Ctrl-C: give the workers 2 s to finish their trial, then interrupt the
    ones left, then kill any that has not ended a minute later."""
    deadline = time.monotonic() + 2.0
    while time.monotonic() < deadline and any(w.process.is_alive() for w in workers):
        time.sleep(0.05)
    for w in workers:
        if w.process.is_alive() and w.process.pid is not None:
            os.kill(w.process.pid, signal.SIGINT)
    for w in workers:
        w.process.join(timeout=60)
        if w.process.is_alive():
            w.process.kill()
            w.process.join()


def _worker_process(cfg: SweepConfig, spec: StorageSpec, study: str, index: int,
                    send: Connection) -> None:  # fmt: skip
    """A worker process: its :class:`WorkerReport` sent back; exit status 130 if
    interrupted."""
    warnings.simplefilter("ignore", AxisNote)  # the parent process says it once
    try:
        send.send(run_worker(cfg, spec, study, index))
    except KeyboardInterrupt:
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        sys.exit(130)
