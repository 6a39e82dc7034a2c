"""The aggregate a sweep minimises over its moves (mean, CVaR, worst) and the rule that a
setting is feasible only if it is feasible on every move."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import optuna
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from vfgym import cli, tuning
from vfgym.axis import load_axis
from vfgym.params import PAPER_SETTINGS
from vfgym.scoring import CONSTRAINTS, Evaluation, evaluate
from vfgym.tuning import AGGREGATES, aggregate, aggregate_costs
from vfgym.tuning._aggregate import check_aggregate


def cvar(costs, alpha=0.25) -> float:
    return float(aggregate_costs(costs, "cvar", alpha))


AXES = Path(__file__).resolve().parents[2] / "experiments" / "axes"

COSTS = np.array([[3.0, 1.0, 4.0, 2.0], [5.0, 5.0, 5.0, 5.0]])


@pytest.mark.parametrize(
    ("how", "alpha", "want"),
    [
        ("mean", 0.25, [2.5, 5.0]),
        ("worst", 0.25, [4.0, 5.0]),
        ("cvar", 0.25, [4.0, 5.0]),  # the worst quarter of four moves: the worst one
        ("cvar", 0.5, [3.5, 5.0]),  # the worst half: (4 + 3) / 2
        ("cvar", 0.3, [(0.25 * 4.0 + 0.05 * 3.0) / 0.3, 5.0]),  # 3 in part
        ("cvar", 1.0, [2.5, 5.0]),  # all of them: the mean
        ("cvar", 0.01, [4.0, 5.0]),  # less than one move's share: the worst
    ],
)
def test_aggregates_of_made_up_costs(how, alpha, want):
    assert aggregate_costs(COSTS, how, alpha) == pytest.approx(want, rel=1e-15)
    # one controller as a 1-D row
    assert float(aggregate_costs(COSTS[0], how, alpha)) == pytest.approx(want[0], rel=1e-15)


def test_undefined_costs_are_left_out():
    row = [np.nan, 2.0, 6.0, np.nan]
    assert float(aggregate_costs(row, "mean")) == 4.0
    assert float(aggregate_costs(row, "worst")) == 6.0
    assert float(aggregate_costs(row, "cvar", 0.5)) == 6.0
    assert math.isnan(float(aggregate_costs([np.nan, np.nan], "mean")))
    assert math.isnan(cvar([]))


costs_st = st.lists(st.floats(0.0, 1e3, allow_nan=False), min_size=1, max_size=40)
alpha_st = st.floats(1e-6, 1.0)


@settings(max_examples=200, deadline=None)
@given(costs_st, alpha_st, alpha_st)
def test_cvar_lies_between_the_mean_and_the_worst_and_grows_as_alpha_shrinks(x, a, b):
    mean, worst = float(np.mean(x)), max(x)
    c = cvar(x, a)
    tol = 1e-9 * max(1.0, worst)
    assert mean - tol <= c <= worst + tol
    lo, hi = sorted((a, b))
    assert cvar(x, lo) >= cvar(x, hi) - tol
    assert cvar(x, 1.0) == pytest.approx(mean, rel=1e-12, abs=1e-12)
    assert cvar(x, 1.0 / len(x)) == pytest.approx(worst, rel=1e-12)
    assert cvar(x[::-1], a) == pytest.approx(c, rel=1e-12, abs=1e-12)  # order does not count


@settings(max_examples=100, deadline=None)
@given(costs_st, st.integers(1, 40))
def test_cvar_of_a_whole_number_of_moves_is_the_mean_of_the_costliest(x, k):
    k = min(k, len(x))
    top = sorted(x, reverse=True)[:k]
    assert cvar(x, k / len(x)) == pytest.approx(float(np.mean(top)), rel=1e-12, abs=1e-12)


@pytest.mark.parametrize(
    ("how", "alpha", "name"),
    [
        ("median", 0.25, "aggregate"),
        ("Mean", 0.25, "aggregate"),
        ("cvar", 0.0, "cvar_alpha"),
        ("cvar", 1.5, "cvar_alpha"),
        ("cvar", -0.1, "cvar_alpha"),
        ("cvar", float("nan"), "cvar_alpha"),
        ("cvar", "a quarter", "cvar_alpha"),
    ],
)
def test_bad_aggregates_name_the_parameter(how, alpha, name):
    with pytest.raises(ValueError, match=f"^{name}=") as exc:
        check_aggregate(how, alpha)
    assert "\n" not in str(exc.value)
    with pytest.raises(ValueError, match=f"^{name}="):
        tuning.SweepConfig(aggregate=how, cvar_alpha=alpha)


def _made_up(cons: np.ndarray) -> Evaluation:
    n_ctrl, n_moves = cons.shape[:2]
    cost = np.ones((n_ctrl, n_moves))
    return Evaluation([], [], [], cost, cons, np.zeros((n_ctrl, n_moves, 3)))


def test_feasible_only_if_feasible_on_every_move():
    k = len(CONSTRAINTS)
    cons = -np.ones((3, 4, k))
    cons[1, 2, k - 1] = 1e-9  # one constraint on one move, barely violated
    cons[2, :, 0] = 0.0  # on the bound everywhere: feasible
    agg = aggregate(_made_up(cons))
    assert agg.feasible.tolist() == [True, False, True]
    assert agg.constraints[1, k - 1] == 1e-9  # the worst over the moves
    for how in AGGREGATES:  # feasibility does not depend on the aggregate
        assert aggregate(_made_up(cons), how).feasible.tolist() == [True, False, True]


def test_the_objective_minimises_the_aggregate_and_needs_every_train_move():
    axis = load_axis(AXES / "vertical.yaml")
    train = axis.scenarios("train")
    on = {"axis": axis}
    ev = evaluate(PAPER_SETTINGS, train, **on)
    ok = [sc for sc, f in zip(train, ev.feasible[0], strict=True) if f]
    bad = [sc for sc, f in zip(train, ev.feasible[0], strict=True) if not f]
    assert ok and bad  # the paper's settings: feasible on some of the vertical axis's moves
    for how, want in (
        ("mean", float(ev.cost[0].mean())),
        ("worst", float(ev.cost[0].max())),
        ("cvar", float(np.mean(np.sort(ev.cost[0])[::-1][: len(train) // 4]))),
    ):
        obj = tuning.Objective(train, ("rise",), "cost", **on, aggregate=how, cvar_alpha=0.25)
        (value, attrs) = obj.score_many([PAPER_SETTINGS])[0]
        assert value == pytest.approx(want, rel=1e-12) and attrs["cost"] == value
        assert attrs["feasible"] is False
    (ok_res,) = tuning.Objective(ok, ("rise",), "cost", **on).score_many([PAPER_SETTINGS])
    assert ok_res.attrs["feasible"]
    mixed = tuning.Objective([ok[0], bad[0]], ("rise",), "cost", **on)
    assert mixed.score_many([PAPER_SETTINGS])[0].attrs["feasible"] is False


def sweep(tmp_path: Path, *extra: str, study: str = "s") -> int:
    return cli.main(
        ["sweep", "--runs-dir", str(tmp_path), "--study", study, "--no-progress", "--no-plots",
         *extra]
    )  # fmt: skip


def test_a_worst_case_sweep_scores_each_trial_by_its_costliest_move(tmp_path, capsys):
    scen = "short-move,reversal,paper-step"
    assert sweep(tmp_path, "--trials", "4", "--scenarios", scen, "--aggregate", "worst") == 0
    out = capsys.readouterr().out
    storage = tuning.open_storage(tuning.resolve_storage("sqlite", tmp_path / "sweep" / "s"))
    study = optuna.load_study(study_name="s", storage=storage)
    for t in study.trials:
        ev = evaluate(tuning.trial_settings(t), scen.split(","))
        assert t.value == pytest.approx(float(ev.cost[0].max()), rel=1e-12)
    paper = float(evaluate(PAPER_SETTINGS, scen.split(",")).cost[0].max())
    assert f"worst cost {tuning.best_trial(study).value:.4f}" in out
    assert f"against the paper's {paper:.4f}" in out
    # a study keeps its aggregate: continuing it with another is refused
    assert sweep(tmp_path, "--trials", "5", "--scenarios", scen) == 2
    err = capsys.readouterr().err
    assert "aggregate" in err and "'worst'" in err and len(err.strip().splitlines()) == 1


@pytest.mark.parametrize(
    ("args", "option"),
    [
        (["--aggregate", "median"], "aggregate"),
        (["--aggregate", ""], "aggregate"),
        (["--aggregate", "cvar", "--cvar-alpha", "0"], "cvar_alpha"),
        (["--cvar-alpha", "2"], "cvar_alpha"),
    ],
)
def test_bad_aggregate_options_exit_2_with_one_line(tmp_path, capsys, args, option):
    assert sweep(tmp_path, *args) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1, err
    assert err.startswith(f"vfgym sweep: error: {option}=")
    assert not (tmp_path / "sweep").exists()
