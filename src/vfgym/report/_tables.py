"""A report as text and Markdown tables: per scenario and in aggregate, with win / loss;
and the compact table a sweep or the grid prints (each controller's settling, overshoot,
acceleration and cost per scenario and over the set)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from typing import NamedTuple

import numpy as np

from vfgym.report._comparison import Column, Report


@dataclass(frozen=True)
class TableColumn:
    """A column of the printed table.

    Parameters
    ----------
    key : str
        The measure, as :meth:`Column.values` takes it.
    header : str
        The column's header.
    unit : str
        The unit shown after the header (after scaling).
    scale : float
        Factor from the measure's unit to the shown one (1e3: s to ms).
    fmt : str
        Format spec of the values.
    """

    key: str
    header: str
    unit: str
    scale: float = 1.0
    fmt: str = ".3g"


TABLE_COLUMNS: tuple[TableColumn, ...] = (
    TableColumn("cost", "cost", ""),
    TableColumn("overshoot_counts", "overshoot", "counts"),
    TableColumn("settling_time_s", "settling", "ms", 1e3),
    TableColumn("move_time_s", "move time", "ms", 1e3),
    TableColumn("accel_ratio_pulse", "acc/limit pulses", ""),
    TableColumn("accel_ratio_motor", "acc/limit motor", ""),
    TableColumn("torque_limit_time_s", "at torque limit", "ms", 1e3),
    TableColumn("tracking_rms_rad", "tracking rms", "rad"),
    TableColumn("feasible", "feasible", "share", 1.0, ".2f"),
    TableColumn("arrived", "arrived", "share", 1.0, ".2f"),
)
"""What the table shows per scenario and in aggregate (the CSV and JSON hold every measure).

Peak acceleration against the limit is given for the pulse train (the constraint the
tuning respects, windowed second difference) and for the motor (per tick, from ω).
``arrived``: the run ended settled in the in-position window (a sine: followed); see
:mod:`vfgym.scoring`. A run that did not arrive is infeasible."""
SHARES = ("feasible", "arrived")
"""Yes/no columns: per scenario yes or no, in aggregate a count."""


def _fmt(x: float, m: TableColumn) -> str:
    if x is None or not math.isfinite(x):
        return "n/a"
    if m.key in SHARES:
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


def _header(m: TableColumn) -> str:
    return f"{m.header} [{m.unit}]" if m.unit and m.key not in SHARES else m.header


def _unit(m: TableColumn) -> str:
    return f" [{m.unit}]" if m.unit and m.key not in SHARES else ""


def _count(col: Column, key: str = "feasible") -> str:
    """``k/n feasible`` or ``k/n arrived`` (a share has no useful median)."""
    f = col.values(key)
    ok = f[np.isfinite(f)]
    return f"{int(ok.sum())}/{ok.size} {key}"


def format_table(report: Report) -> str:
    """The report as text: per scenario, in aggregate (spread), and win/loss.

    Parameters
    ----------
    report : Report
        The comparison, as :func:`compare` returns it.

    Returns
    -------
    str
        The table, one line per row.
    """
    lines: list[str] = []
    ns = len(report.scenarios)
    spec = f" '{report.scenario_spec}'" if report.scenario_spec else ""
    lines.append(
        f"{ns} scenario{'s' if ns != 1 else ''}{spec}; cost: lower is better "
        "(move time / ideal, or tracking; see vfgym.scoring)"
    )
    lines.append("")
    per = [m for m in TABLE_COLUMNS if m.key not in SHARES]
    wl = report.win_losses()
    by_pair = {(w.tuned, w.baseline): w for w in wl}
    head = ["scenario", "controller", *[_header(m) for m in per], *SHARES]
    head += [f"vs {b.label}" for b in report.baselines] if report.tuned else []
    rows = [head]
    for si, sc in enumerate(report.scenarios):
        for k, col in enumerate(report.columns):
            row = [sc.name if k == 0 else "", col.label]
            row += [_fmt(float(col.values(m.key)[si]), m) for m in per]
            row += [_yes_no(float(col.values(key)[si])) for key in SHARES]
            if report.tuned:
                for b in report.baselines:
                    w = by_pair.get((col.label, b.label))
                    row.append(w.outcomes[si] if w else "")
            rows.append(row)
    lines += _grid(rows, right=set(range(2, len(per) + 2)))
    lines.append(
        "arrived: in the in-position window at the scenario's end (a sine: followed within "
        "the -3 dB bandwidth); a run that did not arrive is infeasible, its settling and move "
        "times are the run's duration (a lower bound)"
    )
    lines.append("")
    lines.append(
        f"Aggregate over the scenarios (n = scenarios where defined): median [interquartile "
        f"range]; mean (95 % bootstrap interval, {report.resamples} resamples, seed "
        f"{report.seed})"
    )
    rows = [["measure", "controller", "n", "median [IQR]", "mean (95 % CI)"]]
    for m in TABLE_COLUMNS:
        for k, col in enumerate(report.columns):
            s = report.spread(col.label, m.key)
            rows.append(
                [
                    f"{m.header}{_unit(m)}" if k == 0 else "",
                    col.label,
                    str(s.n),
                    _count(col, m.key)
                    if m.key in SHARES
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
        cm = TableColumn("cost", "cost", "")
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


def markdown_table(report: Report, measures: Sequence[TableColumn] = TABLE_COLUMNS) -> str:
    """Aggregate table as Markdown (for README pages).

    Parameters
    ----------
    report : Report
        The comparison, as :func:`compare` returns it.
    measures : sequence of TableColumn
        The columns to show.

    Returns
    -------
    str
        Per controller, each measure's median [IQR]; then the win/loss of each tuned
        candidate.
    """
    head = ["controller", "n", *[f"{m.header}{_unit(m)}" for m in measures]]
    # n: scenarios where the controller applies (a pulse source cannot follow a sine)
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for col in report.columns:
        cells = [col.label, str(report.spread(col.label, "cost").n)]
        for m in measures:
            s = report.spread(col.label, m.key)
            if m.key in SHARES:
                cells.append(_count(col, m.key).removesuffix(f" {m.key}"))
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
        cm = TableColumn("cost", "cost", "")
        for w in wl:
            d = w.cost_diff
            lines.append(
                f"| {w.tuned} | {w.baseline} | {w.wins} | {w.losses} | {w.ties} | "
                f"{w.not_applicable} | {_fmt(d.mean, cm)} ({_fmt(d.ci_low, cm)}, "
                f"{_fmt(d.ci_high, cm)}) |"
            )
    return "\n".join(lines) + "\n"


def markdown_costs(report: Report) -> str:
    """Per-scenario cost of every controller as Markdown.

    Parameters
    ----------
    report : Report
        The comparison, as :func:`compare` returns it.

    Returns
    -------
    str
        One row per scenario; ``*`` marks a violated constraint, ``†`` a run that did not
        arrive (not settled in the in-position window at the scenario's end, or a sine not
        followed), n/a a controller that does not apply.
    """
    cols = report.columns
    head = ["scenario", *[c.label for c in cols]]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for si, sc in enumerate(report.scenarios):
        cells = [sc.name]
        for c in cols:
            x = float(c.cost[si])
            if not math.isfinite(x):
                cells.append("n/a")
                continue
            star = "" if c.feasible[si] > 0.5 else "*"
            star += "" if c.values("arrived")[si] > 0.5 else "†"
            cells.append(f"{x:.3g}{star}")
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


# --- the compact table (sweeps and the grid: tuned settings against the paper's) ----------


@dataclass(frozen=True)
class CompactRow:
    """One line of the compact table: a controller on one scenario, or over the set.

    Over the set: the mean settling time of the point-to-point scenarios, the worst
    overshoot and acceleration, the mean cost, and ``feasible`` when it is on every
    scenario where it applies (``feasible_count`` of them).

    Attributes
    ----------
    scenario : str
        The scenario's name, or ``set (N)`` over the set.
    settings : str
        The controller's label.
    settle_ms : float
        Settling time into the in-position window (ms); NaN on a moving reference.
    arrived : bool
        Arrived: settled in the in-position window at the scenario's end (a sine:
        followed), as the scoring path's ``arrival`` constraint says.
    overshoot_mrad : float
        Overshoot (mrad).
    overshoot_win : float
        Overshoot in in-position windows.
    accel_krad_s2 : float
        The pulse train's peak acceleration (krad/s²).
    accel_ratio : float
        That peak against the limit, the loaded motor's usable acceleration.
    cost : float
        The cost (over the set: the mean).
    feasible : bool
        Every constraint ≤ 0 (over the set: on every scenario where it applies).
    feasible_count : int or None
        Set rows: on how many scenarios the controller is feasible.
    """

    scenario: str
    settings: str
    settle_ms: float
    arrived: bool
    overshoot_mrad: float
    overshoot_win: float
    accel_krad_s2: float
    accel_ratio: float
    cost: float
    feasible: bool
    feasible_count: int | None = None

    def as_dict(self) -> dict[str, str | float | bool | int]:
        """The row as a mapping.

        Returns
        -------
        dict
            The fields by name (per-scenario rows without ``feasible_count``).
        """
        d = asdict(self)
        if self.feasible_count is None:
            del d["feasible_count"]
        return d


class CompactTable(NamedTuple):
    """The compact table's rows: each controller on each scenario, then over the set.

    What :func:`compact_rows` returns.

    Attributes
    ----------
    rows : list of CompactRow
        Each controller on each scenario, scenario by scenario.
    set : list of CompactRow
        Each controller over the set.
    scenario_count : int
        The number of scenarios.
    """

    rows: list[CompactRow]
    set: list[CompactRow]
    scenario_count: int

    def as_dict(self) -> dict[str, list[dict[str, str | float | bool | int]]]:
        """The table as a sweep's ``summary.yaml`` holds it.

        Returns
        -------
        dict
            ``{"rows": [...], "set": [...]}``, each row as :meth:`CompactRow.as_dict`.
        """
        return {"rows": [r.as_dict() for r in self.rows], "set": [r.as_dict() for r in self.set]}


def compact_rows(report: Report) -> CompactTable:
    """The report's controllers in the compact layout, scenario by scenario and over the
    set.

    Parameters
    ----------
    report : Report
        Any report (its columns in order; a sweep's: the paper's settings, then the tuned).

    Returns
    -------
    CompactTable
        Each column on each scenario, then over the set (see :class:`CompactRow`).
    """
    rows: list[CompactRow] = []
    for si, sc in enumerate(report.scenarios):
        for col in report.columns:
            m = col.metrics[si]
            rows.append(
                CompactRow(
                    scenario=sc.name,
                    settings=col.label,
                    settle_ms=math.nan if sc.tracking else 1e3 * m["settling_time_s"],
                    arrived=bool(m["arrived"]),
                    overshoot_mrad=1e3 * m["overshoot_rad"],
                    overshoot_win=m["overshoot_rad"] / m["window_rad"],
                    accel_krad_s2=m["peak_accel_pulse_rad_s2"] / 1e3,
                    accel_ratio=m["accel_ratio_pulse"],
                    cost=float(col.cost[si]),
                    feasible=bool(col.feasible[si] > 0.5),
                )
            )
    n = len(report.scenarios)
    sets = []
    for col in report.columns:
        mine = [r for r in rows if r.settings == col.label]
        settle = [r.settle_ms for r in mine if not math.isnan(r.settle_ms)]
        count = sum(r.feasible for r in mine)
        applies = int(np.isfinite(col.feasible).sum())
        sets.append(
            CompactRow(
                scenario=f"set ({n})",
                settings=col.label,
                settle_ms=float(np.mean(settle)) if settle else math.nan,
                arrived=all(r.arrived for r in mine),
                overshoot_mrad=max(r.overshoot_mrad for r in mine),
                overshoot_win=max(r.overshoot_win for r in mine),
                accel_krad_s2=max(r.accel_krad_s2 for r in mine),
                accel_ratio=max(r.accel_ratio for r in mine),
                cost=col.mean_cost,
                feasible=applies > 0 and count == applies,
                feasible_count=count,
            )
        )
    return CompactTable(rows, sets, n)


def format_compact(report: Report) -> str:
    """The compact table as text, as ``vfgym sweep`` and ``vfgym grid`` print it.

    Parameters
    ----------
    report : Report
        The controllers to show, in column order.

    Returns
    -------
    str
        Each controller on each scenario (a blank line between scenarios) and, for
        several scenarios, over the set; a settling time not reached is starred, that of
        a moving reference is ``-``; a footnote line explains the columns.
    """
    table = compact_rows(report)
    head = (
        f"{'scenario':14s} {'settings':8s} {'settle ms':>10s} {'overshoot mrad':>15s} "
        f"{'(windows)':>9s} {'peak accel krad/s2':>19s} {'/limit':>7s} {'cost':>7s} feasible"
    )
    lines = [head, "-" * len(head)]
    k = len(report.columns)
    groups = [table.rows[i : i + k] for i in range(0, len(table.rows), k)]
    if table.scenario_count > 1:
        groups.append(table.set)
    for g, group in enumerate(groups):
        if g > 0:
            lines.append("")
        for r in group:
            settle = "-" if math.isnan(r.settle_ms) else f"{r.settle_ms:.2f}"
            if not r.arrived:
                settle += "*"
            feas = "yes" if r.feasible else "no"
            if r.feasible_count is not None:
                feas = f"{r.feasible_count}/{table.scenario_count}"
            lines.append(
                f"{r.scenario:14s} {r.settings:8s} {settle:>10s} {r.overshoot_mrad:15.3f} "
                f"{r.overshoot_win:9.2f} {r.accel_krad_s2:19.1f} {r.accel_ratio:7.3f} "
                f"{r.cost:7.4f} {feas}"
            )
    lines.append(
        "settle: settling time into the in-position window (- a moving reference; * did not "
        "arrive: not settled at the end, or a sine not followed); accel: the pulse train's "
        "peak against the limit (the loaded motor's usable acceleration; docs/model.md "
        "§5.1); feasible: at most 1 + the tolerance, Measures.accel_tolerance_pct"
    )
    return "\n".join(lines)
