"""``vfgym.permove.load_tuner``: a settings model as one callable, and its one-line warnings on
another axis or on moves unlike its training moves."""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import pytest

from vfgym.axis import PAPER_AXIS, load_axis, machine_digest
from vfgym.cli import main
from vfgym.permove import (
    PRETRAINED,
    Tuner,
    TunerWarning,
    load_settings_model,
    load_tuner,
    trained_on,
)

REPO = Path(__file__).resolve().parents[2]
BELT = str(REPO / "experiments/axes/belt.yaml")


def test_the_shipped_model_is_a_tuner_and_says_nothing_on_its_own_axis():
    seen: list[str] = []
    tuner = load_tuner(warn=seen.append)
    assert isinstance(tuner, Tuner) and tuner.source == "pretrained settings model"
    model = load_settings_model(PRETRAINED)
    for name in ("paper-step", "test-0", "test-5", "short-move"):
        assert tuner(name) == model.settings(PAPER_AXIS.scenario(name))
    assert seen == []
    # the paper's axis file is the same machine
    load_tuner(axis=str(REPO / "experiments/axes/paper.yaml"), warn=seen.append)("test-1")
    assert seen == []


def test_another_axis_and_moves_outside_the_training_ranges_are_said_once():
    seen: list[str] = []
    tuner = load_tuner(axis=BELT, warn=seen.append)
    belt = load_axis(BELT)
    assert len(seen) == 1 and "learnt on axis 'paper', used on axis 'belt'" in seen[0]
    sc = belt.scenario("test-0")
    assert tuner(sc) == load_settings_model(PRETRAINED).settings(sc, belt.plant)
    for i in range(1, 4):
        tuner(f"test-{i}")
    assert len(seen) == 2 and "outside its training moves" in seen[1]
    assert all("\n" not in s for s in seen)
    with pytest.warns(TunerWarning, match="used on axis 'belt'"):
        load_tuner(axis=belt)


def test_a_model_fitted_on_an_axis_is_quiet_there_and_not_on_the_paper_axis(tmp_path):
    belt = load_axis(BELT)
    d = json.loads(PRETRAINED.read_text()) | {"trained_on": trained_on(belt)}
    path = tmp_path / "m.json"
    path.write_text(json.dumps(d))
    assert load_settings_model(path).trained_on == {"axis": "belt", "machine": machine_digest(belt)}
    seen: list[str] = []
    load_tuner(path, BELT, warn=seen.append)
    assert not any("used on axis" in s for s in seen)
    with warnings.catch_warnings(record=True) as got:
        warnings.simplefilter("always")
        load_tuner(path)
    assert str(got[0].message).startswith(f"model {path}: learnt on axis 'belt'")


def test_predict_and_evaluate_take_a_settings_model_and_warn_in_one_line(tmp_path, capsys):
    assert main(["predict", "--axis", BELT, "--scenario", "test-0"]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert err and all(
        e.startswith("vfgym predict: warning: pretrained settings model") for e in err
    )
    args = ["evaluate", "--model", str(PRETRAINED), "--against", "paper", "--scenarios",
            "paper-step,short-move", "--runs-dir", str(tmp_path), "--name", "e"]  # fmt: skip
    assert main(args) == 0
    out = capsys.readouterr()
    assert "model:settings_model" in out.out and out.err == ""
