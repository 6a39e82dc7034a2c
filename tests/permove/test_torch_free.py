"""The per-move settings models need neither torch nor stable-baselines3: ``vfgym.permove``
and ``vfgym.load_tuner`` are imported, and the shipped model predicts a move's settings,
in a fresh interpreter where importing either raises ``ModuleNotFoundError`` (as without
the agents extra)."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from vfgym.permove import load_tuner

SRC = Path(__file__).resolve().parents[2] / "src"
BLOCKED = ("torch", "stable_baselines3", "sb3_contrib")

CHILD = textwrap.dedent(
    """
    import sys

    BLOCKED = {blocked!r}


    class Blocker:
        def find_spec(self, name, path=None, target=None):
            if name.partition(".")[0] in BLOCKED:
                raise ModuleNotFoundError(f"No module named {{name!r}} (blocked)", name=name)
            return None


    sys.meta_path.insert(0, Blocker())
    {body}
    """
)


def run_blocked(body: str) -> subprocess.CompletedProcess[str]:
    """``body`` in a fresh interpreter with torch, stable-baselines3 and sb3-contrib
    blocked; ``src/`` first on the path."""
    code = CHILD.format(blocked=BLOCKED, body=textwrap.dedent(body))
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(SRC), os.environ.get("PYTHONPATH", "")]))
    return subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=600
    )


def test_the_blocker_blocks() -> None:
    """The child's blocker makes ``import torch`` fail, so the test below means something."""
    out = run_blocked("import torch\n")
    assert out.returncode != 0 and "No module named 'torch' (blocked)" in out.stderr


def test_permove_predicts_without_torch_or_stable_baselines3() -> None:
    out = run_blocked(
        """
        import vfgym
        import vfgym.permove
        from vfgym.permove import fit_axis, move_optima, refine  # noqa: F401

        print(repr(vfgym.load_tuner()("short-move")))
        print(repr(vfgym.permove.load_tuner()("test-3")))
        print(sorted(m for m in sys.modules if m.partition(".")[0] in BLOCKED))
        """
    )
    assert out.returncode == 0, out.stderr
    lines = out.stdout.strip().splitlines()
    shipped = load_tuner()
    assert lines[-3:] == [repr(shipped("short-move")), repr(shipped("test-3")), "[]"]


def test_a_trained_agent_is_not_read_by_permove(tmp_path: Path) -> None:
    """A ``.zip`` names the loader that reads it rather than failing on torch."""
    agent = tmp_path / "best_model.zip"
    agent.write_bytes(b"x")
    with pytest.raises(ValueError, match=r"a trained agent; vfgym\.agents\.load_tuner reads it"):
        load_tuner(agent)
