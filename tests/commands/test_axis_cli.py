"""``--axis FILE`` on every command: sweep tunes on the axis's train moves, evaluate judges on
its test moves, simulate/plot/export/grid use its plant and moves; the run folders keep a
copy of the axis that loads back equal; a bad file is one line and exit status 2."""

from __future__ import annotations

import csv
from pathlib import Path

import pytest
import yaml

from vfgym import evaluate
from vfgym.axis import AXIS_FILE, load_axis
from vfgym.cli import main
from vfgym.commands._common import load_settings

AXES = Path(__file__).resolve().parents[2] / "experiments" / "axes"

SMALL = {
    "plant": {"motor": {"inertia_ratio": 2.0, "load_torque_nm": 0.003}},
    "moves": {
        "train": [
            {"name": "up", "profile": "trapezoid", "distance_rad": 1.5, "duration_s": 0.05},
            {"name": "down", "profile": "step", "distance_rad": -0.8, "duration_s": 0.05},
        ],
        "test": {"random": {"count": 3, "distance_rad": [0.2, 2.0], "settle_s": 0.02}},
    },
}


def write_axis_file(path: Path, data: dict = SMALL) -> str:
    path.write_text(yaml.safe_dump(data))
    return str(path)


def sweep(tmp_path: Path, *extra: str, study: str = "s") -> int:
    runs = str(tmp_path / "runs")
    return main(["sweep", "--runs-dir", runs, "--study", study, "--no-progress", *extra])


def test_sweep_tunes_on_the_axis_train_moves(tmp_path, capsys):
    """The smoke run of the issue: an engineered axis, three trials."""
    path = str(AXES / "vertical.yaml")
    assert sweep(tmp_path, "--axis", path, "--trials", "3", "--no-plots") == 0
    out = capsys.readouterr().out
    axis = load_axis(path)
    run = tmp_path / "runs" / "sweep" / "s"
    assert load_axis(run / AXIS_FILE) == axis  # the copy in the run folder loads back equal
    conf = yaml.safe_load((run / "config.yaml").read_text())
    assert conf["axis"] == path and conf["scenarios"] == "train"
    best = yaml.safe_load((run / "best.yaml").read_text())
    train = axis.scenarios("train")
    assert best["scenarios"] == [s.name for s in train] and best["axis"] == path
    ev = evaluate(load_settings(str(run / "best.yaml"), axis), train, axis=axis)
    assert best["cost"] == pytest.approx(float(ev.mean_cost[0]), rel=1e-12)
    assert f"set ({len(train)})" in out


def test_sweep_workers_take_the_axis_and_a_study_keeps_its_axis(tmp_path, capsys):
    small = write_axis_file(tmp_path / "small.yaml")
    assert sweep(tmp_path, "--axis", small, "--trials", "4", "--workers", "2", "--no-plots") == 0
    best = yaml.safe_load((tmp_path / "runs/sweep/s/best.yaml").read_text())
    axis = load_axis(small)
    ev = evaluate(
        load_settings(str(tmp_path / "runs/sweep/s/best.yaml"), axis),
        axis.scenarios("train"),
        axis=axis,
    )
    assert best["cost"] == pytest.approx(float(ev.mean_cost[0]), rel=1e-12)
    # the same study on another axis with the same move names is refused
    other = SMALL | {"plant": {"motor": {"inertia_ratio": 4.0}}}
    other_path = write_axis_file(tmp_path / "other.yaml", other)
    capsys.readouterr()
    assert sweep(tmp_path, "--axis", other_path, "--trials", "5", "--no-plots") == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "already optimises axis='small:" in err


def test_evaluate_judges_on_the_axis_test_moves(tmp_path, capsys):
    """The smoke run of the issue on an engineered axis, a small bootstrap."""
    tuned = tmp_path / "tuned.yaml"
    tuned.write_text(yaml.safe_dump({"value_rad": 2.0, "error_limit_rad": 2.0, "k": 2000.0}))
    path = str(AXES / "belt.yaml")
    args = ["evaluate", "--axis", path, "--settings", str(tuned), "--against", "paper,scurve"]
    args += ["--runs-dir", str(tmp_path / "runs"), "--bootstrap", "200", "--name", "e"]
    assert main(args) == 0
    run = tmp_path / "runs" / "evaluate" / "e"
    axis = load_axis(path)
    assert load_axis(run / AXIS_FILE) == axis
    test = axis.scenarios("test")
    ev = evaluate(load_settings(str(tuned), axis), test, axis=axis)
    with (run / "results.csv").open() as fh:
        rows = [r for r in csv.DictReader(fh) if r["controller"] == "tuned"]
    assert [r["scenario"] for r in rows] == [s.name for s in test]
    assert [float(r["cost"]) for r in rows] == list(ev.cost[0])
    conf = yaml.safe_load((run / "config.yaml").read_text())
    assert conf["axis"] == {"file": path, "name": "belt"} and conf["count"] is None
    assert "wrote" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("extra", "needle"),
    [
        (["--count", "5"], "--count=5 is not allowed with --axis"),
        (["--first-seed", "3"], "--first-seed=3 is not allowed with --axis"),
        (["--scenarios", "train-3"], "scenario='train-3' is not known on axis 'small'"),
    ],
)
def test_evaluate_options_that_do_not_apply_to_an_axis(tmp_path, capsys, extra, needle):
    small = write_axis_file(tmp_path / "small.yaml")
    tuned = tmp_path / "t.yaml"
    tuned.write_text(yaml.safe_dump({"value_rad": 1.0}))
    args = ["evaluate", "--axis", small, "--settings", str(tuned), *extra]
    assert main([*args, "--runs-dir", str(tmp_path / "runs")]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and needle in err
    assert not (tmp_path / "runs").exists()


@pytest.mark.parametrize("command", ["simulate", "evaluate", "sweep", "grid", "export", "plot"])
def test_a_bad_axis_file_is_one_line_and_exit_2(tmp_path, capsys, command):
    bad = write_axis_file(tmp_path / "bad.yaml", {"plant": {"motor": {"preset": "SGMX"}}})
    args = {
        "simulate": ["simulate"],
        "evaluate": ["evaluate", "--settings", "x.yaml"],
        "sweep": ["sweep", "--no-progress"],
        "grid": ["grid", "--no-progress"],
        "export": ["export", "--format", "csv", "--out", str(tmp_path / "o.csv")],
        "plot": ["plot", "response", "--out", str(tmp_path / "o.png")],
    }[command]
    runs = (
        ["--runs-dir", str(tmp_path / "runs")] if command in ("evaluate", "sweep", "grid") else []
    )
    assert main([*args, "--axis", bad, *runs]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err
    assert f"{bad}: plant.motor.preset='SGMX' is not a known motor" in err
    assert not (tmp_path / "runs").exists()


def test_simulate_export_and_plot_use_the_axis(tmp_path, capsys):
    small = write_axis_file(tmp_path / "small.yaml")
    axis = load_axis(small)
    assert main(["simulate", "--axis", small, "--scenario", "up"]) == 0
    out = capsys.readouterr().out
    ev = evaluate("paper", [axis.scenario("up")], axis=axis)
    assert f"on up: cost {ev.cost[0, 0]:.4g}" in out
    assert main(["simulate", "--axis", small, "--list"]) == 0
    listed = capsys.readouterr().out.split("\n")
    assert listed[0].startswith("up") and listed[1].startswith("down")
    csv_path = tmp_path / "up.csv"
    code = main(["export", "--axis", small, "--scenario", "test-1", "--format", "csv",
                 "--out", str(csv_path), "--decimation", "50"])  # fmt: skip
    assert code == 0 and csv_path.stat().st_size > 1000
    png = tmp_path / "up.png"
    assert main(["plot", "response", "--axis", small, "--scenario", "up", "--out", str(png)]) == 0
    assert png.stat().st_size > 10_000


def test_grid_on_an_axis_is_the_reference_of_a_sweep_on_it(tmp_path, capsys):
    small = write_axis_file(tmp_path / "small.yaml")
    runs = str(tmp_path / "runs")
    grid = ["grid", "--axis", small, "--points", "2", "--refine", "0", "--runs-dir", runs]
    assert main([*grid, "--no-progress", "--name", "g"]) == 0
    ref = yaml.safe_load((tmp_path / "runs/grid/g/reference.yaml").read_text())
    assert ref["scenarios"] == ["up", "down"] and ref["axis"].startswith("small:")
    assert load_axis(tmp_path / "runs/grid/g" / AXIS_FILE) == load_axis(small)
    capsys.readouterr()
    assert sweep(tmp_path, "--axis", small, "--trials", "2", "--no-plots") == 0
    assert "gap to the grid reference" in capsys.readouterr().out
    # a sweep off the axis with moves of the same names finds no reference
    same_names = SMALL | {"plant": {"motor": {"inertia_ratio": 3.0}}}
    other = write_axis_file(tmp_path / "other.yaml", same_names)
    assert sweep(tmp_path, "--axis", other, "--trials", "2", "--no-plots", study="o") == 0
    assert "gap to the grid reference" not in capsys.readouterr().out
