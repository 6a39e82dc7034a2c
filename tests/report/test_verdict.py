"""The held-out verdict: its numbers are report.compare's (and so vfgym.evaluate's) on the
same moves, it names moves that were tuned on, and a sweep ends with it."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest
import yaml

from vfgym import PAPER_SETTINGS, Scenario, Settings, cli, evaluate
from vfgym.axis import PAPER_AXIS, load_axis
from vfgym.commands._common import load_settings
from vfgym.moves.distribution import scenario_set
from vfgym.report import (
    VERDICT_BASELINES,
    Candidate,
    axis_verdict,
    baseline_candidates,
    compare,
    format_verdict,
    held_out_verdict,
    verdict,
)

AXES = Path(__file__).resolve().parents[2] / "experiments" / "axes"
TUNED = Settings(value_rad=0.75, error_limit_rad=0.66, k=470.0, ts_over_tf=0.98)
MOVES = scenario_set("test", 12, 0) + scenario_set("paper-sine")  # a pulse source: n/a on a sine


@pytest.fixture(scope="module")
def held_out():
    return held_out_verdict(TUNED, MOVES, axis=PAPER_AXIS)


def test_the_verdict_numbers_are_compare_s_on_the_same_moves(held_out):
    rep = compare([Candidate("tuned", TUNED)], baseline_candidates(VERDICT_BASELINES), MOVES)
    assert [r.label for r in held_out.rows] == ["tuned", *VERDICT_BASELINES]
    for r in held_out.rows:
        col = rep.column(r.label)
        assert r.cost == rep.spread(r.label, "cost")
        assert r.feasible == int(np.nansum(col.feasible))
        assert r.applicable == int(np.isfinite(col.cost).sum())
        if r.label == "tuned":
            assert r.versus is None
        else:
            assert r.versus == rep.win_loss("tuned", r.label)


def test_the_verdict_numbers_are_the_scoring_path_s(held_out):
    """The same numbers from vfgym.evaluate directly, counted with numpy."""
    ev = evaluate([TUNED, *VERDICT_BASELINES], MOVES)
    tuned = ev.cost[0]
    for i, r in enumerate(held_out.rows):
        cost = ev.cost[i]
        ok = np.isfinite(cost)
        assert r.applicable == int(ok.sum())
        assert r.feasible == int((ev.feasible[i] & ok).sum())
        assert r.cost.median == pytest.approx(float(np.median(cost[ok])), rel=1e-12)
        q1, q3 = np.percentile(cost[ok], [25, 75])
        assert (r.cost.q1, r.cost.q3) == pytest.approx((q1, q3), rel=1e-12)
        assert r.cost.mean == pytest.approx(float(cost[ok].mean()), rel=1e-12)
        if i == 0:
            continue
        w = r.versus
        both = ok & np.isfinite(tuned)
        assert w.wins == int((tuned[both] < cost[both]).sum())
        assert w.losses == int((tuned[both] > cost[both]).sum())
        assert w.not_applicable == int((~both).sum())
        d = tuned[both] - cost[both]
        assert w.cost_diff.mean == pytest.approx(float(d.mean()), rel=1e-9, abs=1e-12)
        assert w.cost_diff.ci_low <= w.cost_diff.mean <= w.cost_diff.ci_high
    assert held_out.row("scurve").versus.not_applicable == 1  # the sine


def test_the_printed_verdict_shows_the_numbers(held_out):
    text = format_verdict(held_out)
    lines = text.splitlines()
    assert lines[0].startswith("held-out verdict: tuned against the baselines on 13 moves")
    assert "(not tuned on)" in lines[0]
    for r in held_out.rows:
        row = next(line for line in lines if line.startswith(r.label + " "))
        assert f"{r.feasible}/{r.applicable}" in row
        assert f"{r.cost.median:.3g} [{r.cost.q1:.3g}, {r.cost.q3:.3g}]" in row
        if r.versus is not None:
            w = r.versus
            assert f"{w.wins}/{w.losses}/{w.ties}" in row
            d = w.cost_diff
            assert f"{d.mean:.3g} ({d.ci_low:.3g}, {d.ci_high:.3g})" in row
    p = held_out.row("paper").versus
    assert f"beats paper on {p.wins}/{p.wins + p.losses + p.ties}" in text


def test_a_setting_that_loses_on_most_moves_is_told_so_plainly(held_out):
    """The last line names the baseline it loses to on most moves and points to per-move
    settings; a setting that wins has no such line."""
    assert held_out.losing_to() == ()
    assert "loses to" not in format_verdict(held_out) and "vfgym fit" not in format_verdict(
        held_out
    )
    poor = Settings(value_rad=3.0, error_limit_rad=3.0, k=900.0, ts_over_tf=0.1)
    v = held_out_verdict(poor, MOVES[:6], axis=PAPER_AXIS, baselines=("paper", "scurve"))
    assert [r.label for r in v.losing_to()] == ["paper", "scurve"]
    last = format_verdict(v, axis_file="belt.yaml").splitlines()[-1]
    w = v.row("paper").versus
    assert last.startswith(f"tuned loses to paper on {w.losses}/{w.wins + w.losses + w.ties}")
    assert "scurve on" in last and last.endswith("vfgym fit --axis belt.yaml")
    # a fitted per-move model's verdict names the baseline without sending the user to fit
    fitted = format_verdict(v, axis_file="belt.yaml", per_move=True).splitlines()[-1]
    assert fitted.startswith("tuned loses to paper") and "vfgym fit" not in fitted
    # most, not some: half the moves lost is not most
    half = dataclasses.replace(w, outcomes=("win", "loss") * 3)
    row = dataclasses.replace(v.row("paper"), versus=half)
    assert dataclasses.replace(v, rows=(v.rows[0], row)).losing_to() == ()


def test_moves_tuned_on_are_named_whatever_their_name():
    moves = scenario_set("test", 3, 0)
    renamed = [dataclasses.replace(moves[1], name="mine")]
    v = held_out_verdict(TUNED, moves, axis=PAPER_AXIS, baselines="paper", tuned_on=renamed)
    assert v.seen == (moves[1].name,)
    assert "(1 of them also tuned on)" in format_verdict(v)
    assert held_out_verdict(
        TUNED, moves, axis=PAPER_AXIS, baselines="paper", tuned_on=moves[:1]
    ).seen == (moves[0].name,)


def test_a_verdict_needs_a_tuned_candidate_and_a_baseline():
    with pytest.raises(ValueError, match="tuned candidate"):
        verdict(compare([], ["paper"], MOVES[:1]))
    with pytest.raises(ValueError, match="baseline"):
        verdict(compare([Candidate("t", TUNED)], [], MOVES[:1]))


def test_the_axis_verdict_is_on_the_axis_test_moves():
    axis = load_axis(AXES / "vertical.yaml")
    v = axis_verdict(TUNED, axis)
    assert v.report.scenarios == axis.scenarios("test")
    assert v.title == "the 32 test moves of axis vertical"
    ev = evaluate(TUNED, axis.scenarios("test"), axis=axis)
    assert v.rows[0].cost.mean == pytest.approx(float(ev.cost[0].mean()), rel=1e-12)
    # no axis: the paper's, whose test moves are the random test set
    assert axis_verdict(TUNED, PAPER_AXIS).report.scenarios == scenario_set("test", 32, 0)
    assert PAPER_AXIS.scenarios("test") == scenario_set("test", 32, 0)


def test_a_sweep_ends_with_the_held_out_verdict(tmp_path, capsys):
    """The smoke run: `vfgym sweep --axis experiments/axes/vertical.yaml --trials 3`."""
    path = str(AXES / "vertical.yaml")
    code = cli.main(
        ["sweep", "--axis", path, "--trials", "3", "--runs-dir", str(tmp_path), "--study", "s",
         "--no-progress", "--no-plots"]
    )  # fmt: skip
    assert code == 0
    out = capsys.readouterr().out
    run = tmp_path / "sweep" / "s"
    axis = load_axis(path)
    best = load_settings(str(run / "best.yaml"), axis)
    want = format_verdict(axis_verdict(best, axis, tuned_on=axis.scenarios("train")), path)
    assert out.rstrip().endswith(want)  # the report ends with it, as printed
    assert (run / "report.txt").read_text().rstrip().endswith(want)
    assert (
        "held-out verdict: tuned against the baselines on the 32 test moves of axis vertical" in out
    )
    summary = yaml.safe_load((run / "summary.yaml").read_text())
    rows = {r["controller"]: r for r in summary["verdict"]["controllers"]}
    ev = evaluate([best, "paper"], axis.scenarios("test"), axis=axis)
    assert rows["tuned"]["feasible"] == int(ev.feasible[0].sum())
    assert rows["paper"]["wins"] == int((ev.cost[0] < ev.cost[1]).sum())
    assert summary["verdict"]["seen_in_tuning"] == []
    assert not math.isnan(rows["tuned"]["cost"]["mean"])


def test_a_verdict_says_why_it_will_surprise_moves_outside_the_tuning_and_limits_broken():
    """Tuned on short steps only, a setting whose error limit winds up breaks the limits on
    long held-out steps: the verdict names the test moves that lie outside the moves tuned
    on (what lies outside, against the range tuned on), and the moves it breaks a limit on
    with the limit, the worst first; a move inside the range is not named."""
    short = [Scenario(name=f"short-{i}", profile="step", distance_rad=d, duration_s=0.15)
             for i, d in enumerate((0.5, 1.0, 2.0, 3.0))]  # fmt: skip
    test = [Scenario(name=f"long-{i}", profile="step", distance_rad=d, duration_s=0.4)
            for i, d in enumerate((1.5, 40.0, 60.0))]  # fmt: skip
    winds_up = Settings(value_rad=0.5, error_limit_rad=2.0, k=60.0)
    v = held_out_verdict(winds_up, test, axis=PAPER_AXIS, baselines="paper", tuned_on=short,
                         across=False)  # fmt: skip
    assert [name for name, _ in v.outside] == ["long-1", "long-2"]
    assert dict(v.outside)["long-1"] == "distance 40 rad (tuned on 0.5 to 3)"
    assert [name for name, _ in v.worst] == ["long-2", "long-1", "long-0"]  # worst first
    assert "acceleration" in dict(v.worst)["long-1"] and "overshoot" in dict(v.worst)["long-1"]
    text = format_verdict(v)
    assert "warning: tuned breaks a limit on 3/3 test moves, worst long-2: acceleration" in text
    assert "warning: 2/3 test moves lie outside the moves tuned on" in text
    assert v.to_dict()["outside_tuning"] == dict(v.outside)
    # the paper's settings hold every limit there, and nothing tuned on: nothing to say
    quiet = held_out_verdict(PAPER_SETTINGS, test, axis=PAPER_AXIS, baselines="scurve",
                             across=False)  # fmt: skip
    assert quiet.outside == () and quiet.worst == ()
    assert "warning" not in format_verdict(quiet)
