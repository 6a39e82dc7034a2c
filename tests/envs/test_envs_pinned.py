"""Golden episodes: the vector envs' rewards, scenarios and observations for one seed and
one sequence of actions, bit for bit as main 886b643 gave them (printed there with
``float.hex``), so that speeding up the envs' Python (scenario draws, commands, scoring,
infos) cannot change an episode. The numbers were computed by the code before the
change, not by the code under test."""

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
        "-0x1.b2acc3fc6fecap+5",
        "-0x1.6649f286840bfp+4",
        "-0x1.f47a0b47fc8b2p+8",
        "-0x1.18844f274038bp+2",
    ],
    ["0x0.0p+0"] * 4,  # next-step autoreset: the step that resets every sub-env
    [
        "-0x1.02977f0cf815bp+4",
        "-0x1.84cb4951e63e3p+2",
        "-0x1.2f8b2ebdc85f2p+5",
        "-0x1.702c244772d71p+3",
    ],
]
TUNE_OBS_SUMS = ["0x1.6f8bead200000p+4", "0x1.68f752e300000p+4", "0x1.68f752e300000p+4"]

SERVO_RETURNS = ["-0x1.82b143f116e67p+7", "-0x1.3261fe3f25255p+8", "-0x1.01aa017159850p+8"]
SERVO_ENDS = [
    (54, 1, "train-1357624910", "0x1.26bcee62a64b2p+5"),
    (70, 0, "train-1829338325", "0x1.027ce8f7497d6p+6"),
    (89, 2, "train-1214225396", "0x1.0a3a7460f30bbp+7"),
    (102, 1, "train-17191595", "0x1.07a935f42fb8ap+5"),
    (121, 2, "train-830544272", "0x1.afd9df9b75c18p+4"),
    (155, 1, "train-318890903", "0x1.fa3f0042d96e5p+4"),
    (198, 2, "train-766530883", "0x1.6818412932e12p+4"),
    (201, 1, "train-828676468", "0x1.b70e4a1df9a16p+5"),
    (242, 1, "train-611780520", "0x1.6069858c3db79p+4"),
    (244, 0, "train-384259586", "0x1.d64ac10c26d88p+5"),
    (281, 1, "train-177211672", "0x1.1de435797a75cp+5"),
    (281, 2, "train-1272505875", "0x1.c4cb39df68d45p+5"),
    (294, 0, "train-56731231", "0x1.ca5c5700dfc55p+5"),
    (331, 1, "train-1025641960", "0x1.af8637c6144ecp+4"),
    (371, 1, "train-1069235513", "0x1.90559703f42c5p+5"),
]
SERVO_OBS_SUM = "0x1.075530d7e7a00p+5"


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
    ["-0x1.b2acc4p+5", "-0x1.664598p+4", "-0x1.f47a0ep+8", "-0x1.18845p+2"],
    ["-0x1.6dc80cp+4", "-0x1.4a3c52p+4", "-0x1.e63b72p+2", "-0x1.2cf992p+6"],
    ["-0x1.c8b7b4p+5", "-0x1.0932ap+4", "-0x1.c6377p+3", "-0x1.74e75cp+5"],
]
SB3_TUNE_OBS_SUMS = ["0x1.68f752e3p+4", "0x1.67317c7cp+4", "0x1.91fc6385p+4"]
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
