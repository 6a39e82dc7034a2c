"""Sweep and grid configurations: frozen, validated, merged from defaults, a YAML file and
the command line (in that order)."""

from __future__ import annotations

import re
from dataclasses import dataclass, fields
from os import PathLike
from typing import Any

from vfgym._validate import (
    check_bool,
    check_choice,
    check_int,
    check_name,
    check_real,
    number_from_text,
)
from vfgym.axis import PAPER_AXIS, Axis, axis_digest, load_axis
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
    axis: Axis = PAPER_AXIS  # the default axis: the one place it is named as the default
    axis_file: str | None = None  # the file the axis was read from (records only)

    def _check_scenarios(self) -> None:
        s = object.__setattr__
        given: Any = self.axis
        if isinstance(given, (str, PathLike)):  # a file: loaded here, once
            s(self, "axis_file", str(given))
            s(self, "axis", load_axis(str(given)))  # a bad axis file fails here, naming itself
        if not isinstance(self.axis, Axis):
            raise ValueError(f"axis={self.axis!r} is not allowed: give an axis file or an Axis")
        if self.axis_file is not None:
            s(self, "axis_file", str(self.axis_file))
        if self.scenarios is None:  # an axis is tuned on its train moves
            s(self, "scenarios", "paper-step" if self.default_axis else "train")
        if isinstance(self.scenarios, (list, tuple)):
            s(self, "scenarios", ",".join(str(x) for x in self.scenarios))
        s(self, "scenarios", str(self.scenarios))
        s(self, "scenario_count", check_int("scenario_count", self.scenario_count, 1))
        s(self, "first_seed", check_int("first_seed", self.first_seed, 0))
        s(self, "laws", _laws(self.laws))

    @property
    def default_axis(self) -> bool:
        """Whether the axis is the default one, given by no file: its ``train`` / ``test``
        draws are then ``scenario_count`` from ``first_seed``, and records name no axis."""
        return self.axis_file is None and self.axis == PAPER_AXIS

    @classmethod
    def resolve(cls, file_data: Any = None, cli: dict[str, Any] | None = None, source: str = ""):
        """A configuration from its defaults, then a config file's values, then the
        command line's; an axis file named by either is loaded here, once.

        Parameters
        ----------
        file_data : dict or None
            A config file's mapping (``-`` in keys read as ``_``); ``axis``: a file.
        cli : dict or None
            Command-line options (``None``: not given), text read as a number for a
            number field; ``axis``: a file.
        source : str
            Names the file in error messages.

        Returns
        -------
        SweepConfig or GridConfig
            The validated configuration.

        Raises
        ------
        ValueError
            If the file is not a mapping, has an unknown key, a value is out of range, or
            the command line gives a move-set option an axis file overrides.
        """
        known = {f.name for f in fields(cls)} - {"axis_file"}  # type: ignore[arg-type]
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
        if data.get("axis", "") is None:  # (``axis: null``: the default axis)
            del data["axis"]
        numeric = {f.name for f in fields(cls) if re.search(r"\b(int|float)\b", str(f.type))}  # type: ignore[arg-type]
        cli = {k: v for k, v in (cli or {}).items() if v is not None}
        axis = cli.get("axis", data.get("axis"))
        for key in ("scenario_count", "first_seed") if axis is not None else ():
            if key in cli:  # (a config file's stay its default for runs without an axis)
                raise ValueError(
                    f"--{key.replace('_', '-')}={cli[key]!r} is ignored with --axis {axis}: "
                    "the axis file sets its move sets (moves.train, moves.test); leave it out"
                )
        for k, v in cli.items():
            data[k] = number_from_text(v) if k in numeric else v
        return cls(**data)

    def to_dict(self) -> dict[str, Any]:
        """The configuration as plain data (``config.yaml``): the axis as its file's
        path (``None`` without one; the run folder's ``axis.yaml`` holds the axis).

        Returns
        -------
        dict
            Field name to value.
        """
        out = {f.name: getattr(self, f.name) for f in fields(self) if f.name != "axis_file"}  # type: ignore[arg-type]
        return out | {"laws": list(self.laws), "axis": self.axis_file}

    def command_words(self, command: str) -> list[str]:
        """A command line that gives this configuration (after ``vfgym``): each option
        that differs from its default, as ``--name=value``.

        Parameters
        ----------
        command : str
            The sub-command (``sweep``, ``grid``).

        Returns
        -------
        list of str
            The command, then the options (an axis as its file; an axis given as an
            object has none: the run folder's ``axis.yaml`` holds it).
        """
        words = [command]
        for f in fields(self):  # type: ignore[arg-type]
            value = self.axis_file if f.name == "axis" else getattr(self, f.name)
            if f.name == "axis_file" or value == f.default or value is None:
                continue
            flag = "--" + f.name.replace("_", "-")
            if isinstance(value, bool):
                words.append(flag if value else "--no-" + flag[2:])
            else:
                words.append(f"{flag}={','.join(value) if isinstance(value, tuple) else value}")
        return words

    def axis_key(self) -> str | None:
        """The axis as a study and a grid reference record it, so that neither is taken
        for another problem's.

        Returns
        -------
        str or None
            :func:`~vfgym.axis.axis_digest` of the axis; ``None`` for the default axis
            (as studies and references recorded it before axis files).
        """
        return None if self.default_axis else axis_digest(self.axis)

    def scenario_list(self) -> list[Scenario]:
        """The scenarios the configuration names.

        Returns
        -------
        list of Scenario
            The axis's scenario set of ``scenarios``; the default axis's ``train`` /
            ``test`` draws as ``scenario_count`` and ``first_seed`` say.
        """
        if self.default_axis:
            return scenario_set(str(self.scenarios), self.scenario_count, self.first_seed)
        return self.axis.scenario_set(str(self.scenarios))


@dataclass(frozen=True)
class SweepConfig(_Options):
    """What ``vfgym sweep`` does; every field is a command-line option and a config key.

    Parameters
    ----------
    scenarios : str
        A scenario set (:meth:`vfgym.axis.Axis.scenario_set`; a list is joined with
        commas); default ``train`` on an axis given, else ``paper-step``.
    scenario_count, first_seed : int
        The default axis's random draws of a ``train`` / ``test`` set (≥ 1), and the
        first one's seed (≥ 0); another axis's move sets are its own.
    laws : tuple of str
        The acceleration laws searched (:data:`vfgym.params.ACCEL_LAWS`; one: fixed).
    axis : Axis, str or PathLike
        The problem (:class:`vfgym.axis.Axis`): its plant, measures, move sets and
        uncertainty; an axis file is loaded once, here. Default: the paper's axis.
    axis_file : str or None
        The file the axis was read from, for the records (set from ``axis`` when that is
        a file).
    sampler : str
        One of :data:`SAMPLERS`.
    objective : str or None
        ``cost`` or ``pareto``; default: pareto for nsga2, else cost.
    aggregate, cvar_alpha : str, float
        What the cost form minimises over the scenarios (:func:`vfgym.tuning.aggregate`).
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

    def aggregate_label(self) -> str:
        """The aggregate as reports and studies name it.

        Returns
        -------
        str
            ``mean``, ``worst`` or ``cvar 0.25``.
        """
        return f"cvar {self.cvar_alpha:g}" if self.aggregate == "cvar" else self.aggregate


@dataclass(frozen=True)
class GridConfig(_Options):
    """What ``vfgym grid`` does; every field is a command-line option and a config key.

    ``points`` values per dimension over the whole space, then ``refine`` rounds that
    re-grid one grid step either side of the ``keep`` best distinct points.

    Parameters
    ----------
    scenarios, scenario_count, first_seed, laws, axis, axis_file
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
