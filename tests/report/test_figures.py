"""Figures: the signals they draw agree with the measures, the panels show what they claim,
sweep folders give history and Pareto plots, and ``vfgym plot`` writes PNGs."""

from __future__ import annotations

import numpy as np
import optuna
import pytest
import yaml

from vfgym import Settings, evaluate
from vfgym.cli import main
from vfgym.moves.baselines import scurve
from vfgym.params import PAPER_PLANT
from vfgym.report.figures import (
    compare_figure,
    frequency_figure,
    history_figure,
    importances_figure,
    motor_accel,
    objective_points,
    pareto_figure,
    pareto_mask,
    pulse_accel,
    pulse_frequency,
    pulse_speed,
    response_figure,
    scurve_figure,
)
from vfgym.scoring import CONSTRAINTS, OBJECTIVES

PNG = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def step_traces():
    ev = evaluate(["paper", "fixed-frequency"], ["paper-step"], keep_traces=True)
    return ev, ev.traces[0][0], ev.traces[1][0]


def test_pulse_signals_agree_with_the_measures(step_traces):
    ev, vf, ff = step_traces
    _, a = pulse_accel(vf)
    assert np.abs(a).max() == pytest.approx(ev.metrics[0][0]["peak_accel_pulse_rad_s2"], rel=1e-12)
    _, a = pulse_accel(ff)
    assert np.abs(a).max() == pytest.approx(ev.metrics[1][0]["peak_accel_pulse_rad_s2"], rel=1e-12)
    # cruise at one pulse a tick: speed δ·f; the fixed-frequency train at f/2 = 70 kHz
    t, v = pulse_speed(vf)
    cruise = (t > 0.008) & (t < 0.018)
    np.testing.assert_allclose(v[cruise], PAPER_PLANT.pulse_top_speed_rad_s, rtol=1e-12)
    t, f = pulse_frequency(ff)
    assert f.max() == pytest.approx(70e3, rel=1e-12)
    assert np.all(f[(t > 0.005) & (t < 0.04)] == pytest.approx(70e3, rel=1e-12))


def test_decimated_traces_give_the_same_signals():
    ev1 = evaluate("paper", ["short-move"], keep_traces=True)
    ev7 = evaluate("paper", ["short-move"], keep_traces=True, decimation=7)
    t1, t7 = ev1.traces[0][0], ev7.traces[0][0]
    for fn in (pulse_speed, pulse_accel):
        x1, y1 = fn(t1, 0.7e-3)
        x7, y7 = fn(t7, 0.7e-3)  # 98 ticks = 14 samples of 7
        np.testing.assert_allclose(x7, x1[6::7], rtol=1e-12, atol=1e-15)
        np.testing.assert_allclose(y7, y1[6::7], rtol=1e-12, atol=1e-9)


@pytest.mark.parametrize("stride", [1, 5])
def test_motor_acceleration_integrates_to_the_speed(step_traces, stride):
    _, vf, _ = step_traces
    _, a = motor_accel(vf, stride)
    dt = vf.plant.tick_s
    np.testing.assert_allclose(
        np.cumsum(a) * stride * dt, vf.speed_rad_s[stride - 1 :: stride], atol=1e-9
    )


def _lines(ax):
    return {ln.get_label(): ln for ln in ax.get_lines()}


def test_response_figure_shows_limit_and_peaks(step_traces, tmp_path):
    ev, vf, _ = step_traces
    fig = response_figure(vf, title="paper-step", metrics=ev.metrics[0][0], max_points=800)
    axes = fig.get_axes()
    assert len(axes) == 4
    acc = _lines(axes[3])
    lim = next(ln for k, ln in acc.items() if k.startswith("motor limit"))
    assert set(lim.get_ydata()) == {140.0}
    assert any(np.all(np.asarray(ln.get_ydata()) == -140.0) for ln in axes[3].get_lines())
    pulse_line = next(ln for k, ln in acc.items() if k.startswith("pulse train"))
    # thinned for drawing, the pulse train's peak is still near the measured 1.000× limit
    peak = ev.metrics[0][0]["peak_accel_pulse_rad_s2"] / 1e3
    assert 0.9 * peak <= np.abs(pulse_line.get_ydata()).max() <= peak + 1e-9
    pos = _lines(axes[0])
    assert {"command P", "pulse train n·δ", "motor θ"} <= set(pos)
    assert pos["motor θ"].get_ydata()[-1] == pytest.approx(10.0, abs=0.01)
    out = tmp_path / "r.png"
    fig.savefig(out, dpi=30)
    assert out.read_bytes()[:8] == PNG


def test_scurve_figure_triangle_prevention():
    fig = scurve_figure(short_rad=1.0, long_rad=10.0)
    ax_short, ax_long = fig.get_axes()[0], fig.get_axes()[1]
    short = _lines(ax_short)
    on = short["triangle prevention on (rule of 1/12)"].get_ydata()
    off = short["prevention off (triangle)"].get_ydata()
    dv = scurve(PAPER_PLANT).speed_rad_s
    assert on.max() < off.max() < dv  # the short move never reaches the drive speed
    assert any(k.startswith("P/12 pulses out") for k in short)
    long_speed = _lines(ax_long)["reaches drive speed"].get_ydata()
    assert long_speed.max() == pytest.approx(dv, rel=1e-9)
    # the triangle's acceleration jumps at its peak; with prevention it passes through 0
    acc = _lines(fig.get_axes()[2])
    a_off = acc["prevention off (triangle)"].get_ydata()
    a_on = acc["triangle prevention on (rule of 1/12)"].get_ydata()
    assert np.abs(np.diff(a_off)).max() > 100.0  # krad/s² in one step of the drawing grid
    assert np.abs(np.diff(a_on)).max() < 5.0


def test_frequency_and_compare_figures(step_traces, tmp_path):
    _, vf, ff = step_traces
    fig = frequency_figure({"V-F": vf, "fixed": ff}, max_points=500)
    lines = _lines(fig.get_axes()[0])
    assert lines["fixed"].get_ydata().max() == pytest.approx(70.0)
    assert lines["V-F"].get_ydata().max() == pytest.approx(140.0)
    fig = compare_figure({"V-F": vf, "fixed": ff}, title="t", max_points=500)
    assert len(fig.get_axes()) == 4
    fig.savefig(tmp_path / "c.png", dpi=30)
    ev = evaluate(["paper", Settings(k=100.0)], ["paper-sine"], keep_traces=True, decimation=5)
    fig = compare_figure({"a": ev.traces[0][0], "b": ev.traces[1][0]}, tracking=True)
    fig.savefig(tmp_path / "s.png", dpi=30)


# --- sweeps ------------------------------------------------------------------------------


def test_pareto_mask():
    pts = np.array([[1, 3], [2, 2], [3, 1], [2, 3], [3, 3], [1, 3]])
    assert pareto_mask(pts).tolist() == [True, True, True, False, False, True]


def _objectives(trial):
    s = Settings(
        value_rad=trial.suggest_float("value_rad", 0.2, 3.0, log=True),
        error_limit_rad=1.0,
        k=trial.suggest_float("k", 50.0, 2000.0, log=True),
    )
    ev = evaluate(s, ["short-move"])
    for name, c in zip(CONSTRAINTS, ev.constraints[0, 0], strict=True):
        trial.set_constraint(name, float(c))
    trial.set_user_attr("objectives", [float(v) for v in ev.objectives[0, 0]])  # as sweeps do
    return ev


def make_sweep(tmp_path, multi: bool):
    """A sweep folder as the sweeps issue writes it: study.db + config.yaml."""
    d = tmp_path / ("multi" if multi else "single")
    d.mkdir()
    storage = f"sqlite:///{d / 'study.db'}"
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    if multi:
        study = optuna.create_study(
            study_name="m",
            storage=storage,
            directions=["minimize"] * 3,
            sampler=optuna.samplers.NSGAIISampler(seed=0, population_size=4),
        )
        study.optimize(lambda t: tuple(_objectives(t).objectives[0, 0]), n_trials=10)
    else:
        study = optuna.create_study(
            study_name="s",
            storage=storage,
            sampler=optuna.samplers.TPESampler(seed=0, n_startup_trials=4),
        )
        study.optimize(lambda t: float(_objectives(t).cost[0, 0]), n_trials=10)
    (d / "config.yaml").write_text(
        yaml.safe_dump({"study_name": study.study_name, "storage": storage})
    )
    return d, study


def test_history_and_pareto_from_sweep_folders(tmp_path, capsys):
    d1, s1 = make_sweep(tmp_path, multi=False)
    d3, s3 = make_sweep(tmp_path, multi=True)
    names, vals, feas, nums = objective_points(s1)
    assert names == list(OBJECTIVES) and vals.shape == (10, 3)
    assert nums.tolist() == list(range(10))
    assert feas.tolist() == [all(c <= 0 for c in t.constraints.values()) for t in s1.trials]
    assert vals.tolist() == [t.user_attrs["objectives"] for t in s1.trials]
    fig = history_figure(s1)
    best = _lines(fig.get_axes()[0])["best feasible so far"].get_ydata()
    assert np.all(np.diff(best) <= 0)
    feasible_costs = [t.value for t in s1.trials if all(c <= 0 for c in t.constraints.values())]
    assert 0 < len(feasible_costs) < 10  # both kinds drawn
    assert best[-1] == min(feasible_costs)
    names, vals, feas, _ = objective_points(s3)
    fig = pareto_figure(s3, x="time_ratio", y="overshoot_windows")
    front = next(ln for ln in fig.get_axes()[0].get_lines() if "Pareto" in ln.get_label())
    pts = np.column_stack([vals[feas, 1], vals[feas, 0]])
    assert len(front.get_xdata()) == int(pareto_mask(pts).sum())
    for kind, d in (("history", d1), ("pareto", d1), ("history", d3), ("pareto", d3)):
        out = tmp_path / f"{kind}-{d.name}.png"
        assert main(["plot", kind, "--sweep", str(d), "--out", str(out), "--dpi", "30"]) == 0
        assert out.read_bytes()[:8] == PNG
    with pytest.raises(ValueError, match="objective='nope'"):
        pareto_figure(s3, x="nope")
    bare = optuna.create_study(study_name="bare")
    bare.optimize(lambda t: t.suggest_float("x", 0, 1), n_trials=2)
    with pytest.raises(ValueError, match="no Pareto front"):
        pareto_figure(bare)


# --- the command ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    "argv",
    [
        ["response", "--scenario", "short-move"],
        ["response", "--scenario", "paper-sine", "--baseline", "rule-of-thumb"],
        ["scurve", "--short-rad", "0.5"],
        ["frequency", "--scenario", "short-move"],
        ["compare", "--scenario", "short-move", "--against", "paper,scurve"],
    ],
)
def test_plot_cli(tmp_path, capsys, argv):
    out = tmp_path / "fig.png"  # in an existing folder: a missing one is refused
    assert main(["plot", *argv, "--out", str(out), "--dpi", "30"]) == 0
    assert out.read_bytes()[:8] == PNG
    assert str(out) in capsys.readouterr().out


def test_plot_cli_with_settings_file(tmp_path, capsys):
    f = tmp_path / "best.yaml"
    f.write_text(yaml.safe_dump({"settings": {"value_rad": 0.5, "k": 300.0}, "cost": 2.0}))
    out = tmp_path / "cmp.png"
    args = ["plot", "compare", "--scenario", "short-move", "--settings", str(f)]
    assert main([*args, "--out", str(out), "--dpi", "30"]) == 0
    assert out.is_file()


@pytest.mark.parametrize(
    ("argv", "needle"),
    [
        (["history"], "needs --sweep"),
        (["pareto", "--sweep", "no/such/dir"], "no such folder"),
        (["compare", "--against", "paper,pid"], "baseline='pid'"),
        (["frequency", "--scenario", "paper-sine"], "moving reference"),
        (["response", "--settings", "nope.yaml"], "nope.yaml: no such file"),
        (["response", "--out", "fig.jpg"], "give a .png file"),
    ],
)
def test_plot_cli_bad_input(tmp_path, capsys, argv, needle):
    out = ["--out", str(tmp_path / "x.png")] if "--out" not in argv else []
    assert main(["plot", *argv, *out]) == 2
    err = capsys.readouterr().err.strip()
    assert needle in err and "\n" not in err


def test_importances_figure_draws_optunas_importances(tmp_path):
    _, s1 = make_sweep(tmp_path, multi=False)
    fig = importances_figure(s1, target_name="cost")
    bars = {p.get_y() + p.get_height() / 2: p.get_width() for p in fig.get_axes()[0].patches}
    names = [t.get_text() for t in fig.get_axes()[0].get_yticklabels()]
    want = optuna.importance.get_param_importances(s1)
    assert sorted(names) == sorted(want) and len(bars) == len(want)
    assert [bars[y] for y in sorted(bars)] == pytest.approx(list(want.values())[::-1])
    one = optuna.create_study(study_name="one")
    one.optimize(lambda t: t.suggest_float("x", 0, 1), n_trials=1)
    with pytest.raises(ValueError, match="fewer than 2"):
        importances_figure(one)


def test_objectives_from_user_attributes():
    from vfgym.report._sweep_figures import _attr_objectives

    names = list(OBJECTIVES)
    forms = [
        {"overshoot_windows": 1.0, "time_ratio": 2.0, "accel_violation": 3.0},
        {"objectives": [1.0, 2.0, 3.0]},
        {"objectives": {"accel_violation": 3.0, "time_ratio": 2.0, "overshoot_windows": 1.0}},
    ]
    for attrs in forms:
        t = optuna.trial.create_trial(value=0.5, user_attrs=attrs)
        assert _attr_objectives(t, names) == [1.0, 2.0, 3.0]
    t = optuna.trial.create_trial(value=0.5, user_attrs={"objectives": [1.0]})
    assert _attr_objectives(t, names) is None
