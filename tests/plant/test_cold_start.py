"""A first call that compiles says so in one line on stderr (with its expected duration);
one that finds its machine code cached says nothing; a long one (the vector env's) also
shows its progress. The mechanism is tested on a small kernel in fresh processes (a fresh
cache folder, cold then warm); the entry points' wiring in-process, with the cache check
made to answer "not compiled". The vector env compiles its kernels for one type of
action only: float32 (SB3) and float64 actions give the same numbers."""

from __future__ import annotations

import os
import re
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import vfgym
from vfgym.envs import _batch as B
from vfgym.envs.vector import VFServoVectorEnv
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


PROGRESS = """
import sys, time
sys.path.insert(0, sys.argv[1])
import tiny
from vfgym.plant import _notice as N
N.COLD_COMPILE_S["tiny"] = 40.0
N.PROGRESS_EVERY_S = 0.1
with N.compiling("tiny", "a tiny kernel", tiny.plus_one):
    assert tiny.plus_one(1) == 2
    time.sleep(0.45)  # a long compile
with N.compiling("tiny", "a tiny kernel", tiny.plus_one):  # once per process
    time.sleep(0.25)
"""


def _runner(tmp_path, code: str):
    """A function running ``code`` in a fresh process on ``tmp_path``'s cache; its stderr."""
    (tmp_path / "tiny.py").write_text(TINY)
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"))

    def run() -> str:
        out = subprocess.run(
            [sys.executable, "-c", textwrap.dedent(code), str(tmp_path)],
            env=env,
            capture_output=True,
            text=True,
            timeout=300,
        )
        assert out.returncode == 0, out.stderr[-2000:]
        return out.stderr

    return run


def test_a_cold_compile_says_so_once_and_a_cached_one_says_nothing(tmp_path):
    run = _runner(tmp_path, RUN)
    cold, warm = run(), run()
    assert cold == "vfgym: compiling a tiny kernel once (about 7 s; cached for later runs) ...\n"
    assert warm == ""
    (tmp_path / "tiny.py").write_text(TINY + "\n# edited\n")  # a stale cache compiles again
    assert run() == cold


def test_a_long_compile_shows_its_progress_and_a_cached_one_nothing(tmp_path):
    run = _runner(tmp_path, PROGRESS)
    cold, warm = run(), run()
    lines = cold.splitlines()
    assert lines[0] == "vfgym: compiling a tiny kernel once (about 40 s; cached for later runs) ..."
    # stderr is a pipe here, not a terminal: a line every PROGRESS_EVERY_S (the compile
    # and the 0.45 s sleep: at least 4), then the total
    spent = [re.fullmatch(r"vfgym: \.\.\. compiling, (\d+) s", line) for line in lines[1:-1]]
    assert len(spent) >= 4 and all(spent), cold
    seconds = [int(m.group(1)) for m in spent]
    assert seconds == sorted(seconds), cold
    total = re.fullmatch(r"vfgym: compiled in (\d+) s", lines[-1])
    assert total and int(total.group(1)) >= seconds[-1], cold
    assert warm == ""


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
        (
            lambda: _step_servo(vector=True, envs=B.PARALLEL_MIN_ENVS),
            "the vector env's SIMD-lane kernels on threads",
        ),
    ],
    ids=["simulate", "evaluate", "servo env", "vector env", "vector env, threads"],
)
def test_each_entry_point_announces_its_compile(cold, capsys, call, line):
    call()
    err = capsys.readouterr().err.splitlines()
    assert err[0].startswith(f"vfgym: compiling {line} once (about "), err
    if "SIMD" in line:  # the vector env's (long) compile shows its progress (if it is real)
        assert all(re.fullmatch(r"vfgym: \.\.\. compiling, \d+ s", x) for x in err[1:-1]), err
        assert re.fullmatch(r"vfgym: compiled in \d+ s", err[-1]), err
    else:
        assert len(err) == 1, err
    call()
    assert capsys.readouterr().err == ""


def _step_servo(vector: bool, envs: int = 2) -> None:
    import gymnasium as gym

    if vector:
        env = gym.make_vec(
            "vfgym/VFServo-v0", num_envs=envs, vectorization_mode="vector_entry_point"
        )
        env.reset(seed=0)
        env.step(np.zeros((envs, 4), dtype=np.float32))
    else:
        env = gym.make("vfgym/VFServo-v0")
        env.reset(seed=0)
        env.step(np.zeros(4, dtype=np.float32))


def test_float32_and_float64_actions_step_alike_through_one_compiled_kernel():
    n = 20  # a block in lanes and a block env by env
    envs = [VFServoVectorEnv(n, seed_range=(0, 30)), VFServoVectorEnv(n, seed_range=(0, 30))]
    for env in envs:
        env.reset(seed=5)
    rng = np.random.default_rng(1)
    for _ in range(30):
        a32 = rng.uniform(-1, 1, (n, 4)).astype(np.float32)
        out32 = envs[0].step(a32)
        out64 = envs[1].step(a32.astype(np.float64))
        for x, y in zip(out32[:4], out64[:4], strict=True):
            assert x.dtype == y.dtype and x.tobytes() == y.tobytes()
        assert envs[0]._W.tobytes() == envs[1]._W.tobytes()
    # one compiled step, for float64 actions: SB3's float32 ones are converted first
    assert [str(sig[0]) for sig in B._step_serial.signatures] == ["array(float64, 2d, C)"]


def test_single_servo_env_steps_float32_actions_through_the_float64_kernel():
    import gymnasium as gym

    envs = [gym.make("vfgym/VFServo-v0").unwrapped for _ in range(2)]
    for env in envs:
        env.reset(seed=3)
    rng = np.random.default_rng(2)
    for _ in range(40):
        a32 = rng.uniform(-1, 1, 4).astype(np.float32)
        out32 = envs[0].step(a32)
        out64 = envs[1].step(a32.astype(np.float64))
        assert out32[0].tobytes() == out64[0].tobytes()
        assert out32[1:4] == out64[1:4]
        if out32[2] or out32[3]:
            break
    sigs = {str(sig[0]) for sig in B.step_one.signatures}
    assert sigs == {"array(float64, 1d, C)"}, sigs
