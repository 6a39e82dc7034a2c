"""The sweep and the grid as library calls (``tuning.sweep``, ``tuning.grid``), as a
notebook runs them: the run folder the command writes, the result returned; the axis
loaded once, where the configuration is made; the package imported without Optuna or
scikit-learn."""

from __future__ import annotations

import dataclasses
import os
import subprocess
import sys
from pathlib import Path

import yaml

from vfgym import tuning
from vfgym.axis import AXIS_FILE, PAPER_AXIS, load_axis

SRC = Path(__file__).resolve().parents[2] / "src"

SMALL = {
    "plant": {"motor": {"inertia_ratio": 2.0}},
    "moves": {
        "train": [
            {"name": "up", "profile": "trapezoid", "distance_rad": 1.5, "duration_s": 0.05},
            {"name": "down", "profile": "step", "distance_rad": -0.8, "duration_s": 0.05},
        ],
        "test": [{"name": "far", "profile": "trapezoid", "distance_rad": 3.0, "duration_s": 0.08}],
    },
}


def test_a_sweep_is_a_call_that_writes_its_run_folder_and_returns_what_it_found(tmp_path):
    cfg = tuning.SweepConfig(scenarios="short-move", trials=4, runs_dir=str(tmp_path),
                             study="lib", plots=False, progress=False)  # fmt: skip
    starts, steps = [], []
    result = tuning.sweep(cfg, on_start=starts.append, on_progress=steps.append)
    run = tmp_path / "sweep" / "lib"
    assert result.run_dir == run and result.created and not result.interrupted
    assert result.counts.complete == 4 and not result.unfinished
    assert (run / "report.txt").read_text() == result.text() + "\n"
    assert yaml.safe_load((run / "summary.yaml").read_text()) == yaml.safe_load(
        yaml.safe_dump(result.as_dict())
    )
    assert result.best is not None
    assert yaml.safe_load((run / "best.yaml").read_text()) == result.best.as_dict()
    assert result.best.trial == tuning.best_trial(result.study).number
    # told once before the first trial, then how far, the last report final
    (start,) = starts
    assert start.study == "lib" and start.created and start.complete == 0 and start.budget == 4
    assert steps and steps[-1].final and steps[-1].complete == 4
    assert steps[-1].best_cost == result.best.cost
    # the command line it stands for, and the axis it tuned on
    assert (run / "command.txt").read_text() == (
        "vfgym sweep --scenarios=short-move --objective=cost --trials=4 --study=lib "
        f"--runs-dir={tmp_path} "
        "--no-plots --no-progress\n"
    )
    assert load_axis(run / AXIS_FILE) == PAPER_AXIS
    # continued: the same call with more trials
    again = tuning.sweep(dataclasses.replace(cfg, trials=6))
    assert not again.created and again.counts.complete == 6
    assert [len(w.trials) for w in again.workers] == [2] and again.workers[0].exit == 0


def test_a_grid_is_a_call_that_writes_its_run_folder(tmp_path):
    cfg = tuning.GridConfig(scenarios="short-move", points=2, refine=0, runs_dir=str(tmp_path),
                            name="g", progress=False)  # fmt: skip
    done = tuning.grid(cfg)
    run = tmp_path / "grid" / "g"
    assert done.run_dir == run and len(done.result.rows) == 2**4
    assert (run / "report.txt").read_text() == done.text() + "\n"
    assert yaml.safe_load((run / "reference.yaml").read_text()) == done.reference
    assert done.reference["cost"] == done.result.best.cost and done.reference["axis"] is None
    assert load_axis(run / AXIS_FILE) == PAPER_AXIS


def test_an_axis_file_is_loaded_once_where_the_config_is_made(tmp_path):
    """The configuration holds the axis: nothing after it reads the file again (here it
    is gone before the sweep runs, in this process and in two worker processes)."""
    path = tmp_path / "small.yaml"
    path.write_text(yaml.safe_dump(SMALL))
    cfg = tuning.SweepConfig.resolve(
        {"axis": str(path), "trials": 3, "plots": False, "progress": False},
        {"runs_dir": str(tmp_path / "runs"), "study": "s", "workers": "2"},
    )
    axis = load_axis(path)
    assert cfg.axis == axis and cfg.axis_file == str(path) and cfg.scenarios == "train"
    assert not cfg.default_axis and cfg.axis_key() is not None
    os.remove(path)
    result = tuning.sweep(cfg)
    assert result.counts.complete == 3 and sorted(w.exit for w in result.workers) == [0, 0]
    run = result.run_dir
    assert load_axis(run / AXIS_FILE) == axis
    assert yaml.safe_load((run / "config.yaml").read_text())["axis"] == str(path)
    assert result.best is not None and result.best.axis == str(path)
    assert result.best.scenarios == ["up", "down"]
    assert result.verdict is not None and result.verdict.title.endswith("axis small")


def test_an_axis_object_is_a_problem_of_its_own():
    axis = dataclasses.replace(PAPER_AXIS, name="other", description="an axis made in Python")
    cfg = tuning.SweepConfig(axis=axis)
    assert cfg.axis is axis and cfg.axis_file is None and not cfg.default_axis
    assert cfg.scenarios == "train" and cfg.axis_key() is not None
    assert [s.name for s in cfg.scenario_list()] == [s.name for s in axis.scenarios("train")]
    default = tuning.SweepConfig(scenarios="train", scenario_count=3, first_seed=5)
    assert default.default_axis and default.axis_key() is None and default.axis is PAPER_AXIS
    assert [s.name for s in default.scenario_list()] == ["train-5", "train-6", "train-7"]
    assert tuning.SweepConfig().to_dict()["axis"] is None


def test_importing_tuning_and_the_sweep_command_loads_neither_optuna_nor_sklearn():
    code = (
        "import sys, vfgym.tuning, vfgym.commands.sweep, vfgym.commands.grid; "
        "print(sorted(m for m in ('optuna', 'sklearn', 'sqlalchemy', 'matplotlib') "
        "if m in sys.modules))"
    )
    env = {**os.environ, "PYTHONPATH": str(SRC)}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env,
                         check=True)  # fmt: skip
    assert out.stdout.strip() == "[]"


def test_an_interrupted_sweep_keeps_its_trials_and_gives_ctrl_c_back(tmp_path):
    """Ctrl-C in the middle of a two-worker sweep: the call returns what the study holds,
    marked interrupted, and Ctrl-C is acted on again afterwards, as before the call."""
    import signal
    import threading
    import time

    before = signal.getsignal(signal.SIGINT)
    # the timeout bounds the test if the interrupt is lost: it then fails, not hangs
    cfg = tuning.SweepConfig(scenarios="short-move", trials=100_000, workers=2, study="i",
                             runs_dir=str(tmp_path), plots=False, progress=False,
                             timeout=300.0)  # fmt: skip
    started = []

    def interrupt(p: tuning.SweepProgress) -> None:
        if p.complete >= 4 and not started:  # some trials done: Ctrl-C, as from a terminal
            started.append(time.monotonic())
            threading.Timer(0.1, os.kill, (os.getpid(), signal.SIGINT)).start()

    result = tuning.sweep(cfg, on_progress=interrupt)
    assert started and result.interrupted and not result.unfinished
    assert result.counts.complete >= 4 and result.verdict is None
    assert (result.run_dir / "summary.yaml").is_file() and result.best is not None
    assert signal.getsignal(signal.SIGINT) is before


def test_a_ctrl_c_while_the_sweep_reads_its_study_is_not_lost(tmp_path):
    """Ctrl-C that arrives while the parent reads the study (where library code could
    swallow the KeyboardInterrupt, as a finaliser does) still stops a two-worker sweep."""
    import signal
    import time

    cfg = tuning.SweepConfig(scenarios="short-move", trials=100_000, workers=2, study="j",
                             runs_dir=str(tmp_path), plots=False, progress=False,
                             timeout=120.0)  # fmt: skip
    sent, swallowed = [], []

    def swallowing(p: tuning.SweepProgress) -> None:
        if p.complete >= 2 and not sent:
            sent.append(time.monotonic())
            try:  # as code that catches everything would
                os.kill(os.getpid(), signal.SIGINT)
                time.sleep(0.2)
            except KeyboardInterrupt:
                swallowed.append(True)

    result = tuning.sweep(cfg, on_progress=swallowing)
    assert sent and not swallowed and result.interrupted
    assert time.monotonic() - sent[0] < 90.0
