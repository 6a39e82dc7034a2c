"""A report as text and Markdown tables: per scenario and in aggregate, with win / loss."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

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
