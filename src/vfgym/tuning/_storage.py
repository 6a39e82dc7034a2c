"""Where a study lives: SQLite in the run folder (default), Optuna's JournalStorage on a
file, or PostgreSQL shared by workers on many machines.

RDB storages run Optuna's heartbeat: ``fail_stale_trials`` fails the trial of a worker
that stopped beating and ``RetryHeartbeatStaleTrialCallback`` enqueues it again. What is
added, each for what Optuna does not do, is said where it lives.
"""

from __future__ import annotations

import fcntl
import functools
import os
import random
import re
import time
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from optuna import Study
    from optuna.storages import BaseStorage, RDBStorage
    from optuna.trial import FrozenTrial

STORAGE_HELP = (
    "sqlite, journal, sqlite:///FILE, journal:FILE or postgresql://USER:PASS@HOST:PORT/DB?OPTIONS"
)


@dataclass(frozen=True)
class StorageSpec:
    """Where a study lives (:func:`resolve_storage`).

    Parameters
    ----------
    kind : str
        ``sqlite``, ``journal`` or ``postgresql``.
    url : str
        The URL Optuna opens (the file path for a journal).
    path : str or None
        The storage's file, if any.
    """

    kind: str
    url: str
    path: str | None = None

    @property
    def display(self) -> str:
        """The URL without its password, for files and messages."""
        return mask_url(self.url) if self.kind == "postgresql" else self.url


def mask_url(url: str) -> str:
    """``url`` with any password as ``***`` (in a text SQLAlchemy cannot read, anything
    between ``user:`` and ``@``)."""
    from sqlalchemy.engine import make_url

    try:
        parsed = make_url(url)
        return url if parsed.password is None else parsed.render_as_string(hide_password=True)
    except Exception:  # not a URL SQLAlchemy reads (ArgumentError, a bad port, ...)
        return re.sub(r"^([^:/]*://[^:/@]*):[^@]*@", r"\1:***@", url)


def _file_spec(kind: str, path: Path) -> StorageSpec:
    p = path.resolve()
    return StorageSpec(kind, f"sqlite:///{p}" if kind == "sqlite" else str(p), str(p))


def resolve_storage(text: str, run_dir: Path) -> StorageSpec:
    """The storage named by ``--storage``: any SQLite file URL or PostgreSQL URL
    SQLAlchemy reads, with a synchronous driver.

    Parameters
    ----------
    text : str
        ``sqlite``, ``journal``, ``sqlite:///FILE``, ``journal:FILE`` or a PostgreSQL URL
        ``postgresql[+DRIVER]://[USER[:PASS]@][HOST[:PORT]]/DB[?OPTIONS]``.
    run_dir : pathlib.Path
        The run folder, where ``sqlite`` and ``journal`` put their file.

    Returns
    -------
    StorageSpec
        The storage, with absolute file paths.

    Raises
    ------
    ValueError
        If the text names no storage, another database, an in-memory SQLite one, or a
        driver vfgym cannot use (the password masked).
    """
    from sqlalchemy.engine import make_url

    t = str(text).strip()
    if t == "sqlite":
        return _file_spec("sqlite", run_dir / "study.db")
    if t == "journal":
        return _file_spec("journal", run_dir / "journal.log")
    if t.startswith("journal:"):
        rest = t[len("journal:") :]
        rest = rest[2:] if rest.startswith("//") else rest
        if not rest or rest.endswith("/"):
            raise ValueError(f"storage={text!r} is not allowed: give journal:FILE")
        return _file_spec("journal", Path(rest).expanduser())
    head = f"storage={mask_url(t)!r} is not allowed"
    try:
        url = make_url(t)
        backend = url.get_backend_name()
        port = url.port
    except Exception:  # sqlalchemy's ArgumentError; a port that is not a number
        raise ValueError(f"{head}: give {STORAGE_HELP}") from None
    if backend == "postgres":
        raise ValueError(f"{head}: SQLAlchemy names it postgresql://, not postgres://")
    try:
        dialect = url.get_dialect() if backend in ("sqlite", "postgresql") else None
    except Exception:  # NoSuchModuleError
        raise ValueError(
            f"{head}: SQLAlchemy has no {backend} driver {url.get_driver_name()!r}"
        ) from None
    if dialect is None:
        raise ValueError(
            f"{head}: vfgym keeps studies in SQLite or PostgreSQL; give {STORAGE_HELP}"
        )
    if getattr(dialect, "is_async", False):
        raise ValueError(
            f"{head}: driver {url.get_driver_name()} is asynchronous; give a synchronous one "
            "(postgresql://, postgresql+psycopg:// or postgresql+psycopg2://)"
        )
    if backend == "sqlite":
        if url.database in (None, "", ":memory:"):
            raise ValueError(
                f"{head}: an in-memory database is lost when the sweep ends; give sqlite:///FILE"
            )
        path = Path(url.database).expanduser().resolve()
        url = url.set(database=str(path))
        return StorageSpec("sqlite", url.render_as_string(hide_password=False), str(path))
    if port is not None and not 1 <= port <= 65535:
        raise ValueError(
            f"{head}: port {port} is out of range: allowed whole numbers in [1, 65535]"
        )
    return StorageSpec("postgresql", url.render_as_string(hide_password=False))


def find_storage(text: str, run_dir: Path) -> StorageSpec:
    """The storage of a sweep's run folder, its file looked for in the folder if no longer
    where recorded (the folder was moved).

    Parameters
    ----------
    text : str
        What the run folder's ``config.yaml`` recorded (:attr:`StorageSpec.display`), or
        what ``--storage`` names.
    run_dir : pathlib.Path
        The run folder.

    Returns
    -------
    StorageSpec
        The storage, its file found.

    Raises
    ------
    ValueError
        Naming ``storage``, for a masked password, an unknown URL or a missing file.
    """
    t = str(text).strip()
    if "***" in t:
        raise ValueError(f"storage={t!r}: the password is masked; give the storage URL again")
    known = t in ("sqlite", "journal") or t.startswith(("journal:", "sqlite:")) or "://" in t
    spec = resolve_storage(t if known else f"journal:{t}", run_dir)  # a journal shows as its path
    if spec.path is None or Path(spec.path).is_file():
        return spec
    moved = run_dir / ("study.db" if spec.kind == "sqlite" else Path(spec.path).name)
    if not moved.is_file():
        raise ValueError(f"storage={t!r}: no {spec.kind} file {spec.path} (nor {moved})")
    return _file_spec(spec.kind, moved)


def open_storage(spec: StorageSpec, heartbeat: int = 10, grace: int | None = None) -> BaseStorage:
    """The Optuna storage for ``spec``: RDB with the heartbeat and retry of stale trials,
    or JournalStorage.

    Parameters
    ----------
    spec : StorageSpec
        The storage.
    heartbeat : int
        Seconds between a running trial's heartbeats (RDB).
    grace : int or None
        Seconds without a heartbeat before a trial is taken as dead (default twice the
        heartbeat).

    Returns
    -------
    optuna.storages.BaseStorage
        The opened storage.

    Raises
    ------
    ValueError
        Naming ``storage``, if it cannot be opened or its database driver is missing.
    """
    import optuna

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", optuna.exceptions.ExperimentalWarning)
        try:
            if spec.kind == "journal":
                from optuna.storages.journal import JournalFileBackend, JournalStorage

                Path(spec.url).parent.mkdir(parents=True, exist_ok=True)
                return JournalStorage(JournalFileBackend(spec.url, _Flock(spec.url + ".flock")))  # type: ignore[arg-type]
            if spec.path:
                Path(spec.path).parent.mkdir(parents=True, exist_ok=True)
            storage = _rdb(spec, heartbeat, grace)
            if spec.kind == "sqlite":
                _sqlite_wal(storage)
            return storage
        except ImportError as exc:
            if spec.kind != "postgresql":
                raise
            raise ValueError(
                f"storage={spec.display!r} needs a database driver: pip install "
                f"'vfgym[postgres]' ({exc})"
            ) from None
        except Exception as exc:  # sqlalchemy's OperationalError, ArgumentError, ...
            first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
            raise ValueError(f"storage={spec.display!r} cannot be opened: {first}") from None


def _rdb(spec: StorageSpec, heartbeat: int, grace: int | None, tries: int = 8) -> RDBStorage:
    """Optuna's RDB storage, tried again when another process creating the same new
    database's tables makes it fail: Optuna's table creation is not safe against that
    ("table studies already exists"); a later try finds them made."""
    import optuna
    import sqlalchemy

    kw: dict[str, Any] = (
        {"connect_args": {"timeout": 600}}
        if spec.kind == "sqlite"
        else {"pool_pre_ping": True, "pool_size": 2, "max_overflow": 2}
    )

    def rdb() -> RDBStorage:
        common: dict[str, Any] = {
            "engine_kwargs": kw,
            "heartbeat_interval": heartbeat,
            "grace_period": grace or 2 * heartbeat,
            "heartbeat_stale_trial_callback": retry,
        }
        if spec.kind == "sqlite" and spec.path:
            return _sqlite_storage()(spec.url, spec.path + ".pop", **common)
        return optuna.storages.RDBStorage(spec.url, **common)

    for attempt in range(tries - 1):
        try:
            return rdb()
        except (sqlalchemy.exc.SQLAlchemyError, optuna.exceptions.StorageInternalError):
            time.sleep(random.uniform(0.05, 0.25) * (attempt + 1))
    return rdb()


MAX_RETRY = 3
"""A trial whose worker died is enqueued again at most this many times."""


def retry(study: Study, trial: FrozenTrial) -> None:
    """Optuna's ``RetryHeartbeatStaleTrialCallback``: the failed trial enqueued again with its
    settings. Each storage lets one process only fail a running trial (PostgreSQL's row
    lock, the journal's order, the SQLite file's ``flock`` below), so it is retried once."""
    import optuna

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", optuna.exceptions.ExperimentalWarning)
        callback = optuna.storages.RetryHeartbeatStaleTrialCallback(max_retry=MAX_RETRY)
    callback(study, trial)


class _Flock:
    """An ``flock`` on the file ``path``, which the kernel drops when its holder dies:
    Optuna's journal file locks outlive a holder killed while writing, stalling the others
    for a grace period. Every process writing the journal must use it."""

    def __init__(self, path: str) -> None:
        self._path = path
        self._fd: int | None = None

    def acquire(self) -> bool:
        fd = os.open(self._path, os.O_RDWR | os.O_CREAT, 0o644)
        fcntl.flock(fd, fcntl.LOCK_EX)
        self._fd = fd
        return True

    def release(self) -> None:
        if self._fd is not None:
            os.close(self._fd)  # (closing the file drops the lock)
            self._fd = None

    def __enter__(self) -> None:
        self.acquire()

    def __exit__(self, *exc: object) -> None:
        self.release()


def _sqlite_wal(storage: RDBStorage) -> None:
    """Put the SQLite file in write-ahead-log mode with ``synchronous=NORMAL``: readers never
    wait for a writer (a worker frozen mid-write blocks none), and a commit needs no fsync
    (a process's crash loses nothing committed; a power cut may lose the last commits)."""
    import sqlalchemy

    def on_connect(dbapi_conn: Any, _record: Any) -> None:
        dbapi_conn.execute("PRAGMA synchronous=NORMAL")

    sqlalchemy.event.listen(storage.engine, "connect", on_connect)
    storage.engine.dispose()  # pooled connections opened before the listener
    with storage.engine.connect() as conn:
        if str(conn.exec_driver_sql("PRAGMA journal_mode").scalar()).lower() != "wal":
            conn.exec_driver_sql("PRAGMA journal_mode=WAL")


@functools.cache
def _sqlite_storage() -> Callable[..., RDBStorage]:
    """Optuna's RDB storage for a SQLite file, each change of a trial's state made atomic:
    SQLite has no ``SELECT ... FOR UPDATE``, so Optuna's read of a trial's state and its
    write of the next one let two workers both pop the same waiting trial
    (optuna/optuna#4002; the later one then failed with "Cannot tell a COMPLETE trial"), or
    both fail the same stale one and retry it twice. That read and write run under an
    ``flock`` of the file's ``.pop`` (the kernel drops it when its holder dies); readers
    are not held up."""
    import optuna

    class SQLiteStorage(optuna.storages.RDBStorage):
        def __init__(self, url: str, pop_lock: str, **kw: Any) -> None:
            self.pop_lock = pop_lock
            super().__init__(url, **kw)

        def set_trial_state_values(
            self, trial_id: int, state: Any, values: Sequence[float] | None = None
        ) -> bool:
            with _Flock(self.pop_lock):
                return super().set_trial_state_values(trial_id, state, values)

    return SQLiteStorage
