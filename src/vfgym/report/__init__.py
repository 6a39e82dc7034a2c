"""Comparing controllers: tuned settings against baselines, through the one scoring path.

Every number here comes from :func:`vfgym.evaluate`; this package only arranges and
summarises what it returns.

Modules
-------
_comparison
    Candidates (settings, baselines, per-scenario policies) run on a scenario set into a
    :class:`Report`.
_stats
    Spreads (median, IQR, bootstrap interval) and win / loss / tie.
_tables
    Text and Markdown tables, and the compact table of sweeps and the grid.
_files
    CSV and JSON files of a report in a run folder.
_verdict
    The held-out verdict a sweep ends with: the tuned setting against the baselines on
    the test moves, read off a :class:`Report`.
figures
    The paper's figures, S-curve and frequency plots, overlays, sweep history and Pareto
    front (matplotlib, imported only when a figure is drawn).
"""

from vfgym.report._comparison import (
    EXTRA_METRICS,
    Candidate,
    Column,
    Policy,
    Report,
    baseline_candidates,
    compare,
)
from vfgym.report._files import (
    result_rows,
    results_csv,
    results_json,
    summary_csv,
    summary_rows,
    win_loss_rows,
    write_report,
)
from vfgym.report._stats import DEFAULT_RESAMPLES, TIE_RTOL, Spread, WinLoss, outcome, spread
from vfgym.report._tables import (
    TABLE_COLUMNS,
    CompactRow,
    CompactTable,
    TableColumn,
    compact_rows,
    format_compact,
    format_table,
    markdown_costs,
    markdown_table,
)
from vfgym.report._verdict import (
    VERDICT_BASELINES,
    Verdict,
    VerdictRow,
    axis_verdict,
    format_across,
    format_verdict,
    held_out_verdict,
    verdict,
)

__all__ = [
    "DEFAULT_RESAMPLES",
    "EXTRA_METRICS",
    "TABLE_COLUMNS",
    "TIE_RTOL",
    "VERDICT_BASELINES",
    "Candidate",
    "Column",
    "CompactRow",
    "CompactTable",
    "Policy",
    "Report",
    "Spread",
    "TableColumn",
    "Verdict",
    "VerdictRow",
    "WinLoss",
    "axis_verdict",
    "baseline_candidates",
    "compact_rows",
    "compare",
    "format_across",
    "format_compact",
    "format_table",
    "format_verdict",
    "held_out_verdict",
    "markdown_costs",
    "markdown_table",
    "outcome",
    "result_rows",
    "results_csv",
    "results_json",
    "spread",
    "summary_csv",
    "summary_rows",
    "verdict",
    "win_loss_rows",
    "write_report",
]
