"""The environments on an axis (``env_kwargs={"axis": FILE}``): its plant and measures,
its move sets as the splits, names resolved on it; vector envs equal single ones."""

from __future__ import annotations

import math
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
import yaml
from gymnasium.vector import AutoresetMode
from test_envs import run_episode
from test_envs_vector import compare_runs

import vfgym.envs  # noqa: F401  (registers the ids)
from vfgym import PAPER_PLANT, PAPER_SETTINGS, Measures, evaluate
from vfgym.axis import LOADS_AXIS, load_axis
from vfgym.envs.servo import VFServoEnv
from vfgym.envs.tune import VFTuneEnv
from vfgym.plant.measures import NAMES as METRIC_NAMES
from vfgym.space import from_action, to_action

AXES = Path(__file__).resolve().parents[2] / "experiments" / "axes"

SMALL = {
    "name": "small",
    "plant": {"motor": {"inertia_ratio": 2.0, "load_torque_nm": 0.003}},
    "measures": {"in_position_counts": 10},
    "moves": {
        "train": [
            {"name": "up", "profile": "trapezoid", "distance_rad": 1.5, "duration_s": 0.05},
            {"name": "down", "profile": "step", "distance_rad": -0.8, "duration_s": 0.05},
            {"name": "back", "profile": "scurve", "distance_rad": -0.7, "duration_s": 0.06},
        ],
        "test": {
            "random": {
                "count": 4,
                "distance_rad": [0.2, 2.0],
                "inertia_ratio": [0.0, 1.0],
                "time_factor": 2.0,
                "settle_s": 0.02,
            }
        },
    },
}


@pytest.fixture
def small(tmp_path) -> Path:
    path = tmp_path / "small.yaml"
    path.write_text(yaml.safe_dump(SMALL))
    return path


@pytest.mark.parametrize("cls", [VFTuneEnv, VFServoEnv])
def test_an_env_on_an_axis_draws_its_moves_and_simulates_its_plant(cls, small):
    axis = load_axis(small)
    env = cls(axis=str(small))
    names = set()
    for seed in range(8):
        _, info = env.reset(seed=seed)
        names.add(info["scenario"])
        ep = env.episode
        assert ep.plant == ep.scenario.plant(axis.plant)
    assert names <= {"up", "down", "back"} and len(names) >= 2
    # seeds cycle through a listed set; names resolve on the axis
    env.reset(options={"scenario_seed": 4})
    assert env.episode.scenario.name == "down"
    env.reset(options={"scenario": "back"})
    assert env.episode.scenario == axis.scenario("back")
    test = cls(axis=axis, split="test")
    _, info = test.reset(options={"scenario_seed": 2})
    assert info["scenario"] == "test-2"
    assert test.episode.scenario == axis.moves.test.random.draw(2, "test", axis.plant)


def test_tune_reward_on_an_axis_is_minus_evaluate_on_the_axis(small):
    axis = load_axis(small)
    env = gym.make("vfgym/VFTune-v0", axis=str(small), split="test")
    env.reset(options={"scenario_seed": 1})
    a = np.array([0.2, -0.1, 0.3, 0.0], dtype=np.float32)
    _, reward, _, _, info = env.step(a)
    sc = axis.scenario("test-1")
    ev = evaluate(from_action(a), [sc], axis=axis)
    assert reward == -ev.cost[0, 0] and info["scenario"] == "test-1"
    assert info["window_rad"] == pytest.approx(10 * axis.plant.motor.count_rad)
    # the paper's plant would score the same move otherwise
    other = evaluate(from_action(a), [sc])
    assert other.cost[0, 0] != ev.cost[0, 0]


def test_servo_constant_action_on_an_axis_scores_as_evaluate(small):
    axis = load_axis(small)
    env = gym.make("vfgym/VFServo-v0", axis=str(small), scenario="up")
    action = to_action(PAPER_SETTINGS).astype(np.float32)
    rewards, _, _, _, info = run_episode(env, action)
    sc = axis.scenario("up")
    ev = evaluate(from_action(action), [sc], axis=axis)
    assert info["cost"] == ev.cost[0, 0]
    for name in METRIC_NAMES:
        assert info[name] == ev.metrics[0][0][name] or math.isnan(info[name]), name
    assert rewards.sum() == pytest.approx(-info["cost"], rel=1e-9, abs=1e-12)


@pytest.mark.parametrize(("env_id", "steps"), [("vfgym/VFTune-v0", 3), ("vfgym/VFServo-v0", 80)])
def test_vector_envs_on_an_axis_equal_single_envs(env_id, steps, small):
    ended = compare_runs(env_id, 4, steps, AutoresetMode.NEXT_STEP, axis=str(small))
    assert ended >= 4


def test_the_axis_is_the_envs_one_problem_argument(small):
    # no plant or measures beside it: an axis brings its own
    with pytest.raises(TypeError, match="plant"):
        VFTuneEnv(axis=str(small), plant=PAPER_PLANT.with_motor(inertia_ratio=1.0))
    with pytest.raises(TypeError, match="measures"):
        VFServoEnv(axis=str(small), measures=Measures(in_position_counts=3))
    with pytest.raises(ValueError, match=r"axis=3 is not allowed"):
        VFTuneEnv(axis=3)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=r"nope\.yaml: no such file"):
        gym.make("vfgym/VFTune-v0", axis=str(small.parent / "nope.yaml"))
    env = VFTuneEnv(axis=str(small))
    assert env.config.axis == load_axis(small)  # resolved once, in EnvConfig
    assert env.config.plant == load_axis(small).plant
    assert env.config.measures == load_axis(small).measures
    # without one, the agents' distribution: the paper's plant under a random load a move
    assert VFTuneEnv().config.axis == LOADS_AXIS == load_axis(AXES / "loads.yaml")


def test_the_engineered_axes_make_environments():
    for name in ("belt", "vertical"):
        env = VFTuneEnv(axis=str(AXES / f"{name}.yaml"), split="test")
        obs, info = env.reset(seed=0)
        assert info["scenario"].startswith("test-") and np.all(np.isfinite(obs))
