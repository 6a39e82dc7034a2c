"""Sweep and grid configurations: frozen, validated, merged from defaults, a YAML file and
the command line (in that order).
"""

from __future__ import annotations

import re
from dataclasses import asdict, dataclass, fields
from typing import Any

from vfgym._validate import check_choice, check_int, check_real
from vfgym.moves.scenarios import Scenario, scenario_set
from vfgym.params import ACCEL_LAWS

SAMPLERS = ("compass", "tpe", "cmaes", "gp", "nsga2", "grid", "random")
"""Samplers of ``vfgym sweep --sampler``: the compass search with model checks in the
problem's own coordinates (default; :mod:`vfgym.tuning._compass`), TPE, CMA-ES, a
Gaussian process for the deterministic objective, NSGA-II (the Pareto form by default), a
grid over :func:`vfgym.space.grid`, and uniform random sampling (a control)."""
FORMS = ("cost", "pareto")
"""``cost``: minimise the mean cost; ``pareto``: minimise the three objectives."""
NAME_RE = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._-]{0,99}$")


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
    grid sampler. batch: trials a worker claims at once and simulates in one batched call
    (default: the sampler's own, :func:`vfgym.tuning.batch_size`).
    """

    scenarios: str = "paper-step"
    scenario_count: int = 16
    first_seed: int = 0
    laws: tuple[str, ...] = ("rise",)
    sampler: str = "compass"
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
    batch: int | None = None
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
        if form == "pareto" and self.sampler in ("cmaes", "compass"):
            raise ValueError(
                f"objective='pareto' is not allowed with sampler={self.sampler!r}: use nsga2"
            )
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
        if self.batch is not None:
            s(self, "batch", check_int("batch", self.batch, 1, 1024))
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
