"""What a finished sweep reports: its best trial, the trials as CSV, its figures, the tuned
settings against the paper's (a :class:`vfgym.report.Report`), and the gap to a grid
reference.
"""

from __future__ import annotations

import csv
import io
import json
import math
import os
import warnings
from collections.abc import Callable
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any, NamedTuple

from vfgym import report, space
from vfgym.io.runs import read_yaml, write_text
from vfgym.moves.axis import machine_digest
from vfgym.moves.scenarios import Scenario
from vfgym.params import DEFAULT_MEASURES, PAPER_PLANT, PAPER_SETTINGS, Measures, Plant, Settings
from vfgym.report import Candidate, Report
from vfgym.scoring import CONSTRAINTS, OBJECTIVES
from vfgym.tuning._config import SweepConfig
from vfgym.tuning._objective import RESULT_ATTR, stored_result
from vfgym.tuning._storage import StorageSpec

if TYPE_CHECKING:
    from matplotlib.figure import Figure
    from optuna import Study
    from optuna.trial import FrozenTrial


def best_trial(study: Study) -> FrozenTrial | None:
    """The sweep's best trial.

    Parameters
    ----------
    study : optuna.Study
        The study.

    Returns
    -------
    optuna.trial.FrozenTrial or None
        The completed trial of least cost among the feasible ones; if none is, among those
        that arrive on every scenario; else among all. Ties go to the earlier trial;
        ``None`` before any completes.
    """
    import optuna

    done = [
        (t, r)
        for t in study.get_trials(deepcopy=False, states=(optuna.trial.TrialState.COMPLETE,))
        if (r := stored_result(t)) is not None
    ]
    if not done:
        return None
    feas = [d for d in done if d[1].feasible]
    arrive = [d for d in done if d[1].arrives]
    return min(feas or arrive or done, key=lambda d: (d[1].cost, d[0].number))[0]


def trial_settings(trial: FrozenTrial) -> Settings:
    """The settings a trial scored (as stored with its result).

    Parameters
    ----------
    trial : optuna.trial.FrozenTrial
        A trial scored by a sweep.

    Returns
    -------
    Settings
        Its settings.

    Raises
    ------
    ValueError
        If the trial holds no result.
    """
    res = stored_result(trial)
    if res is None or res.settings is None:
        raise ValueError(f"trial {trial.number} holds no result")
    return space.settings_from_dict(res.settings, source=f"trial {trial.number}")


def write_trials_csv(study: Study, path: Path) -> Path:
    """The trials as CSV (``trials.csv``), one row each, written atomically.

    Parameters
    ----------
    study : optuna.Study
        The study.
    path : pathlib.Path
        The file.

    Returns
    -------
    pathlib.Path
        ``path``. Its columns are those ``study.trials_dataframe()`` names (number,
        value(s), times, params_*, user_attrs_* with each part of the stored result a
        column, state); lists and dicts as JSON.
    """
    trials = study.get_trials(deepcopy=False)
    names = study.metric_names or (
        ["value"] if len(study.directions) == 1 else [str(i) for i in range(len(study.directions))]
    )
    value_cols = ["value"] if len(names) == 1 else [f"values_{n}" for n in names]
    params = sorted({k for t in trials for k in t.params})
    flat = []
    for t in trials:
        ua = dict(t.user_attrs)
        res = ua.pop(RESULT_ATTR, None)
        flat.append(ua | res if isinstance(res, dict) else ua)
    attrs = sorted({k for ua in flat for k in ua})
    cols = ["number", *value_cols, "datetime_start", "datetime_complete", "duration"]
    cols += [f"params_{p}" for p in params] + [f"user_attrs_{a}" for a in attrs] + ["state"]
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(cols)
    for t, ua in zip(trials, flat, strict=True):
        vals = list(t.values) if t.values is not None else [""] * len(value_cols)
        dur = (
            (t.datetime_complete - t.datetime_start).total_seconds()
            if t.datetime_complete and t.datetime_start
            else ""
        )
        row = [t.number, *vals, t.datetime_start or "", t.datetime_complete or "", dur]
        row += [t.params.get(p, "") for p in params]
        row += [_cell(ua.get(a, "")) for a in attrs]
        row.append(t.state.name)
        w.writerow(row)
    return write_text(path, buf.getvalue())


def _cell(v: object) -> object:
    return json.dumps(v) if isinstance(v, (list, dict)) else v


def write_plots(study: Study, run_dir: Path, form: str) -> dict[str, str]:
    """The study's figures as PNG in the run folder, drawn by :mod:`vfgym.report.figures`
    (as ``vfgym plot history|pareto`` draws them), each written atomically.

    Parameters
    ----------
    study : optuna.Study
        The study.
    run_dir : Path
        Where ``history.png``, ``importances.png`` and, in the Pareto form,
        ``pareto_front.png`` go.
    form : str
        The sweep's objective, ``cost`` or ``pareto``.

    Returns
    -------
    dict of str to str
        Each figure's file name, or ``skipped: REASON`` for one that cannot be drawn (too
        few trials, no spread to rank, ...).
    """
    import optuna

    from vfgym.report import figures

    complete = (optuna.trial.TrialState.COMPLETE,)

    def cost(t: FrozenTrial) -> float:
        r = stored_result(t)
        return math.nan if r is None else r.cost

    target = None if form == "cost" else cost
    jobs: dict[str, Callable[[], Figure]] = {
        "history": lambda: figures.history_figure(study),
        "importances": lambda: figures.importances_figure(study, target=target, target_name="cost"),
    }
    if form == "pareto":
        jobs["pareto_front"] = lambda: figures.pareto_figure(study)
    out: dict[str, str] = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for name, draw in jobs.items():
            try:
                if len(study.get_trials(deepcopy=False, states=complete)) < 2:
                    raise ValueError("fewer than 2 completed trials")
                fig = draw()
                tmp = run_dir / f".{name}.tmp.png"
                fig.savefig(tmp, dpi=100)
                os.replace(tmp, run_dir / f"{name}.png")
                out[name] = f"{name}.png"
            except Exception as exc:  # Optuna refuses some figures (e.g. no spread to rank)
                out[name] = f"skipped: {str(exc).splitlines()[0] if str(exc) else exc!r}"
    return out


def compare(
    best: Settings,
    scenarios: list[Scenario],
    label: str = "tuned",
    *,
    plant: Plant = PAPER_PLANT,
    measures: Measures = DEFAULT_MEASURES,
) -> Report:
    """The paper's settings against ``best`` on each scenario (:func:`vfgym.report.compare`).

    Parameters
    ----------
    best : Settings
        The tuned settings.
    scenarios : list of Scenario
        The sweep's (or grid's) scenario set.
    label : str
        ``best``'s column label (``tuned``; the grid: ``grid``).
    plant : Plant
        The plant the scenarios run on (an axis's; each scenario applies its load).
    measures : Measures
        Windows and bands of the measures (an axis's).

    Returns
    -------
    vfgym.report.Report
        Columns ``paper`` (role baseline) then ``label``, as
        :func:`vfgym.report.format_compact` prints the sweep's table.
    """
    candidates = [
        Candidate("paper", PAPER_SETTINGS, source="paper", role="baseline"),
        Candidate(label, best, source=label),
    ]
    return report.compare(candidates, [], scenarios, plant=plant, measures=measures)


class FoundReference(NamedTuple):
    """A grid reference found for a sweep (:func:`find_reference`).

    Attributes
    ----------
    record : dict
        The ``reference.yaml`` mapping (:func:`grid_reference`).
    path : pathlib.Path
        The file.
    """

    record: dict[str, Any]
    path: Path

    @property
    def cost(self) -> float:
        """The reference's cost."""
        return float(self.record["cost"])


def find_reference(
    cfg_reference: str | None,
    runs_dir: str,
    scenarios: list[Scenario],
    laws: tuple[str, ...],
    axis: str | None = None,
) -> FoundReference | None:
    """A grid reference for these scenarios, laws and axis.

    Parameters
    ----------
    cfg_reference : str or None
        ``--reference PATH``: a ``reference.yaml`` or a grid run folder; ``None`` searches
        ``runs_dir``'s ``grid/*/reference.yaml`` for the best matching one.
    runs_dir : str
        The runs folder.
    scenarios : list of Scenario
        The sweep's scenarios.
    laws : tuple of str
        The sweep's laws.
    axis : str or None
        The axis's :func:`~vfgym.moves.axis.axis_digest`.

    Returns
    -------
    FoundReference or None
        The reference, or ``None`` when none matches.

    Raises
    ------
    ValueError
        If the given reference is not a grid reference, or is for other scenarios, laws
        or axis.
    """
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
        if data.get("axis") != axis:
            raise ValueError(
                f"reference={str(p)!r} is for axis {data.get('axis')}, not {axis}: give a "
                "grid reference made with the same --axis"
            )
        return FoundReference(data, p)
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
            and data.get("axis") == axis
            and isinstance(data.get("cost"), (int, float))
        ):
            found.append((float(data["cost"]), str(p), data))
    if not found:
        return None
    _, p, data = min(found, key=lambda x: (x[0], x[1]))
    return FoundReference(data, Path(p))


def gap_pct(cost: float, ref_cost: float) -> float:
    """How far a cost is above a reference's.

    Parameters
    ----------
    cost, ref_cost : float
        The sweep's best cost, and the grid reference's.

    Returns
    -------
    float
        100·(cost − ref)/ref, in % (negative: below the reference).
    """
    return 100.0 * (cost - ref_cost) / ref_cost


@dataclass(frozen=True)
class ReferenceGap:
    """A sweep's best against a grid reference (``best.yaml``'s ``reference``).

    Attributes
    ----------
    path : str
        The reference's ``reference.yaml``.
    cost : float
        The reference's cost.
    gap_pct : float
        :func:`gap_pct` of the sweep's best cost to it.
    """

    path: str
    cost: float
    gap_pct: float

    @classmethod
    def between(cls, cost: float, found: FoundReference) -> ReferenceGap:
        """The gap of ``cost`` to the reference ``found``.

        Parameters
        ----------
        cost : float
            The sweep's best cost.
        found : FoundReference
            The reference.

        Returns
        -------
        ReferenceGap
            Its path, its cost and the gap.
        """
        return cls(str(found.path), found.record["cost"], gap_pct(cost, found.cost))


@dataclass(frozen=True)
class BestRecord:
    """A sweep's best trial as ``best.yaml`` holds it (:func:`best_record`): the settings
    (what ``vfgym evaluate --settings`` reads), its scores, and where they come from.

    Attributes
    ----------
    settings : dict
        As :func:`vfgym.space.settings_to_dict` gives them.
    cost, feasible : float, bool
        The cost's aggregate over the scenarios; every constraint ≤ 0 on every scenario.
    constraints, objectives : dict of str to float
        The worst of each constraint, and each objective's mean, over the scenarios.
    study, storage : str
        The study, and its storage (password masked).
    trial : int
        The trial's number.
    sampler, objective : str
        The sweep's sampler and objective.
    scenarios, laws : list of str
        The scenarios' names and the laws searched.
    axis : str or None
        The axis file tuned on (``None``: the paper's axis).
    paper_cost : float or None
        The paper's settings' cost on the same scenarios.
    reference : ReferenceGap or None
        The gap to a grid reference, if one was found.
    machine : str or None
        The axis's :func:`~vfgym.moves.axis.machine_digest`: a settings file used on an
        axis with another plant, measures or uncertainty is noted.
    """

    settings: dict[str, float | str]
    cost: float
    feasible: bool
    constraints: dict[str, float]
    objectives: dict[str, float]
    study: str
    storage: str
    trial: int
    sampler: str
    objective: str | None
    scenarios: list[str]
    laws: list[str]
    axis: str | None
    paper_cost: float | None = None
    reference: ReferenceGap | None = None
    machine: str | None = None

    def with_reference(self, gap: ReferenceGap) -> BestRecord:
        """This record with ``reference`` set to ``gap``.

        Parameters
        ----------
        gap : ReferenceGap
            The gap.

        Returns
        -------
        BestRecord
            A copy with ``reference`` set.
        """
        return replace(self, reference=gap)

    def as_dict(self) -> dict[str, Any]:
        """The mapping written to ``best.yaml``.

        Returns
        -------
        dict
            The fields in order; ``paper_cost`` and ``reference`` left out when ``None``.
        """
        out = asdict(self)
        for k in ("paper_cost", "reference"):
            if out[k] is None:
                del out[k]
        return out


def best_record(
    study: Study,
    trial: FrozenTrial,
    cfg: SweepConfig,
    spec: StorageSpec,
    scenarios: list[Scenario],
    paper_cost: float | None = None,
) -> BestRecord:
    """A sweep's best trial and where it comes from, as ``best.yaml`` holds it.

    Parameters
    ----------
    study : optuna.Study
        The study.
    trial : optuna.trial.FrozenTrial
        The best trial (:func:`best_trial`).
    cfg : SweepConfig
        The sweep's configuration.
    spec : StorageSpec
        Where the study lives.
    scenarios : list of Scenario
        The sweep's scenarios.
    paper_cost : float, optional
        The paper's settings' cost on the same scenarios.

    Returns
    -------
    BestRecord
        The record.

    Raises
    ------
    ValueError
        If the trial holds no result (it did not complete in a sweep).
    """
    r = stored_result(trial)
    if r is None or r.settings is None:
        raise ValueError(f"trial {trial.number} holds no result")
    return BestRecord(
        settings=r.settings,
        cost=r.cost,
        feasible=r.feasible,
        constraints=dict(zip(CONSTRAINTS, r.constraints, strict=True)),
        objectives=dict(zip(OBJECTIVES, r.objectives, strict=True)),
        study=study.study_name,
        storage=spec.display,
        trial=trial.number,
        sampler=cfg.sampler,
        objective=cfg.objective,
        scenarios=[s.name for s in scenarios],
        laws=list(cfg.laws),
        axis=cfg.axis,
        paper_cost=paper_cost,
        machine=machine_digest(cfg.axis_or_paper()),
    )
