"""Golden episodes: the vector envs' rewards, scenarios and observations for one seed and
one sequence of actions, bit for bit as the commit that brought in the acceleration measure
of docs/model.md §5.1 gave them (printed there with ``float.hex``), so that speeding up the
envs' Python (scenario draws, commands, scoring, infos) cannot change an episode. The
numbers were computed by the code before any such change, not by the code under test; they
change only with a change of definition, as that one was."""

from __future__ import annotations

import numba
import numpy as np
import pytest

from vfgym.envs.vector import VFServoVectorEnv, VFTuneVectorEnv

H = float.fromhex

TUNE_SCENARIOS = [
    ["train-1829338325", "train-1357624910", "train-1214225396", "train-602772360"],
    ["train-384259586", "train-17191595", "train-830544272", "train-1716092143"],
]
TUNE_REWARDS = [
    [
        "-0x1.b6619faa7b7b8p+5",
        "-0x1.6649f286840bfp+4",
        "-0x1.f614e389ee2fcp+8",
        "-0x1.290ad2115ea0cp+2",
    ],
    ["0x0.0p+0"] * 4,  # next-step autoreset: the step that resets every sub-env
    [
        "-0x1.086094d3bb83fp+4",
        "-0x1.84cb4951e63e3p+2",
        "-0x1.31515cc21d462p+5",
        "-0x1.702c244772d71p+3",
    ],
]
TUNE_OBS_SUMS = ["0x1.6f8bead200000p+4", "0x1.68f752e300000p+4", "0x1.68f752e300000p+4"]

SERVO_RETURNS = ["-0x1.89451a810fafdp+7", "-0x1.39a66f4683f70p+8", "-0x1.04bc6bd62c4a1p+8"]
SERVO_ENDS = [
    (54, 1, "train-1357624910", "0x1.2c87aaecf4768p+5"),
    (70, 0, "train-1829338325", "0x1.08443636b168bp+6"),
    (89, 2, "train-1214225396", "0x1.0d65ef0377a46p+7"),
    (102, 1, "train-17191595", "0x1.0f540da704c72p+5"),
    (121, 2, "train-830544272", "0x1.b230e83c07136p+4"),
    (155, 1, "train-318890903", "0x1.039655b00233ep+5"),
    (198, 2, "train-766530883", "0x1.6b7cd73197278p+4"),
    (201, 1, "train-828676468", "0x1.bda7f700efab1p+5"),
    (242, 1, "train-611780520", "0x1.694046087f38ep+4"),
    (244, 0, "train-384259586", "0x1.dc25f6034adf8p+5"),
    (281, 1, "train-177211672", "0x1.2dd831033fd9fp+5"),
    (281, 2, "train-1272505875", "0x1.c9491507e4da4p+5"),
    (294, 0, "train-56731231", "0x1.d23ee1a340e4dp+5"),
    (331, 1, "train-1025641960", "0x1.b9d73dba21b44p+4"),
    (371, 1, "train-1069235513", "0x1.95d7c539afa68p+5"),
]
SERVO_OBS_SUM = "0x1.0799b3b23ba00p+5"  # the observation as a drive measures it (encoder
# counts, speed counter, torque command: a change of definition; 0x1.079233f7e7a00p+5 with
# the simulator's continuous angle, speed and torque), its rewards and ends unchanged


def test_tune_episodes_as_before() -> None:
    env = VFTuneVectorEnv(4)
    env.reset(seed=2026)
    rng = np.random.default_rng(5)
    for k in range(3):
        obs, rew, _, _, info = env.step(rng.uniform(-1, 1, (4, 4)))
        assert rew.tolist() == [H(x) for x in TUNE_REWARDS[k]], k
        assert float(obs.astype(np.float64).sum()) == H(TUNE_OBS_SUMS[k]), k
        assert list(info["scenario"]) == TUNE_SCENARIOS[min(k, 1)], k


def test_servo_episodes_as_before() -> None:
    env = VFServoVectorEnv(3)
    env.reset(seed=2026)
    rng = np.random.default_rng(5)
    total = np.zeros(3)
    ends = []
    for k in range(400):
        obs, rew, term, trunc, info = env.step(rng.uniform(-1, 1, (3, 4)))
        total += rew
        for i in np.flatnonzero(term | trunc):
            ends.append((k, int(i), info["scenario"][i], float(info["cost"][i]).hex()))
    assert total.tolist() == [H(x) for x in SERVO_RETURNS]
    assert ends == SERVO_ENDS
    assert float(obs.astype(np.float64).sum()) == H(SERVO_OBS_SUM)


SB3_TUNE_REWARDS = [  # float32, as the SB3 adapter returns them
    [
        "-0x1.b661a00000000p+5",
        "-0x1.6645980000000p+4",
        "-0x1.f614e60000000p+8",
        "-0x1.290ad40000000p+2",
    ],
    [
        "-0x1.7250ae0000000p+4",
        "-0x1.4a3c520000000p+4",
        "-0x1.f5d9e40000000p+2",
        "-0x1.2cf9920000000p+6",
    ],
    [
        "-0x1.ca437a0000000p+5",
        "-0x1.0932a00000000p+4",
        "-0x1.c637700000000p+3",
        "-0x1.756a2e0000000p+5",
    ],
]
SB3_TUNE_OBS_SUMS = ["0x1.68f752e300000p+4", "0x1.67317c7c00000p+4", "0x1.91fc638500000p+4"]
SB3_TUNE_NEXT = [
    ["train-384259586", "train-17191595", "train-830544272", "train-1716092143"],
    ["train-56731231", "train-318890903", "train-766530883", "train-595477346"],
    ["train-1374203059", "train-828676468", "train-1272505875", "train-82488969"],
]


@pytest.mark.parametrize("threads", [1, 2])
def test_sb3_tune_episodes_as_before(threads: int) -> None:
    """The SB3 adapter's same-step path, where VFTune-v0 draws the next moves while the
    batch simulates (beside it on a worker thread with two numba threads, after it with
    one): main's numbers either way."""
    if threads > numba.config.NUMBA_NUM_THREADS:
        pytest.skip("numba started with fewer threads")
    from vfgym.envs.sb3 import make_sb3_vec_env

    before = numba.get_num_threads()
    numba.set_num_threads(threads)
    try:
        venv = make_sb3_vec_env("vfgym/VFTune-v0", n_envs=4, seed=2026)
        venv.reset()
        rng = np.random.default_rng(5)
        for k in range(3):
            obs, rew, done, infos = venv.step(rng.uniform(-1, 1, (4, 4)).astype(np.float32))
            assert rew.tolist() == [H(x) for x in SB3_TUNE_REWARDS[k]], k
            assert float(obs.astype(np.float64).sum()) == H(SB3_TUNE_OBS_SUMS[k]), k
            assert done.all()
            assert [r["scenario"] for r in venv.reset_infos] == SB3_TUNE_NEXT[k], k
            last = [np.asarray(i["terminal_observation"], np.float64).sum() for i in infos]
            previous = SB3_TUNE_OBS_SUMS[k - 1] if k else "0x1.6f8bead2p+4"
            assert float(sum(last)) == H(previous), k
    finally:
        numba.set_num_threads(before)
