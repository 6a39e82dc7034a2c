"""Smoke runs of the benchmarks that have a small budget: they must run to the end.

The benchmarks print figures and assert nothing (the machine is shared), so what can be
tested is that each still runs against today's package; their figures are not checked.
"""

from __future__ import annotations

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
    stdout = _run("bench_sweep.py", "--trials", "10", "--long", "12")
    assert "sweep / kernel:" in stdout
    assert "12 / 10 trials, time:" in stdout
