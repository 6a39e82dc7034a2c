"""The compact table sweeps and the grid print (report.compact_rows / format_compact): the
main job's table digit for digit from its best settings, its set rows from the per-scenario
ones, and its marks (did not arrive, moving reference, infeasible) on made-up columns."""

# ruff: noqa: E501  (the table as printed)
from __future__ import annotations

import math

import numpy as np
import pytest

from vfgym import PAPER_AXIS, Settings, evaluate, get_scenario
from vfgym.report import Column, Report, compact_rows, format_compact
from vfgym.tuning._results import against_paper

# An earlier main job's best (quick.yaml on three named scenarios, trial 38): a fixed input.
QUICK_BEST = Settings(
    value_rad=0.6371293687865839,
    error_limit_rad=0.5141381797916926,
    k=1140.438031528555,
    ts_over_tf=0.6381667266823572,
)
QUICK_TABLE = """\
scenario       settings  settle ms  overshoot mrad (windows)  peak accel krad/s2  /limit    cost feasible
---------------------------------------------------------------------------------------------------------
paper-step     paper         63.61           1.024      0.17               140.0   1.000  2.4306 yes
paper-step     tuned         55.19           0.472      0.08               141.7   1.012  2.1138 no

short-move     paper         31.12           0.257      0.04               114.5   0.818  8.2381 yes
short-move     tuned         23.14           0.225      0.04                64.5   0.461  6.1267 yes

long-move      paper        273.06           0.680      0.11               140.0   1.000  1.1687 yes
long-move      tuned        314.73           0.402      0.07               141.7   1.012  1.3504 no

set (3)        paper        122.60           1.024      0.17               140.0   1.000  3.9458 3/3
set (3)        tuned        131.02           0.472      0.08               141.7   1.012  3.1970 1/3
settle: settling time into the in-position window (- a moving reference; * did not arrive: \
not settled at the end, or a sine not followed); accel: the pulse train's peak against the \
limit (the loaded motor's usable acceleration; docs/model.md §5.1); feasible: at most 1 + \
the tolerance, Measures.accel_tolerance_pct"""
QUICK = ["paper-step", "short-move", "long-move"]


def test_the_main_jobs_table_digit_for_digit():
    cmp = against_paper(QUICK_BEST, [get_scenario(n) for n in QUICK], "tuned", PAPER_AXIS)
    assert [c.label for c in cmp.columns] == ["paper", "tuned"]
    assert [c.role for c in cmp.columns] == ["baseline", "tuned"]
    assert format_compact(cmp) == QUICK_TABLE


def test_rows_are_evaluates_and_the_set_aggregates_them():
    scens = ["short-move", "paper-sine", "reversal", "test-3"]
    cmp = against_paper(QUICK_BEST, scens, "grid", PAPER_AXIS)
    ev = evaluate([Settings(), QUICK_BEST], scens)
    table = compact_rows(cmp)
    assert table.scenario_count == 4 and len(table.rows) == 8 and len(table.set) == 2
    for r, (si, ci) in zip(table.rows, [(s, c) for s in range(4) for c in range(2)], strict=True):
        m = ev.metrics[ci][si]
        assert r.settings == ("paper", "grid")[ci] and r.scenario == ev.scenarios[si].name
        assert r.cost == ev.cost[ci, si] and r.feasible == bool(ev.feasible[ci, si])
        assert r.accel_ratio == m["accel_ratio_pulse"]
        assert r.overshoot_mrad == 1e3 * m["overshoot_rad"]
        assert math.isnan(r.settle_ms) == ev.scenarios[si].tracking
    for ci, s in enumerate(table.set):
        mine = table.rows[ci::2]
        assert s.scenario == "set (4)" and s.feasible_count == sum(r.feasible for r in mine)
        assert s.cost == ev.mean_cost[ci]  # bit for bit: the sweep's objective
        assert s.overshoot_win == max(r.overshoot_win for r in mine)
        assert s.settle_ms == pytest.approx(
            np.mean([r.settle_ms for r in mine if r.scenario != "paper-sine"])
        )
        assert s.feasible == all(r.feasible for r in mine)
    d = table.as_dict()
    assert list(d) == ["rows", "set"]
    assert (
        "feasible_count" not in d["rows"][0]
        and d["set"][1]["feasible_count"] == table.set[1].feasible_count
    )


def _column(label, rows):
    """A made-up column: (cost, feasible, arrived, settling ms, overshoot mrad) per scenario."""
    metrics = [
        {
            "settling_time_s": t / 1e3,
            "arrived": arrived,
            "overshoot_rad": ov / 1e3,
            "window_rad": 6e-3,
            "peak_accel_pulse_rad_s2": 7e4,
            "accel_ratio_pulse": 0.5,
        }
        for _, _, arrived, t, ov in rows
    ]
    cons = np.array(
        [[-1.0, 0.0, -0.5, -1.0] if ok else [0.2, 0.0, -0.5, 0.3] for _, ok, *_ in rows]
    )
    cost = np.array([c for c, *_ in rows])
    return Column(label, "tuned", "", [None] * len(rows), cost, cons, metrics)


def test_marks_on_made_up_columns():
    scens = [get_scenario("short-move"), get_scenario("paper-sine")]
    a = _column("a", [(2.0, True, True, 10.0, 0.0), (3.0, True, True, 0.0, 0.0)])
    b = _column("b", [(5.0, False, False, 80.0, 12.0), (1.0, True, True, 0.0, 0.0)])
    text = format_compact(Report(scens, [a, b], PAPER_AXIS))
    lines = [" ".join(x.split()) for x in text.splitlines()]  # cells one space apart
    assert lines[2:10] == [
        "short-move a 10.00 0.000 0.00 70.0 0.500 2.0000 yes",
        "short-move b 80.00* 12.000 2.00 70.0 0.500 5.0000 no",
        "",
        "paper-sine a - 0.000 0.00 70.0 0.500 3.0000 yes",  # a moving reference: no settling
        "paper-sine b - 0.000 0.00 70.0 0.500 1.0000 yes",
        "",
        "set (2) a 10.00 0.000 0.00 70.0 0.500 2.5000 2/2",
        "set (2) b 80.00* 12.000 2.00 70.0 0.500 3.0000 1/2",
    ]
    assert not compact_rows(Report(scens, [a, b], PAPER_AXIS)).set[1].feasible
    one = format_compact(Report(scens[:1], [a, b], PAPER_AXIS)).splitlines()
    assert len(one) == 5 and not any(
        x.startswith("set (") for x in one
    )  # one scenario: no set rows
