"""``vfgym fit``: a settings model for an axis from per-move optima, its run folder and
held-out verdict, checkpointed optima, and the training distribution of a listed set."""

from __future__ import annotations

import json
from pathlib import Path

import yaml

from vfgym.axis import load_axis
from vfgym.cli import main
from vfgym.permove import fit as F
from vfgym.permove.optima import OptimumSearch, read_optima
from vfgym.permove.supervised import load_settings_model

REPO = Path(__file__).resolve().parents[2]
SMALL = {
    "plant": {"motor": {"inertia_ratio": 2.0}},
    "moves": {
        "train": {"random": {"count": 2, "distance_rad": [0.5, 5.0], "settle_s": 0.03}},
        "test": {"random": {"count": 3, "distance_rad": [0.5, 5.0], "settle_s": 0.03}},
    },
}
TINY = OptimumSearch(points=3, rounds=1, keep=1)


def test_cli_fit_writes_the_model_and_its_verdict_and_predict_uses_it(tmp_path, capsys):
    path = tmp_path / "small.yaml"
    path.write_text(yaml.safe_dump(SMALL))
    args = ["fit", "--axis", str(path), "--runs-dir", str(tmp_path), "--moves", "8"]
    assert main([*args, "--no-progress"]) == 0
    run = tmp_path / "fit" / "small"
    for f in ("settings_model.json", "config.yaml", "command.txt", "optima.csv", "verdict.txt"):
        assert (run / f).is_file(), f
    out = capsys.readouterr().out
    assert "held-out verdict: fitted against the baselines on the 3 test moves" in out
    assert "fitted beats best-fixed on" in out and "scurve on" in out
    summary = yaml.safe_load((run / "summary.yaml").read_text())
    labels = [r["controller"] for r in summary["verdict"]["controllers"]]
    assert labels == ["fitted", "best-fixed", "paper", "scurve"]
    assert len(read_optima(run / "optima.csv")) == 8
    assert load_settings_model(run / "settings_model.json").trained_on["axis"] == "small"
    cfg = yaml.safe_load((run / "config.yaml").read_text())
    assert cfg["moves"] == 8 and cfg["search"]["points"] == F.FIT_SEARCH.points
    model = str(run / "settings_model.json")
    assert main(["predict", "--model", model, "--axis", str(path), "--scenario", "test-1"]) == 0
    got = capsys.readouterr()
    assert "used on axis" not in got.err and yaml.safe_load(got.out)["source"] == f"model {model}"
    assert main(["predict", "--model", model]) == 0  # on the paper's axis: said
    assert "learnt on axis 'small', used on axis 'paper'" in capsys.readouterr().err


def test_an_interrupted_fit_keeps_its_optima_and_searches_only_the_rest(tmp_path, monkeypatch):
    axis = load_axis(REPO / "experiments/axes/paper.yaml")
    moves = F.fit_moves(axis, 6)
    path = tmp_path / "optima.csv"
    kw = {"plant": axis.plant, "measures": axis.measures, "chunk": 2}
    first = F.checkpointed_optima(moves[:4], TINY, path, **kw)
    assert [o.scenario for o in read_optima(path)] == [sc.name for sc in moves[:4]]
    searched: list[str] = []
    real = F.move_optima

    def counting(scs, *a, **k):
        searched.extend(sc.name for sc in scs)
        return real(scs, *a, **k)

    monkeypatch.setattr(F, "move_optima", counting)
    done = F.checkpointed_optima(moves, TINY, path, **kw)
    assert searched == [sc.name for sc in moves[4:]]
    assert done[:4] == first and len(read_optima(path)) == 6
    # the optima of other moves of the same names, or of another search, are not taken
    belt = load_axis(REPO / "experiments/axes/belt.yaml")
    other = F.fit_moves(belt, 6)
    assert [sc.name for sc in other] == [sc.name for sc in moves]
    for scs, search, ax in ((other, TINY, belt), (moves, OptimumSearch(3, 2, 1), axis)):
        searched.clear()
        kw = {"plant": ax.plant, "measures": ax.measures, "chunk": 2}
        F.checkpointed_optima(scs[:2], search, path, **kw)
        assert searched == [sc.name for sc in scs[:2]]


def test_a_listed_train_set_gives_a_distribution_spanning_its_moves():
    belt = load_axis(REPO / "experiments/axes/belt.yaml")
    d = F.fit_distribution(belt)
    assert d.distance_rad == (7.0, 174.5) and d.both_directions
    assert set(d.profiles) == {"step", "trapezoid", "scurve"}
    assert d.inertia_ratio == (0.0, 1.55) and d.time_factor == 1.0 and 0.1 < d.settle_s < 0.6
    moves = F.fit_moves(belt, 40)
    assert all(7.0 <= abs(sc.distance_rad) <= 174.5 for sc in moves)
    assert {sc.distance_rad > 0 for sc in moves} == {True, False}
    loads = load_axis(REPO / "experiments/axes/loads.yaml")
    assert F.fit_distribution(loads) == loads.moves.train.random


def test_the_cost_table_is_each_optimum_on_each_move(tmp_path):
    axis = load_axis(REPO / "experiments/axes/paper.yaml")
    moves = F.fit_moves(axis, 3)
    optima = F.checkpointed_optima(moves, TINY, tmp_path / "o.csv")
    cost, feas = F.candidate_costs(moves, optima)
    # the diagonal: each move's own optimum, as the search scored it
    assert all(abs(cost[i, i] - optima[i].cost) <= 1e-9 * max(1.0, optima[i].cost)
               for i in range(3))  # fmt: skip
    assert cost.shape == feas.shape == (3, 3)
    json.dumps(cost.tolist())


def test_bad_fit_input_is_one_line_and_makes_no_run_folder(tmp_path, capsys):
    belt = str(REPO / "experiments/axes/belt.yaml")
    for args, needle in (
        (["--axis", belt, "--moves", "3"], "--moves='3' is out of range"),
        (["--axis", str(tmp_path / "none.yaml")], "none.yaml"),
        (["--axis", belt, "--name", "a/b"], "--name"),
    ):
        assert main(["fit", *args, "--runs-dir", str(tmp_path / "runs")]) == 2
        err = capsys.readouterr().err.strip()
        assert needle in err and "\n" not in err and err.startswith("vfgym fit: error:"), err
    assert not (tmp_path / "runs").exists()
