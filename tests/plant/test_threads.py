"""vfgym never changes the torch thread count a user set (numba's OpenMP layer and torch
share libgomp's thread setting); checked in fresh processes, both import orders."""

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

torch.set_num_threads(1)
vfgym.evaluate(["paper", "rule-of-thumb", "scurve"], ["paper-step", "short-move", "reversal"])
assert torch.get_num_threads() == 1, ("evaluate", torch.get_num_threads())
envs = gym.make_vec("vfgym/VFServo-v0", num_envs=600, vectorization_mode="vector_entry_point")
envs.reset(seed=0)
for _ in range(2):
    envs.step(np.zeros((600, 4), dtype=np.float32))
assert torch.get_num_threads() == 1, ("vector env", torch.get_num_threads())
torch.set_num_threads(2)
vfgym.evaluate(["paper"], ["paper-step", "short-move"])
assert torch.get_num_threads() == 2, ("evaluate at 2", torch.get_num_threads())
print("ok")
"""


@pytest.mark.parametrize("order", ["torch-first", "vfgym-first"])
def test_parallel_calls_keep_the_torch_thread_count(order: str) -> None:
    out = subprocess.run(
        [sys.executable, "-c", textwrap.dedent(SCRIPT), order],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.strip().endswith("ok")
