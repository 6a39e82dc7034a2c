"""Workers on a study, run as Optuna runs them: each worker is ``study.optimize`` in its
own process, on one machine or on many sharing one RDB storage.

Optuna does the rest: the heartbeat of a running trial, failing the trials of dead
workers and enqueueing them again with their settings (RDB storages, :mod:`._storage`),
the timeout, the trials' bookkeeping. What is kept here, each for what Optuna does not do:
the trial budget of the whole study (``MaxTrialsCallback`` counts after a trial, so
several workers would overshoot it), the dead workers of a journal (its storage has no
heartbeat) and of a trial killed before its first heartbeat (Optuna never takes it as
stale), and a Ctrl-C that only lands inside a simulation (:class:`DeferredInterrupt`).
"""

from __future__ import annotations

import copy
import datetime
import json
import os
import signal
import socket
import subprocess
import sys
import threading
import time
import warnings
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import asdict, dataclass, field
from typing import TYPE_CHECKING, Any

from vfgym.moves.axis import axis_kwargs
from vfgym.params import PAPER_SETTINGS
from vfgym.scoring import evaluate
from vfgym.tuning._config import SweepConfig
from vfgym.tuning._objective import Objective
from vfgym.tuning._storage import RetryStale, StorageSpec, open_storage, retry_once
from vfgym.tuning._study import make_sampler, trial_budget

if TYPE_CHECKING:
    from optuna import Study, Trial
    from optuna.trial import FrozenTrial

RETRY = "failed_trial"
"""System attribute of a retried trial (Optuna's ``RetryHeartbeatStaleTrialCallback``)."""

WORKER_ATTR = "worker"
"""User attribute of a trial: ``host/pid/start-time`` of the process that ran it."""


class DeferredInterrupt:
    """SIGINT raises KeyboardInterrupt only inside :meth:`allowed` blocks (a trial's
    simulation, a wait); anywhere else it is held until the next such block, a trial's
    end or the end of the ``with``: kept because Optuna's ``optimize`` lets a Ctrl-C land
    anywhere, inside a storage write too.

    The decision is taken by the Python-level handler, which runs in the main thread
    between bytecodes; off the main thread the process's handler is left as it is.

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
        Numbers of the trials it completed.
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
) -> WorkerReport:
    """Run trials of ``study_name`` (``study.optimize``) until it holds the trials asked
    for, or the timeout.

    A worker starts a trial only while the completed and running trials number fewer than
    asked, and waits while the others run the last ones, so a study ends with exactly the
    trials asked for however many workers share it (two workers that start one at the same
    moment: the later-numbered trial waits, and is pruned if the budget fills). SIGINT is
    held back (:class:`DeferredInterrupt`) except inside a simulation and while waiting;
    an interrupted trial is failed (by Optuna) and enqueued again with its settings.

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
    seed = None if cfg.seed is None else cfg.seed + index
    with DeferredInterrupt() as interrupts:
        storage = open_storage(spec, cfg.heartbeat, cfg.grace)
        sampler = make_sampler(cfg, seed, scenarios, storage)
        study = optuna.load_study(study_name=study_name, storage=storage, sampler=sampler)
        axis = cfg.load_axis()
        on_axis = axis_kwargs(axis)
        objective = Objective(
            scenarios,
            cfg.laws,
            str(cfg.objective),
            **on_axis,  # type: ignore[arg-type]
            aggregate=cfg.aggregate,
            cvar_alpha=cfg.cvar_alpha,
            plants=() if axis is None else axis.design_plants(),
        )
        objective.guard = interrupts.allowed
        # First call compiles/loads the kernel before any trial is started.
        evaluate(PAPER_SETTINGS, scenarios[:1], **on_axis)
        gate = _Budget(study, cfg, spec, interrupts)
        current: list[int] = []

        def run_trial(trial: Trial) -> float | list[float]:
            trial.set_user_attr(WORKER_ATTR, worker_id())
            go = gate.wait(trial.number)
            if go is None:
                raise optuna.TrialPruned("a retried trial takes the last place")
            if not go:
                study.stop()
                raise optuna.TrialPruned("the study already holds the trials asked for")
            current[:] = [trial.number]
            return objective(trial)

        def after(st: Study, trial: FrozenTrial) -> None:
            current.clear()
            if trial.state == optuna.trial.TrialState.COMPLETE:
                rep.trials.append(trial.number)
            if on_trial is not None:
                on_trial(st)
            if not gate.wait(made=trial.number + 1):
                st.stop()
            interrupts.check()

        try:
            while gate.wait():
                try:
                    study.optimize(run_trial, timeout=cfg.timeout, callbacks=[after])
                    break
                except optuna.exceptions.UpdateFinishedTrialError:
                    # Another worker took this one's trial as dead (its heartbeat late past
                    # the grace period) and retried it: go on with the next.
                    current.clear()
            rep.stopped = "done" if gate.done() else "timeout"
        except KeyboardInterrupt:
            rep.stopped = "interrupted"
            _retry_interrupted(study, current, spec.path)
            raise
        finally:
            rep.simulated = objective.simulated
            cb = getattr(storage, "get_heartbeat_stale_trial_callback", lambda: None)()
            noted = cb.failed if isinstance(cb, RetryStale) else []
            rep.recovered = sorted(set(gate.recovered) | set(noted))
    return rep


class _Budget:
    """The study's trial budget across workers: :meth:`wait` says whether a trial may run
    (waiting, interrupts allowed, while the running ones could fill the budget), looking
    for dead workers' trials meanwhile (Optuna's ``fail_stale_trials`` on RDB storages,
    which ``optimize`` only runs when a trial starts; on a journal, by process; and a
    trial whose worker died before writing its name, which has no heartbeat either)."""

    def __init__(self, study: Study, cfg: SweepConfig, spec: StorageSpec, interrupts: Any) -> None:
        self.study, self.budget, self.every = study, trial_budget(cfg), cfg.heartbeat
        self.workers = cfg.workers  # (this command's; other commands on the study: rare)
        self.journal, self.lock = spec.kind == "journal", spec.path
        self.interrupts = interrupts
        self.recovered: list[int] = []
        self.orphan_s = max(30.0, 6.0 * self.every)
        self._due = 0.0
        # trials made, and those completed, running or waiting, at the last read
        self._last = (0, self.budget)

    def done(self) -> bool:
        """Whether the study holds the trials asked for."""
        import optuna

        complete = (optuna.trial.TrialState.COMPLETE,)
        return len(self.study.get_trials(deepcopy=False, states=complete)) >= self.budget

    def wait(self, number: int | None = None, made: int = 0, poll_s: float = 0.2) -> bool | None:
        """Wait until a trial may run: False once the study holds its trials, else True
        when the completed and running trials (those numbered below ``number``: the
        trial's own is running) are fewer than asked; None when trial ``number`` must give
        its place to a dead worker's retried trial (waiting, it runs next). No read is
        needed while the last one left room for every trial made since (``number``, else
        ``made``, trials known to exist), each of which may be running, as may every
        trial then waiting."""
        import optuna

        state = optuna.trial.TrialState
        self._recover()
        made_then, busy = self._last
        # Between trials, room also for a trial each other worker may have made since.
        known = number if number is not None else made + self.workers
        if busy + (known - made_then) < self.budget:
            return True
        while True:
            trials = self.study.get_trials(deepcopy=False)
            n = sum(t.state == state.COMPLETE for t in trials)
            waiting = sum(t.state == state.WAITING for t in trials)
            running = sum(t.state == state.RUNNING for t in trials)
            self._last = (len(trials), n + running + waiting)
            if n >= self.budget:
                return False
            lower = trials if number is None else trials[:number]
            taken = n + sum(t.state == state.RUNNING for t in lower)
            if number is not None and taken < self.budget:
                retries = [
                    t for t in trials if t.state == state.WAITING and RETRY in t.system_attrs
                ]
                if taken + len(retries) >= self.budget:
                    return None  # a dead worker's retried trial takes the place first
            if taken < self.budget:
                return True
            with self.interrupts.allowed():
                time.sleep(poll_s)
            self._recover()

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
            else:  # (a retry holds its dead worker's name until its new worker writes its own)
                dead = self.journal and age > self.every and _worker_alive(worker) is False
            if dead and _fail_and_retry(self.study, copy.deepcopy(t), self.lock):
                self.recovered.append(t.number)


def _retry_interrupted(study: Study, current: list[int], lock: str | None) -> None:
    """Enqueue again the trial an interrupt failed (its settings kept)."""
    import optuna

    for number in current:
        t = copy.deepcopy(study.get_trials(deepcopy=False)[number])
        if t.state == optuna.trial.TrialState.FAIL:
            retry_once(study, t, lock)
        elif t.state == optuna.trial.TrialState.RUNNING:
            _fail_and_retry(study, t, lock)


def _fail_and_retry(study: Study, trial: FrozenTrial, lock: str | None) -> bool:
    """Mark a running trial failed and enqueue its settings again; False if it had ended."""
    import optuna

    try:
        study.tell(trial.number, state=optuna.trial.TrialState.FAIL)
    except (RuntimeError, ValueError, optuna.exceptions.UpdateFinishedTrialError):
        return False
    return retry_once(study, trial, lock)


def worker_id() -> str:
    """``host/pid/start-time`` of this process (the start time guards against pid reuse).

    Returns
    -------
    str
        What :data:`WORKER_ATTR` records.
    """
    pid = os.getpid()
    return f"{socket.gethostname()}/{pid}/{_proc_start(pid)}"


def _proc_start(pid: int) -> str:
    try:
        with open(f"/proc/{pid}/stat", encoding="ascii", errors="replace") as fh:
            rest = fh.read().rsplit(")", 1)[1].split()
        return "Z" if rest[0] in ("Z", "X") else rest[19]
    except (OSError, IndexError):
        return ""


def _worker_alive(worker: str) -> bool | None:
    """Whether the process that ran a trial is alive; None when it is on another host."""
    host, _, rest = worker.partition("/")
    pid_s, _, start = rest.partition("/")
    if host != socket.gethostname() or not pid_s.isdigit():
        return None
    pid = int(pid_s)
    if os.path.isdir("/proc"):
        now = _proc_start(pid)
        return bool(now) and now != "Z" and (not start or now == start)
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


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
