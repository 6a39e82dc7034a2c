"""``vfgym evaluate`` end to end: the run folder, its numbers against vfgym.evaluate, an
agent plugged in through vfgym.agents.load_tuner, and one-line errors on bad input."""

from __future__ import annotations

import csv
import json
import sys
import types
from pathlib import Path

import numpy as np
import pytest
import yaml

from vfgym import Settings, evaluate
from vfgym.cli import main
from vfgym.moves.baselines import rule_of_thumb
from vfgym.moves.distribution import scenario_set

ROOT = Path(__file__).resolve().parents[2]
TUNED = {"value_rad": 0.7, "error_limit_rad": 0.7, "k": 350.0, "ts_over_tf": 0.25}


def write_settings(path, data):
    path.write_text(yaml.safe_dump(data))
    return str(path)


def run_eval(tmp_path, *args):
    return main(["evaluate", *args, "--runs-dir", str(tmp_path / "runs"), "--bootstrap", "300"])


def test_run_folder_and_numbers(tmp_path, capsys):
    f = write_settings(tmp_path / "best.yaml", {"settings": TUNED, "cost": 1.23})
    g = write_settings(tmp_path / "other.yaml", TUNED | {"k": 600.0})
    args = ["--settings", f, "--settings", g, "--against", "paper,scurve"]
    args += ["--scenarios", "test", "--count", "3", "--first-seed", "5", "--name", "t1"]
    assert run_eval(tmp_path, *args) == 0
    out = capsys.readouterr().out
    d = tmp_path / "runs" / "evaluate" / "t1"
    for name in ("config.yaml", "command.txt", "results.csv", "summary.csv", "results.json"):
        assert (d / name).is_file(), name
    assert "test-5" in out and "win rate" in out and str(d) in out

    cfg = yaml.safe_load((d / "config.yaml").read_text())
    assert cfg["scenario_names"] == ["test-5", "test-6", "test-7"]
    assert cfg["against"] == ["paper", "scurve"]
    assert cfg["settings"][0]["settings"]["k"] == 350.0

    ev = evaluate(
        [Settings(**TUNED), Settings(**(TUNED | {"k": 600.0})), "paper", "scurve"],
        scenario_set("test", 3, 5),
    )
    with (d / "results.csv").open() as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == 12
    for i, label in enumerate(["best", "other", "paper", "scurve"]):
        got = [float(r["cost"]) for r in rows if r["controller"] == label]
        np.testing.assert_array_equal(got, ev.cost[i])
    data = json.loads((d / "results.json").read_text())
    wl = {(w["tuned"], w["baseline"]): w for w in data["win_loss"]}
    assert set(wl) == {
        ("best", "paper"),
        ("best", "scurve"),
        ("other", "paper"),
        ("other", "scurve"),
    }
    w = wl[("best", "paper")]
    assert w["wins"] == int(np.sum(ev.cost[0] < ev.cost[2]))
    assert w["cost_diff"]["n"] == 3


def test_model_plugs_in_through_vfgym_agents(tmp_path, capsys, monkeypatch):
    model = tmp_path / "agent.zip"
    model.write_bytes(b"not really a model")
    seen = []

    def load_tuner(path, axis=None, warn=None):
        seen.append(path)
        return lambda sc: rule_of_thumb(sc.plant())

    fake = types.ModuleType("vfgym.agents")
    fake.load_tuner = load_tuner
    fake.servo_agent = lambda path: None  # not a VFServo-v0 agent
    monkeypatch.setitem(sys.modules, "vfgym.agents", fake)
    args = ["--model", str(model), "--against", "rule-of-thumb", "--scenarios", "named"]
    assert run_eval(tmp_path, *args, "--name", "m") == 0
    assert seen == [str(model)]
    data = json.loads((tmp_path / "runs/evaluate/m/results.json").read_text())
    (w,) = data["win_loss"]
    assert w["tuned"] == "agent:agent" and w["ties"] == 8  # the same settings per scenario


def test_model_without_agent_support(tmp_path, capsys, monkeypatch):
    model = tmp_path / "agent.zip"
    model.write_bytes(b"x")
    monkeypatch.setitem(sys.modules, "vfgym.agents", None)  # import fails
    assert run_eval(tmp_path, "--model", str(model), "--scenarios", "short-move") == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and 'pip install -c constraints.txt -e ".[agents]"' in err
    assert not (tmp_path / "runs").exists()


@pytest.mark.parametrize(
    ("content", "extra", "needle", "names_file"),
    [
        (None, [], "missing.yaml: no such file", True),
        ({"settings": TUNED | {"gain": 2.0}}, [], "unknown key(s) gain", True),
        ({"settings": TUNED | {"k": 0.5}}, [], "k=0.5 is out of range", True),
        ({"settings": TUNED | {"accel_law": "jump"}}, [], "accel_law='jump'", True),
        ("a: [unclosed", [], "not valid YAML", True),
        ("- just\n- a list", [], "expected a mapping", True),
        ({"settings": TUNED}, ["--against", "paper,pid"], "baseline='pid' is not known", False),
        ({"settings": TUNED}, ["--scenarios", "mars"], "scenario='mars' is not known", False),
        ({"settings": TUNED}, ["--first-seed", "-1"], "--first-seed='-1' is out of range", False),
    ],
)
def test_bad_input_one_line(tmp_path, capsys, content, extra, needle, names_file):
    f = tmp_path / "missing.yaml"
    if isinstance(content, str):
        f.write_text(content)
    elif content is not None:
        write_settings(f, content)
    code = run_eval(tmp_path, "--settings", str(f), "--scenarios", "short-move", *extra)
    assert code == 2
    err = capsys.readouterr().err.strip()
    assert needle in err, err
    assert "\n" not in err and err.startswith("vfgym evaluate: error:")
    assert (str(f) in err) == names_file
    assert not (tmp_path / "runs").exists()


def test_nothing_to_evaluate(tmp_path, capsys):
    assert run_eval(tmp_path, "--scenarios", "short-move") == 2
    assert "nothing to evaluate" in capsys.readouterr().err


def test_adaptive_runs_a_settings_model_as_the_scheduler_that_tells_the_plant(tmp_path, capsys):
    """--adaptive MODEL on an uncertain axis: one more column, judged on the same pairs as
    the model itself; recorded in config.yaml."""
    from vfgym.permove import PRETRAINED

    axis = str(ROOT / "experiments" / "axes" / "loads-uncertain.yaml")
    argv = ["evaluate", "--axis", axis, "--adaptive", str(PRETRAINED), "--model",
            str(PRETRAINED), "--against", "paper", "--plants", "2", "--runs-dir",
            str(tmp_path), "--name", "a"]  # fmt: skip
    assert main(argv) == 0
    out = capsys.readouterr().out
    rows = [ln for ln in out.splitlines() if "(move, plant)" not in ln and "/64 (" in ln]
    labels = ["model:settings_model", "adaptive:settings_model"]
    assert [r.split()[0] for r in rows] == [*labels, "paper"]
    held = [ln for ln in out.splitlines() if ln.startswith("adaptive:settings_model: held its")]
    assert len(held) == 1 and " of 96 (move, plant) runs: " in held[0], out  # 32 x (1 + 2)
    cfg = yaml.safe_load((tmp_path / "evaluate" / "a" / "config.yaml").read_text())
    assert [m["label"] for m in cfg["models"]] == labels
