"""Tuned settings against baselines: per-scenario measures, spreads and win/loss, as tables.

Every number here comes from :func:`vfgym.evaluate`, the one scoring path; this module only
arranges and summarises what it returns. Candidates are V-F :class:`~vfgym.Settings`, a
baseline name, or a *policy*: a callable ``scenario -> Settings`` (an agent that picks
settings per scenario); a policy's settings are evaluated scenario by scenario, grouped so
that identical settings share one batched call.

Definitions
-----------
win / loss / tie
    per scenario, a tuned candidate *wins* against a baseline when its cost is lower, *loses*
    when higher, and *ties* when the two are equal within a relative 1e-9 (identical
    settings give identical costs). A pulse-source baseline on a moving reference has no
    cost (NaN): that scenario is *n/a* and counted apart. Win rate = wins / (wins + losses
    + ties).
spread
    over the scenarios where a measure is defined: n, the median with its interquartile
    range (25th and 75th percentiles, linear interpolation), and the mean with a percentile
    bootstrap 95 % interval (``resamples`` draws with replacement, seeded, so a report is
    reproducible). Paired cost differences (tuned − baseline) get the same spread.
"""

from __future__ import annotations

import csv
import io
import json
import math
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from vfgym._validate import check_int
from vfgym.baselines import BASELINE_NAMES, Baseline, Controller, resolve
from vfgym.metrics import NAMES as METRIC_NAMES
from vfgym.params import DEFAULT_MEASURES, PAPER_PLANT, Measures, Plant, Settings
from vfgym.scenarios import Scenario, scenario_set
from vfgym.scoring import (
    CONSTRAINTS,
    DEFAULT_BOUNDS,
    DEFAULT_WEIGHTS,
    Bounds,
    CostWeights,
    evaluate,
)
from vfgym.space import settings_to_dict

Policy = Callable[[Scenario], Settings]
"""A per-scenario controller: the settings an agent picks for a scenario."""

TIE_RTOL = 1e-9
DEFAULT_RESAMPLES = 2000

EXTRA_METRICS = ("ideal_time_s", "time_ratio", "window_rad")
"""Measures :func:`vfgym.evaluate` adds to :data:`vfgym.metrics.NAMES`."""


@dataclass(frozen=True)
class Measure:
    """A column of the printed table: the measure's key, a header, its unit and scale."""

    key: str
    header: str
    unit: str
    scale: float = 1.0
    fmt: str = ".3g"


TABLE_MEASURES: tuple[Measure, ...] = (
    Measure("cost", "cost", ""),
    Measure("overshoot_counts", "overshoot", "counts"),
    Measure("settling_time_s", "settling", "ms", 1e3),
    Measure("move_time_s", "move time", "ms", 1e3),
    Measure("accel_ratio_pulse", "acc/limit pulses", ""),
    Measure("accel_ratio_motor", "acc/limit motor", ""),
    Measure("torque_limit_time_s", "at torque limit", "ms", 1e3),
    Measure("tracking_rms_rad", "tracking rms", "rad"),
    Measure("feasible", "feasible", "share", 1.0, ".2f"),
)
"""What the table shows per scenario and in aggregate (the CSV and JSON hold every measure).

Peak acceleration against the limit is given for the pulse train (the constraint the
tuning respects, windowed second difference) and for the motor (per tick, from ω)."""


@dataclass
class Column:
    """One candidate's results on every scenario (arrays indexed by scenario)."""

    label: str
    role: str
    """``tuned`` or ``baseline``."""
    source: str
    """Where it came from: a settings file, a baseline name, a model file."""
    controllers: list[Controller | None]
    """The controller as it ran on each scenario (baselines resolved per plant)."""
    cost: np.ndarray
    constraints: np.ndarray
    metrics: list[dict[str, Any]]

    @property
    def feasible(self) -> np.ndarray:
        """All constraints ≤ 0 (NaN where the candidate does not apply)."""
        ok = np.all(self.constraints <= 0.0, axis=-1).astype(float)
        ok[np.isnan(self.cost)] = np.nan
        return ok

    def values(self, key: str) -> np.ndarray:
        """One measure per scenario as floats: ``cost``, ``feasible``, a constraint
        (``constraint_<name>``) or any measure :func:`vfgym.evaluate` returns."""
        if key == "cost":
            return self.cost.astype(float)
        if key == "feasible":
            return self.feasible
        if key.startswith("constraint_"):
            return self.constraints[:, CONSTRAINTS.index(key.removeprefix("constraint_"))]
        return np.array([float(m.get(key, math.nan)) for m in self.metrics])


@dataclass(frozen=True)
class Spread:
    """n, median with interquartile range, mean with a bootstrap 95 % interval."""

    n: int
    median: float
    q1: float
    q3: float
    mean: float
    ci_low: float
    ci_high: float


@dataclass(frozen=True)
class WinLoss:
    """A tuned candidate against a baseline over the scenarios."""

    tuned: str
    baseline: str
    outcomes: tuple[str, ...]
    """Per scenario: ``win``, ``loss``, ``tie`` or ``n/a``."""
    cost_diff: Spread
    """Tuned cost − baseline cost (negative: tuned better), over the comparable scenarios."""

    @property
    def wins(self) -> int:
        return self.outcomes.count("win")

    @property
    def losses(self) -> int:
        return self.outcomes.count("loss")

    @property
    def ties(self) -> int:
        return self.outcomes.count("tie")

    @property
    def not_applicable(self) -> int:
        return self.outcomes.count("n/a")

    @property
    def win_rate(self) -> float:
        n = self.wins + self.losses + self.ties
        return self.wins / n if n else math.nan


def spread(
    values: Sequence[float] | np.ndarray,
    *,
    resamples: int = DEFAULT_RESAMPLES,
    seed: int = 0,
    level: float = 0.95,
) -> Spread:
    """Spread of the finite values (NaN dropped; see the module docstring)."""
    x = np.asarray(values, dtype=float)
    x = x[np.isfinite(x)]
    n = int(x.size)
    if n == 0:
        nan = math.nan
        return Spread(0, nan, nan, nan, nan, nan, nan)
    q1, med, q3 = np.percentile(x, [25.0, 50.0, 75.0])
    rng = np.random.default_rng(seed)
    means = np.empty(resamples)
    chunk = max(1, 2_000_000 // n)
    for start in range(0, resamples, chunk):
        stop = min(resamples, start + chunk)
        means[start:stop] = x[rng.integers(0, n, size=(stop - start, n))].mean(axis=1)
    alpha = (1.0 - level) / 2.0
    lo, hi = np.quantile(means, [alpha, 1.0 - alpha])
    return Spread(n, float(med), float(q1), float(q3), float(x.mean()), float(lo), float(hi))


def outcome(tuned_cost: float, baseline_cost: float) -> str:
    """``win`` / ``loss`` / ``tie`` for one scenario, ``n/a`` when either cost is NaN."""
    if not (math.isfinite(tuned_cost) and math.isfinite(baseline_cost)):
        return "n/a"
    if math.isclose(tuned_cost, baseline_cost, rel_tol=TIE_RTOL, abs_tol=1e-12):
        return "tie"
    return "win" if tuned_cost < baseline_cost else "loss"


@dataclass(frozen=True)
class Candidate:
    """A controller to report on: fixed settings, a baseline, or a per-scenario policy."""

    label: str
    controller: Settings | Baseline | None = None
    policy: Policy | None = field(default=None, compare=False)
    source: str = ""
    role: str = "tuned"

    def __post_init__(self) -> None:
        if (self.controller is None) == (self.policy is None):
            raise ValueError(f"candidate {self.label!r}: give exactly one of controller, policy")
        if self.role not in ("tuned", "baseline"):
            raise ValueError(f"role={self.role!r} is not allowed: choose one of tuned, baseline")


def baseline_candidates(names: str | Sequence[str]) -> list[Candidate]:
    """Baselines by name (a comma-separated string or a list); unknown names raise."""
    if isinstance(names, str):
        names = [n.strip() for n in names.split(",") if n.strip()]
    out = []
    for name in names:
        if name not in BASELINE_NAMES:
            raise ValueError(
                f"baseline={name!r} is not known: choose one of {', '.join(BASELINE_NAMES)}"
            )
        out.append(Candidate(name, Baseline(name), source=name, role="baseline"))
    return out


@dataclass
class Report:
    """Candidates' results on a scenario set, with spreads and win/loss."""

    scenarios: list[Scenario]
    columns: list[Column]
    resamples: int = DEFAULT_RESAMPLES
    seed: int = 0
    scenario_spec: str = ""

    @property
    def tuned(self) -> list[Column]:
        return [c for c in self.columns if c.role == "tuned"]

    @property
    def baselines(self) -> list[Column]:
        return [c for c in self.columns if c.role == "baseline"]

    def column(self, label: str) -> Column:
        for c in self.columns:
            if c.label == label:
                return c
        raise ValueError(f"controller={label!r} is not in this report")

    def spread(self, label: str, key: str) -> Spread:
        """Spread of one measure of one candidate over the scenarios."""
        return spread(self.column(label).values(key), resamples=self.resamples, seed=self.seed)

    def win_loss(self, tuned: str, baseline: str) -> WinLoss:
        """Per-scenario outcomes and the paired cost difference."""
        a, b = self.column(tuned).cost, self.column(baseline).cost
        outs = tuple(outcome(float(x), float(y)) for x, y in zip(a, b, strict=True))
        diff = spread(a - b, resamples=self.resamples, seed=self.seed)
        return WinLoss(tuned, baseline, outs, diff)

    def win_losses(self) -> list[WinLoss]:
        """Every tuned candidate against every baseline."""
        return [self.win_loss(t.label, b.label) for t in self.tuned for b in self.baselines]


def _column_from_rows(
    cand: Candidate,
    scenarios: list[Scenario],
    plant: Plant,
    results: list[tuple[Controller | Baseline, float, np.ndarray, dict[str, Any]]],
) -> Column:
    ctrls = [resolve(c, sc.plant(plant)) for (c, *_), sc in zip(results, scenarios, strict=True)]
    return Column(
        label=cand.label,
        role=cand.role,
        source=cand.source,
        controllers=ctrls,
        cost=np.array([r[1] for r in results], dtype=float),
        constraints=np.array([r[2] for r in results], dtype=float).reshape(
            len(scenarios), len(CONSTRAINTS)
        ),
        metrics=[r[3] for r in results],
    )


def evaluate_policy(
    policy: Policy,
    scenarios: str | Scenario | Sequence[str | Scenario],
    *,
    plant: Plant = PAPER_PLANT,
    measures: Measures = DEFAULT_MEASURES,
    weights: CostWeights = DEFAULT_WEIGHTS,
    bounds: Bounds = DEFAULT_BOUNDS,
) -> tuple[list[Settings], np.ndarray, np.ndarray, list[dict[str, Any]]]:
    """Each scenario scored with the settings ``policy`` picks for it, through
    :func:`vfgym.evaluate` (scenarios that get identical settings share one call).

    Returns the settings, costs (S,), constraints (S, 3) and measures per scenario.
    """
    scens = scenario_set(scenarios)
    chosen: list[Settings] = []
    for sc in scens:
        s = policy(sc)
        if not isinstance(s, Settings):
            raise ValueError(
                f"policy returned {s!r} for scenario {sc.name!r}: expected vfgym.Settings"
            )
        chosen.append(s)
    groups: dict[Settings, list[int]] = {}
    for i, s in enumerate(chosen):
        groups.setdefault(s, []).append(i)
    cost = np.full(len(scens), np.nan)
    cons = np.full((len(scens), len(CONSTRAINTS)), np.nan)
    metrics: list[dict[str, Any]] = [{} for _ in scens]
    for s, idx in groups.items():
        ev = evaluate(
            s,
            [scens[i] for i in idx],
            plant=plant,
            measures=measures,
            weights=weights,
            bounds=bounds,
        )
        for j, i in enumerate(idx):
            cost[i] = ev.cost[0, j]
            cons[i] = ev.constraints[0, j]
            metrics[i] = ev.metrics[0][j]
    return chosen, cost, cons, metrics


def compare(
    candidates: Sequence[Candidate],
    baselines: str | Sequence[str] | Sequence[Candidate] = BASELINE_NAMES,
    scenarios: str | Scenario | Sequence[str | Scenario] = "test",
    *,
    count: int = 16,
    first_seed: int = 0,
    plant: Plant = PAPER_PLANT,
    measures: Measures = DEFAULT_MEASURES,
    weights: CostWeights = DEFAULT_WEIGHTS,
    bounds: Bounds = DEFAULT_BOUNDS,
    resamples: int = DEFAULT_RESAMPLES,
    seed: int = 0,
) -> Report:
    """Score tuned candidates and baselines on the same scenarios (one batched
    :func:`vfgym.evaluate` call for every fixed controller, one per settings group for
    each policy) and return the :class:`Report`."""
    resamples = check_int("resamples", resamples, 1, 1_000_000)
    seed = check_int("seed", seed, 0)
    if isinstance(baselines, str) or (
        isinstance(baselines, Sequence) and all(isinstance(b, str) for b in baselines)
    ):
        base = baseline_candidates(baselines)  # type: ignore[arg-type]
    else:
        base = list(baselines)  # type: ignore[arg-type]
    cands = [*candidates, *base]
    if not cands:
        raise ValueError("candidates=[] is not allowed: give settings, a policy or baselines")
    labels = [c.label for c in cands]
    dup = sorted({x for x in labels if labels.count(x) > 1})
    if dup:
        raise ValueError(f"controller labels must differ: {', '.join(dup)} given twice")
    spec = scenarios if isinstance(scenarios, str) else ""
    scens = scenario_set(scenarios, count, first_seed)
    fixed = [c for c in cands if c.controller is not None]
    columns: dict[str, Column] = {}
    if fixed:
        ev = evaluate(
            [c.controller for c in fixed],  # type: ignore[misc]
            scens,
            plant=plant,
            measures=measures,
            weights=weights,
            bounds=bounds,
        )
        for ci, cand in enumerate(fixed):
            rows = [
                (cand.controller, ev.cost[ci, si], ev.constraints[ci, si], ev.metrics[ci][si])
                for si in range(len(scens))
            ]
            columns[cand.label] = _column_from_rows(cand, scens, plant, rows)  # type: ignore[arg-type]
    for cand in cands:
        if cand.policy is None:
            continue
        chosen, cost, cons, mets = evaluate_policy(
            cand.policy, scens, plant=plant, measures=measures, weights=weights, bounds=bounds
        )
        rows = [(chosen[i], cost[i], cons[i], mets[i]) for i in range(len(scens))]
        columns[cand.label] = _column_from_rows(cand, scens, plant, rows)  # type: ignore[arg-type]
    return Report(
        scenarios=scens,
        columns=[columns[c.label] for c in cands],
        resamples=resamples,
        seed=seed,
        scenario_spec=spec,
    )


# --- output ------------------------------------------------------------------------------


def _fmt(x: float, m: Measure) -> str:
    if x is None or not math.isfinite(x):
        return "n/a"
    if m.key == "feasible":
        return f"{x:.2f}"
    return format(x * m.scale, m.fmt)


def _yes_no(x: float) -> str:
    return "n/a" if not math.isfinite(x) else ("yes" if x > 0.5 else "no")


def _grid(rows: list[list[str]], right: set[int] | None = None) -> list[str]:
    """Rows of cells as aligned text (columns in ``right`` right-aligned)."""
    right = right or set()
    widths = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
    out = []
    for r in rows:
        cells = [
            c.rjust(w) if i in right else c.ljust(w)
            for i, (c, w) in enumerate(zip(r, widths, strict=True))
        ]
        out.append("  ".join(cells).rstrip())
    return out


def _header(m: Measure) -> str:
    return f"{m.header} [{m.unit}]" if m.unit and m.key != "feasible" else m.header


def _unit(m: Measure) -> str:
    return f" [{m.unit}]" if m.unit and m.key != "feasible" else ""


def _count(col: Column) -> str:
    """``k/n feasible`` (a share has no useful median)."""
    f = col.feasible
    ok = f[np.isfinite(f)]
    return f"{int(ok.sum())}/{ok.size} feasible"


def format_table(report: Report) -> str:
    """The report as text: per scenario, in aggregate (spread), and win/loss."""
    lines: list[str] = []
    ns = len(report.scenarios)
    spec = f" '{report.scenario_spec}'" if report.scenario_spec else ""
    lines.append(
        f"{ns} scenario{'s' if ns != 1 else ''}{spec}; cost: lower is better "
        "(move time / ideal, or tracking; see vfgym.scoring)"
    )
    lines.append("")
    per = [m for m in TABLE_MEASURES if m.key != "feasible"]
    wl = report.win_losses()
    by_pair = {(w.tuned, w.baseline): w for w in wl}
    head = ["scenario", "controller", *[_header(m) for m in per], "feasible"]
    head += [f"vs {b.label}" for b in report.baselines] if report.tuned else []
    rows = [head]
    for si, sc in enumerate(report.scenarios):
        for k, col in enumerate(report.columns):
            row = [sc.name if k == 0 else "", col.label]
            row += [_fmt(float(col.values(m.key)[si]), m) for m in per]
            row.append(_yes_no(float(col.feasible[si])))
            if report.tuned:
                for b in report.baselines:
                    w = by_pair.get((col.label, b.label))
                    row.append(w.outcomes[si] if w else "")
            rows.append(row)
    lines += _grid(rows, right=set(range(2, len(per) + 2)))
    lines.append("")
    lines.append(
        f"Aggregate over the scenarios (n = scenarios where defined): median [interquartile "
        f"range]; mean (95 % bootstrap interval, {report.resamples} resamples, seed "
        f"{report.seed})"
    )
    rows = [["measure", "controller", "n", "median [IQR]", "mean (95 % CI)"]]
    for m in TABLE_MEASURES:
        for k, col in enumerate(report.columns):
            s = report.spread(col.label, m.key)
            rows.append(
                [
                    f"{m.header}{_unit(m)}" if k == 0 else "",
                    col.label,
                    str(s.n),
                    _count(col)
                    if m.key == "feasible"
                    else f"{_fmt(s.median, m)} [{_fmt(s.q1, m)}, {_fmt(s.q3, m)}]",
                    f"{_fmt(s.mean, m)} ({_fmt(s.ci_low, m)}, {_fmt(s.ci_high, m)})",
                ]
            )
    lines += _grid(rows, right={2})
    if wl:
        lines.append("")
        lines.append(
            "Win/loss on cost per scenario (tie: equal within 1e-9; n/a: baseline not "
            "applicable); cost difference tuned − baseline (negative: tuned better)"
        )
        cm = Measure("cost", "cost", "")
        rows = [
            [
                "tuned",
                "baseline",
                "wins",
                "losses",
                "ties",
                "n/a",
                "win rate",
                "diff median [IQR]",
                "diff mean (95 % CI)",
            ]
        ]
        for w in wl:
            d = w.cost_diff
            rows.append(
                [
                    w.tuned,
                    w.baseline,
                    str(w.wins),
                    str(w.losses),
                    str(w.ties),
                    str(w.not_applicable),
                    "n/a" if math.isnan(w.win_rate) else f"{w.win_rate:.2f}",
                    f"{_fmt(d.median, cm)} [{_fmt(d.q1, cm)}, {_fmt(d.q3, cm)}]",
                    f"{_fmt(d.mean, cm)} ({_fmt(d.ci_low, cm)}, {_fmt(d.ci_high, cm)})",
                ]
            )
        lines += _grid(rows, right={2, 3, 4, 5, 6})
    return "\n".join(lines) + "\n"


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
    """One row per (scenario, controller): every measure, constraint and the settings as
    run, plus the outcome against each baseline (tuned rows)."""
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
    """One row per (controller, measure) with its spread; then the cost differences of
    each tuned candidate against each baseline (controller ``A - B``, measure
    ``cost_diff``) and its win/loss counts (``wins`` ... as measures with n only)."""
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
    """One row per (tuned, baseline)."""
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
    """``results.csv``: :func:`result_rows` as CSV (NaN as an empty cell)."""
    fields = [*RESULT_FIELDS, *(f"vs_{b.label}" for b in report.baselines)]
    return _csv(result_rows(report), fields)


def summary_csv(report: Report) -> str:
    """``summary.csv``: :func:`summary_rows` as CSV."""
    return _csv(summary_rows(report), SUMMARY_FIELDS)


def results_json(report: Report) -> str:
    """``results.json``: scenarios, controllers, per-scenario rows, spreads, win/loss."""
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
    """Write ``results.csv``, ``summary.csv``, ``results.json`` and ``table.txt`` into
    ``run_dir`` (atomically); returns their paths."""
    from vfgym.runs import write_text

    d = Path(run_dir)
    return {
        "results.csv": write_text(d / "results.csv", results_csv(report)),
        "summary.csv": write_text(d / "summary.csv", summary_csv(report)),
        "results.json": write_text(d / "results.json", results_json(report)),
        "table.txt": write_text(d / "table.txt", format_table(report)),
    }


def markdown_table(report: Report, measures: Sequence[Measure] = TABLE_MEASURES) -> str:
    """Aggregate table as Markdown: per controller, each measure's median [IQR]; then the
    win/loss of each tuned candidate (for README pages)."""
    head = ["controller", "n", *[f"{m.header}{_unit(m)}" for m in measures]]
    # n: scenarios where the controller applies (a pulse source cannot follow a sine)
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for col in report.columns:
        cells = [col.label, str(report.spread(col.label, "cost").n)]
        for m in measures:
            s = report.spread(col.label, m.key)
            if m.key == "feasible":
                cells.append(_count(col).removesuffix(" feasible"))
            elif s.n == 0:
                cells.append("n/a")
            elif s.n == 1:
                cells.append(_fmt(s.median, m))
            else:
                cells.append(f"{_fmt(s.median, m)} [{_fmt(s.q1, m)}, {_fmt(s.q3, m)}]")
        lines.append("| " + " | ".join(cells) + " |")
    wl = report.win_losses()
    if wl:
        lines += [
            "",
            "| tuned | baseline | wins | losses | ties | n/a | cost diff mean (95 % CI) |",
            "|---|---|---|---|---|---|---|",
        ]
        cm = Measure("cost", "cost", "")
        for w in wl:
            d = w.cost_diff
            lines.append(
                f"| {w.tuned} | {w.baseline} | {w.wins} | {w.losses} | {w.ties} | "
                f"{w.not_applicable} | {_fmt(d.mean, cm)} ({_fmt(d.ci_low, cm)}, "
                f"{_fmt(d.ci_high, cm)}) |"
            )
    return "\n".join(lines) + "\n"


def markdown_costs(report: Report) -> str:
    """Per-scenario cost of every controller as Markdown (``*``: a constraint violated;
    n/a: the controller does not apply), with each tuned candidate's outcome against each
    baseline."""
    cols = report.columns
    head = ["scenario", *[c.label for c in cols]]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for si, sc in enumerate(report.scenarios):
        cells = [sc.name]
        for c in cols:
            x = float(c.cost[si])
            star = "" if not math.isfinite(x) or c.feasible[si] > 0.5 else "*"
            cells.append("n/a" if not math.isfinite(x) else f"{x:.3g}{star}")
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


# --- per-tick traces as CSV ----------------------------------------------------------------

TRACE_FIELDS = (
    "tick",
    "time_s",
    "command_rad",
    "pulse",
    "pulse_count",
    "pulse_rad",
    "motor_rad",
    "encoder_count",
    "speed_rad_s",
    "torque_nm",
    "servo_error_counts",
    "position_counter",
    "feedback_counts",
    "speed_count",
)
"""Columns of a trace CSV: sample j is the state at the end of tick ``tick`` (time
(tick+1)·T); ``pulse`` is that tick's pulse (−1, 0, +1; empty when decimated),
``encoder_count`` = floor(θ / count angle), the count the servo sees."""


def trace_columns(trace: Any) -> dict[str, np.ndarray]:
    """A :class:`vfgym.Trace` as named per-sample columns (see :data:`TRACE_FIELDS`)."""
    n = trace.time_s.size
    dec = trace.decimation
    q = trace.plant.motor.count_rad
    cols: dict[str, np.ndarray] = {
        "tick": (np.arange(n, dtype=np.int64) + 1) * dec - 1,
        "time_s": trace.time_s,
        "command_rad": trace.command_rad,
        "pulse": trace.pulses if dec == 1 else np.zeros(0),
        "pulse_count": trace.pulse_count,
        "pulse_rad": trace.pulse_rad,
        "motor_rad": trace.motor_rad,
        "encoder_count": np.floor(trace.motor_rad / q).astype(np.int64),
        "speed_rad_s": trace.speed_rad_s,
        "torque_nm": trace.torque_nm,
        "servo_error_counts": trace.servo_error_counts,
        "position_counter": trace.position_counter,
        "feedback_counts": trace.feedback_counts,
        "speed_count": trace.speed_count,
    }
    return cols


def write_trace_csv(trace: Any, path: str | Path) -> Path:
    """Write a trace's per-sample columns as CSV (floats with 17 significant digits, so
    the file reads back bit for bit)."""
    from vfgym.runs import write_text

    cols = trace_columns(trace)
    n = trace.time_s.size
    parts = []
    for name in TRACE_FIELDS:
        c = cols[name]
        if c.size == 0:
            parts.append(np.full(n, "", dtype=object))
        elif np.issubdtype(c.dtype, np.integer):
            parts.append(c.astype(str))
        else:
            parts.append(np.char.mod("%.17g", c))
    body = "\n".join(",".join(row) for row in zip(*parts, strict=True))
    return write_text(path, ",".join(TRACE_FIELDS) + "\n" + body + "\n")


__all__ = [
    "DEFAULT_RESAMPLES",
    "TABLE_MEASURES",
    "TRACE_FIELDS",
    "Candidate",
    "Column",
    "Measure",
    "Policy",
    "Report",
    "Spread",
    "WinLoss",
    "baseline_candidates",
    "compare",
    "evaluate_policy",
    "format_table",
    "markdown_costs",
    "markdown_table",
    "outcome",
    "results_csv",
    "results_json",
    "spread",
    "summary_csv",
    "trace_columns",
    "write_report",
    "write_trace_csv",
]
