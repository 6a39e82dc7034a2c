"""What a finished sweep reports: its best trial, the trials as CSV, its figures, the tuned
settings against the paper's, and the gap to a grid reference."""

from __future__ import annotations

import csv
import functools
import io
import json
import math
import warnings
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, NamedTuple

from vfgym import report, space
from vfgym.axis import Axis, machine_digest
from vfgym.io.runs import read_yaml, write_atomically, write_text
from vfgym.moves.scenarios import Scenario
from vfgym.params import PAPER_SETTINGS, Settings
from vfgym.report import Candidate, Report
from vfgym.scoring import CONSTRAINTS, OBJECTIVES, evaluate
from vfgym.tuning._aggregate import aggregate_costs
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

    return best_of(study.get_trials(deepcopy=False, states=(optuna.trial.TrialState.COMPLETE,)))


def best_of(trials: list[FrozenTrial]) -> FrozenTrial | None:
    """:func:`best_trial` among ``trials`` (those complete count)."""
    done = [
        (t, r) for t in trials if t.state.name == "COMPLETE" and (r := stored_result(t)) is not None
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
    """Write ``trials.csv`` atomically: the columns ``study.trials_dataframe()`` names
    (which needs pandas, not a dependency), each part of the stored result a column of
    its own, lists and dicts as JSON."""
    trials = study.get_trials(deepcopy=False)
    names = study.metric_names or [str(i) for i in range(len(study.directions))]
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
    """Write ``history.png``, ``importances.png`` and (Pareto form) ``pareto_front.png`` as
    ``vfgym plot`` draws them; each figure's file, or ``skipped: REASON`` for one Optuna
    cannot draw (too few trials, no spread to rank)."""
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
    if len(study.get_trials(deepcopy=False, states=complete)) < 2:
        return {name: "skipped: fewer than 2 completed trials" for name in jobs}
    out: dict[str, str] = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for name, draw in jobs.items():
            try:
                save = functools.partial(draw().savefig, dpi=100)
                write_atomically(run_dir / f"{name}.png", save, ".png")
                out[name] = f"{name}.png"
            except Exception as exc:  # Optuna refuses some figures (e.g. no spread to rank)
                out[name] = f"skipped: {str(exc).splitlines()[0] if str(exc) else exc!r}"
    return out


def against_paper(best: Settings, scenarios: list[Scenario], label: str, axis: Axis) -> Report:
    """The paper's settings (the baseline) then ``best`` as ``label``, on each scenario."""
    candidates = [
        Candidate("paper", PAPER_SETTINGS, source="paper", role="baseline"),
        Candidate(label, best, source=label),
    ]
    return report.compare(candidates, [], scenarios, axis=axis)


def paper_cost(cfg: SweepConfig, scenarios: list[Scenario]) -> float:
    """The paper's settings' cost over the sweep's scenarios on its axis, aggregated as the
    sweep aggregates a trial's: what the tuned cost is reported against."""
    ev = evaluate(PAPER_SETTINGS, scenarios, axis=cfg.axis)
    return float(aggregate_costs(ev.cost[0], cfg.aggregate, cfg.cvar_alpha))


class FoundReference(NamedTuple):
    """A grid's ``reference.yaml`` mapping (``record``) and its file (``path``)."""

    record: dict[str, Any]
    path: Path

    @property
    def cost(self) -> float:
        return float(self.record["cost"])


def find_reference(
    cfg_reference: str | None,
    runs_dir: str,
    scenarios: list[Scenario],
    laws: tuple[str, ...],
    axis: str | None = None,
) -> FoundReference | None:
    """The grid reference ``--reference`` names (a ``reference.yaml`` or a grid's run
    folder), else the least costly one under ``runs_dir/grid/*/`` for these scenarios,
    laws and axis (its :func:`~vfgym.axis.axis_digest`); ``None`` if none matches.
    ValueError naming ``reference`` if the one given is not one or is for another
    problem."""
    want = {"scenarios": [s.name for s in scenarios], "laws": list(laws), "axis": axis}

    def other(data: dict[str, Any]) -> str | None:  # the first key naming another problem
        return next((k for k, v in want.items() if data.get(k) != v), None)

    if cfg_reference:
        p = Path(cfg_reference)
        p = p / "reference.yaml" if p.is_dir() else p
        data = read_yaml(p)
        if not isinstance(data, dict) or "cost" not in data or "settings" not in data:
            raise ValueError(f"reference={str(p)!r} is not a grid reference (no settings/cost)")
        if (key := other(data)) is not None:
            raise ValueError(
                f"reference={str(p)!r} is for {key} {data.get(key)!r}, not {want[key]!r}: "
                f"give a grid reference made for the same {key}"
            )
        return FoundReference(data, p)
    found = []
    for p in sorted(Path(runs_dir).glob("grid/*/reference.yaml")):
        try:
            data = read_yaml(p)
        except ValueError:
            continue
        cost = data.get("cost") if isinstance(data, dict) else None
        if isinstance(cost, (int, float)) and other(data) is None:
            found.append((float(cost), str(p), data))
    if not found:
        return None
    _, p, data = min(found, key=lambda x: (x[0], x[1]))
    return FoundReference(data, Path(p))


def gap_pct(cost: float, ref_cost: float) -> float:
    """How far ``cost`` is above ``ref_cost``, in % of it."""
    return 100.0 * (cost - ref_cost) / ref_cost


@dataclass(frozen=True)
class ReferenceGap:
    """A sweep's best against a grid reference (``best.yaml``'s ``reference``): the
    reference's file and cost, and :func:`gap_pct` to it."""

    path: str
    cost: float
    gap_pct: float


@dataclass(frozen=True)
class BestRecord:
    """A sweep's best trial as ``best.yaml`` holds it: the settings (what ``vfgym evaluate
    --settings`` reads), their scores over the scenarios (aggregate cost, feasible, worst
    of each constraint, objectives' means), and where they come from (the storage with its
    password masked; the axis file, ``None`` for the paper's; the axis's
    :func:`~vfgym.axis.machine_digest`, so that settings used on another machine are
    noted)."""

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

    def as_dict(self) -> dict[str, Any]:
        """The mapping written to ``best.yaml`` (``paper_cost`` and ``reference`` only
        when known)."""
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
    reference: FoundReference | None = None,
) -> BestRecord:
    """``best.yaml``'s record of the best trial (:func:`best_trial`), with the paper's
    cost on the same scenarios and the gap to ``reference`` when given."""
    r = stored_result(trial)
    if r is None or r.settings is None:
        raise ValueError(f"trial {trial.number} holds no result")
    gap = None
    if reference is not None:
        gap = ReferenceGap(str(reference.path), reference.cost, gap_pct(r.cost, reference.cost))
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
        axis=cfg.axis_file,
        paper_cost=paper_cost,
        reference=gap,
        machine=machine_digest(cfg.axis),
    )
