"""Where a study lives: SQLite in the run folder (default), Optuna's JournalStorage on a
file, or PostgreSQL shared by workers on many machines; and the study-wide claim lock.

A SQLite file is kept in write-ahead-log mode, so no reader waits on a worker frozen or
killed mid-write; journal appends take an ``flock`` the kernel drops when its holder
dies. Each worker claims a trial under a study-wide lock (a file lock beside a SQLite or
journal file, a PostgreSQL advisory lock on a server).
"""

from __future__ import annotations

import hashlib
import os
import re
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from vfgym.tuning._recovery import RetryStale

if TYPE_CHECKING:
    from optuna.storages import BaseStorage, RDBStorage

STORAGE_HELP = "sqlite, journal, sqlite:///FILE, journal:FILE or postgresql://USER:PASS@HOST/DB"


@dataclass(frozen=True)
class StorageSpec:
    """Where a study lives, as :func:`resolve_storage` reads it.

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
    """A URL fit to show.

    Parameters
    ----------
    url : str
        A storage URL.

    Returns
    -------
    str
        ``url`` with any password replaced by ``***``.
    """
    return re.sub(r"^([a-z0-9+]+://[^:/@]*):[^@/]*@", r"\1:***@", url)


def _file_spec(kind: str, path: Path) -> StorageSpec:
    """A SQLite or journal storage on the file ``path`` (made absolute)."""
    p = path.resolve()
    return StorageSpec(kind, f"sqlite:///{p}" if kind == "sqlite" else str(p), str(p))


def resolve_storage(text: str, run_dir: Path) -> StorageSpec:
    """The storage named by ``--storage``.

    Parameters
    ----------
    text : str
        ``sqlite``, ``journal``, ``sqlite:///FILE``, ``journal:FILE`` or
        ``postgresql://USER:PASS@HOST/DB`` (:data:`STORAGE_HELP`).
    run_dir : pathlib.Path
        The run folder, where ``sqlite`` and ``journal`` put their file.

    Returns
    -------
    StorageSpec
        The storage, with absolute file paths.

    Raises
    ------
    ValueError
        If the text names no storage, or a driver vfgym does not support.
    """
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
    m = re.match(r"^sqlite:///(.+)$", t)
    if m:
        return _file_spec("sqlite", Path(m.group(1)).expanduser())
    m = re.match(
        r"^postgres(?:ql)?(\+[a-z0-9]+)?://([^:@/\s]+)(:[^@/\s]*)?@([^:/\s]+)(:\d{1,5})?/(\w[\w.-]*)$",
        t,
    )
    if m:
        driver, user, pw, host, port, db = m.groups()
        if driver not in (None, "+psycopg2", "+psycopg"):
            raise ValueError(
                f"storage={mask_url(t)!r} is not allowed: driver {driver[1:]} is not "
                "supported (use postgresql:// or postgresql+psycopg2://)"
            )
        return StorageSpec(
            "postgresql", f"postgresql{driver or ''}://{user}{pw or ''}@{host}{port or ''}/{db}"
        )
    raise ValueError(f"storage={mask_url(t)!r} is not allowed: give {STORAGE_HELP}")


def find_storage(text: str, run_dir: Path) -> StorageSpec:
    """The storage a sweep's run folder recorded, found again.

    Parsed by :func:`resolve_storage` (the one parser).

    Parameters
    ----------
    text : str
        The folder's ``config.yaml`` ``storage`` (a :attr:`StorageSpec.display`: a
        journal shows as its bare path) or what ``--storage`` names.
    run_dir : Path
        The run folder; a SQLite or journal file no longer where it was recorded is
        looked for in it (the folder was moved).

    Returns
    -------
    StorageSpec
        The storage, pointing at the moved file where it was moved.

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
    """The Optuna storage for ``spec``.

    RDB (with heartbeat and retry of stale trials) for SQLite and PostgreSQL, a SQLite
    file in write-ahead-log mode; JournalStorage on a file, its appends under ``flock``.

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
                return JournalStorage(JournalFileBackend(spec.url, _JournalFlock(spec.url)))  # type: ignore[arg-type]
            kw: dict[str, Any] = (
                {"connect_args": {"timeout": 600}}
                if spec.kind == "sqlite"
                else {"pool_pre_ping": True, "pool_size": 2, "max_overflow": 2}
            )
            if spec.path:
                Path(spec.path).parent.mkdir(parents=True, exist_ok=True)
            storage = optuna.storages.RDBStorage(
                spec.url,
                engine_kwargs=kw,
                heartbeat_interval=heartbeat,
                grace_period=grace or 2 * heartbeat,
                heartbeat_stale_trial_callback=RetryStale(),
            )
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


class _JournalFlock:
    """An ``flock`` on ``PATH.flock`` guarding journal appends (Optuna's journal backend
    only calls ``acquire``/``release``). Unlike Optuna's default symlink lock, the kernel
    drops it when its holder dies, so a worker killed while writing does not stall the
    others for the stale-lock grace period. Every process writing the journal must use
    it (vfgym's workers do; readers take no lock)."""

    def __init__(self, path: str) -> None:
        self._path = path + ".flock"
        self._fd: int | None = None

    def acquire(self) -> bool:
        import fcntl

        fd = os.open(self._path, os.O_RDWR | os.O_CREAT, 0o644)
        fcntl.flock(fd, fcntl.LOCK_EX)
        self._fd = fd
        return True

    def release(self) -> None:
        import fcntl

        if self._fd is not None:
            fcntl.flock(self._fd, fcntl.LOCK_UN)
            os.close(self._fd)
            self._fd = None


def _sqlite_wal(storage: RDBStorage) -> None:
    """Put the SQLite file in write-ahead-log mode (it stays so) with ``synchronous=NORMAL``
    on every connection: readers never wait for a writer, a worker frozen or killed
    mid-write blocks no reader, and a commit needs no fsync (a crash of the process loses
    nothing committed; only a power cut may lose the last commits)."""
    import sqlalchemy

    def on_connect(dbapi_conn: Any, _record: Any) -> None:
        cur = dbapi_conn.cursor()
        cur.execute("PRAGMA synchronous=NORMAL")
        cur.close()

    sqlalchemy.event.listen(storage.engine, "connect", on_connect)
    storage.engine.dispose()  # pooled connections opened before the listener
    with storage.engine.connect() as conn:
        mode = conn.exec_driver_sql("PRAGMA journal_mode").scalar()
        if str(mode).lower() != "wal":
            conn.exec_driver_sql("PRAGMA journal_mode=WAL")


class _FileLock:
    """An exclusive ``flock`` on a file beside a SQLite or journal file (one machine)."""

    def __init__(self, path: str) -> None:
        self._path = path + ".vfgym-lock"
        self._fd: int | None = None
        self.held = False

    def acquire(self) -> None:
        import fcntl

        if self._fd is None:
            self._fd = os.open(self._path, os.O_RDWR | os.O_CREAT, 0o644)
        fcntl.flock(self._fd, fcntl.LOCK_EX)
        self.held = True

    def release(self) -> None:
        import fcntl

        if self.held and self._fd is not None:
            fcntl.flock(self._fd, fcntl.LOCK_UN)
        self.held = False

    def close(self) -> None:
        self.release()
        if self._fd is not None:
            os.close(self._fd)
            self._fd = None


class _PgLock:
    """A PostgreSQL session advisory lock keyed by the study name (all machines)."""

    def __init__(self, url: str, study: str) -> None:
        import sqlalchemy
        from sqlalchemy.pool import NullPool

        digest = hashlib.blake2b(f"vfgym-study:{study}".encode(), digest_size=8).digest()
        self._key = int.from_bytes(digest, "big", signed=True)
        self._engine = sqlalchemy.create_engine(
            url, poolclass=NullPool, isolation_level="AUTOCOMMIT"
        )
        self._conn = self._engine.connect()
        self._text = sqlalchemy.text
        self.held = False

    def acquire(self) -> None:
        self._conn.execute(self._text("SELECT pg_advisory_lock(:k)"), {"k": self._key})
        self.held = True

    def release(self) -> None:
        if self.held:
            self._conn.execute(self._text("SELECT pg_advisory_unlock(:k)"), {"k": self._key})
        self.held = False

    def close(self) -> None:
        self.release()
        self._conn.close()
        self._engine.dispose()


def _claim_lock(spec: StorageSpec, study: str) -> _FileLock | _PgLock:
    return _PgLock(spec.url, study) if spec.kind == "postgresql" else _FileLock(spec.path or "")
