"""A first call that compiles says so in one line on stderr (with its expected duration);
one that finds its machine code cached says nothing. The mechanism is tested on a small
kernel in fresh processes (a fresh cache folder, cold then warm); the entry points'
wiring in-process, with the cache check made to answer "not compiled"."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import vfgym
from vfgym.plant import _notice as N

TINY = """
from vfgym.plant._jit import jit


@jit
def plus_one(x):
    return x + 1
"""

RUN = """
import sys
sys.path.insert(0, sys.argv[1])
import tiny
from vfgym.plant._notice import COLD_COMPILE_S, announce_compile
COLD_COMPILE_S["tiny"] = 7.0
announce_compile("tiny", "a tiny kernel", tiny.plus_one)
assert tiny.plus_one(1) == 2
announce_compile("tiny", "a tiny kernel", tiny.plus_one)  # once per process
"""


def test_a_cold_compile_says_so_once_and_a_cached_one_says_nothing(tmp_path):
    (tmp_path / "tiny.py").write_text(TINY)
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"))
    code = textwrap.dedent(RUN)

    def run() -> str:
        out = subprocess.run(
            [sys.executable, "-c", code, str(tmp_path)],
            env=env,
            capture_output=True,
            text=True,
            timeout=300,
        )
        assert out.returncode == 0, out.stderr[-2000:]
        return out.stderr

    cold, warm = run(), run()
    assert cold == "vfgym: compiling a tiny kernel once (about 7 s; cached for later runs) ...\n"
    assert warm == ""
    (tmp_path / "tiny.py").write_text(TINY + "\n# edited\n")  # a stale cache compiles again
    assert run() == cold


@pytest.fixture
def cold(monkeypatch):
    """Every entry point looks uncompiled, and none has announced itself yet."""
    monkeypatch.setattr(N, "is_compiled", lambda d: False)
    monkeypatch.setattr(N, "_ANNOUNCED", set())


@pytest.mark.parametrize(
    ("call", "line"),
    [
        (lambda: vfgym.simulate(vfgym.step_command(1.0, 700)), "the simulation kernel"),
        (lambda: vfgym.evaluate("paper", "short-move"), "the batched simulation kernel"),
        (
            lambda: _step_servo(vector=False),
            "VFServo-v0's step",
        ),
        (
            lambda: _step_servo(vector=True),
            "the vector env's SIMD-lane kernels",
        ),
    ],
    ids=["simulate", "evaluate", "servo env", "vector env"],
)
def test_each_entry_point_announces_its_compile(cold, capsys, call, line):
    call()
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"vfgym: compiling {line} once (about " in err, err
    call()
    assert capsys.readouterr().err == ""


def _step_servo(vector: bool) -> None:
    import gymnasium as gym

    if vector:
        env = gym.make_vec("vfgym/VFServo-v0", num_envs=2, vectorization_mode="vector_entry_point")
        env.reset(seed=0)
        env.step(np.zeros((2, 4), dtype=np.float32))
    else:
        env = gym.make("vfgym/VFServo-v0")
        env.reset(seed=0)
        env.step(np.zeros(4, dtype=np.float32))
