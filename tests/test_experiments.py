"""Smoke runs of the experiments that measure the sweeps against a grid reference: on a
3-point grid of ``paper-step`` (81 settings) they must run to the end and print their
tables. Their figures are not checked (they are the experiments' output, not properties).
"""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from vfgym.cli import main

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def refs(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A runs folder holding a small grid reference for ``paper-step``."""
    runs = tmp_path_factory.mktemp("refs")
    rc = main(["grid", "--scenarios", "paper-step", "--points", "3", "--refine", "0",
               "--runs-dir", str(runs)])  # fmt: skip
    assert rc == 0
    assert list(runs.glob("grid/*/reference.yaml"))
    return runs


def run(script: str, *args: str) -> str:
    out = subprocess.run(
        [sys.executable, f"experiments/{script}", *args],
        cwd=ROOT, capture_output=True, text=True, timeout=900,
    )  # fmt: skip
    assert out.returncode == 0, out.stderr[-2000:]
    return out.stdout


def test_trials_to_reference_prints_a_row_per_sampler_with_an_even_number_of_seeds(refs):
    # Two seeds: the median of two trial counts may be a half (it once failed to print).
    out = run("trials_to_reference.py", "--refs", str(refs), "--problems", "paper-step",
              "--samplers", "compass,random,cmaes", "--seeds", "0,1", "--max-trials", "6",
              "--storage", "journal")  # fmt: skip
    for sampler in ("compass", "random", "cmaes"):
        row = next(line for line in out.splitlines() if line.startswith(f"{sampler} "))
        assert re.search(r"\d+/2 ", row), row  # every run's best feasible, of 2
        said = next(line for line in out.splitlines() if line.startswith(f"{sampler}:"))
        assert "Relative" in said and "warm starts" in said, said
    assert "sigma0" in next(line for line in out.splitlines() if line.startswith("cmaes:"))


def test_held_out_problems_are_drawn_by_their_seed_apart_from_the_axes_own_moves():
    sys.path.insert(0, str(ROOT / "experiments"))
    try:
        from trials_to_reference import HELD_OUT_AXES, HELD_OUT_MOVES, held_out
    finally:
        sys.path.pop(0)
    a, b = held_out(2, 7), held_out(2, 8)
    assert a == held_out(2, 7) and a != b
    assert len(a) == 2 * len(HELD_OUT_AXES)
    for problem in a:
        axis, _, moves = problem.partition(":")
        assert axis in HELD_OUT_AXES
        seeds = [int(m.removeprefix("test-")) for m in moves.split(",")]
        assert len(set(seeds)) == HELD_OUT_MOVES and min(seeds) >= 10_000  # not 0-31
    out = run("trials_to_reference.py", "--problems", "", "--held-out", "1",
              "--held-out-seed", "7", "--print-held-out")  # fmt: skip
    assert "drawn by seed 7" in out
    assert out.count("reference: vfgym grid --axis ") == len(HELD_OUT_AXES)


def test_reference_basin_prints_a_row_per_box(refs):
    out = run("reference_basin.py", "--refs", str(refs), "--problems", "paper-step",
              "--count", "4")  # fmt: skip
    assert "reference cost" in out
    rows = [line for line in out.splitlines() if line.strip().startswith("±")]
    assert len(rows) == 5, out
    for row in rows:
        feasible, within1, within2 = (float(v) for v in row.split()[2:5])
        assert 0.0 <= within1 <= within2 <= feasible <= 1.0, row


def test_accel_feasibility_runs_and_counts_no_feasible_run_above_the_limit():
    out = subprocess.run(
        [sys.executable, "experiments/accel_feasibility.py", "--controllers", "4", "--moves", "2"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert out.returncode == 0, out.stderr[-2000:]
    lines = [ln for ln in out.stdout.splitlines() if "runs feasible" in ln]
    assert len(lines) == 2 and all(ln.endswith("above 1.01x: 0") for ln in lines)


def test_residual_ridge_runs_and_the_zero_action_costs_the_same_either_way():
    out = subprocess.run(
        [sys.executable, "experiments/residual_ridge.py", "--moves", "2"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert out.returncode == 0, out.stderr[-2000:]
    zero = next(ln for ln in out.stdout.splitlines() if ln.startswith("| zero |"))
    a, b = zero.strip("| ").split(" | ")[1:]
    assert a == b  # the zero action is the base exactly, whatever L's offset means


def test_schedule_headroom_runs_and_no_schedule_is_worse_than_the_optimum():
    """Its own check (the zero schedule costs the optimum's ``evaluate`` cost bit for bit)
    passes, and each search keeps the best found, the optimum included."""
    out = subprocess.run(
        [sys.executable, "experiments/schedule_headroom.py", "--moves", "1", "--evals", "12",
         "--interval-ms", "5", "--show", "1"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=600,
    )  # fmt: skip
    assert out.returncode == 0, out.stderr[-2000:]
    row = next(ln for ln in out.stdout.splitlines() if ln.startswith("| test-0 |"))
    optimum, *found = (float(c.split()[0]) for c in row.strip("| ").split(" | ")[2:])
    assert len(found) == 3 and all(c <= optimum for c in found)
    assert "from interval 0:" in out.stdout


def test_adaptive_headroom_runs_and_no_schedule_is_worse_than_the_base():
    """Its own check (the zero schedule costs the base's evaluate cost bit for bit) holds,
    and each search starts from the zero schedule, so none ends above the base."""
    model = "src/vfgym/permove/pretrained/settings_model.json"
    args = ["--model", model, "--moves", "1", "--plants", "2", "--evals", "12"]
    out = subprocess.run(
        [sys.executable, "experiments/adaptive_headroom.py", *args],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert out.returncode == 0, out.stderr[-2000:]
    ratio = next(ln for ln in out.stdout.splitlines() if ln.startswith("| / base |"))
    cells = [c.strip() for c in ratio.split("|")[2:] if c.strip()]
    assert len(cells) == 4 and all(float(x) <= 1.0 for x in cells)


def test_judged_with_copies_runs_with_env_arguments_and_benchmarks_the_copies(tmp_path):
    from vfgym.agents import hyperparams as hp
    from vfgym.agents import train

    tiny = {"n_envs": 2, "n_steps": 16, "batch_size": 32, "n_epochs": 1, "n_timesteps": 64,
            "eval_freq": 32, "n_eval_scenarios": 2, "checkpoint_freq": 32,
            "policy_kwargs": {"net_arch": [8]}}  # fmt: skip
    params = hp.load("ppo", "vfgym/VFServo-v0", hp.HYPERPARAMS_DIR / "ppo.yml", tiny)
    trained = tmp_path / "run"
    trained.mkdir()
    train("ppo", "vfgym/VFServo-v0", params, trained, seed=0, progress=False, log=lambda _: None)
    out = tmp_path / "judged"
    text = run("judged_with.py", "--runs", str(trained), "--set", "shield_gentler=1",
               "--out", str(out), "--", "--exact", "--base", "own", "--moves", "2")  # fmt: skip
    assert re.search(r"^\| ppo \| 0 \|", text, re.M), text
    copied = yaml.safe_load((out / "runs" / "run" / "config.yaml").read_text())
    assert copied["hyperparams"]["eval_env_kwargs"] == {"shield_gentler": 1}
    assert params["env_kwargs"].get("shield_gentler") == 3  # the run's own, kept
    assert yaml.safe_load((trained / "config.yaml").read_text())["hyperparams"].get(
        "eval_env_kwargs") is None  # fmt: skip
