"""vfgym never changes the torch thread count a user set (numba's OpenMP layer and torch
share libgomp's thread setting); checked in fresh processes, both import orders, after
every kind of parallel call: ``vfgym.evaluate``, a sweep (its objective), a grid, the
VFServo-v0 vector env on numba's threads and the VFTune-v0 vector env (one batched
kernel call a step)."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import pytest

pytest.importorskip("torch")

SCRIPT = """
import sys
if sys.argv[1] == "torch-first":
    import torch
    import vfgym
else:
    import vfgym
    import torch
import gymnasium as gym
import numpy as np
from vfgym.cli import main

runs = sys.argv[2]


def check(what, n):
    assert torch.get_num_threads() == n, (what, torch.get_num_threads(), n)


torch.set_num_threads(1)
# torch reads its count once here: without vfgym's guard, every parallel call below
# would then leave it at numba's (checked by breaking the guard)
check("set", 1)
vfgym.evaluate(["paper", "rule-of-thumb", "scurve"], ["paper-step", "short-move", "reversal"])
check("evaluate", 1)
sweep = ["sweep", "--scenarios", "short-move", "--trials", "3", "--no-progress"]
assert main([*sweep, "--runs-dir", runs, "--study", "s"]) == 0
check("sweep", 1)
grid = ["grid", "--scenarios", "short-move", "--points", "2", "--refine", "0", "--no-progress"]
assert main([*grid, "--runs-dir", runs]) == 0
check("grid", 1)
envs = gym.make_vec("vfgym/VFServo-v0", num_envs=600, vectorization_mode="vector_entry_point")
envs.reset(seed=0)
for _ in range(2):
    envs.step(np.zeros((600, 4), dtype=np.float32))
check("VFServo-v0 vector env", 1)
tune = gym.make_vec("vfgym/VFTune-v0", num_envs=8, vectorization_mode="vector_entry_point")
tune.reset(seed=0)
tune.step(np.zeros((8, 4), dtype=np.float32))
check("VFTune-v0 vector env", 1)
torch.set_num_threads(2)
vfgym.evaluate(["paper"], ["paper-step", "short-move"])
check("evaluate at 2", 2)
print("ok")
"""


@pytest.mark.parametrize("order", ["torch-first", "vfgym-first"])
def test_parallel_calls_keep_the_torch_thread_count(order: str, tmp_path) -> None:
    out = subprocess.run(
        [sys.executable, "-c", textwrap.dedent(SCRIPT), order, str(tmp_path)],
        capture_output=True,
        text=True,
        timeout=900,
    )
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.strip().endswith("ok")


FIRST_CALL = """
import sys
if sys.argv[1] == "torch-first":
    import torch
    import vfgym
else:
    import vfgym
    import torch
import numpy as np
from vfgym.envs.sb3 import make_sb3_vec_env

torch.set_num_threads(1)
assert torch.get_num_threads() == 1
venv = make_sb3_vec_env("vfgym/VFTune-v0", n_envs=4, seed=0)
venv.reset()
for _ in range(2):
    venv.step(np.zeros((4, 4), dtype=np.float32))
assert torch.get_num_threads() == 1, torch.get_num_threads()
print("ok")
"""


@pytest.mark.parametrize("order", ["torch-first", "vfgym-first"])
def test_tune_sb3_first_parallel_call_keeps_the_torch_thread_count(order: str) -> None:
    """VFTune-v0 through the SB3 adapter is the process's first parallel call: it asks
    numba for its threads (which starts them) to decide whether to draw the next moves
    beside the batch, and runs the batch on a worker thread; torch's count stays."""
    out = subprocess.run(
        [sys.executable, "-c", textwrap.dedent(FIRST_CALL), order],
        capture_output=True,
        text=True,
        timeout=900,
    )
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.strip().endswith("ok")
