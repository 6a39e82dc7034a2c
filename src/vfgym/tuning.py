"""Optuna sweeps over the tuned settings, and the exhaustive grid they are judged against.

A sweep is a study over :data:`vfgym.space.SPACE` (and the acceleration law, if several
are searched) on a scenario set. Its objective is the one scoring path,
``vfgym.evaluate(settings, scenarios).mean_cost``; its constraints are
:attr:`vfgym.Evaluation.constraints`, the worst (max) over the scenarios per constraint,
set on each trial with ``trial.set_constraint`` (Optuna 5's replacement for a
``constraints_func``; TPE, GP and NSGA-II use them, CMA-ES and grid ignore them);
the multi-objective (Pareto) form minimises :attr:`vfgym.Evaluation.objectives` averaged
over the scenarios. The paper's settings are enqueued as the study's first trial, and a
setting already scored in the study is not simulated again (its trial copies the result).

Storage and workers. The default storage is a SQLite file in the run folder; ``journal``
is Optuna's JournalStorage on a file (one machine, no server); a ``postgresql://`` URL
is Optuna's RDB storage on a server that workers on many machines share. Each worker
claims a trial under a study-wide lock (a file lock beside a SQLite or journal file,
a PostgreSQL advisory lock on a server) only while the completed, running and waiting
trials number fewer than asked, so a study ends with exactly the trials asked for,
however many workers share it. A worker that dies mid-trial leaves a running trial
behind: on RDB storages Optuna's heartbeat marks it failed after the grace period, on
the journal the other workers see that its process is gone; either way it is marked
failed and enqueued again with the settings it had drawn (the rest are drawn when it
runs). A SQLite file is kept in write-ahead-log mode, so no reader waits on a worker
frozen or killed mid-write; journal appends take an ``flock`` the kernel drops when its
holder dies. Ctrl-C is only acted on inside a
trial's evaluation or while waiting, so an interrupt never leaves a half-written trial:
the interrupted trial is marked failed and enqueued again, and running the same command
with the same ``--study`` continues where it stopped.

The grid (:func:`run_grid`) evaluates :func:`vfgym.space.grid` through the batched kernel,
then refines around its best points; its best is the near-true optimum a sweep's best is
reported against (as a gap in %).
"""

from __future__ import annotations

import copy
import csv
import datetime as _dt
import hashlib
import io
import json
import math
import os
import re
import signal
import socket
import subprocess
import sys
import threading
import time
import warnings
from collections.abc import Callable, Iterator
from contextlib import contextmanager, nullcontext
from dataclasses import asdict, dataclass, field, fields
from pathlib import Path
from typing import Any

import numpy as np

from vfgym import space
from vfgym._validate import check_choice, check_int, check_real
from vfgym.params import ACCEL_LAWS, PAPER_SETTINGS, Settings
from vfgym.runs import read_yaml, write_text
from vfgym.scenarios import Scenario, scenario_set
from vfgym.scoring import CONSTRAINTS, OBJECTIVES, Evaluation, evaluate

SAMPLERS = ("tpe", "cmaes", "gp", "nsga2", "grid", "random")
"""Samplers of ``vfgym sweep --sampler``: TPE (default), CMA-ES, a Gaussian process for the
deterministic objective, NSGA-II (the Pareto form by default), a grid over
:func:`vfgym.space.grid`, and uniform random sampling (a control)."""
FORMS = ("cost", "pareto")
"""``cost``: minimise the mean cost; ``pareto``: minimise the three objectives."""
STORAGE_HELP = "sqlite, journal, sqlite:///FILE, journal:FILE or postgresql://USER:PASS@HOST/DB"
NAME_RE = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._-]{0,99}$")
META_KEY = "vfgym"
"""Study user attribute recording what the study optimises (checked when resumed)."""


# --- configuration -----------------------------------------------------------------------


def _opt_float(name: str, v: Any, lo: float) -> float | None:
    return None if v is None else check_real(name, v, lo, lo_open=True)


def _laws(v: Any) -> tuple[str, ...]:
    items = v.split(",") if isinstance(v, str) else list(v)
    laws = tuple(dict.fromkeys(str(x).strip() for x in items if str(x).strip()))
    if not laws:
        raise ValueError(f"laws={v!r} is not allowed: give one or more of {', '.join(ACCEL_LAWS)}")
    for law in laws:
        check_choice("laws", law, ACCEL_LAWS)
    return laws


def _check_scenario_fields(cfg: Any) -> None:
    """Normalise and check the scenario-set and law fields a sweep and a grid share."""
    s = object.__setattr__
    if isinstance(cfg.scenarios, (list, tuple)):
        s(cfg, "scenarios", ",".join(str(x) for x in cfg.scenarios))
    s(cfg, "scenarios", str(cfg.scenarios))
    s(cfg, "scenario_count", check_int("scenario_count", cfg.scenario_count, 1))
    s(cfg, "first_seed", check_int("first_seed", cfg.first_seed, 0))
    s(cfg, "laws", _laws(cfg.laws))


def _bool(name: str, v: Any) -> bool:
    if isinstance(v, bool):
        return v
    s = str(v).strip().lower()
    if s in ("1", "true", "yes", "on"):
        return True
    if s in ("0", "false", "no", "off"):
        return False
    raise ValueError(f"{name}={v!r} is not allowed: give true or false")


class _Options:
    """Shared by the sweep and grid configurations: merging sources, plain dicts, scenarios."""

    scenarios: str
    scenario_count: int
    first_seed: int
    laws: tuple[str, ...]

    @classmethod
    def resolve(cls, file_data: Any = None, cli: dict[str, Any] | None = None, source: str = ""):
        """Defaults, then a config file's values, then the command line's (not None)."""
        data: dict[str, Any] = {}
        if file_data is not None:
            if not isinstance(file_data, dict):
                raise ValueError(f"{source}: expected a mapping of options")
            data.update(_keys(file_data, cls, source))
        data.update({k: v for k, v in (cli or {}).items() if v is not None})
        return cls(**data)

    def to_dict(self) -> dict[str, Any]:
        d = asdict(self)  # type: ignore[call-overload]
        d["laws"] = list(self.laws)
        return d

    def scenario_list(self) -> list[Scenario]:
        return scenario_set(self.scenarios, self.scenario_count, self.first_seed)


@dataclass(frozen=True)
class SweepConfig(_Options):
    """What ``vfgym sweep`` does; every field is a command-line option and a config key.

    scenarios: a scenario set spec (:func:`vfgym.scenario_set`); scenario_count and
    first_seed size the ``train`` / ``test`` sets. laws: the acceleration laws searched
    (one law: fixed). objective: ``cost`` or ``pareto`` (default: pareto for nsga2).
    trials: completed trials the study ends with (all workers together). timeout: seconds
    after which a worker starts no new trial. storage: see :data:`STORAGE_HELP`.
    study: the study's name, also the run folder's (default: config name + time).
    heartbeat, grace: seconds between a running trial's heartbeats, and without one
    before it is taken as dead (RDB storages). grid_points: values per dimension for the
    grid sampler.
    """

    scenarios: str = "paper-step"
    scenario_count: int = 16
    first_seed: int = 0
    laws: tuple[str, ...] = ("rise",)
    sampler: str = "tpe"
    objective: str | None = None
    trials: int = 100
    timeout: float | None = None
    workers: int = 1
    seed: int | None = 0
    storage: str = "sqlite"
    study: str | None = None
    runs_dir: str = "runs"
    reference: str | None = None
    grid_points: int = 5
    plots: bool = True
    progress: bool = True
    heartbeat: int = 10
    grace: int | None = None

    def __post_init__(self) -> None:
        s = object.__setattr__
        _check_scenario_fields(self)
        check_choice("sampler", self.sampler, SAMPLERS)
        form = self.objective or ("pareto" if self.sampler == "nsga2" else "cost")
        check_choice("objective", form, FORMS)
        if form == "pareto" and self.sampler == "cmaes":
            raise ValueError("objective='pareto' is not allowed with sampler='cmaes': use nsga2")
        s(self, "objective", form)
        s(self, "trials", check_int("trials", self.trials, 1))
        s(self, "timeout", _opt_float("timeout", self.timeout, 0.0))
        s(self, "workers", check_int("workers", self.workers, 1, 256))
        if self.seed is not None:
            s(self, "seed", check_int("seed", self.seed, 0, 2**31 - 1))
        s(self, "storage", str(self.storage))
        if self.study is not None:
            s(self, "study", check_name("study", self.study))
        s(self, "runs_dir", str(self.runs_dir))
        if self.reference is not None:
            s(self, "reference", str(self.reference))
        s(self, "grid_points", check_int("grid_points", self.grid_points, 1, 64))
        s(self, "plots", _bool("plots", self.plots))
        s(self, "progress", _bool("progress", self.progress))
        s(self, "heartbeat", check_int("heartbeat", self.heartbeat, 1))
        if self.grace is not None:
            s(self, "grace", check_int("grace", self.grace, 1))


def _keys(data: dict, cls: type, source: str) -> dict[str, Any]:
    """A config mapping with ``-`` in keys read as ``_``; unknown keys raise."""
    known = {f.name for f in fields(cls)}
    out = {str(k).replace("-", "_"): v for k, v in data.items()}
    unknown = sorted(set(out) - known)
    if unknown:
        raise ValueError(
            f"{source}: unknown key(s) {', '.join(unknown)}; allowed: {', '.join(sorted(known))}"
        )
    return out


def check_name(option: str, name: Any) -> str:
    """A study or run name: it names a folder, so letters, digits, '.', '_', '-'."""
    if not isinstance(name, str) or not NAME_RE.match(name):
        raise ValueError(
            f"{option}={name!r} is not allowed: letters, digits, '.', '_' and '-' "
            "(starting with a letter or digit, at most 100)"
        )
    return name


# --- storages ------------------------------------------------------------------------------


@dataclass(frozen=True)
class StorageSpec:
    """Where a study lives: kind ``sqlite`` / ``journal`` / ``postgresql``, the URL Optuna
    opens (the file path for a journal) and the file, if any."""

    kind: str
    url: str
    path: str | None = None

    @property
    def display(self) -> str:
        """The URL without its password, for files and messages."""
        return mask_url(self.url) if self.kind == "postgresql" else self.url


def mask_url(url: str) -> str:
    """``url`` with any password replaced by ``***``."""
    return re.sub(r"^([a-z0-9+]+://[^:/@]*):[^@/]*@", r"\1:***@", url)


def resolve_storage(text: str, run_dir: Path) -> StorageSpec:
    """The storage named by ``--storage`` (see :data:`STORAGE_HELP`); bad input raises."""
    t = str(text).strip()
    if t == "sqlite":
        p = (run_dir / "study.db").resolve()
        return StorageSpec("sqlite", f"sqlite:///{p}", str(p))
    if t == "journal":
        p = (run_dir / "journal.log").resolve()
        return StorageSpec("journal", str(p), str(p))
    if t.startswith("journal:"):
        rest = t[len("journal:") :]
        rest = rest[2:] if rest.startswith("//") else rest
        if not rest or rest.endswith("/"):
            raise ValueError(f"storage={text!r} is not allowed: give journal:FILE")
        p = Path(rest).expanduser().resolve()
        return StorageSpec("journal", str(p), str(p))
    m = re.match(r"^sqlite:///(.+)$", t)
    if m:
        p = Path(m.group(1)).expanduser().resolve()
        return StorageSpec("sqlite", f"sqlite:///{p}", str(p))
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


def open_storage(spec: StorageSpec, heartbeat: int = 10, grace: int | None = None) -> Any:
    """The Optuna storage for ``spec``: RDB (with heartbeat and retry of stale trials) for
    SQLite and PostgreSQL, JournalStorage on a file. Unreachable storages raise
    ``ValueError`` naming ``storage``."""
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


def _sqlite_wal(storage: Any) -> None:
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


MAX_RETRY = 3
"""A trial whose worker died is enqueued again at most this many times."""


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


# --- the objective -----------------------------------------------------------------------------


def aggregate(ev: Evaluation) -> dict[str, np.ndarray]:
    """Per controller: mean cost, worst (max) constraint over the scenarios, feasibility
    (every constraint ≤ 0 on every scenario) and the objectives' means."""
    cons = np.nanmax(ev.constraints, axis=1)
    return {
        "cost": ev.mean_cost,
        "constraints": cons,
        "feasible": np.all(cons <= 0.0, axis=1),
        "objectives": np.nanmean(ev.objectives, axis=1),
    }


def settings_key(s: Settings) -> tuple:
    return (s.value_rad, s.error_limit_rad, s.k, s.ts_over_tf, s.accel_law)


WORKER_ATTR = "worker"


def _worker_id() -> str:
    """host/pid/start-time of this process (the start time guards against pid reuse)."""
    return f"{socket.gethostname()}/{os.getpid()}/{_proc_start(os.getpid())}"


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


class Objective:
    """Settings from the trial → :func:`vfgym.evaluate` on the scenarios → cost (or the
    three objectives), with the worst constraints and the settings as user attributes.

    A setting already scored (in this process, or by a completed trial of the study) is
    not simulated again: the trial copies that result and records ``cached_from``.
    """

    def __init__(self, scenarios: list[Scenario], laws: tuple[str, ...], form: str) -> None:
        self.scenarios = scenarios
        self.laws = laws
        self.form = form
        self.cache: dict[tuple, tuple[Any, dict[str, Any]]] = {}
        self.simulated = 0
        self.on_enter: Callable[[], None] | None = None
        self.guard: Callable[[], Any] = nullcontext
        self.current: int | None = None

    def __call__(self, trial: Any) -> float | list[float]:
        self.current = trial.number
        # Before the claim lock goes: a retried trial inherits its dead worker's attribute,
        # and another worker's recovery must not see this one running under that name.
        trial.set_user_attr(WORKER_ATTR, _worker_id())
        if self.on_enter:
            self.on_enter()
        return self._run(trial)

    def _run(self, trial: Any) -> float | list[float]:
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
        """Values and user attributes of one setting (one batched evaluation)."""
        agg = aggregate(evaluate(settings, self.scenarios))
        attrs = {
            "settings": space.settings_to_dict(settings),
            "cost": float(agg["cost"][0]),
            "constraints": [float(x) for x in agg["constraints"][0]],
            "feasible": bool(agg["feasible"][0]),
            "objectives": [float(x) for x in agg["objectives"][0]],
        }
        values = attrs["cost"] if self.form == "cost" else list(attrs["objectives"])
        return values, attrs

    def _lookup(self, study: Any, settings: Settings) -> Any:
        import optuna

        want = space.settings_to_dict(settings)
        for t in study.get_trials(deepcopy=False, states=(optuna.trial.TrialState.COMPLETE,)):
            if t.user_attrs.get("settings") == want and "cost" in t.user_attrs:
                attrs = {k: t.user_attrs[k] for k in _RESULT_ATTRS if k in t.user_attrs}
                attrs["cached_from"] = t.user_attrs.get("cached_from", t.number)
                values = t.value if self.form == "cost" else list(t.values)
                return values, attrs
        return None


_RESULT_ATTRS = ("settings", "cost", "constraints", "feasible", "objectives")


SAMPLER_NEEDS = {"cmaes": ("cmaes",), "gp": ("torch", "scipy")}
"""Packages a sampler needs beyond Optuna."""


def check_sampler(cfg: SweepConfig) -> None:
    """Raise ``ValueError`` naming ``sampler`` when a package it needs is missing."""
    import importlib.util

    missing = [m for m in SAMPLER_NEEDS.get(cfg.sampler, ()) if not importlib.util.find_spec(m)]
    if missing:
        raise ValueError(
            f"sampler={cfg.sampler!r} needs {', '.join(missing)}: pip install {' '.join(missing)}"
        )


def make_sampler(cfg: SweepConfig, seed: int | None) -> Any:
    """The Optuna sampler named by ``cfg.sampler``, seeded; constrained where it can be."""
    import optuna

    s = optuna.samplers
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", optuna.exceptions.ExperimentalWarning)
        if cfg.sampler == "tpe":
            return s.TPESampler(seed=seed, multivariate=True)
        if cfg.sampler == "cmaes":
            return s.CmaEsSampler(seed=seed, warn_independent_sampling=False)
        if cfg.sampler == "gp":
            return s.GPSampler(
                seed=seed, deterministic_objective=True, warn_independent_sampling=False
            )
        if cfg.sampler == "nsga2":
            return s.NSGAIISampler(seed=seed)
        if cfg.sampler == "grid":
            return s.GridSampler(grid_space(cfg), seed=seed)
        return s.RandomSampler(seed=seed)


def grid_space(cfg: SweepConfig) -> dict[str, list[Any]]:
    """The grid sampler's values per parameter, from :func:`vfgym.space.grid`."""
    pts = space.grid(cfg.grid_points, cfg.laws[:1])
    # Clipped to the distributions: exp(log(high)) may round one ulp above ``high``.
    out: dict[str, list[Any]] = {
        d.name: sorted({min(max(getattr(p, d.name), d.low), d.high) for p in pts})
        for d in space.SPACE
    }
    if len(cfg.laws) > 1:
        out["accel_law"] = list(cfg.laws)
    return out


def trial_budget(cfg: SweepConfig) -> int:
    """Trials the study ends with: ``trials``, but at most the grid (plus the baseline)."""
    if cfg.sampler == "grid":
        return min(cfg.trials, cfg.grid_points ** len(space.SPACE) * len(cfg.laws) + 1)
    return cfg.trials


def baseline_params(laws: tuple[str, ...]) -> dict[str, Any]:
    """The paper's settings as trial parameters (its law if searched, else the fixed one)."""
    d = space.settings_to_dict(PAPER_SETTINGS)
    law = d.pop("accel_law")
    if len(laws) > 1:
        d["accel_law"] = law if law in laws else laws[0]
    return d


def study_meta(cfg: SweepConfig, scenarios: list[Scenario]) -> dict[str, Any]:
    return {
        "scenarios": [s.name for s in scenarios],
        "laws": list(cfg.laws),
        "objective": cfg.objective,
    }


def create_or_load(
    storage: Any, name: str, cfg: SweepConfig, scenarios: list[Scenario], sampler: Any = None
) -> tuple[Any, bool]:
    """The study ``name``: created with the baseline enqueued first, or loaded (and
    checked to optimise the same thing). Returns (study, created)."""
    import optuna

    optuna.logging.set_verbosity(optuna.logging.WARNING)
    directions = ["minimize"] if cfg.objective == "cost" else ["minimize"] * len(OBJECTIVES)
    meta = study_meta(cfg, scenarios)
    try:
        study = optuna.create_study(
            storage=storage, study_name=name, directions=directions, sampler=sampler
        )
        created = True
    except optuna.exceptions.DuplicatedStudyError:
        study = optuna.load_study(study_name=name, storage=storage, sampler=sampler)
        created = False
    if created:
        study.set_user_attr(META_KEY, meta)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", optuna.exceptions.ExperimentalWarning)
            study.set_metric_names(["cost"] if cfg.objective == "cost" else list(OBJECTIVES))
        study.enqueue_trial(baseline_params(cfg.laws), user_attrs={"baseline": "paper"})
        return study, True
    old = study.user_attrs.get(META_KEY)
    if old is not None:
        for key in ("scenarios", "laws", "objective"):
            if old.get(key) != meta[key]:
                raise ValueError(
                    f"study={name!r} already optimises {key}={old.get(key)!r}, not "
                    f"{meta[key]!r}: give another --study, or the same {key}"
                )
    if len(study.directions) != len(directions):
        raise ValueError(
            f"study={name!r} has {len(study.directions)} objective(s), not "
            f"{len(directions)}: give another --study"
        )
    return study, False


# --- workers -------------------------------------------------------------------------------


class DeferredInterrupt:
    """SIGINT raises KeyboardInterrupt only inside :meth:`allowed` blocks (a trial's
    simulation, a wait); anywhere else it is held until the next such block or the end of
    the ``with``, so a storage write or a lock is never cut in half.

    The decision is taken by the Python-level handler, which runs in the main thread
    between bytecodes, so there is no window between "the signal arrived" and "the block
    closed" in which an interrupt can escape into Optuna's bookkeeping. Off the main thread
    (where handlers cannot be installed) the process's handler is left as it is."""

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
        """Raise an interrupt that was held back."""
        if self.pending:
            self.pending = False
            raise KeyboardInterrupt

    @contextmanager
    def allowed(self) -> Iterator[None]:
        """Let an interrupt through here (raising at once one that was held back)."""
        self.check()
        self.open = True
        try:
            yield
        finally:
            self.open = False


def counts(study: Any) -> dict[str, int]:
    """Trials of the study by state (complete, running, waiting, fail)."""
    out = {"complete": 0, "running": 0, "waiting": 0, "fail": 0, "pruned": 0}
    for t in study.get_trials(deepcopy=False):
        out[t.state.name.lower()] += 1
    return out


def recover(study: Any, storage: Any, spec: StorageSpec, orphan_s: float) -> list[int]:
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

    def __call__(self, study: Any, trial: Any) -> None:
        self.failed.append(trial.number)
        _retry(study, trial)


def _running() -> tuple:
    import optuna

    return (optuna.trial.TrialState.RUNNING,)


def _fail_and_retry(study: Any, trial: Any) -> bool:
    """Mark a running trial failed and enqueue its settings again; False if it had ended."""
    import optuna

    try:
        study.tell(trial.number, state=optuna.trial.TrialState.FAIL)
    except (RuntimeError, ValueError, optuna.exceptions.UpdateFinishedTrialError):
        return False
    _retry(study, trial)
    return True


def _retry(study: Any, trial: Any) -> None:
    import optuna

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", optuna.exceptions.ExperimentalWarning)
        optuna.storages.RetryHeartbeatStaleTrialCallback(max_retry=MAX_RETRY)(study, trial)


@dataclass
class WorkerReport:
    """What one worker did: trials it ran, simulations, dead trials it recovered."""

    trials: list[int] = field(default_factory=list)
    simulated: int = 0
    recovered: list[int] = field(default_factory=list)
    stopped: str = ""


def run_worker(
    cfg: SweepConfig,
    spec: StorageSpec,
    study_name: str,
    index: int = 0,
    on_trial: Callable[[Any], None] | None = None,
    poll_s: float = 0.25,
) -> WorkerReport:
    """Run trials of ``study_name`` until it holds the trials asked for (or the timeout).

    SIGINT is held back (:class:`DeferredInterrupt`) except inside a trial's evaluation
    and while waiting; an interrupted trial is marked failed and enqueued again before
    KeyboardInterrupt propagates."""
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
        study = optuna.load_study(
            study_name=study_name, storage=storage, sampler=make_sampler(cfg, seed)
        )
        objective = Objective(scenarios, cfg.laws, cfg.objective)
        # First call compiles/loads the kernel before any trial is claimed.
        evaluate(PAPER_SETTINGS, scenarios[:1])
        lock = _claim_lock(spec, study_name)

        objective.on_enter = lock.release
        objective.guard = interrupts.allowed
        try:
            while True:
                interrupts.check()
                busy = False
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
                    busy = n["complete"] + n["running"] >= budget and n["waiting"] == 0
                    if not busy:
                        objective.current = None
                        study.optimize(objective, n_trials=1, gc_after_trial=False)
                finally:
                    lock.release()
                if busy:
                    with interrupts.allowed():
                        time.sleep(poll_s)
                    continue
                if objective.current is not None:
                    rep.trials.append(objective.current)
                    if on_trial is not None:
                        on_trial(study)
        except KeyboardInterrupt:
            rep.stopped = "interrupted"
            if objective.current is not None:
                t = copy.deepcopy(study.get_trials(deepcopy=False)[objective.current])
                if t.state == optuna.trial.TrialState.FAIL:
                    _retry(study, t)
                elif t.state == optuna.trial.TrialState.RUNNING:
                    _fail_and_retry(study, t)
            raise
        finally:
            rep.simulated = objective.simulated
            cb = getattr(storage, "heartbeat_stale_trial_callback", None)
            if isinstance(cb, RetryStale):  # also those failed inside study.optimize
                rep.recovered = sorted(set(rep.recovered) | set(cb.failed))
            lock.close()
    return rep


def _worker_main() -> int:
    """Entry of a worker process (``python -m vfgym.tuning``): its job as JSON on stdin."""
    job = json.loads(sys.stdin.read())
    cfg = SweepConfig(**job["config"])
    spec = StorageSpec(**job["storage"])
    try:
        rep = run_worker(cfg, spec, job["study"], job["index"])
    except KeyboardInterrupt:
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        return 130
    print(json.dumps(asdict(rep)), flush=True)
    return 0


def spawn_workers(cfg: SweepConfig, spec: StorageSpec, study: str, n: int) -> list[Any]:
    """Start ``n`` worker processes on the study (their job goes through stdin, so the
    storage password never shows on a command line)."""
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


# --- results -----------------------------------------------------------------------------------


def best_trial(study: Any) -> Any:
    """The completed trial with the lowest cost among the feasible ones (any, if none is)."""
    import optuna

    done = [
        t
        for t in study.get_trials(deepcopy=False, states=(optuna.trial.TrialState.COMPLETE,))
        if "cost" in t.user_attrs
    ]
    if not done:
        return None
    feas = [t for t in done if t.user_attrs.get("feasible")]
    return min(feas or done, key=lambda t: (t.user_attrs["cost"], t.number))


def trial_settings(trial: Any) -> Settings:
    return space.settings_from_dict(trial.user_attrs["settings"], source=f"trial {trial.number}")


def write_trials_csv(study: Any, path: Path) -> Path:
    """The trials as CSV, one row each, with the columns ``study.trials_dataframe()`` names
    (number, value(s), times, params_*, user_attrs_*, state), written atomically."""
    trials = study.get_trials(deepcopy=False)
    names = study.metric_names or (
        ["value"] if len(study.directions) == 1 else [str(i) for i in range(len(study.directions))]
    )
    value_cols = ["value"] if len(names) == 1 else [f"values_{n}" for n in names]
    params = sorted({k for t in trials for k in t.params})
    attrs = sorted({k for t in trials for k in t.user_attrs})
    cols = ["number", *value_cols, "datetime_start", "datetime_complete", "duration"]
    cols += [f"params_{p}" for p in params] + [f"user_attrs_{a}" for a in attrs] + ["state"]
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(cols)
    for t in trials:
        vals = list(t.values) if t.values is not None else [""] * len(value_cols)
        dur = (
            (t.datetime_complete - t.datetime_start).total_seconds()
            if t.datetime_complete and t.datetime_start
            else ""
        )
        row = [t.number, *vals, t.datetime_start or "", t.datetime_complete or "", dur]
        row += [t.params.get(p, "") for p in params]
        row += [_cell(t.user_attrs.get(a, "")) for a in attrs]
        row.append(t.state.name)
        w.writerow(row)
    return write_text(path, buf.getvalue())


def _cell(v: Any) -> Any:
    return json.dumps(v) if isinstance(v, (list, dict)) else v


def write_plots(study: Any, run_dir: Path, form: str) -> dict[str, str]:
    """Optimisation history, parameter importances and (Pareto form) the Pareto front as
    PNG; a plot Optuna cannot draw (too few trials, ...) is skipped with its reason."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import optuna
    from optuna.visualization import matplotlib as ovm

    def cost(t: Any) -> float:
        return float(t.user_attrs.get("cost", math.nan))

    target = None if form == "cost" else cost
    jobs: dict[str, Callable[[], Any]] = {
        "history": lambda: ovm.plot_optimization_history(study, target=target, target_name="cost"),
        "importances": lambda: ovm.plot_param_importances(study, target=target, target_name="cost"),
    }
    if form == "pareto":
        jobs["pareto_front"] = lambda: ovm.plot_pareto_front(study, target_names=list(OBJECTIVES))
    out: dict[str, str] = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for name, draw in jobs.items():
            try:
                if len(study.get_trials(states=(optuna.trial.TrialState.COMPLETE,))) < 2:
                    raise ValueError("fewer than 2 completed trials")
                ax = draw()
                if name == "history":  # costs span decades: the best's progress shows on log
                    ax.set_yscale("log")
                fig = ax.figure if hasattr(ax, "figure") else ax.flat[0].figure
                fig.set_size_inches(8, 5)
                fig.tight_layout()
                path = run_dir / f"{name}.png"
                tmp = run_dir / f".{name}.tmp.png"
                fig.savefig(tmp, dpi=100)
                os.replace(tmp, path)
                out[name] = path.name
            except Exception as exc:  # Optuna refuses some plots (e.g. no spread to rank)
                out[name] = f"skipped: {str(exc).splitlines()[0] if str(exc) else exc!r}"
            finally:
                plt.close("all")
    return out


ROW_KEYS = ("settle_ms", "overshoot_mrad", "overshoot_win", "accel_krad_s2", "accel_ratio", "cost")


def compare(best: Settings, scenarios: list[Scenario], label: str = "tuned") -> dict[str, Any]:
    """The tuned settings against the paper's on each scenario and over the set: settling
    time, overshoot, peak pulse-train acceleration against the motor's limit, cost."""
    ev = evaluate([PAPER_SETTINGS, best], scenarios)
    agg = aggregate(ev)
    rows: list[dict[str, Any]] = []
    for si, sc in enumerate(scenarios):
        for ci, name in enumerate(("paper", label)):
            m = ev.metrics[ci][si]
            limit = sc.plant().motor.accel_limit_rad_s2
            rows.append(
                {
                    "scenario": sc.name,
                    "settings": name,
                    "settle_ms": math.nan if sc.tracking else 1e3 * m["settling_time_s"],
                    "settled": bool(m["settled"]) or sc.tracking,
                    "overshoot_mrad": 1e3 * m["overshoot_rad"],
                    "overshoot_win": m["overshoot_rad"] / m["window_rad"],
                    "accel_krad_s2": m["peak_accel_pulse_rad_s2"] / 1e3,
                    "accel_ratio": m["peak_accel_pulse_rad_s2"] / limit,
                    "cost": float(ev.cost[ci, si]),
                    "feasible": bool(ev.feasible[ci, si]),
                }
            )
    sets = []
    for ci, name in enumerate(("paper", label)):
        mine = [r for r in rows if r["settings"] == name]
        settle = [r["settle_ms"] for r in mine if not math.isnan(r["settle_ms"])]
        sets.append(
            {
                "scenario": f"set ({len(scenarios)})",
                "settings": name,
                "settle_ms": float(np.mean(settle)) if settle else math.nan,
                "settled": all(r["settled"] for r in mine),
                "overshoot_mrad": max(r["overshoot_mrad"] for r in mine),
                "overshoot_win": max(r["overshoot_win"] for r in mine),
                "accel_krad_s2": max(r["accel_krad_s2"] for r in mine),
                "accel_ratio": max(r["accel_ratio"] for r in mine),
                "cost": float(agg["cost"][ci]),
                "feasible": bool(agg["feasible"][ci]),
                "feasible_count": sum(r["feasible"] for r in mine),
            }
        )
    return {"rows": rows, "set": sets}


def format_comparison(cmp: dict[str, Any]) -> str:
    """The comparison as a text table (set rows: mean settling, worst overshoot and
    acceleration, mean cost)."""
    head = (
        f"{'scenario':14s} {'settings':8s} {'settle ms':>10s} {'overshoot mrad':>15s} "
        f"{'(windows)':>9s} {'peak accel krad/s2':>19s} {'/limit':>7s} {'cost':>7s} feasible"
    )
    lines = [head, "-" * len(head)]
    rows = cmp["rows"]
    multi = len({r["scenario"] for r in rows}) > 1
    for r in rows + (cmp["set"] if multi else []):
        settle = "-" if math.isnan(r["settle_ms"]) else f"{r['settle_ms']:.2f}"
        if not r["settled"]:
            settle += "*"
        feas = "yes" if r["feasible"] else "no"
        if "feasible_count" in r:
            n = int(r["scenario"].split("(")[1].rstrip(")"))
            feas = f"{r['feasible_count']}/{n}"
        if r["settings"] == "paper" and r is not rows[0]:
            lines.append("")
        lines.append(
            f"{r['scenario']:14s} {r['settings']:8s} {settle:>10s} {r['overshoot_mrad']:15.3f} "
            f"{r['overshoot_win']:9.2f} {r['accel_krad_s2']:19.1f} {r['accel_ratio']:7.3f} "
            f"{r['cost']:7.4f} {feas}"
        )
    lines.append(
        "settle: settling time into the in-position window (* not settled; - a moving "
        "reference); accel: the pulse train's peak over 1 ms against the motor's limit"
    )
    return "\n".join(lines)


def find_reference(
    cfg_reference: str | None, runs_dir: str, scenarios: list[Scenario], laws: tuple[str, ...]
) -> tuple[dict[str, Any], Path] | None:
    """A grid reference for these scenarios and laws: ``--reference PATH`` (a
    ``reference.yaml`` or a grid run folder), else the best of ``RUNS/grid/*/reference.yaml``
    that matches."""
    names = [s.name for s in scenarios]
    if cfg_reference:
        p = Path(cfg_reference)
        p = p / "reference.yaml" if p.is_dir() else p
        data = read_yaml(p)
        if not isinstance(data, dict) or "cost" not in data or "settings" not in data:
            raise ValueError(f"reference={str(p)!r} is not a grid reference (no settings/cost)")
        if data.get("scenarios") != names or list(data.get("laws", [])) != list(laws):
            raise ValueError(
                f"reference={str(p)!r} is for scenarios {data.get('scenarios')} and laws "
                f"{data.get('laws')}, not {names} and {list(laws)}"
            )
        return data, p
    found = []
    for p in sorted(Path(runs_dir).glob("grid/*/reference.yaml")):
        try:
            data = read_yaml(p)
        except ValueError:
            continue
        if (
            isinstance(data, dict)
            and data.get("scenarios") == names
            and list(data.get("laws", [])) == list(laws)
            and isinstance(data.get("cost"), (int, float))
        ):
            found.append((float(data["cost"]), str(p), data))
    if not found:
        return None
    _, p, data = min(found, key=lambda x: (x[0], x[1]))
    return data, Path(p)


def gap_pct(cost: float, ref_cost: float) -> float:
    """How far a cost is above the reference's, in % (negative: below it)."""
    return 100.0 * (cost - ref_cost) / ref_cost


def best_record(
    study: Any, trial: Any, cfg: SweepConfig, spec: StorageSpec, scenarios: list[Scenario]
) -> dict[str, Any]:
    """``best.yaml``: the settings (what ``vfgym evaluate --settings`` reads) and where
    they come from."""
    return {
        "settings": trial.user_attrs["settings"],
        "cost": trial.user_attrs["cost"],
        "feasible": bool(trial.user_attrs.get("feasible")),
        "constraints": dict(zip(CONSTRAINTS, trial.user_attrs["constraints"], strict=True)),
        "objectives": dict(zip(OBJECTIVES, trial.user_attrs["objectives"], strict=True)),
        "study": study.study_name,
        "storage": spec.display,
        "trial": trial.number,
        "sampler": cfg.sampler,
        "objective": cfg.objective,
        "scenarios": [s.name for s in scenarios],
        "laws": list(cfg.laws),
    }


# --- the exhaustive grid ----------------------------------------------------------------------


@dataclass(frozen=True)
class GridConfig(_Options):
    """What ``vfgym grid`` does: ``points`` values per dimension over the whole space, then
    ``refine`` rounds that re-grid (``points`` per dimension) the neighbourhood of the
    ``keep`` best distinct points, one grid step either side; ``batch`` settings per
    compiled call."""

    scenarios: str = "paper-step"
    scenario_count: int = 16
    first_seed: int = 0
    laws: tuple[str, ...] = ("rise",)
    points: int = 12
    refine: int = 2
    keep: int = 4
    batch: int = 4096
    name: str | None = None
    runs_dir: str = "runs"
    progress: bool = True

    def __post_init__(self) -> None:
        s = object.__setattr__
        _check_scenario_fields(self)
        s(self, "points", check_int("points", self.points, 2, 64))
        s(self, "refine", check_int("refine", self.refine, 0, 10))
        s(self, "keep", check_int("keep", self.keep, 1, 64))
        s(self, "batch", check_int("batch", self.batch, 1, 1 << 20))
        if self.name is not None:
            s(self, "name", check_name("name", self.name))
        s(self, "runs_dir", str(self.runs_dir))
        s(self, "progress", _bool("progress", self.progress))


def _unit_axes(center: np.ndarray, step: float, points: int) -> list[np.ndarray]:
    return [np.linspace(max(-1.0, c - step), min(1.0, c + step), points) for c in center]


def run_grid(
    cfg: GridConfig, progress: Callable[[int, int, float], None] | None = None
) -> dict[str, Any]:
    """Evaluate the dense grid and its refinements through :func:`vfgym.evaluate`, one
    compiled call per batch. Returns the rows (unit coordinates, law, level, cost,
    worst constraints, feasible) and the best."""
    scenarios = cfg.scenario_list()
    evaluate(PAPER_SETTINGS, scenarios)  # compile/load once before timing batches
    levels: list[tuple[int, list[Settings]]] = [(0, space.grid(cfg.points, cfg.laws))]
    total = len(levels[0][1]) * (1 + cfg.refine * cfg.keep)
    rows: dict[tuple, dict[str, Any]] = {}
    done = 0
    best_cost = math.inf
    step = 2.0 / (cfg.points - 1)
    for level in range(cfg.refine + 1):
        if level > 0:
            pool = sorted(
                (r for r in rows.values() if r["feasible"]), key=lambda r: r["cost"]
            ) or sorted(rows.values(), key=lambda r: r["cost"])
            centers: list[dict[str, Any]] = []
            for r in pool:
                if all(
                    r["accel_law"] != c["accel_law"] or np.max(np.abs(r["u"] - c["u"])) > step
                    for c in centers
                ):
                    centers.append(r)
                if len(centers) == cfg.keep:
                    break
            step = step * 2.0 / (cfg.points - 1)
            pts = []
            for c in centers:
                axes = _unit_axes(c["u"], step * (cfg.points - 1) / 2.0, cfg.points)
                pts += [
                    space.from_action(np.array(u), c["accel_law"])
                    for u in np.array(np.meshgrid(*axes, indexing="ij")).reshape(4, -1).T
                ]
            levels.append((level, pts))
        todo = [s for s in levels[-1][1] if settings_key(s) not in rows]
        for i in range(0, len(todo), cfg.batch):
            chunk = todo[i : i + cfg.batch]
            agg = aggregate(evaluate(chunk, scenarios))
            for j, s in enumerate(chunk):
                rows[settings_key(s)] = {
                    "level": level,
                    "settings": s,
                    "accel_law": s.accel_law,
                    "u": np.array([d.to_unit(getattr(s, d.name)) for d in space.SPACE]),
                    "cost": float(agg["cost"][j]),
                    "constraints": agg["constraints"][j].astype(float),
                    "feasible": bool(agg["feasible"][j]),
                }
                if agg["feasible"][j]:
                    best_cost = min(best_cost, float(agg["cost"][j]))
            done += len(chunk)
            if progress is not None:
                progress(done, max(total, done), best_cost)
    feas = [r for r in rows.values() if r["feasible"]]
    best = min(feas or rows.values(), key=lambda r: r["cost"])
    return {"rows": list(rows.values()), "best": best, "scenarios": scenarios}


def write_grid_csv(rows: list[dict[str, Any]], path: Path) -> Path:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(
        ["level", *space.NAMES, "accel_law", "cost", *[f"c_{c}" for c in CONSTRAINTS], "feasible"]
    )
    for r in rows:
        s = r["settings"]
        w.writerow(
            [
                r["level"],
                *[repr(float(getattr(s, n))) for n in space.NAMES],
                s.accel_law,
                repr(r["cost"]),
                *[repr(float(x)) for x in r["constraints"]],
                int(r["feasible"]),
            ]
        )
    return write_text(path, buf.getvalue())


def grid_reference(cfg: GridConfig, result: dict[str, Any]) -> dict[str, Any]:
    """``reference.yaml``: the grid's best, in the Settings-YAML format."""
    b = result["best"]
    return {
        "settings": space.settings_to_dict(b["settings"]),
        "cost": b["cost"],
        "feasible": b["feasible"],
        "constraints": dict(zip(CONSTRAINTS, [float(x) for x in b["constraints"]], strict=True)),
        "scenarios": [s.name for s in result["scenarios"]],
        "laws": list(cfg.laws),
        "points": cfg.points,
        "refine": cfg.refine,
        "keep": cfg.keep,
        "evaluated": len(result["rows"]),
        "source": "vfgym grid",
    }


if __name__ == "__main__":
    sys.exit(_worker_main())
