"""The supervised amortised tuner: per-move optima, the ridge regression, the shipped
model (it beats the paper's settings, and its training command reproduces it), the
refinement sweep and ``vfgym predict`` without a trained agent."""

from __future__ import annotations

import itertools
import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st

from vfgym import PAPER_AXIS, PAPER_PLANT, PAPER_SETTINGS, evaluate, get_scenario, scenario_set
from vfgym.cli import main
from vfgym.moves import LOAD_DISTRIBUTION as LOAD
from vfgym.moves.features import scenario_features
from vfgym.params import DEFAULT_MEASURES
from vfgym.permove.fit import optima_key
from vfgym.permove.optima import MoveOptimum, OptimumSearch, move_optima, read_optima, write_optima
from vfgym.permove.refine import refine
from vfgym.permove.supervised import (
    PRETRAINED,
    TrainConfig,
    fit_pick_model,
    fit_settings_model,
    load_settings_model,
    settings_targets,
    target_settings,
    train_settings_model,
)
from vfgym.space import SPACE, from_action

REPO = Path(__file__).resolve().parents[2]


def test_optima_with_no_refinement_are_the_grid_minimum():
    """rounds=0: each move's optimum is the coarse grid's feasible minimum, found by
    scoring the same grid through vfgym.evaluate move by move."""
    moves = scenario_set("test", 2, 900, LOAD)
    search = OptimumSearch(points=3, rounds=0)
    found = move_optima(moves, search)
    grid = [from_action(np.array(u)) for u in itertools.product((-1.0, 0.0, 1.0), repeat=4)]
    for sc, opt in zip(moves, found, strict=True):
        ev = evaluate(grid, sc)
        cost, feas = ev.cost[:, 0], ev.feasible[:, 0]
        want = cost[feas].min() if feas.any() else cost.min()
        assert opt.cost == pytest.approx(want, rel=1e-12)
        assert opt.feasible == bool(feas.any())
        again = evaluate(opt.settings, sc)
        assert again.cost[0, 0] == pytest.approx(opt.cost, rel=1e-12)


def test_refinement_rounds_never_lose_the_grid_minimum():
    moves = scenario_set("test", 2, 900, LOAD)
    coarse = move_optima(moves, OptimumSearch(points=3, rounds=0))
    fine = move_optima(moves, OptimumSearch(points=3, rounds=2, keep=1))
    for a, b in zip(coarse, fine, strict=True):
        assert (not a.feasible or b.feasible) and b.cost <= a.cost + 1e-12


def test_optima_csv_round_trip(tmp_path):
    rows = [
        MoveOptimum("test-1", PAPER_SETTINGS, 2.5, True),
        MoveOptimum("train-7", from_action(np.array([0.1, -0.3, 0.9, 1.0])), 1e3 / 7, False),
    ]
    write_optima(tmp_path / "o.csv", rows, header="two rows\nsecond line")
    assert read_optima(tmp_path / "o.csv") == rows
    (tmp_path / "bad.csv").write_text("scenario,value_rad\ntest-1,x\n")
    with pytest.raises(ValueError, match="bad row"):
        read_optima(tmp_path / "bad.csv")


@settings(max_examples=50, deadline=None)
@given(
    u=st.lists(st.floats(-1.0, 1.0), min_size=4, max_size=4),
    seed=st.integers(0, 10_000),
)
def test_targets_and_settings_are_inverse(u, seed):
    s = from_action(np.array(u))
    plant = get_scenario(f"train-{seed}", LOAD).plant()
    back = target_settings(settings_targets(s, plant), plant)
    for d in SPACE:
        assert getattr(back, d.name) == pytest.approx(getattr(s, d.name), rel=1e-9)


def test_fit_recovers_an_exact_linear_map():
    """Optima made by a known linear map of the features (degree 1) are fitted exactly
    (ridge 0), and the model's settings give them back."""
    moves = scenario_set("train", 60, 5000, LOAD)
    x = np.array([scenario_features(sc, PAPER_PLANT) for sc in moves])
    w = np.random.default_rng(0).normal(0.0, 0.05, (x.shape[1], 4))
    t = np.clip(0.1 + x @ w, -0.9, 0.9)
    opt = [
        MoveOptimum(sc.name, target_settings(ti, sc.plant()), 1.0, True)
        for sc, ti in zip(moves, t, strict=True)
    ]
    model = fit_settings_model(moves, opt, degree=1, ridge=0.0)
    for sc, o in zip(moves[:5], opt[:5], strict=True):
        got = model.settings(sc)
        for d in SPACE:
            assert getattr(got, d.name) == pytest.approx(getattr(o.settings, d.name), rel=1e-6)
    with pytest.raises(ValueError, match="differ"):
        fit_settings_model(moves[1:], opt[:-1])


def test_shipped_model_beats_the_papers_settings_on_unseen_test_moves():
    """Test moves beyond the report's 64 (never used to train or to choose the model)."""
    model = load_settings_model()
    moves = scenario_set("test", 8, 5000, LOAD)
    picks = [model.settings(sc) for sc in moves]
    ours = np.array([evaluate(s, sc).cost[0, 0] for s, sc in zip(picks, moves, strict=True)])
    paper = evaluate(PAPER_SETTINGS, moves).cost[0]
    assert np.all(ours < paper), (ours, paper)


def test_shipped_model_is_reproduced_by_its_training_command():
    folder = PRETRAINED.parent
    cfg = TrainConfig(**yaml.safe_load((folder / "config.yaml").read_text()))
    command = (folder / "command.txt").read_text().split()
    assert command[:2] == ["python", "experiments/train_settings_model.py"]
    for flag, value in (("--kind", cfg.kind), ("--optima", cfg.optima), ("--costs", cfg.costs),
                        ("--neighbours", str(cfg.neighbours)), ("--library", str(cfg.library)),
                        ("--ignore", ",".join(cfg.ignore)),
                        ("--check", str(cfg.check))):  # fmt: skip
        assert command[command.index(flag) + 1] == value
    # one command builds it from nothing: the optima file is its checkpoint of these moves
    count = int(command[command.index("--build") + 1])
    moves = scenario_set("train", count, 0, LOAD)
    key = optima_key(moves, OptimumSearch(), PAPER_PLANT, DEFAULT_MEASURES)
    assert (REPO / cfg.optima).read_text().partition("\n")[0] == f"# {key}"
    again = train_settings_model(cfg, REPO).to_dict()
    shipped = json.loads(PRETRAINED.read_text())
    assert again.keys() == shipped.keys()
    for key, value in again.items():
        if isinstance(value, list) and key not in ("features", "targets"):
            np.testing.assert_allclose(np.array(value), np.array(shipped[key]), rtol=1e-9)
        else:
            assert value == shipped[key], key


def test_pick_model_picks_the_candidate_best_on_the_nearest_moves():
    """Three training moves, two candidates: a move's own features pick, among its
    nearest ``neighbours`` training moves, the candidate of least mean cost ratio."""
    moves = scenario_set("train", 3, 7000, LOAD)
    opt = [MoveOptimum(sc.name, from_action(np.full(4, 0.1 * i)), 1.0, True)
           for i, sc in enumerate(moves)]  # fmt: skip
    # candidate 0 is twice the optimum on move 2 and infeasible on move 1; 2 is best there
    cost = np.array([[1.0, 1.5, 1.2], [1.0, 1.0, 1.1], [2.0, 3.0, 1.0]])
    feas = np.array([[True, True, True], [False, True, True], [True, True, True]])
    m = fit_pick_model(moves, opt, cost, feas, neighbours=1, library=3, ignore=())
    x = [scenario_features(sc, PAPER_PLANT) for sc in moves]
    lib = [tuple(np.round(t, 9)) for t in m.library]
    targets = [tuple(np.round(settings_targets(o.settings, sc.plant()), 9))
               for o, sc in zip(opt, moves, strict=True)]  # fmt: skip
    assert [lib.index(targets[j]) for j in (0, 1, 2)] == [m.pick(x[i]) for i in (0, 1, 2)]
    m3 = fit_pick_model(moves, opt, cost, feas, neighbours=3, library=3, ignore=())
    # mean ratios with the infeasible penalty: [4/3+1/3, 5.5/3, 3.3/3] -> candidate 2
    assert m3.pick(x[0]) == lib.index(targets[2])


def test_a_checked_pick_is_the_best_on_the_move_of_its_best_ranked_candidates():
    """With ``check`` = K the model returns, of its K best-ranked candidates, the one
    best on the move as :func:`vfgym.evaluate` scores them: feasible first, then cost."""
    model = load_settings_model()
    assert model.check == 8
    plain = replace(model, check=0)
    for name in ("paper-step", "short-move", "test-3", "test-11", "test-40"):
        sc = get_scenario(name, LOAD)
        loaded = sc.plant(PAPER_PLANT)
        top = plain.ranked(scenario_features(sc, PAPER_PLANT, loaded))[:5]
        cands = [target_settings(model.library[j], loaded, model.accel_law) for j in top]
        ev = evaluate(cands, [sc])
        key = [(not ev.feasible[i, 0], ev.cost[i, 0], i) for i in range(5)]
        assert replace(model, check=5).settings(sc) == cands[min(key)[2]]
        assert plain.settings(sc) == replace(model, check=1).settings(sc) == cands[0]
    with pytest.raises(ValueError, match="check=65 is out of range"):
        replace(model, check=65)


def test_refine_starts_from_the_prediction_and_never_ends_worse():
    sc = get_scenario("test-901", LOAD)
    start = load_settings_model().settings(sc)
    r = refine(sc, start, 6, axis=PAPER_AXIS)
    assert len(r.costs) == 6
    assert r.start_cost == pytest.approx(evaluate(start, sc).cost[0, 0], rel=1e-12)
    assert r.cost <= r.start_cost or (r.feasible and not evaluate(start, sc).feasible[0, 0])
    assert r.cost == pytest.approx(evaluate(r.settings, sc).cost[0, 0], rel=1e-9)


def test_predict_uses_the_shipped_model_without_training(tmp_path, capsys):
    out = tmp_path / "s.yaml"
    assert main(["predict", "--scenario", "test-3", "--out", str(out)]) == 0
    doc = yaml.safe_load(out.read_text())
    assert doc["source"] == "pretrained settings model"
    want = load_settings_model().settings(get_scenario("test-3"))
    assert doc["settings"]["k"] == pytest.approx(want.k)
    args = ["evaluate", "--settings", str(out), "--scenarios", "test-3"]
    assert main([*args, "--runs-dir", str(tmp_path)]) == 0
    capsys.readouterr()
    assert main(["predict", "--scenario", "test-3", "--refine", "4"]) == 0
    doc = yaml.safe_load(capsys.readouterr().out)
    assert doc["cost"] <= doc["predicted"]["cost"]
    assert "refined by 4 trials" in doc["source"]


def test_predict_on_an_axis(capsys):
    axis = REPO / "experiments" / "axes" / "belt.yaml"
    assert main(["predict", "--axis", str(axis), "--scenario", "test-0"]) == 0
    doc = yaml.safe_load(capsys.readouterr().out)
    assert set(doc["settings"]) >= {"value_rad", "error_limit_rad", "k", "ts_over_tf"}


def test_the_wheel_carries_the_shipped_model():
    """pyproject's package-data covers every file of the pretrained folder, so a wheel
    holds them (``pip wheel .`` then ``vfgym predict`` from that install, checked by hand)."""
    import fnmatch
    import tomllib

    data = tomllib.loads((REPO / "pyproject.toml").read_text())
    globs = data["tool"]["setuptools"]["package-data"]["vfgym"]
    files = [p for p in PRETRAINED.parent.iterdir() if p.is_file()]
    assert {p.name for p in files} == {"settings_model.json", "config.yaml", "command.txt"}
    for p in files:
        rel = p.relative_to(REPO / "src" / "vfgym").as_posix()
        assert any(fnmatch.fnmatch(rel, g) for g in globs), rel


def test_a_pick_model_file_of_the_older_targets_picks_the_same_settings(tmp_path):
    """Files written with the older targets (value, L and Ts/Tf as the search space's unit
    coordinates, k as log10(k / k_a)) still load: their library is read into today's
    coordinates and picks the same settings; an older regression is refused, in one line."""
    d = json.loads(PRETRAINED.read_text())
    old = []
    for row in np.array(d["library"]):  # today's log coordinates, back to the older ones
        value, limit = np.exp(row[0]), np.exp(row[0] + row[1])
        old.append([SPACE[0].to_unit(value), SPACE[1].to_unit(limit), row[2] / np.log(10.0),
                    SPACE[3].to_unit(np.exp(row[3]))])  # fmt: skip
    d |= {"targets": ["value_rad", "error_limit_rad", "log10_k_over_ka", "ts_over_tf"]}
    (tmp_path / "old.json").write_text(json.dumps(d | {"library": old}))
    then, now = load_settings_model(tmp_path / "old.json"), load_settings_model()
    for sc in scenario_set("test", 6, 7, LOAD):
        a, b = then.settings(sc), now.settings(sc)
        for f in SPACE:
            assert getattr(a, f.name) == pytest.approx(getattr(b, f.name), rel=1e-12)
    fit = fit_settings_model(scenario_set("train", 8, 3, LOAD), read_optima_rows(8), degree=1)
    fit.save(tmp_path / "reg.json")
    reg = json.loads((tmp_path / "reg.json").read_text()) | {"targets": d["targets"]}
    (tmp_path / "reg.json").write_text(json.dumps(reg))
    with pytest.raises(ValueError, match="older vfgym's regression: fit it again") as e:
        load_settings_model(tmp_path / "reg.json")
    assert "\n" not in str(e.value)


def read_optima_rows(n: int) -> list[MoveOptimum]:
    """n optima of the shipped training set's first moves, renamed onto scenario_set's."""
    rows = read_optima(REPO / "experiments" / "optima" / "train.csv")[:n]
    moves = scenario_set("train", n, 3, LOAD)
    return [replace(o, scenario=sc.name) for o, sc in zip(rows, moves, strict=True)]
