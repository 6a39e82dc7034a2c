"""Which worker runs a trial, whether it is still alive, and how the trials of dead
workers are failed and enqueued again with the settings they had drawn."""

from __future__ import annotations

import copy
import datetime as _dt
import os
import socket
import warnings
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from optuna import Study
    from optuna.storages import BaseStorage
    from optuna.trial import FrozenTrial, TrialState

    from vfgym.tuning._storage import StorageSpec


WORKER_ATTR = "worker"


def _worker_id() -> str:
    """host/pid/start-time of this process (the start time guards against pid reuse);
    read once per process (a forked child has another pid, so reads its own)."""
    pid = os.getpid()
    if pid not in _WORKER_IDS:
        _WORKER_IDS[pid] = f"{socket.gethostname()}/{pid}/{_proc_start(pid)}"
    return _WORKER_IDS[pid]


_WORKER_IDS: dict[int, str] = {}


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


def counts(study: Study) -> dict[str, int]:
    """Trials of the study by state.

    Parameters
    ----------
    study : optuna.Study
        The study.

    Returns
    -------
    dict of str to int
        Counts of ``complete``, ``running``, ``waiting``, ``fail`` and ``pruned`` trials.
    """
    out = {"complete": 0, "running": 0, "waiting": 0, "fail": 0, "pruned": 0}
    for t in study.get_trials(deepcopy=False):
        out[t.state.name.lower()] += 1
    return out


def recover(study: Study, storage: BaseStorage, spec: StorageSpec, orphan_s: float) -> list[int]:
    """Mark the trials of dead workers failed and enqueue them again (same settings);
    returns their numbers.

    RDB storages: Optuna's heartbeat (``fail_stale_trials``). Journal: a running trial
    whose worker process on this host is gone. Any storage: a running trial that never
    reached its objective (no worker recorded) for ``orphan_s`` seconds."""

    import optuna

    failed: list[int] = []
    cb = getattr(storage, "heartbeat_stale_trial_callback", None)
    if isinstance(cb, RetryStale):
        n0 = len(cb.failed)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", optuna.exceptions.ExperimentalWarning)
            optuna.storages.fail_stale_trials(study)
        failed += cb.failed[n0:]
    now = _dt.datetime.now()
    for t in study.get_trials(deepcopy=False, states=_running()):
        worker = t.user_attrs.get(WORKER_ATTR)
        if worker is None:
            start = t.datetime_start
            dead = start is not None and (now - start).total_seconds() > orphan_s
        else:
            dead = spec.kind == "journal" and _worker_alive(worker) is False
        if dead and _fail_and_retry(study, copy.deepcopy(t)):
            failed.append(t.number)
    return failed


class RetryStale:
    """Heartbeat-stale trial callback: enqueue the trial again (Optuna's
    ``RetryHeartbeatStaleTrialCallback``, at most :data:`MAX_RETRY` times) and note it."""

    def __init__(self) -> None:
        self.failed: list[int] = []

    def __call__(self, study: Study, trial: FrozenTrial) -> None:
        self.failed.append(trial.number)
        _retry(study, trial)


def _running() -> tuple[TrialState]:
    import optuna

    return (optuna.trial.TrialState.RUNNING,)


def _fail_and_retry(study: Study, trial: FrozenTrial) -> bool:
    """Mark a running trial failed and enqueue its settings again; False if it had ended."""
    import optuna

    try:
        study.tell(trial.number, state=optuna.trial.TrialState.FAIL)
    except (RuntimeError, ValueError, optuna.exceptions.UpdateFinishedTrialError):
        return False
    _retry(study, trial)
    return True


def _retry(study: Study, trial: FrozenTrial) -> None:
    import optuna

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", optuna.exceptions.ExperimentalWarning)
        optuna.storages.RetryHeartbeatStaleTrialCallback(max_retry=MAX_RETRY)(study, trial)


MAX_RETRY = 3
"""A trial whose worker died is enqueued again at most this many times."""
