"""A training run's progress bar ends at its total, and ``evaluations.csv`` and
TensorBoard give each held-out evaluation the same step count."""

from __future__ import annotations

import csv
from pathlib import Path

import pytest

pytest.importorskip("stable_baselines3")
pytest.importorskip("tensorboard")

import tqdm.auto
from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

from vfgym.agents import hyperparams as hp
from vfgym.agents.training import train

BARS: list = []


class _Recorded(tqdm.auto.tqdm):
    def __init__(self, *a, **kw):
        super().__init__(*a, **kw)
        BARS.append(self)


def _params(**over) -> dict:
    base = {"n_envs": 2, "n_steps": 24, "batch_size": 48, "n_epochs": 1,
            "eval_freq": 20, "n_eval_scenarios": 1, "checkpoint_freq": 10_000,
            "policy_kwargs": {"net_arch": [8]}}  # fmt: skip
    return hp.load("ppo", "vfgym/VFTune-v0", hp.HYPERPARAMS_DIR / "ppo.yml", base | over)


def test_the_bar_ends_at_its_total_when_rollouts_overrun_n_timesteps(tmp_path, monkeypatch):
    """100 timesteps in rollouts of 24 x 2 = 48 end at 144: the bar's total says so."""
    BARS.clear()
    monkeypatch.setattr(tqdm.auto, "tqdm", _Recorded)
    model = train("ppo", "vfgym/VFTune-v0", _params(n_timesteps=100), tmp_path, seed=0,
                  progress=True, log=lambda _: None)  # fmt: skip
    (bar,) = [b for b in BARS if b.desc == "train"]
    assert model.num_timesteps == 144
    assert bar.n == bar.total == 144


def test_evaluations_csv_and_tensorboard_give_the_same_steps(tmp_path):
    train("ppo", "vfgym/VFTune-v0", _params(n_timesteps=96), tmp_path, seed=0, progress=False,
          log=lambda _: None)  # fmt: skip
    with (tmp_path / "evaluations.csv").open() as fh:
        rows = list(csv.DictReader(fh))
    csv_steps = [int(r["timesteps"]) for r in rows]
    assert len(csv_steps) >= 3  # every 20 steps of 96, on 2 envs: 2, 22, 42, ...
    (events,) = {p.parent for p in Path(tmp_path, "tb").rglob("events.out.tfevents.*")}
    acc = EventAccumulator(str(events))
    acc.Reload()
    scalars = acc.Scalars("eval/mean_cost")
    assert [s.step for s in scalars] == csv_steps
    for s, r in zip(scalars, rows, strict=True):
        assert s.value == pytest.approx(float(r["mean_cost"]), rel=1e-5)
