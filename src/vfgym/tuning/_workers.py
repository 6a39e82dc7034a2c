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
from typing import TYPE_CHECKING, Any

from vfgym.moves.axis import axis_kwargs
from vfgym.params import PAPER_SETTINGS, Settings
from vfgym.scoring import evaluate
from vfgym.tuning._batch import (
    Claimed,
    Heartbeats,
    claim,
    give_back,
    once,
    one_write,
    run_batch,
    run_planned,
)
from vfgym.tuning._config import SweepConfig
from vfgym.tuning._objective import Objective
from vfgym.tuning._recovery import (
    RetryStale,
    counts,
    recover,
)
from vfgym.tuning._storage import StorageSpec, _claim_lock, open_storage
from vfgym.tuning._stored import study_format
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

    @contextmanager
    def held(self) -> Iterator[None]:
        """Hold interrupts back here, inside an :meth:`allowed` block too (work on this
        thread while a simulation runs on another: writes that must not be cut short).

        Yields
        ------
        None
            Inside the block, SIGINT is held back as outside :meth:`allowed`.
        """
        was, self.open = self.open, False
        try:
            yield
        finally:
            self.open = was


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
    then tells the study each result. A sampler that plans its trials (the compass) has
    its batch planned under the lock and created while it is simulated, the lock held
    until the trials exist (:func:`vfgym.tuning._batch.run_planned`). Dead workers'
    trials are looked for at most once a heartbeat. SIGINT is held back (:class:`DeferredInterrupt`)
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
        objective.trial_format = study_format(study)
        # First call compiles/loads the kernel before any trial is claimed.
        evaluate(PAPER_SETTINGS, scenarios[:1], **on_axis)
        lock = _claim_lock(spec, study_name)
        beats = Heartbeats(storage)
        study_id = storage.get_study_id_from_name(study_name)
        maker = one_write(sampler, storage, study_id, objective.trial_format)
        objective.guard = interrupts.allowed
        claimed: list[Claimed] = []
        recovery_due = 0.0
        try:
            while True:
                interrupts.check()
                planned: list[tuple[Any, Settings]] = []
                lock.acquire()
                try:
                    if time.monotonic() >= recovery_due:
                        # At most once a heartbeat: no trial goes stale faster.
                        rep.recovered += recover(study, storage, spec, orphan_s)
                        recovery_due = time.monotonic() + cfg.heartbeat
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
                    if maker is not None and n["waiting"] == 0:
                        # Created while simulated (the lock goes once they are made).
                        planned = [maker.plan(study, i == 0, objective.laws) for i in range(take)]
                    else:
                        claimed = claim(
                            study, objective, take, beats, maker, n["waiting"], study_id
                        )
                finally:
                    if not planned:
                        lock.release()
                if planned and maker is not None:
                    claimed = []
                    release = once(lock.release)
                    run_planned(
                        study, objective, maker, beats, planned, claimed, release, interrupts.held
                    )
                elif not claimed:
                    with interrupts.allowed():
                        time.sleep(poll_s)
                    continue
                else:
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
