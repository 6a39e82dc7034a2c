"""The command line's progress bars end at their total: ``vfgym grid`` (whose first total
is an estimate that counts refinement points already on the grid) and ``vfgym sweep``.
The training bar is tested in tests/agents/test_train_steps.py."""

from __future__ import annotations

from pathlib import Path

import tqdm

from vfgym.cli import main

REPO = Path(__file__).resolve().parents[2]

BARS: list = []


class _Recorded(tqdm.tqdm):
    def __init__(self, *a, **kw):
        super().__init__(*a, **kw)
        BARS.append(self)


def _bars(monkeypatch) -> list:
    BARS.clear()
    monkeypatch.setattr(tqdm, "tqdm", _Recorded)
    return BARS


def test_grid_bar_ends_at_its_total(tmp_path, monkeypatch):
    bars = _bars(monkeypatch)
    argv = ["grid", "--config", str(REPO / "experiments/grid-paper-step.yaml"), "--points", "3",
            "--refine", "1", "--keep", "2", "--runs-dir", str(tmp_path), "--progress"]  # fmt: skip
    assert main(argv) == 0
    (bar,) = bars
    assert bar.n == bar.total > 3**4


def test_sweep_bar_ends_at_its_total(tmp_path, monkeypatch):
    bars = _bars(monkeypatch)
    argv = ["sweep", "--scenarios", "paper-step", "--trials", "6", "--runs-dir", str(tmp_path),
            "--no-plots", "--progress"]  # fmt: skip
    assert main(argv) == 0
    (bar,) = bars
    assert bar.n == bar.total == 6
