"""What a finished sweep reports: its best feasible trial, the trials as CSV, and the gap to
a grid reference.
"""

from __future__ import annotations

import csv
import io
import json
import math
import os
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from vfgym import space
from vfgym.io.runs import read_yaml, write_text
from vfgym.moves.scenarios import Scenario
from vfgym.params import DEFAULT_MEASURES, PAPER_PLANT, PAPER_SETTINGS, Measures, Plant, Settings
from vfgym.scoring import CONSTRAINTS, OBJECTIVES, evaluate
from vfgym.tuning._config import SweepConfig
from vfgym.tuning._objective import aggregate
from vfgym.tuning._storage import StorageSpec


def _arrives(trial: Any) -> bool:
    """Whether a trial's settings arrived on every scenario (worst arrival constraint ≤ 0)."""
    cons = trial.user_attrs.get("constraints") or ()
    i = CONSTRAINTS.index("arrival")
    return len(cons) == len(CONSTRAINTS) and cons[i] <= 0.0


def best_trial(study: Any) -> Any:
    """The sweep's best trial.

    Parameters
    ----------
    study : optuna.Study
        The study.

    Returns
    -------
    optuna.trial.FrozenTrial or None
        The completed trial with the lowest cost among the feasible ones; if none is, among
        those that arrive on every scenario (a move that never gets there is no candidate
        while one that does exists); else among all. Ties go to the earlier trial; ``None``
        before any completes.
    """
    import optuna

    done = [
        t
        for t in study.get_trials(deepcopy=False, states=(optuna.trial.TrialState.COMPLETE,))
        if "cost" in t.user_attrs
    ]
    if not done:
        return None
    feas = [t for t in done if t.user_attrs.get("feasible")]
    arrive = [t for t in done if _arrives(t)]
    return min(feas or arrive or done, key=lambda t: (t.user_attrs["cost"], t.number))


def trial_settings(trial: Any) -> Settings:
    """The settings a trial scored.

    Parameters
    ----------
    trial : optuna.trial.FrozenTrial
        A trial with the ``settings`` user attribute :class:`Objective` sets.

    Returns
    -------
    Settings
        Its settings.
    """
    return space.settings_from_dict(trial.user_attrs["settings"], source=f"trial {trial.number}")


def write_trials_csv(study: Any, path: Path) -> Path:
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
        value(s), times, params_*, user_attrs_*, state); lists and dicts as JSON.
    """
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
    """Optimisation history, parameter importances and (Pareto form) the Pareto front as PNG.

    Parameters
    ----------
    study : optuna.Study
        The study.
    run_dir : pathlib.Path
        The run folder the PNG files go to.
    form : str
        ``cost`` or ``pareto``.

    Returns
    -------
    dict of str to str
        Per plot, its file name, or ``skipped: <reason>`` for a plot Optuna cannot draw
        (too few trials …).
    """
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


def compare(
    best: Settings,
    scenarios: list[Scenario],
    label: str = "tuned",
    *,
    plant: Plant = PAPER_PLANT,
    measures: Measures = DEFAULT_MEASURES,
) -> dict[str, Any]:
    """The tuned settings against the paper's on each scenario and over the set.

    Parameters
    ----------
    best : Settings
        The tuned settings.
    scenarios : list of Scenario
        The sweep's scenarios.
    label : str
        The tuned settings' name in the table.
    plant, measures
        The plant and measures the scenarios run on (an axis's).

    Returns
    -------
    dict
        ``rows``: per scenario and settings, the settling time, overshoot, peak
        pulse-train acceleration against the loaded motor's usable acceleration, cost and
        feasibility; ``set``: the same over the set (mean settling, worst overshoot and
        acceleration, mean cost).
    """
    ev = evaluate([PAPER_SETTINGS, best], scenarios, plant=plant, measures=measures)
    agg = aggregate(ev)
    rows: list[dict[str, Any]] = []
    for si, sc in enumerate(scenarios):
        for ci, name in enumerate(("paper", label)):
            m = ev.metrics[ci][si]
            limit = sc.plant(plant).motor.usable_accel_rad_s2
            rows.append(
                {
                    "scenario": sc.name,
                    "settings": name,
                    "settle_ms": math.nan if sc.tracking else 1e3 * m["settling_time_s"],
                    "arrived": bool(m["arrived"]),
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
                "arrived": all(r["arrived"] for r in mine),
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
    """The comparison as a text table.

    Parameters
    ----------
    cmp : dict
        What :func:`compare` returned.

    Returns
    -------
    str
        One line per scenario and settings, then the set's rows (mean settling, worst
        overshoot and acceleration, mean cost) when there are several scenarios.
    """
    head = (
        f"{'scenario':14s} {'settings':8s} {'settle ms':>10s} {'overshoot mrad':>15s} "
        f"{'(windows)':>9s} {'peak accel krad/s2':>19s} {'/limit':>7s} {'cost':>7s} feasible"
    )
    lines = [head, "-" * len(head)]
    rows = cmp["rows"]
    multi = len({r["scenario"] for r in rows}) > 1
    for r in rows + (cmp["set"] if multi else []):
        settle = "-" if math.isnan(r["settle_ms"]) else f"{r['settle_ms']:.2f}"
        if not r["arrived"]:
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
        "settle: settling time into the in-position window (- a moving reference; * did not "
        "arrive: not settled at the end, or a sine not followed); accel: the pulse train's "
        "peak over 1 ms against the limit (the loaded motor's usable acceleration)"
    )
    return "\n".join(lines)


def find_reference(
    cfg_reference: str | None,
    runs_dir: str,
    scenarios: list[Scenario],
    laws: tuple[str, ...],
    axis: str | None = None,
) -> tuple[dict[str, Any], Path] | None:
    """A grid reference for these scenarios and laws.

    Parameters
    ----------
    cfg_reference : str or None
        ``--reference PATH``: a ``reference.yaml`` or a grid run folder; ``None`` searches
        ``runs_dir``.
    runs_dir : str
        The runs folder whose ``grid/*/reference.yaml`` are searched.
    scenarios : list of Scenario
        The sweep's scenarios; a reference must be for the same.
    laws : tuple of str
        The sweep's laws; a reference must be for the same.
    axis : str or None
        The axis's :func:`~vfgym.moves.axis.axis_digest`; a reference must be for the same.

    Returns
    -------
    tuple of (dict, pathlib.Path) or None
        The reference's data and file (the best matching one when searching), or ``None``
        when none matches.

    Raises
    ------
    ValueError
        If the given reference is not a grid reference, or is for other scenarios or laws.
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
            and data.get("axis") == axis
            and isinstance(data.get("cost"), (int, float))
        ):
            found.append((float(data["cost"]), str(p), data))
    if not found:
        return None
    _, p, data = min(found, key=lambda x: (x[0], x[1]))
    return data, Path(p)


def gap_pct(cost: float, ref_cost: float) -> float:
    """How far a cost is above the reference's.

    Parameters
    ----------
    cost : float
        The sweep's best cost.
    ref_cost : float
        The grid reference's cost.

    Returns
    -------
    float
        100·(cost − ref)/ref, in % (negative: below the reference).
    """
    return 100.0 * (cost - ref_cost) / ref_cost


def best_record(
    study: Any, trial: Any, cfg: SweepConfig, spec: StorageSpec, scenarios: list[Scenario]
) -> dict[str, Any]:
    """``best.yaml``: the settings (what ``vfgym evaluate --settings`` reads) and their origin.

    Parameters
    ----------
    study : optuna.Study
        The study.
    trial : optuna.trial.FrozenTrial
        Its best trial (:func:`best_trial`).
    cfg : SweepConfig
        The sweep's configuration.
    spec : StorageSpec
        Where the study lives (shown without a password).
    scenarios : list of Scenario
        The sweep's scenarios.

    Returns
    -------
    dict
        The settings, cost, feasibility, constraints, objectives, and the study, storage,
        trial, sampler, objective, scenarios and laws they come from.
    """
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
        "axis": cfg.axis,
    }
