"""A report as files: results and summary CSV, results JSON, and the text table, written
atomically into a run folder.
"""

from __future__ import annotations

import csv
import io
import json
import math
from collections.abc import Sequence
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np

from vfgym.moves.baselines import Controller
from vfgym.params import Settings
from vfgym.plant.measures import NAMES as METRIC_NAMES
from vfgym.report._comparison import EXTRA_METRICS, Report
from vfgym.report._stats import Spread
from vfgym.report._tables import format_table
from vfgym.scoring import (
    CONSTRAINTS,
)
from vfgym.space import settings_to_dict


def _settings_fields(c: Controller | None) -> dict[str, Any]:
    if isinstance(c, Settings):
        return settings_to_dict(c)
    return dict.fromkeys(("value_rad", "error_limit_rad", "k", "ts_over_tf", "accel_law"), "")


RESULT_FIELDS = (
    "scenario",
    "controller",
    "role",
    "source",
    "cost",
    "feasible",
    *(f"constraint_{c}" for c in CONSTRAINTS),
    *METRIC_NAMES,
    *EXTRA_METRICS,
    "value_rad",
    "error_limit_rad",
    "k",
    "ts_over_tf",
    "accel_law",
)
"""Columns of ``results.csv`` (then one ``vs_<baseline>`` column per baseline)."""

SUMMARY_FIELDS = ("controller", "measure", *(f.name for f in Spread.__dataclass_fields__.values()))


def result_rows(report: Report) -> list[dict[str, Any]]:
    """Per-scenario results as rows (``results.csv``).

    Parameters
    ----------
    report : Report
        The comparison, as :func:`compare` returns it.

    Returns
    -------
    list of dict
        One per (scenario, controller): every measure, constraint and the settings as
        run, plus the outcome against each baseline (tuned rows).
    """
    wl = {(w.tuned, w.baseline): w for w in report.win_losses()}
    out = []
    for si, sc in enumerate(report.scenarios):
        for col in report.columns:
            m = col.metrics[si]
            feas = float(col.feasible[si])
            row: dict[str, Any] = {
                "scenario": sc.name,
                "controller": col.label,
                "role": col.role,
                "source": col.source,
                "cost": float(col.cost[si]),
                "feasible": None if math.isnan(feas) else bool(feas),
            }
            for j, c in enumerate(CONSTRAINTS):
                row[f"constraint_{c}"] = float(col.constraints[si, j])
            for k in (*METRIC_NAMES, *EXTRA_METRICS):
                v = m.get(k, math.nan)
                row[k] = v if isinstance(v, (bool, np.bool_)) else float(v)
            row |= _settings_fields(col.controllers[si])
            for b in report.baselines:
                w = wl.get((col.label, b.label))
                row[f"vs_{b.label}"] = w.outcomes[si] if w else ""
            out.append(row)
    return out


def summary_rows(report: Report) -> list[dict[str, Any]]:
    """Aggregate results as rows (``summary.csv``).

    Parameters
    ----------
    report : Report
        The comparison, as :func:`compare` returns it.

    Returns
    -------
    list of dict
        One per (controller, measure) with its spread; then the cost differences of
        each tuned candidate against each baseline (controller ``A - B``, measure
        ``cost_diff``).
    """
    keys = ["cost", "feasible", *(f"constraint_{c}" for c in CONSTRAINTS)]
    keys += [*METRIC_NAMES, *EXTRA_METRICS]
    out = []
    for col in report.columns:
        for k in keys:
            out.append(
                {"controller": col.label, "measure": k} | asdict(report.spread(col.label, k))
            )
    for w in report.win_losses():
        out.append(
            {"controller": f"{w.tuned} - {w.baseline}", "measure": "cost_diff"}
            | asdict(w.cost_diff)
        )
    return out


def win_loss_rows(report: Report) -> list[dict[str, Any]]:
    """Win / loss as rows (``results.json``).

    Parameters
    ----------
    report : Report
        The comparison, as :func:`compare` returns it.

    Returns
    -------
    list of dict
        One per (tuned, baseline): counts, win rate, cost difference, outcomes.
    """
    return [
        {
            "tuned": w.tuned,
            "baseline": w.baseline,
            "wins": w.wins,
            "losses": w.losses,
            "ties": w.ties,
            "not_applicable": w.not_applicable,
            "win_rate": w.win_rate,
            "cost_diff": asdict(w.cost_diff),
            "outcomes": dict(zip((s.name for s in report.scenarios), w.outcomes, strict=True)),
        }
        for w in report.win_losses()
    ]


def _csv(rows: list[dict[str, Any]], fields: Sequence[str]) -> str:
    buf = io.StringIO()
    wr = csv.DictWriter(buf, fieldnames=list(fields), lineterminator="\n")
    wr.writeheader()
    for r in rows:
        wr.writerow({k: ("" if _isnan(v) else v) for k, v in r.items() if k in fields})
    return buf.getvalue()


def _isnan(v: Any) -> bool:
    return isinstance(v, float) and math.isnan(v)


def _json_safe(x: Any) -> Any:
    """NaN and infinities as null (JSON has neither), numpy scalars as Python ones."""
    if isinstance(x, dict):
        return {str(k): _json_safe(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_json_safe(v) for v in x]
    if isinstance(x, np.generic):
        x = x.item()
    if isinstance(x, float) and not math.isfinite(x):
        return None
    return x


def results_csv(report: Report) -> str:
    """``results.csv``: :func:`result_rows` as CSV.

    Parameters
    ----------
    report : Report
        The comparison, as :func:`compare` returns it.

    Returns
    -------
    str
        The CSV text (NaN as an empty cell).
    """
    fields = [*RESULT_FIELDS, *(f"vs_{b.label}" for b in report.baselines)]
    return _csv(result_rows(report), fields)


def summary_csv(report: Report) -> str:
    """``summary.csv``: :func:`summary_rows` as CSV.

    Parameters
    ----------
    report : Report
        The comparison, as :func:`compare` returns it.

    Returns
    -------
    str
        The CSV text.
    """
    return _csv(summary_rows(report), SUMMARY_FIELDS)


def results_json(report: Report) -> str:
    """``results.json``: scenarios, controllers, per-scenario rows, spreads, win/loss.

    Parameters
    ----------
    report : Report
        The comparison, as :func:`compare` returns it.

    Returns
    -------
    str
        The JSON text (NaN and infinities as null).
    """
    data = {
        "scenario_spec": report.scenario_spec,
        "scenarios": [
            {k: v for k, v in asdict(sc).items() if k != "moves"} | {"moves": list(sc.moves)}
            for sc in report.scenarios
        ],
        "controllers": [
            {"label": c.label, "role": c.role, "source": c.source} for c in report.columns
        ],
        "bootstrap": {"resamples": report.resamples, "seed": report.seed, "level": 0.95},
        "per_scenario": result_rows(report),
        "aggregate": summary_rows(report),
        "win_loss": win_loss_rows(report),
    }
    return json.dumps(_json_safe(data), indent=1) + "\n"


def write_report(report: Report, run_dir: str | Path) -> dict[str, Path]:
    """Write ``results.csv``, ``summary.csv``, ``results.json`` and ``table.txt``.

    Parameters
    ----------
    report : Report
        The comparison, as :func:`compare` returns it.
    run_dir : str or pathlib.Path
        The run folder; each file is written atomically.

    Returns
    -------
    dict of str to pathlib.Path
        The path of each file, by name.
    """
    from vfgym.io.runs import write_text

    d = Path(run_dir)
    return {
        "results.csv": write_text(d / "results.csv", results_csv(report)),
        "summary.csv": write_text(d / "summary.csv", summary_csv(report)),
        "results.json": write_text(d / "results.json", results_json(report)),
        "table.txt": write_text(d / "table.txt", format_table(report)),
    }
