"""The stable-baselines3 adapter: the same numbers as SB3's DummyVecEnv over single envs with
the same seeds, seeds and options at reset, and a small PPO run on it."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

pytest.importorskip("stable_baselines3")

from stable_baselines3.common.vec_env import DummyVecEnv, VecMonitor

import vfgym.envs
from vfgym.envs.sb3 import SB3VecEnv, make_sb3_vec_env

TUNE, SERVO = vfgym.envs.ENV_IDS


def assert_same_infos(a: list[dict], b: list[dict]) -> None:
    assert len(a) == len(b)
    for x, y in zip(a, b, strict=True):
        assert x.keys() == y.keys()
        for k in x:
            if isinstance(x[k], np.ndarray):
                assert x[k].dtype == y[k].dtype and np.array_equal(x[k], y[k]), k
            elif isinstance(x[k], float) and np.isnan(x[k]):
                assert np.isnan(y[k]), k
            else:
                assert x[k] == y[k] and type(x[k]) is type(y[k]), k


@pytest.mark.parametrize(
    ("env_id", "steps", "kwargs"),
    [
        (TUNE, 4, {}),
        (SERVO, 260, {"seed_range": (0, 50)}),
    ],
)
def test_adapter_equals_dummy_vec_env_of_single_envs(env_id, steps, kwargs):
    n = 3
    ours = make_sb3_vec_env(env_id, n, seed=11, **kwargs)
    ref = DummyVecEnv([lambda: gym.make(env_id, **kwargs) for _ in range(n)])
    ref.seed(11)
    assert np.array_equal(ours.reset(), ref.reset())
    assert ours.reset_infos == ref.reset_infos
    rng = np.random.default_rng(1)
    ended = 0
    for _ in range(steps):
        a = rng.uniform(-1, 1, (n, 4)).astype(np.float32)
        (o1, r1, d1, i1), (o2, r2, d2, i2) = ours.step(a), ref.step(a)
        for x, y in ((o1, o2), (r1, r2), (d1, d2)):
            assert x.dtype == y.dtype and np.array_equal(x, y)
        assert_same_infos(i1, i2)
        assert ours.reset_infos == ref.reset_infos
        ended += int(d1.sum())
    assert ended >= 6


def test_adapter_seed_and_options_reach_the_next_reset():
    ours = make_sb3_vec_env(TUNE, 2)
    ours.seed(5)
    ours.set_options({"scenario": "paper-step"})
    obs = ours.reset()
    single = gym.make(TUNE)
    assert np.array_equal(obs[1], single.reset(seed=6, options={"scenario": "paper-step"})[0])
    assert [i["scenario"] for i in ours.reset_infos] == ["paper-step", "paper-step"]
    # seeds and options are used once, as SB3's own VecEnvs do
    ours.reset()
    assert all(i["scenario"].startswith("train-") for i in ours.reset_infos)
    assert ours.get_attr("num_envs") == [2, 2]
    assert ours.env_is_wrapped(gym.Wrapper) == [False, False]
    with pytest.raises(NotImplementedError):
        ours.env_method("render")
    with pytest.raises(ValueError, match="vfgym vector env"):
        SB3VecEnv(gym.make_vec(TUNE, num_envs=2, vectorization_mode="sync"))


def test_ppo_learns_a_few_steps_on_the_batched_servo_env():
    from stable_baselines3 import PPO

    venv = VecMonitor(make_sb3_vec_env(SERVO, 4, seed=0, scenario="short-move"))
    model = PPO("MlpPolicy", venv, n_steps=32, batch_size=64, n_epochs=1, seed=0, device="cpu")
    model.learn(total_timesteps=256)
    obs = venv.reset()
    action, _ = model.predict(obs, deterministic=True)
    assert action.shape == (4, 4) and np.all(np.abs(action) <= 1.0)
