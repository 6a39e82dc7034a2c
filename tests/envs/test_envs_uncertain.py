"""Episodes on uncertain plants: on an axis with ``uncertainty:`` both envs draw each
episode's true plant within it (seeded), simulate and score the move on it, observe the
modelled plant, and put the true plant in ``info``; the reset options can set it. Their
rewards are the scoring path's on the same (move, true plant) pair."""

from __future__ import annotations

from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import vfgym  # noqa: F401  (registers the envs)
from vfgym import evaluate, load_axis
from vfgym.axis import NOMINAL, PlantVariant
from vfgym.envs.tune import action_settings

AXIS = Path(__file__).resolve().parents[2] / "experiments" / "axes" / "loads-uncertain.yaml"


def test_vftune_draws_true_plants_within_the_uncertainty_and_scores_on_them():
    env = gym.make("vfgym/VFTune-v0", axis=str(AXIS))
    axis = load_axis(AXIS)
    seen = []
    for k in range(12):
        env.reset(seed=100 + k)
        _, _, terminated, _, info = env.step(np.zeros(4, np.float32))
        assert terminated
        v = info["true_plant"]
        assert 0.8 <= v.inertia <= 1.25
        seen.append(v.inertia)
        sc = env.unwrapped.episode.scenario
        s = action_settings(np.zeros(4), "rise")
        ev = evaluate([s], [sc], axis=axis, plants=[v])
        assert ev.across is not None
        assert info["cost"] == pytest.approx(float(ev.across.cost[0, 0, 0]), rel=1e-12)
    assert len(set(seen)) == 12  # a plant a draw
    again = gym.make("vfgym/VFTune-v0", axis=str(AXIS))
    again.reset(seed=100)
    _, _, _, _, info = again.step(np.zeros(4, np.float32))
    assert info["true_plant"].inertia == seen[0]  # seeded


def test_the_observation_is_the_modelled_plant_and_the_options_set_the_true_one():
    env = gym.make("vfgym/VFTune-v0", axis=str(AXIS))
    obs_a, _ = env.reset(options={"scenario_seed": 5, "plant": PlantVariant(inertia=0.8)})
    _, _, _, _, info_a = env.step(np.zeros(4, np.float32))
    obs_b, _ = env.reset(options={"scenario_seed": 5, "plant": PlantVariant(inertia=1.25)})
    _, _, _, _, info_b = env.step(np.zeros(4, np.float32))
    assert np.array_equal(obs_a, obs_b)  # a controller cannot tell them apart beforehand
    assert info_a["true_plant"].inertia == 0.8 and info_b["true_plant"].inertia == 1.25
    assert info_a["cost"] != info_b["cost"]
    env.reset(options={"scenario_seed": 5, "plant": NOMINAL})
    _, _, _, _, info = env.step(np.zeros(4, np.float32))
    assert "true_plant" not in info
    with pytest.raises(ValueError, match=r"options\['plant'\]=1.2 must be a"):
        env.reset(options={"plant": 1.2})


def test_vfservo_runs_its_move_on_the_true_plant():
    env = gym.make("vfgym/VFServo-v0", axis=str(AXIS))
    costs = {}
    for f in (0.8, 1.25):
        env.reset(options={"scenario_seed": 3, "plant": PlantVariant(inertia=f)})
        done, info = False, {}
        while not done:
            _, _, term, trunc, info = env.step(np.zeros(4, np.float32))
            done = term or trunc
        assert info["true_plant"].inertia == f
        costs[f] = info["cost"]
    assert costs[0.8] != costs[1.25]


def test_an_exact_axis_draws_nothing_more():
    """Without uncertainty the episodes (and the generator's stream) are as before."""
    env = gym.make("vfgym/VFTune-v0")
    env.reset(seed=7)
    _, _, _, _, info = env.step(np.zeros(4, np.float32))
    assert "true_plant" not in info
    assert (
        env.unwrapped.episode.plant
        is env.unwrapped.episode.scenario.plant(env.unwrapped.source.base)
        or env.unwrapped.episode.model is None
    )
