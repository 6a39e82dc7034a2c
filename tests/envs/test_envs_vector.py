"""The native vector envs: the same numbers as N single envs (Gymnasium's SyncVectorEnv over
``gymnasium.make``) with the same seeds, under each autoreset mode; bad actions; the batched
scoring equal to ``evaluate`` pair by pair; thread count not changing any number."""

from __future__ import annotations

import math
import os
import subprocess
import sys

import gymnasium as gym
import numba
import numpy as np
import pytest
from gymnasium.vector import AutoresetMode

import vfgym.envs
import vfgym.envs._batch
from vfgym import LOADS_AXIS, PAPER_SETTINGS, evaluate
from vfgym.envs._common import ScenarioSource
from vfgym.envs.tune import evaluate_pairs
from vfgym.envs.vector import VFServoVectorEnv, VFTuneVectorEnv
from vfgym.params import DEFAULT_MEASURES
from vfgym.plant import _jit as J
from vfgym.plant import _layout as L
from vfgym.scoring import DEFAULT_BOUNDS, DEFAULT_WEIGHTS
from vfgym.space import from_action, to_action

TUNE, SERVO = vfgym.envs.ENV_IDS
PAPER_ACTION = to_action(PAPER_SETTINGS)


def assert_same(x, y, path="") -> None:
    """Equal data, exactly, with the same types and dtypes (NaN equal to NaN)."""
    assert type(x) is type(y), (path, type(x), type(y))
    if isinstance(x, dict):
        assert x.keys() == y.keys(), (path, sorted(set(x) ^ set(y)))
        for k in x:
            assert_same(x[k], y[k], f"{path}.{k}")
    elif isinstance(x, (tuple, list)):
        assert len(x) == len(y), path
        for k, (a, b) in enumerate(zip(x, y, strict=True)):
            assert_same(a, b, f"{path}[{k}]")
    elif isinstance(x, np.ndarray):
        assert x.dtype == y.dtype and x.shape == y.shape, (path, x.dtype, y.dtype)
        if x.dtype == object:
            for a, b in zip(x.flat, y.flat, strict=True):
                assert_same(a, b, path)
        else:
            assert np.array_equal(x, y, equal_nan=x.dtype.kind == "f"), path
    elif isinstance(x, float) and math.isnan(x):
        assert math.isnan(y), path
    else:
        assert x == y, path


def compare_runs(env_id, n, steps, mode, seed=21, probe=None, **kwargs):
    """Step the native vector env and a SyncVectorEnv of single envs side by side."""
    native = gym.make_vec(
        env_id, num_envs=n, vectorization_mode="vector_entry_point", autoreset_mode=mode, **kwargs
    )
    sync = gym.make_vec(
        env_id,
        num_envs=n,
        vectorization_mode="sync",
        vector_kwargs={"autoreset_mode": mode},
        **kwargs,
    )
    assert native.metadata["autoreset_mode"] == sync.metadata["autoreset_mode"] == mode
    assert_same(native.reset(seed=seed), sync.reset(seed=seed))
    rng = np.random.default_rng(seed)
    ended = 0
    for _ in range(steps):
        a = rng.uniform(-1, 1, (n, *native.single_action_space.shape)).astype(np.float32)
        out_native, out_sync = native.step(a), sync.step(a)
        assert_same(out_native, out_sync)
        ended += int(np.sum(out_native[2] | out_native[3]))
        if probe is not None:
            probe(native)
    return ended


@pytest.mark.parametrize("mode", [AutoresetMode.NEXT_STEP, AutoresetMode.SAME_STEP])
def test_tune_vector_env_equals_single_envs(mode):
    assert compare_runs(TUNE, 5, 4, mode) >= 10


@pytest.mark.parametrize("mode", [AutoresetMode.NEXT_STEP, AutoresetMode.SAME_STEP])
@pytest.mark.parametrize("n", [4, 21])
def test_servo_vector_env_equals_single_envs(mode, n):
    # Short random moves, so that several episodes end and sub-envs autoreset. With 21
    # envs, the first 16 tick in SIMD lanes and leave them at their episodes' ends (the
    # last, partial interval runs alone); the other 5 are too few for a block of lanes.
    ended = compare_runs(SERVO, n, 260, mode, seed_range=(0, 50), settle_time_s=0.002)
    assert ended >= 6 * (n // 4)


def test_servo_lanes_with_friction_and_envs_leaving_the_lanes():
    """Random train moves (Coulomb friction on about half, loads, random settings): envs
    enter the lanes, leave them at their episodes' ends and for the autoreset step (their
    counts go back to their rings), and come back; every number equals the single envs'."""
    seen = {"lanes": 0, "friction": 0}

    def probe(native) -> None:
        env = native.unwrapped
        seen["lanes"] += int((env._W[:, vfgym.envs._batch.X_LANE] != 0).sum())
        seen["friction"] += sum(ep.scenario.coulomb_nm > 0 for ep in env._eps)

    ended = compare_runs(SERVO, 18, 200, AutoresetMode.NEXT_STEP, seed=8, probe=probe,
                         seed_range=(0, 400), settle_time_s=0.002)  # fmt: skip
    assert ended >= 20 and seen["lanes"] > 1000 and seen["friction"] > 200


@pytest.mark.parametrize("n", [3, 17])
def test_servo_vector_env_equals_single_envs_with_violation_endings(n):
    ended = compare_runs(
        SERVO, n, 40, AutoresetMode.NEXT_STEP, terminate_on_violation=True, tracking_weight=0.5
    )
    assert ended >= n


def test_servo_lanes_out_of_step_with_the_servo_sample_period():
    # 0.2 ms intervals (28 ticks) against 70-tick servo samples: the lanes' sample periods
    # drift apart as envs reset, so each lane latches on its own (a move without friction:
    # the single-pass tick)
    phases = []

    def probe(native) -> None:
        W = native.unwrapped._W[:16]
        phases.append(len(set(W[:, vfgym.envs._batch.W_ST + L.S_NSLEFT])))

    ended = compare_runs(SERVO, 17, 400, AutoresetMode.NEXT_STEP, probe=probe, interval_s=0.0002,
                         scenario="short-move", settle_time_s=0.001)  # fmt: skip
    assert ended >= 8 and max(phases) >= 3


def test_disabled_autoreset_needs_a_reset_mask():
    kw = {"scenario": "short-move"}
    native = VFServoVectorEnv(3, autoreset_mode=AutoresetMode.DISABLED, **kw)
    singles = [gym.make(SERVO, **kw) for _ in range(3)]
    obs, _ = native.reset(seed=4)
    for i, env in enumerate(singles):
        assert np.array_equal(env.reset(seed=4 + i)[0], obs[i])
    acts = np.tile(PAPER_ACTION, (3, 1))
    acts[1] = [0.0, 0.0, 0.0, 0.0]
    done = np.zeros(3, dtype=bool)
    while not done.all():
        obs, rew, term, trunc, _ = native.step(np.where(done[:, None], PAPER_ACTION, acts))
        for i, env in enumerate(singles):
            if not done[i]:
                o, r, te, tr, _ = env.step(acts[i])
                assert np.array_equal(o, obs[i]) and r == rew[i] and (te, tr) == (term[i], trunc[i])
        if (term | trunc).any():
            with pytest.raises(ValueError, match="reset_mask"):
                native.step(acts)
            mask = term | trunc
            native.reset(options={"reset_mask": mask})
            done |= mask
    with pytest.raises(ValueError, match="reset_mask"):
        native.reset(options={"reset_mask": np.zeros(3, dtype=bool)})


def test_make_vec_prefers_the_native_env_and_its_spaces_match():
    venv = gym.make_vec(SERVO, num_envs=3)
    assert isinstance(venv, VFServoVectorEnv)
    assert venv.metadata["autoreset_mode"] == AutoresetMode.NEXT_STEP
    single = gym.make(SERVO)
    assert venv.single_observation_space == single.observation_space
    assert venv.single_action_space == single.action_space
    assert venv.observation_space.shape == (3, *single.observation_space.shape)
    obs, _ = venv.reset(seed=0)
    assert obs in venv.observation_space
    assert isinstance(gym.make_vec(TUNE, num_envs=2), VFTuneVectorEnv)


def test_vector_seeds_and_options_per_sub_env():
    venv = VFTuneVectorEnv(3)
    _, info = venv.reset(seed=[5, None, 7], options={"scenario_seed": 9})
    assert list(info["scenario"]) == ["train-9"] * 3
    _, info = venv.reset(seed=[5, 6, 7])
    single = [gym.make(TUNE).reset(seed=s)[1]["scenario"] for s in (5, 6, 7)]
    assert list(info["scenario"]) == single
    assert venv.np_random_seed == (5, 6, 7)
    with pytest.raises(ValueError, match="one per sub-env"):
        venv.reset(seed=[1, 2])
    with pytest.raises(ValueError, match="unknown key"):
        venv.reset(options={"distance": 3.0})


@pytest.mark.parametrize("cls", [VFTuneVectorEnv, VFServoVectorEnv])
def test_vector_bad_actions_raise_and_step_nothing(cls):
    venv, ref = cls(3, scenario="short-move"), cls(3, scenario="short-move")
    venv.reset(seed=0)
    ref.reset(seed=0)
    good = np.tile(PAPER_ACTION, (3, 1))
    bad = good.copy()
    bad[2, 1] = np.nan
    with pytest.raises(ValueError, match=r"actions\[2\].*finite"):
        venv.step(bad)
    bad[2, 1] = -1.5
    with pytest.raises(ValueError, match=r"actions\[2\].*out of range"):
        venv.step(bad)
    with pytest.raises(ValueError, match=r"\(3, 4\) array"):
        venv.step(good[:2])
    assert_same(venv.step(good), ref.step(good))
    if cls is VFTuneVectorEnv:
        # every sub-env has ended: next-step autoreset ignores this step's actions...
        assert_same(venv.step(bad), ref.step(good))
        # ...and checks the next ones before stepping anything
        with pytest.raises(ValueError, match=r"actions\[2\]"):
            venv.step(bad)
        assert_same(venv.step(good), ref.step(good))


def test_vector_env_arguments_are_checked():
    with pytest.raises(ValueError, match="num_envs"):
        VFServoVectorEnv(0)
    with pytest.raises(ValueError, match="autoreset_mode"):
        VFTuneVectorEnv(2, autoreset_mode="sometimes")
    with pytest.raises(ValueError, match="render_mode"):
        VFServoVectorEnv(2, render_mode="rgb_array")
    with pytest.raises(gym.error.ResetNeeded):
        VFServoVectorEnv(2).step(np.zeros((2, 4)))


@pytest.mark.parametrize("n", [6, 40])
def test_thread_count_changes_no_number(n, monkeypatch):
    # every block on numba's threads, whatever the batch's size
    monkeypatch.setattr(vfgym.envs._batch, "PARALLEL_MIN_ENVS", 1)
    outs = []
    threads = numba.get_num_threads()
    try:
        for th in sorted({1, threads}):
            numba.set_num_threads(th)
            venv = VFServoVectorEnv(n, seed_range=(0, 30))
            venv.reset(seed=3)
            acts = np.random.default_rng(2).uniform(-1, 1, (40, n, 4))
            outs.append([venv.step(a)[:4] for a in acts])
    finally:
        numba.set_num_threads(threads)
    monkeypatch.undo()  # and on the calling thread alone
    venv = VFServoVectorEnv(n, seed_range=(0, 30))
    venv.reset(seed=3)
    acts = np.random.default_rng(2).uniform(-1, 1, (40, n, 4))
    outs.append([venv.step(a)[:4] for a in acts])
    for other in outs[1:]:
        assert_same(outs[0], other)


def test_evaluate_pairs_equals_evaluate_pair_by_pair():
    source = ScenarioSource(None, "train", None, LOADS_AXIS)
    rng = np.random.default_rng(8)
    eps = [source.draw(rng, None) for _ in range(4)]
    eps += [source.draw(rng, {"scenario": name}) for name in ("paper-sine", "multi-move")]
    eps.append(eps[0])  # a shared command
    settings = [from_action(a) for a in rng.uniform(-1, 1, (len(eps), 4))]
    got = evaluate_pairs(
        settings, eps, measures=DEFAULT_MEASURES, weights=DEFAULT_WEIGHTS, bounds=DEFAULT_BOUNDS
    )
    for s, ep, res in zip(settings, eps, got, strict=True):
        ev = evaluate(s, ep.scenario, axis=LOADS_AXIS)
        assert res.cost == ev.cost[0, 0]
        assert np.array_equal(res.constraints, ev.constraints[0, 0])
        assert_same(res.metrics, ev.metrics[0][0])


@pytest.mark.parametrize("cls", [VFTuneVectorEnv, VFServoVectorEnv])
def test_same_step_bad_actions_raise_and_step_nothing(cls):
    """Same-step autoreset (the SB3 adapter's path): VFServo-v0 leaves the range check to
    its compiled step, which must refuse the batch before stepping any env."""
    venv = cls(3, scenario="short-move", autoreset_mode="SameStep")
    ref = cls(3, scenario="short-move", autoreset_mode="SameStep")
    venv.reset(seed=0)
    ref.reset(seed=0)
    good = np.tile(PAPER_ACTION, (3, 1))
    for value, message in ((np.nan, "finite"), (-1.5, "out of range"), (1.0 + 2e-6, "range")):
        bad = good.copy()
        bad[2, 1] = value
        with pytest.raises(ValueError, match=rf"actions\[2\].*{message}"):
            venv.step(bad)
    for _ in range(3):
        assert_same(venv.step(good), ref.step(good))


def test_a_bad_action_leaves_pending_autoresets_pending():
    venv, ref = (VFServoVectorEnv(2, scenario="short-move") for _ in range(2))
    venv.reset(seed=0)
    ref.reset(seed=0)
    acts = np.array([PAPER_ACTION, [0.9, 0.9, 0.0, 0.0]], dtype=np.float32)
    done = np.zeros(2, dtype=bool)
    while not done[0]:
        out = venv.step(acts)
        assert_same(out, ref.step(acts))
        done = out[2] | out[3]
    assert not done[1]  # sub-env 0 waits for its autoreset, sub-env 1 runs on
    bad = acts.copy()
    bad[1, 0] = np.nan
    with pytest.raises(ValueError, match=r"actions\[1\]"):
        venv.step(bad)
    assert_same(venv.step(acts), ref.step(acts))


@pytest.mark.parametrize(
    ("environ", "spin"),
    [
        ({}, True),  # libgomp's own default: spin a while, then sleep
        ({"OMP_WAIT_POLICY": "PASSIVE"}, False),
        ({"OMP_WAIT_POLICY": "passive "}, False),
        ({"OMP_WAIT_POLICY": "ACTIVE"}, True),
        ({"GOMP_SPINCOUNT": "300000"}, True),
        ({"GOMP_SPINCOUNT": "0"}, False),
        ({"GOMP_SPINCOUNT": "300000", "OMP_WAIT_POLICY": "PASSIVE"}, False),
    ],
)
def test_wait_policy_read_as_libgomp_reads_it(environ, spin):
    assert J.workers_spin(environ) is spin


def test_threads_start_where_the_wait_policy_makes_them_pay():
    """vfgym makes numba's workers sleep unless the user opted in to spinning, and the
    vector envs go parallel from 512 envs with sleeping workers, from 32 with spinning."""
    code = (
        "import vfgym.envs._batch as B, vfgym.plant._jit as J, os;"
        "print(os.environ.get('OMP_WAIT_POLICY'), J.SPINNING_WORKERS, B.PARALLEL_MIN_ENVS)"
    )
    base = {k: v for k, v in os.environ.items() if k not in ("OMP_WAIT_POLICY", "GOMP_SPINCOUNT")}
    runs = [base, {**base, "GOMP_SPINCOUNT": "300000"}, {**base, "OMP_WAIT_POLICY": "ACTIVE"}]
    out = [
        subprocess.run(
            [sys.executable, "-c", code], env=e, check=True, capture_output=True, text=True
        ).stdout.split()
        for e in runs
    ]
    assert out == [["PASSIVE", "False", "512"], ["None", "True", "32"], ["ACTIVE", "True", "32"]]


def test_info_batching_equals_gymnasiums():
    """The vector envs batch infos with their own _add_info; it must build what
    Gymnasium's does: the same arrays, dtypes and masks, nested dicts and final_obs."""
    env = VFServoVectorEnv(num_envs=3, scenario="short-move")
    infos = [
        (0, {"a": 1.5, "b": True, "c": 3, "d": np.float32(2.0), "s": "x", "v": np.arange(2.0)}),
        (2, {"a": 2.5, "final_obs": np.ones(2), "final_info": {"m": 1, "n": {"o": False}}}),
        (1, {"c": 7, "final_info": {"m": 4}, "e": None}),
        (2, {"s": "y", "v": np.arange(2.0) + 1, "final_obs": np.zeros(2)}),
    ]
    ours: dict = {}
    theirs: dict = {}
    for i, info in infos:
        ours = env._add_info(ours, info, i)
        theirs = gym.vector.VectorEnv._add_info(env, theirs, info, i)
    assert_same(ours, theirs)
