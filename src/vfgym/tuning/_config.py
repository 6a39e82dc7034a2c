"""Sweep and grid configurations: frozen, validated, merged from defaults, a YAML file and
the command line (in that order)."""

from __future__ import annotations

import re
from dataclasses import asdict, dataclass, fields
from typing import Any

from vfgym._validate import (
    check_bool,
    check_choice,
    check_int,
    check_name,
    check_real,
    number_from_text,
)
from vfgym.axis import PAPER_AXIS, Axis, load_axis
from vfgym.moves.distribution import scenario_set
from vfgym.moves.scenarios import Scenario
from vfgym.params import ACCEL_LAWS
from vfgym.tuning._aggregate import DEFAULT_AGGREGATE, DEFAULT_CVAR_ALPHA, check_aggregate

SAMPLERS = ("compass", "tpe", "cmaes", "gp", "nsga2", "grid", "random")
"""Samplers of ``vfgym sweep --sampler``: the compass search (default), Optuna's TPE, CMA-ES,
GP and NSGA-II (the Pareto form by default), a grid over :func:`vfgym.space.grid`, and
uniform random sampling (a control)."""
FORMS = ("cost", "pareto")
"""``cost``: minimise the aggregate cost; ``pareto``: minimise the three objectives."""


def _laws(v: Any) -> tuple[str, ...]:
    items = v.split(",") if isinstance(v, str) else list(v)
    laws = tuple(dict.fromkeys(str(x).strip() for x in items if str(x).strip()))
    if not laws:
        raise ValueError(f"laws={v!r} is not allowed: give one or more of {', '.join(ACCEL_LAWS)}")
    for law in laws:
        check_choice("laws", law, ACCEL_LAWS)
    return laws


@dataclass(frozen=True)
class _Options:
    """What the sweep and grid configurations share: the scenario set, laws and axis."""

    scenarios: str | None = None  # None only as given: construction fills in the default
    scenario_count: int = 16
    first_seed: int = 0
    laws: tuple[str, ...] = ("rise",)
    axis: str | None = None

    def _check_scenarios(self) -> None:
        s = object.__setattr__
        if self.axis is not None:
            s(self, "axis", str(self.axis))
            load_axis(self.axis)  # a bad axis file fails here, naming itself
        if self.scenarios is None:  # an axis is tuned on its train moves
            s(self, "scenarios", "paper-step" if self.axis is None else "train")
        if isinstance(self.scenarios, (list, tuple)):
            s(self, "scenarios", ",".join(str(x) for x in self.scenarios))
        s(self, "scenarios", str(self.scenarios))
        s(self, "scenario_count", check_int("scenario_count", self.scenario_count, 1))
        s(self, "first_seed", check_int("first_seed", self.first_seed, 0))
        s(self, "laws", _laws(self.laws))

    @classmethod
    def resolve(cls, file_data: Any = None, cli: dict[str, Any] | None = None, source: str = ""):
        """A configuration from its defaults, then a config file's values, then the
        command line's.

        Parameters
        ----------
        file_data : dict or None
            A config file's mapping (``-`` in keys read as ``_``).
        cli : dict or None
            Command-line options (``None``: not given), text read as a number for a
            number field.
        source : str
            Names the file in error messages.

        Returns
        -------
        SweepConfig or GridConfig
            The validated configuration.

        Raises
        ------
        ValueError
            If the file is not a mapping, has an unknown key, or a value is out of range.
        """
        known = {f.name for f in fields(cls)}  # type: ignore[arg-type]
        data: dict[str, Any] = {}
        if file_data is not None:
            if not isinstance(file_data, dict):
                raise ValueError(f"{source}: expected a mapping of options")
            data = {str(k).replace("-", "_"): v for k, v in file_data.items()}
            unknown = sorted(set(data) - known)
            if unknown:
                raise ValueError(
                    f"{source}: unknown key(s) {', '.join(unknown)}; allowed: "
                    f"{', '.join(sorted(known))}"
                )
        numeric = {f.name for f in fields(cls) if re.search(r"\b(int|float)\b", str(f.type))}  # type: ignore[arg-type]
        for k, v in (cli or {}).items():
            if v is not None:
                data[k] = number_from_text(v) if k in numeric else v
        return cls(**data)

    def to_dict(self) -> dict[str, Any]:
        """The configuration as plain data (``config.yaml``).

        Returns
        -------
        dict
            Field name to value.
        """
        return asdict(self) | {"laws": list(self.laws)}  # type: ignore[call-overload]

    def load_axis(self) -> Axis | None:
        """The axis file loaded.

        Returns
        -------
        Axis or None
            ``None`` without a file.
        """
        return None if self.axis is None else load_axis(self.axis)

    def axis_or_paper(self) -> Axis:
        """The axis tuned on.

        Returns
        -------
        Axis
            The axis file's, or :data:`~vfgym.axis.PAPER_AXIS` without one.
        """
        return self.load_axis() or PAPER_AXIS

    def scenario_list(self) -> list[Scenario]:
        """The scenarios the configuration names.

        Returns
        -------
        list of Scenario
            An axis's ``train`` / ``test`` move set, else :func:`vfgym.scenario_set` of
            ``scenarios``, ``scenario_count``, ``first_seed``.
        """
        axis = self.load_axis()
        if axis is not None:
            return axis.scenario_set(str(self.scenarios))
        return scenario_set(str(self.scenarios), self.scenario_count, self.first_seed)


@dataclass(frozen=True)
class SweepConfig(_Options):
    """What ``vfgym sweep`` does; every field is a command-line option and a config key.

    Parameters
    ----------
    scenarios : str
        A scenario set (:func:`vfgym.scenario_set`; a list is joined with commas); default
        ``train`` on an axis, else ``paper-step``.
    scenario_count, first_seed : int
        Random draws of a ``train`` / ``test`` set (≥ 1), and the first one's seed (≥ 0).
    laws : tuple of str
        The acceleration laws searched (:data:`vfgym.params.ACCEL_LAWS`; one: fixed).
    axis : str or None
        An axis file (:mod:`vfgym.axis`): its plant, measures and move sets.
    sampler : str
        One of :data:`SAMPLERS`.
    objective : str or None
        ``cost`` or ``pareto``; default: pareto for nsga2, else cost.
    aggregate, cvar_alpha : str, float
        What the cost form minimises over the scenarios (:mod:`vfgym.tuning._aggregate`).
    trials : int
        Completed trials the study ends with (all workers together), ≥ 1.
    timeout : float or None
        Seconds after which a worker starts no new trial.
    workers : int
        Worker processes sharing the study, 1 to 256.
    seed : int or None
        The sampler's seed (worker i: seed + i; ``None``: unseeded).
    storage : str
        ``sqlite``, ``journal`` or a PostgreSQL URL (:func:`resolve_storage`).
    study : str or None
        The study's name, also the run folder's (default: config name + time).
    runs_dir : str
        Folder under which the run folder is made.
    reference : str or None
        A grid run (or its ``reference.yaml``) to report the gap to.
    grid_points : int
        Values per dimension for the grid sampler, 2 to 64.
    plots, progress : bool
        Draw the figures; show a progress bar.
    heartbeat : int
        Seconds between a running trial's heartbeats (Optuna's ``heartbeat_interval``, RDB
        storages; a journal worker's death is seen this often), ≥ 1.
    grace : int or None
        Seconds without a heartbeat before a trial is taken as dead (Optuna's
        ``grace_period``; default twice ``heartbeat``).

    Raises
    ------
    ValueError
        If a value is out of its range or the objective does not suit the sampler.
    """

    sampler: str = "compass"
    objective: str | None = None
    aggregate: str = DEFAULT_AGGREGATE
    cvar_alpha: float = DEFAULT_CVAR_ALPHA
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
        self._check_scenarios()
        check_choice("sampler", self.sampler, SAMPLERS)
        form = self.objective or ("pareto" if self.sampler == "nsga2" else "cost")
        check_choice("objective", form, FORMS)
        if form == "pareto" and self.sampler in ("cmaes", "compass"):
            raise ValueError(
                f"objective='pareto' is not allowed with sampler={self.sampler!r}: use nsga2"
            )
        s(self, "objective", form)
        how, alpha = check_aggregate(self.aggregate, self.cvar_alpha)
        s(self, "aggregate", how)
        s(self, "cvar_alpha", alpha)
        ints = (("trials", 1, None), ("workers", 1, 256), ("seed", 0, 2**31 - 1),
                ("grid_points", 2, 64), ("heartbeat", 1, None), ("grace", 1, None))  # fmt: skip
        for name, lo, hi in ints:  # (seed and grace may be None)
            if getattr(self, name) is not None:
                s(self, name, check_int(name, getattr(self, name), lo, hi))
        if self.timeout is not None:
            s(self, "timeout", check_real("timeout", self.timeout, 0.0, lo_open=True))
        if self.study is not None:
            s(self, "study", check_name("study", self.study))
        for name in ("storage", "runs_dir") + (("reference",) if self.reference else ()):
            s(self, name, str(getattr(self, name)))
        s(self, "plots", check_bool("plots", self.plots))
        s(self, "progress", check_bool("progress", self.progress))


@dataclass(frozen=True)
class GridConfig(_Options):
    """What ``vfgym grid`` does; every field is a command-line option and a config key.

    ``points`` values per dimension over the whole space, then ``refine`` rounds that
    re-grid one grid step either side of the ``keep`` best distinct points.

    Parameters
    ----------
    scenarios, scenario_count, first_seed, laws, axis
        As in :class:`SweepConfig`.
    points, refine, keep : int
        Values per dimension (2 to 64), refinement rounds (0 to 10), best distinct points
        refined around each round (1 to 64).
    batch : int
        Settings per compiled call.
    name : str or None
        The run's name (default: config name + time).
    runs_dir : str
        Folder under which the run folder is made.
    progress : bool
        Show a progress bar.

    Raises
    ------
    ValueError
        If a value is out of its range.
    """

    points: int = 12
    refine: int = 2
    keep: int = 4
    batch: int = 4096
    name: str | None = None
    runs_dir: str = "runs"
    progress: bool = True

    def __post_init__(self) -> None:
        s = object.__setattr__
        self._check_scenarios()
        ints = (("points", 2, 64), ("refine", 0, 10), ("keep", 1, 64), ("batch", 1, 1 << 20))
        for name, lo, hi in ints:
            s(self, name, check_int(name, getattr(self, name), lo, hi))
        if self.name is not None:
            s(self, "name", check_name("name", self.name))
        s(self, "runs_dir", str(self.runs_dir))
        s(self, "progress", check_bool("progress", self.progress))
