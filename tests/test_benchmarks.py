"""Smoke runs of the benchmarks that have a small budget: they must run to the end.

The benchmarks print figures and assert nothing (the machine is shared), so what can be
tested is that each still runs against today's package; their figures are not checked.
"""

from __future__ import annotations

import importlib.util
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SMALL_BUDGET = ["--seconds", "0.01", "--rounds", "1", "--envs", "16"]


def _run(script: str, *args: str) -> str:
    """A benchmark's stdout; it must exit 0."""
    out = subprocess.run(
        [sys.executable, f"benchmarks/{script}", *args],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=900,
    )
    assert out.returncode == 0, out.stderr[-2000:]
    return out.stdout


def test_bench_envs_runs_to_the_end_on_a_small_budget():
    stdout = _run("bench_envs.py", *SMALL_BUDGET)
    assert "VFServo-v0 step" in stdout
    assert "VFTune-v0 on paper-step" in stdout


def test_bench_sweep_runs_to_the_end_on_a_small_budget():
    stdout = _run("bench_sweep.py", "--trials", "10", "--long", "12", "--repeat", "2", "--sql")
    assert "vfgym sweep --config quick.yaml, 10 trials:" in stdout
    assert "floor: a bare Optuna study of 10 trials" in stdout and "sweep / floor:" in stdout
    assert "(fastest of 2)" in stdout and "SQL statements a trial:" in stdout
    assert "vfgym sweep, 12 trials:" in stdout
    assert "wall ms a trial, by completion: 0-3:" in stdout


def test_bench_fit_runs_to_the_end_on_a_small_budget(tmp_path):
    args = ["--axes", "experiments/axes/belt.yaml", "--moves", "8", "--reference-points", "2"]
    stdout = _run("bench_fit.py", *args, "--reference-rounds", "0", "--out", str(tmp_path))
    assert "| belt | 32 |" in stdout
    assert (tmp_path / "belt" / "fit" / "settings_model.json").is_file()
    assert (tmp_path / "belt" / "test-optima.csv").is_file()


def test_bench_agents_runs_to_the_end_on_a_few_hundred_steps(tmp_path):
    tiny = ["n_envs=4", "n_steps=8", "batch_size=16", "n_epochs=1", "eval_freq=64",
            "n_eval_scenarios=2"]  # fmt: skip
    args = ["--algos", "ppo", "--envs", "VFTune-v0,VFServo-v0", "--seeds", "0",
            "--steps", "128", "--moves", "2", "--out", str(tmp_path)]  # fmt: skip
    _run("bench_agents.py", *args, "--hyperparams", *tiny)
    md = (tmp_path / "benchmark.md").read_text()
    # the shipped agents are residual on the shipped model, checked on the move (as vfgym
    # predict uses it): each row has its base's ratio
    for env, base in (("VFTune-v0", "model"), ("VFServo-v0", "model")):
        assert re.search(rf"\| ppo \| {env} \| {base} \(\d\.\d{{3}}x\) \| 128 \|", md)
    assert md.count("vfgym train --algo ppo") == 2
    assert (tmp_path / "learning_curves.png").stat().st_size > 1000
    # the two run folders again, combined: one row each (two envs), and their curves
    runs = [str(tmp_path / "train" / f"ppo-{env}-seed0") for env in ("VFTune-v0", "VFServo-v0")]
    out = tmp_path / "combined"
    stdout = _run("bench_agents.py", "--moves", "2", "--combine", *runs, "--out", str(out))
    for env, base in (("VFTune-v0", "model"), ("VFServo-v0", "model")):
        row = re.search(rf"\| ppo \| {env} \| {base} \(\d\.\d{{3}}x\) \| 128 \| nan \|", stdout)
        assert row and row.group(0) in (out / "benchmark.md").read_text()
    assert (out / "learning_curves.png").stat().st_size > 1000


def test_bench_agents_groups_run_folders_by_algo_env_and_hyperparameters(tmp_path, monkeypatch):
    path = ROOT / "benchmarks" / "bench_agents.py"
    spec = importlib.util.spec_from_file_location("bench_agents", path)
    bench = importlib.util.module_from_spec(spec)
    monkeypatch.setitem(sys.modules, "bench_agents", bench)  # its dataclass looks itself up
    spec.loader.exec_module(bench)
    runs = {"a0": ("sac", 0, 1e-4), "b0": ("sac", 0, 3e-4), "a1": ("sac", 1, 1e-4),
            "c0": ("td3", 0, 1e-4)}  # fmt: skip
    for name, (algo, seed, lr) in runs.items():
        (tmp_path / name).mkdir()
        (tmp_path / name / "config.yaml").write_text(
            f"algo: {algo}\nenv: vfgym/VFServo-v0\nseed: {seed}\n"
            f"hyperparams:\n  learning_rate: {lr}\n"
        )
    got = bench.groups([tmp_path / n for n in runs])
    assert {k: [f.name for f in v] for k, v in got.items()} == {
        ("sac", "VFServo-v0"): ["a0", "a1"],
        ("sac", "VFServo-v0 #2"): ["b0"],
        ("td3", "VFServo-v0"): ["c0"],
    }


def test_bench_estimating_runs_and_the_scheduler_holds_the_bases_feasibility():
    """On a few pairs, with the shipped model as the base: the scheduler row is there, and
    it breaks no limit the base holds (what its continuations are checked for)."""
    args = ["--model", "src/vfgym/permove/pretrained/settings_model.json", "--moves", "2",
            "--plants", "3", "--evals", "12"]  # fmt: skip
    stdout = _run("bench_estimating.py", *args)
    row = next(ln for ln in stdout.splitlines() if ln.startswith("| estimating scheduler |"))
    assert row.rstrip().endswith("| 0 |"), row  # limits broken where the base holds


def test_bench_estimating_outside_runs_and_prints_the_goals():
    """``--outside`` on one move: a row per plant outside the ranges, the goals' line, and
    no limit broken outside where the base holds."""
    args = ["--model", "src/vfgym/permove/pretrained/settings_model.json", "--outside",
            "--moves", "1", "--plants", "2", "--evals", "12", "--levels", "0.1"]  # fmt: skip
    stdout = _run("bench_estimating.py", *args)
    rows = [ln for ln in stdout.splitlines() if ln.startswith("| ")]
    assert any(ln.startswith("| gain 1 x 0.9 |") for ln in rows), stdout
    assert any(ln.startswith("| inertia 1.25 x 1.1 |") for ln in rows), stdout
    assert sum(ln.startswith("| outside, all 6 |") for ln in rows) == 1, stdout
    goals = next(ln for ln in stdout.splitlines() if ln.startswith("goals:"))
    assert goals.startswith("goals: breaks where the base holds, outside: 0 "), goals


def test_bench_identify_resonance_runs_to_the_end_on_one_plant():
    stdout = _run("bench_identify_resonance.py", "--resonance-plants", "1")
    assert "== resonance: 1 plants of seed" in stdout
    assert "goal: resonance within 5%: " in stdout
    assert "goal: identification within 30 s wall: " in stdout
