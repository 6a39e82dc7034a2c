"""The evaluation report: its numbers are vfgym.evaluate's, its spreads and win/loss are
right on known data, policies plug in per scenario, and the files read back."""

from __future__ import annotations

import csv
import io
import json
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from vfgym import Settings, evaluate
from vfgym.moves.baselines import rule_of_thumb
from vfgym.report import (
    Candidate,
    compare,
    format_table,
    markdown_costs,
    markdown_table,
    outcome,
    results_csv,
    results_json,
    spread,
    summary_csv,
    write_report,
)

TUNED = Settings(value_rad=0.6, error_limit_rad=0.6, k=300.0, ts_over_tf=0.3)
SCENS = ["short-move", "paper-sine", "test-3", "test-7"]


@pytest.fixture(scope="module")
def report():
    return compare(
        [Candidate("tuned", TUNED)],
        ["paper", "fixed-frequency", "scurve"],
        SCENS,
        resamples=500,
    )


# --- spread ----------------------------------------------------------------------------------


def test_spread_known_values():
    s = spread([4.0, 1.0, 3.0, 2.0, math.nan], resamples=200, seed=1)
    assert s.n == 4
    assert (s.median, s.q1, s.q3, s.mean) == (2.5, 1.75, 3.25, 2.5)
    assert 1.0 <= s.ci_low <= s.mean <= s.ci_high <= 4.0
    assert spread([4.0, 1.0, 3.0, 2.0], resamples=200, seed=1) == s  # seeded: reproducible
    assert spread([4.0, 1.0, 3.0, 2.0], resamples=200, seed=2) != s
    one = spread([7.0])
    assert one.n == 1 and one.ci_low == one.ci_high == one.mean == 7.0
    empty = spread([math.nan])
    assert empty.n == 0 and math.isnan(empty.median) and math.isnan(empty.ci_low)


def test_bootstrap_interval_matches_the_normal_approximation():
    x = np.random.default_rng(5).normal(10.0, 2.0, 400)
    s = spread(x, resamples=4000, seed=0)
    half = 1.96 * x.std(ddof=1) / math.sqrt(x.size)
    assert s.ci_low == pytest.approx(x.mean() - half, abs=0.15 * half)
    assert s.ci_high == pytest.approx(x.mean() + half, abs=0.15 * half)


@settings(max_examples=40, deadline=None)
@given(st.lists(st.floats(-1e6, 1e6), min_size=1, max_size=30))
def test_spread_orders(values):
    s = spread(values, resamples=100)
    lo, hi = min(values), max(values)
    tol = 1e-9 * (1 + max(abs(lo), abs(hi)))
    assert lo - tol <= s.q1 <= s.median + tol and s.median <= s.q3 + tol <= hi + 2 * tol
    assert lo - tol <= s.ci_low <= s.ci_high <= hi + tol
    assert s.n == len(values)


def test_outcome():
    assert outcome(1.0, 2.0) == "win"
    assert outcome(2.0, 1.0) == "loss"
    assert outcome(1.0, 1.0 + 1e-12) == "tie"
    assert outcome(1.0, math.nan) == "n/a"
    assert outcome(math.nan, 1.0) == "n/a"


# --- one scoring path ------------------------------------------------------------------------


def test_numbers_are_evaluates(report):
    ev = evaluate([TUNED, "paper", "fixed-frequency", "scurve"], SCENS)
    for i, col in enumerate(report.columns):
        np.testing.assert_array_equal(col.cost, ev.cost[i])
        np.testing.assert_array_equal(col.constraints, ev.constraints[i])
        for si in range(len(SCENS)):
            assert col.metrics[si] == pytest.approx(ev.metrics[i][si], nan_ok=True)
    assert [c.label for c in report.columns] == ["tuned", "paper", "fixed-frequency", "scurve"]


def test_win_loss_counts(report):
    tuned = report.column("tuned").cost
    for w in report.win_losses():
        base = report.column(w.baseline).cost
        ok = np.isfinite(base)
        assert w.wins == int(np.sum(tuned[ok] < base[ok]))
        assert w.losses == int(np.sum(tuned[ok] > base[ok]))
        assert w.wins + w.losses + w.ties + w.not_applicable == len(SCENS)
        assert w.cost_diff.n == int(ok.sum())
        assert w.cost_diff.mean == pytest.approx(float(np.mean(tuned[ok] - base[ok])))
    ff = report.win_loss("tuned", "fixed-frequency")
    assert ff.outcomes[SCENS.index("paper-sine")] == "n/a"  # a pulse source cannot follow a sine
    assert ff.not_applicable == 1
    assert report.spread("fixed-frequency", "cost").n == len(SCENS) - 1


def test_policy_is_scored_per_scenario():
    # an "agent" that picks the rule of thumb for each scenario's own plant ties with it
    scens = ["heavy-load", "short-move", "test-1"]

    def rot(sc):
        return rule_of_thumb(sc.plant())

    r = compare([Candidate("agent", policy=rot)], ["rule-of-thumb", "paper"], scens)
    w = r.win_loss("agent", "rule-of-thumb")
    assert w.ties == 3 and w.wins == w.losses == 0
    np.testing.assert_array_equal(r.column("agent").cost, r.column("rule-of-thumb").cost)
    # settings that differ per scenario: each scenario's cost is evaluate()'s for its own
    picks = {"heavy-load": TUNED, "short-move": Settings(), "test-1": TUNED.replace(k=50.0)}
    r = compare([Candidate("agent", policy=lambda sc: picks[sc.name])], [], scens)
    for si, name in enumerate(scens):
        assert r.column("agent").cost[si] == evaluate(picks[name], [name]).cost[0, 0]
        assert r.column("agent").controllers[si] == picks[name]
    with pytest.raises(ValueError, match=r"a tuner gives vfgym\.Settings"):
        compare([Candidate("bad", policy=lambda sc: "paper")], [], ["short-move"])


def test_bad_input():
    with pytest.raises(ValueError, match="baseline='bogus'"):
        compare([Candidate("t", TUNED)], "paper,bogus", ["short-move"])
    with pytest.raises(ValueError, match="given twice"):
        compare([Candidate("paper", TUNED)], "paper", ["short-move"])
    with pytest.raises(ValueError, match="exactly one"):
        Candidate("x")
    with pytest.raises(ValueError, match="scenario='nowhere'"):
        compare([Candidate("t", TUNED)], "paper", ["nowhere"])


# --- outputs ---------------------------------------------------------------------------------


def test_files_read_back(report, tmp_path):
    paths = write_report(report, tmp_path)
    assert sorted(paths) == ["results.csv", "results.json", "summary.csv", "table.txt"]
    rows = list(csv.DictReader(io.StringIO(results_csv(report))))
    assert len(rows) == len(SCENS) * 4
    tuned = [r for r in rows if r["controller"] == "tuned"]
    assert [float(r["cost"]) for r in tuned] == list(report.column("tuned").cost)
    assert [r["vs_paper"] for r in tuned] == list(report.win_loss("tuned", "paper").outcomes)
    sine_ff = next(
        r
        for r in rows
        if r["scenario"] == "paper-sine"
        and r["role"] == "baseline"
        and r["controller"] == "fixed-frequency"
    )
    assert sine_ff["cost"] == "" and sine_ff["feasible"] == ""
    assert float(tuned[0]["value_rad"]) == TUNED.value_rad

    def no_nan(tok):
        raise AssertionError(f"{tok} in JSON")

    data = json.loads(results_json(report), parse_constant=no_nan)
    assert [s["name"] for s in data["scenarios"]] == SCENS
    assert data["bootstrap"]["resamples"] == 500
    agg = {(a["controller"], a["measure"]): a for a in data["aggregate"]}
    s = report.spread("tuned", "cost")
    assert agg[("tuned", "cost")]["median"] == s.median and agg[("tuned", "cost")]["n"] == 4
    wl = {(w["tuned"], w["baseline"]): w for w in data["win_loss"]}
    assert wl[("tuned", "fixed-frequency")]["outcomes"]["paper-sine"] == "n/a"
    summary = list(csv.DictReader(io.StringIO(summary_csv(report))))
    assert {r["measure"] for r in summary} >= {"cost", "overshoot_counts", "cost_diff"}


def test_text_tables(report):
    text = format_table(report)
    for name in (*SCENS, "tuned", "scurve", "median [IQR]", "95 % CI", "win rate"):
        assert name in text
    md = markdown_table(report)
    assert "| tuned | 4 |" in md and "| fixed-frequency | 3 |" in md  # n: where it applies
    assert "| tuned | paper |" in md


def test_tables_mark_runs_that_did_not_arrive():
    never = Settings(value_rad=1e9, error_limit_rad=1e9)  # emits no pulse
    r = compare([Candidate("still", never)], ["paper"], ["short-move", "paper-sine"])
    text = format_table(r)
    head, *rows = text.splitlines()[2:7]
    assert head.split()[-4:] == ["feasible", "arrived", "vs", "paper"]
    for row in rows:  # still: ... no no loss; paper: ... yes yes
        cells = row.split()
        assert cells[-3:] == ["no", "no", "loss"] if "still" in row else cells[-2:] == ["yes"] * 2
    assert "0/2 arrived" in text and "2/2 arrived" in text
    assert "did not arrive" in text  # the legend
    costs = markdown_costs(r).splitlines()[2:]
    assert all(c.split("|")[2].strip().endswith("*†") for c in costs)  # still: never arrives
    assert not any("†" in c.split("|")[3] for c in costs)  # the paper's arrive
    assert "| arrived |" in markdown_table(r).splitlines()[0] + "|"
    rows = list(csv.DictReader(io.StringIO(results_csv(r))))
    assert [row["arrived"] for row in rows] == ["False", "True", "False", "True"]
    assert all(float(row["constraint_arrival"]) > 0 for row in rows[::2])
