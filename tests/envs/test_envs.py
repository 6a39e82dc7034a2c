"""VFTune-v0 and VFServo-v0: Gymnasium's and SB3's checkers, rewards against the one scoring
path, episode ends, determinism across processes, train/test separation, rendering and
bad input."""

from __future__ import annotations

import dataclasses
import json
import math
import os
import subprocess
import sys
import warnings
from dataclasses import replace
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import vfgym.envs
from vfgym import (
    DEFAULT_MEASURES,
    LOADS_AXIS,
    PAPER_SETTINGS,
    Bounds,
    CostWeights,
    Measures,
    evaluate,
    get_scenario,
)
from vfgym.axis import PlantVariant, load_axis
from vfgym.envs import _batch as B
from vfgym.envs.servo import SERVO_FEATURES, VFServoEnv
from vfgym.envs.tune import VFTuneEnv
from vfgym.moves.features import SCENARIO_FEATURES
from vfgym.plant import _layout as L
from vfgym.plant import pack, simulate
from vfgym.plant.measures import NAMES as METRIC_NAMES
from vfgym.scoring import CONSTRAINTS, DEFAULT_WEIGHTS
from vfgym.space import NAMES, from_action, settings_from_dict, to_action

TUNE, SERVO = vfgym.envs.ENV_IDS
PAPER_ACTION = to_action(PAPER_SETTINGS)
SRC = str(Path(__file__).resolve().parents[2] / "src")
AXES = Path(__file__).resolve().parents[2] / "experiments" / "axes"


def run_episode(env: gym.Env, action, seed: int | None = None, **reset_kw):
    """Constant action to the episode's end: (rewards, last obs, terminated, truncated,
    info)."""
    env.reset(seed=seed, **reset_kw)
    rewards = []
    while True:
        obs, r, term, trunc, info = env.step(action)
        rewards.append(r)
        if term or trunc:
            return np.array(rewards), obs, term, trunc, info


# --- registration and the checkers --------------------------------------------------------


def test_both_ids_registered_with_vector_entry_points():
    for env_id in vfgym.envs.ENV_IDS:
        spec = gym.spec(env_id)
        assert spec.entry_point.startswith("vfgym.envs.")
        assert spec.vector_entry_point.startswith("vfgym.envs.vector:")
        assert spec.nondeterministic is False
    vfgym.envs.register_envs()  # idempotent
    assert isinstance(gym.make(TUNE).unwrapped, VFTuneEnv)
    assert isinstance(gym.make(SERVO).unwrapped, VFServoEnv)


@pytest.mark.parametrize("env_id", vfgym.envs.ENV_IDS)
@pytest.mark.parametrize("render_mode", [None, "rgb_array"])
def test_gymnasium_check_env_passes_with_warnings_as_errors(env_id, render_mode):
    from gymnasium.utils.env_checker import check_env

    env = gym.make(env_id, render_mode=render_mode)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_env(env.unwrapped)


@pytest.mark.parametrize("env_id", vfgym.envs.ENV_IDS)
def test_sb3_check_env_passes_with_warnings_as_errors(env_id):
    check_env = pytest.importorskip("stable_baselines3.common.env_checker").check_env

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_env(gym.make(env_id).unwrapped, warn=True)


# --- VFTune-v0 ------------------------------------------------------------------------------


def test_tune_reward_is_minus_the_cost_of_evaluate_and_info_carries_everything():
    env = gym.make(TUNE, scenario="friction")
    rng = np.random.default_rng(3)
    for a in [PAPER_ACTION, *rng.uniform(-1, 1, (3, 4)).astype(np.float32)]:
        obs0, info0 = env.reset()
        assert info0 == {"scenario": "friction"}
        obs, r, term, trunc, info = env.step(a)
        ev = evaluate(from_action(a), "friction")
        assert r == -ev.cost[0, 0]
        assert (term, trunc) == (True, False)
        assert np.array_equal(obs, obs0)
        for name in METRIC_NAMES:
            assert info[name] == ev.metrics[0][0][name] or math.isnan(info[name]), name
        for j, name in enumerate(CONSTRAINTS):
            assert info[f"constraint_{name}"] == ev.constraints[0, 0, j]
        assert info["feasible"] == bool(ev.feasible[0, 0])
        assert info["cost"] == ev.cost[0, 0]
        assert settings_from_dict({k: info[k] for k in (*NAMES, "accel_law")}) == from_action(a)


def test_tune_draws_train_scenarios_from_its_generator_and_options_pick_one():
    env = gym.make(TUNE)
    names = [env.reset(seed=7)[1]["scenario"]] + [env.reset()[1]["scenario"] for _ in range(5)]
    assert all(n.startswith("train-") for n in names) and len(set(names)) == 6
    obs, info = env.reset(options={"scenario": "short-move"})
    assert info["scenario"] == "short-move"
    assert obs in env.observation_space
    assert env.reset(options={"scenario_seed": 12})[1]["scenario"] == "train-12"
    test_env = gym.make(TUNE, split="test")
    assert test_env.reset(options={"scenario_seed": 12})[1]["scenario"] == "test-12"
    narrow = gym.make(TUNE, seed_range=(40, 43))
    drawn = {narrow.reset()[1]["scenario"] for _ in range(30)}
    assert drawn <= {"train-40", "train-41", "train-42"}


def test_tune_step_needs_a_reset_each_episode():
    env = VFTuneEnv(scenario="paper-step")
    with pytest.raises(gym.error.ResetNeeded):
        env.step(PAPER_ACTION)
    env.reset()
    env.step(PAPER_ACTION)
    with pytest.raises(gym.error.ResetNeeded, match="one step long"):
        env.step(PAPER_ACTION)


# --- VFServo-v0 -----------------------------------------------------------------------------


@pytest.mark.parametrize("scenario", ["paper-step", "reversal", "paper-sine", "train-5"])
def test_servo_constant_action_scores_exactly_as_evaluate_and_returns_minus_the_cost(scenario):
    env = VFServoEnv(scenario=scenario)
    a = np.array([0.1, 0.05, 0.35, 0.2], dtype=np.float32)
    rewards, _, term, trunc, info = run_episode(env, a)
    ev = evaluate(from_action(a), scenario, axis=LOADS_AXIS)  # the env's axis: names alike
    assert info["cost"] == ev.cost[0, 0]
    for name in METRIC_NAMES:
        assert info[name] == ev.metrics[0][0][name] or math.isnan(info[name]), name
    assert rewards.sum() == pytest.approx(-info["cost"], rel=1e-9, abs=1e-12)
    assert term != trunc
    n = LOADS_AXIS.scenario(scenario).command().size
    assert info["steps"] == len(rewards) == math.ceil(info["control_ticks"] / 140)
    assert info["control_ticks"] <= n
    if trunc:
        assert info["control_ticks"] == n


def test_servo_passes_its_scoring_inputs_to_the_scoring_path():
    measures = Measures(in_position_counts=0.5, accel_window_s=5e-4)  # under one count
    weights = CostWeights(time=2.0, overshoot=0.3, unsettled=1.0)
    bounds = Bounds(overshoot_windows=3.0)
    kw = {"axis": replace(LOADS_AXIS, measures=measures), "weights": weights, "bounds": bounds}
    env = VFServoEnv(scenario="short-move", **kw)
    rewards, _, _, _, info = run_episode(env, PAPER_ACTION)
    ev = evaluate(from_action(PAPER_ACTION), "short-move", **kw)
    assert info["cost"] == ev.cost[0, 0]
    assert info["constraint_overshoot"] == ev.constraints[0, 0, 2]
    assert rewards.sum() == pytest.approx(-info["cost"], rel=1e-9)
    tune = VFTuneEnv(scenario="short-move", **kw)
    tune.reset()
    assert tune.step(PAPER_ACTION)[1] == -ev.cost[0, 0]


def test_servo_terminates_when_settled_and_truncates_at_the_time_limit():
    env = VFServoEnv(scenario="paper-step")
    _, _, term, trunc, info = run_episode(env, PAPER_ACTION)
    assert (term, trunc) == (True, False)
    assert info["ended_settled"] and info["settled"] and not info["ended_violation"]
    # the motor stayed in position for settle_time_s before the episode ended
    assert info["control_ticks"] - info["move_time_s"] * 140e3 >= 0.005 * 140e3 - 1
    assert info["control_ticks"] < get_scenario("paper-step").command().size
    # a sluggish setting (value at its top: Kv tiny) never gets there
    slow = np.array([1.0, 1.0, 0.0, 0.0], dtype=np.float32)
    rewards, _, term, trunc, info = run_episode(env, slow)
    assert (term, trunc) == (False, True)
    assert not info["settled"] and info["cost"] > 5.0
    # not arriving is infeasible, and its arrival term is in the last reward: the return
    # is still minus the cost of the whole move
    assert not info["arrived"] and not info["feasible"] and info["constraint_arrival"] > 0.0
    assert rewards.sum() == pytest.approx(-info["cost"], rel=1e-9)
    assert -rewards[-1] > DEFAULT_WEIGHTS.unsettled


def test_servo_terminate_on_violation_ends_early_with_the_penalty():
    env = VFServoEnv(scenario="paper-step", terminate_on_violation=True, violation_penalty=2.5)
    harsh = np.array([-1.0, 1.0, -1.0, 0.0], dtype=np.float32)  # k = 1: no acceleration law
    rewards, _, term, trunc, info = run_episode(env, harsh)
    assert (term, trunc) == (True, False)
    assert info["ended_violation"] and not info["feasible"]
    assert info["constraint_accel"] > 0.0
    assert rewards.sum() == pytest.approx(-info["cost"] - 2.5, rel=1e-9)
    assert info["cost"] == evaluate(from_action(harsh), "paper-step").cost[0, 0]


def test_servo_tracking_shaping_term_adds_the_tracking_error_integral():
    w = 0.7
    env = VFServoEnv(scenario="short-move", tracking_weight=w)
    rewards, _, _, _, info = run_episode(env, PAPER_ACTION)
    n = get_scenario("short-move").command().size
    ise = info["tracking_rms_rad"] ** 2 * n  # Σ (P − θ)² over every tick
    d = env.episode.scale_rad
    shaping = w * ise / 140e3 / (d * d * info["ideal_time_s"])
    assert rewards.sum() == pytest.approx(-info["cost"] - shaping, rel=1e-9)


def test_servo_observation_at_reset_and_causality_of_actions():
    env = VFServoEnv(scenario="paper-step")
    obs, _ = env.reset()
    f = dict(zip(SERVO_FEATURES, obs, strict=True))
    assert f["error"] == 0.0 and f["speed_counter"] == 0.0 and f["progress"] == 0.0
    assert f["remaining"] == f["command_remaining"] == f["command_ahead"] == 1.0
    assert np.array_equal(obs[14:18], PAPER_ACTION)
    assert f["profile_step"] == 1.0 and f["direction"] == 1.0
    # the same actions for 20 intervals, then different ones: identical until the change
    rng = np.random.default_rng(0)
    acts = rng.uniform(-1, 1, (30, 4)).astype(np.float32)
    other = acts.copy()
    other[20:] = 0.0
    traj = []
    for seq in (acts, other):
        env.reset()
        traj.append(np.array([env.step(a)[0] for a in seq]))
    assert np.array_equal(traj[0][:20], traj[1][:20])
    assert not np.array_equal(traj[0][20], traj[1][20])
    assert np.array_equal(traj[0][19, 14:18], acts[19])


def test_servo_observation_is_what_a_drive_measures_and_info_the_motor_state():
    """Each interval's observation, from the same move simulated by vfgym.simulate: the
    motor's position as its encoder count, the speed counter's latched output, the torque
    command of the drive's gain as set (the modelled plant's, here 1.1 x off on the true
    plant); the continuous angle, speed and torque in info alone."""
    axis = load_axis(AXES / "belt-uncertain.yaml")
    true = PlantVariant(inertia=1.1, torque_per_count=1.1)
    env = VFServoEnv(axis=axis, interval_s=1e-3, residual=True)  # 0: the paper's settings
    obs, _ = env.reset(options={"scenario_seed": 3, "plant": true})
    ep = env.episode
    tr = simulate(ep.command, env.core.config.initial_settings, ep.plant, measures=axis.measures)
    p, q = ep.plant, ep.plant.motor.count_rad
    ns, b = p.servo.sample_ticks, p.servo.speed_gain_b
    f = dict(zip(SERVO_FEATURES, obs, strict=True))
    assert f["error"] == 0.0 and f["torque_command"] == 0.0
    D, k3_set = ep.scale_rad, ep.model.torque_per_count_nm
    assert k3_set != ep.plant.torque_per_count_nm
    seen = 0
    for step in range(40):
        obs, _, term, trunc, info = env.step(np.zeros(4, np.float32))
        if term or trunc:
            break
        f = dict(zip(SERVO_FEATURES, obs.astype(np.float64), strict=True))
        i = env.core.interval_ticks * (step + 1) - 1  # the interval's last tick
        P, theta = tr.command_rad[i], tr.motor_rad[i]
        count = math.floor(theta / q)
        assert f["error"] == pytest.approx((P - count * q) / D, rel=1e-6, abs=1e-7)
        assert f["remaining"] == pytest.approx((ep.target_rad - count * q) / D, rel=1e-6)
        speed = tr.speed_count[i] / b * q / (ns / p.tick_hz) / p.pulse_top_speed_rad_s
        assert f["speed_counter"] == pytest.approx(speed, rel=1e-6, abs=1e-9)
        torque = k3_set * tr.servo_error_counts[i] / p.motor.peak_torque_nm
        assert f["torque_command"] == pytest.approx(np.clip(torque, -10, 10), rel=1e-6, abs=1e-9)
        assert info["motor_angle_rad"] == theta and info["motor_speed_rad_s"] == tr.speed_rad_s[i]
        assert info["motor_torque_nm"] == tr.torque_nm[i]
        seen += abs(theta - count * q) > 0.0
    assert seen > 10  # the continuous angle was off the count: the observation did not see it


_MAPPING_ENV = VFServoEnv(scenario="paper-step")
_MAPPING_ENV.reset()
PAPER_PLANT_REF = get_scenario("paper-step").plant()


@settings(max_examples=60, deadline=None)
@given(
    st.lists(st.floats(-1.0, 1.0, width=32), min_size=4, max_size=4),
    st.sampled_from([np.float32, np.float64]),
)
def test_kernel_action_mapping_is_the_search_space_bit_for_bit(a, dtype):
    env = _MAPPING_ENV
    act = np.array(a, dtype=dtype)
    w = env._w.copy()
    assert B.apply_action(act, w)
    s = from_action(act)
    ref = pack(s, PAPER_PLANT_REF, DEFAULT_MEASURES, 10.0, 21000)
    for slot in (L.P_VALUE, L.P_LIMIT, L.P_STEP, L.P_A):
        assert w[B.W_PRM + slot] == ref[slot]
    assert np.array_equal(w[B.X_SET : B.X_SET + 4], np.clip(act.astype(np.float64), -1, 1))


def test_servo_step_needs_reset_and_a_new_one_after_the_end():
    env = VFServoEnv(scenario="short-move")
    with pytest.raises(gym.error.ResetNeeded):
        env.step(PAPER_ACTION)
    run_episode(env, PAPER_ACTION)
    with pytest.raises(gym.error.ResetNeeded, match="ended"):
        env.step(PAPER_ACTION)


# --- determinism, splits ----------------------------------------------------------------------

_EPISODES_SCRIPT = r"""
import json, sys
import numpy as np
import gymnasium as gym
import vfgym.envs
heavy = sorted(m for m in ("torch", "stable_baselines3", "matplotlib") if m in sys.modules)
out = {"heavy": heavy}
act = np.array([0.3, -0.2, 0.4, 0.1], dtype=np.float32)
for env_id in vfgym.envs.ENV_IDS:
    env = gym.make(env_id)
    eps = []
    for k in range(4):
        obs, info = env.reset(seed=1234) if k == 0 else env.reset()
        rewards = [env.step(act)[1] for _ in range(3 if "Servo" in env_id else 1)]
        eps.append([info["scenario"], obs.tolist(), rewards])
    out[env_id] = eps
out["plugin"] = gym.make("vfgym.envs:vfgym/VFTune-v0").spec.id
print(json.dumps(out))
"""


def _episodes_here() -> dict:
    out = {}
    act = np.array([0.3, -0.2, 0.4, 0.1], dtype=np.float32)
    for env_id in vfgym.envs.ENV_IDS:
        env = gym.make(env_id)
        eps = []
        for k in range(4):
            obs, info = env.reset(seed=1234) if k == 0 else env.reset()
            rewards = [env.step(act)[1] for _ in range(3 if "Servo" in env_id else 1)]
            eps.append([info["scenario"], obs.tolist(), rewards])
        out[env_id] = eps
    return out


def test_seeded_reset_then_plain_resets_replay_the_same_episodes_in_another_process():
    env = dict(os.environ, PYTHONPATH=SRC + os.pathsep + os.environ.get("PYTHONPATH", ""))
    res = subprocess.run(
        [sys.executable, "-c", _EPISODES_SCRIPT], env=env, capture_output=True, text=True
    )
    assert res.returncode == 0, res.stderr
    there = json.loads(res.stdout.strip().splitlines()[-1])
    here = _episodes_here()
    for env_id in vfgym.envs.ENV_IDS:
        assert there[env_id] == here[env_id]  # names, observations, rewards: exactly
        assert len({e[0] for e in here[env_id]}) == 4
    # making the envs pulls in neither torch nor matplotlib; "module:id" registers itself
    assert there["heavy"] == []
    assert there["plugin"] == TUNE


_CACHE_SCRIPT = r"""
from vfgym.envs import _batch
print(_batch.step_one._cache._cache_path)
"""


def test_the_batch_cache_is_dropped_when_the_kernel_changes(tmp_path):
    # numba keys a cache on the function's own file; _batch compiles the kernel into itself
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path), PYTHONPATH=SRC)

    def import_batch() -> str:
        res = subprocess.run(
            [sys.executable, "-c", _CACHE_SCRIPT], env=env, capture_output=True, text=True
        )
        assert res.returncode == 0, res.stderr
        return res.stdout.strip()

    cache = Path(import_batch())
    stamp = (cache / "_batch.kernel-sha256").read_text()
    stale = cache / "_batch.env_step-1.py311.nbi"
    stale.write_text("machine code of an older kernel")
    import_batch()
    assert stale.exists()  # same kernel: the cache stays
    (cache / "_batch.kernel-sha256").write_text("another kernel")
    import_batch()
    assert not stale.exists()
    assert (cache / "_batch.kernel-sha256").read_text() == stamp


def test_train_and_test_episodes_never_share_a_scenario():
    def physical(sc):
        return dataclasses.replace(sc, name="", description="")

    seen = {}
    for split in ("train", "test"):
        env = VFTuneEnv(split=split, seed_range=(0, 400))
        scs = []
        for k in range(150):
            env.reset(seed=99 if k == 0 else None)
            scs.append(env.episode.scenario)
        assert all(s.name.startswith(f"{split}-") for s in scs)
        seen[split] = {physical(s) for s in scs}
    assert seen["train"].isdisjoint(seen["test"])
    # the same seed in both splits gives two different moves
    assert physical(get_scenario("train-17")) != physical(get_scenario("test-17"))


# --- rendering --------------------------------------------------------------------------------


def test_tune_render_is_an_rgb_picture_that_changes_with_the_move():
    env = gym.make(TUNE, scenario="paper-step", render_mode="rgb_array")
    env.reset()
    before = env.render()
    env.step(PAPER_ACTION)
    paper = env.render()
    env.reset()
    env.step(np.array([-0.5, 0.5, -0.2, 0.0], dtype=np.float32))
    other = env.render()
    for img in (before, paper, other):
        assert img.shape == (480, 640, 3) and img.dtype == np.uint8
        assert img.std() > 10  # not blank
    assert not np.array_equal(paper, other) and not np.array_equal(before, paper)


def test_servo_render_shows_the_move_so_far_and_is_replayed_exactly():
    env = VFServoEnv(scenario="short-move", render_mode="rgb_array")
    env.reset()
    for _ in range(5):
        env.step(PAPER_ACTION)
    early = env.render()
    # the replay the picture draws is the episode itself
    rec = env._replay()
    assert rec.shape == (L.N_ROWS, 5 * 140)
    assert rec[L.R_THETA, -1] == env._w[B.W_ST + L.S_THETA]
    run_episode(env, PAPER_ACTION)
    full = env.render()
    assert early.shape == full.shape == (480, 640, 3) and full.dtype == np.uint8
    assert not np.array_equal(early, full)
    assert env._replay().shape[1] == get_scenario("short-move").command().size


def test_render_without_a_render_mode_warns_and_returns_none():
    for env in (VFTuneEnv(), VFServoEnv()):
        env.reset(seed=0)
        with pytest.warns(UserWarning, match="render_mode"):
            assert env.render() is None


# --- bad input ----------------------------------------------------------------------------------

BAD_ACTIONS = [
    ([np.nan, 0, 0, 0], "finite"),
    ([0, np.inf, 0, 0], "finite"),
    ([0, 0, 1.5, 0], "out of range"),
    ([0, -1.01, 0, 0], "out of range"),
    ([0, 0, 0], "4 numbers"),
    ([[0, 0, 0, 0]], "4 numbers"),
    ("fast", "4 numbers"),
]


@pytest.mark.parametrize("env_cls", [VFTuneEnv, VFServoEnv])
@pytest.mark.parametrize(("action", "message"), BAD_ACTIONS)
def test_bad_actions_raise_clear_errors_and_change_nothing(env_cls, action, message):
    env = env_cls(scenario="short-move")
    ref = env_cls(scenario="short-move")
    env.reset()
    ref.reset()
    with pytest.raises(ValueError, match=message):
        env.step(np.asarray(action, dtype=np.float64) if not isinstance(action, str) else action)
    a, b = env.step(PAPER_ACTION), ref.step(PAPER_ACTION)
    assert np.array_equal(a[0], b[0]) and a[1] == b[1]


@pytest.mark.parametrize("env_cls", [VFTuneEnv, VFServoEnv])
def test_the_box_edge_is_the_search_space_tolerance(env_cls):
    # the compiled check and vfgym.space.from_action accept and refuse the same actions
    env = env_cls(scenario="short-move")
    env.reset()
    env.step(np.array([0.0, 1.0 + 5e-7, -1.0 - 5e-7, 0.0]))
    env.reset()
    with pytest.raises(ValueError, match="out of range"):
        env.step(np.array([0.0, 1.0 + 2e-6, 0.0, 0.0]))


@pytest.mark.parametrize("env_cls", [VFTuneEnv, VFServoEnv])
@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"speed": 3}, "unknown key"),
        ("paper-step", "must be a dict"),
        ({"scenario": "no-such-move"}, "not known"),
        ({"scenario": 3}, "scenario name"),
        (
            {
                "scenario": get_scenario("paper-step").with_(
                    name="still", profile="multi", distance_rad=0.0, moves=((0.0, 0.1),)
                )
            },
            "no move",
        ),
        ({"scenario_seed": -1}, "scenario_seed"),
        ({"scenario_seed": 1.5}, "scenario_seed"),
        ({"scenario": "paper-step", "scenario_seed": 3}, "not both"),
    ],
)
def test_bad_reset_options_raise_clear_errors(env_cls, options, message):
    with pytest.raises(ValueError, match=message):
        env_cls().reset(options=options)


@pytest.mark.parametrize(
    ("env_cls", "kwargs", "message"),
    [
        (VFTuneEnv, {"split": "valid"}, "split"),
        (VFTuneEnv, {"seed_range": (5, 5)}, "seed_range"),
        (VFTuneEnv, {"seed_range": 5}, "seed_range"),
        (VFTuneEnv, {"scenario": "nowhere"}, "not known"),
        (VFTuneEnv, {"accel_law": "jerk"}, "accel_law"),
        (VFTuneEnv, {"render_mode": "human"}, "render_mode"),
        (VFTuneEnv, {"weights": 3}, "weights"),
        (VFServoEnv, {"interval_s": 1.5 / 140e3}, "whole number of ticks"),
        (VFServoEnv, {"interval_s": 0.0}, "interval_s"),
        (VFServoEnv, {"settle_time_s": -1.0}, "settle_time_s"),
        (VFServoEnv, {"initial_settings": {"k": 3}}, "initial_settings"),
        (VFServoEnv, {"tracking_weight": -1.0}, "tracking_weight"),
        (VFServoEnv, {"terminate_on_violation": "yes"}, "terminate_on_violation"),
        (VFServoEnv, {"axis": "SGME"}, "SGME: no such file"),
    ],
)
def test_bad_constructor_arguments_raise_clear_errors(env_cls, kwargs, message):
    with pytest.raises(ValueError, match=message):
        env_cls(**kwargs)


def test_docstrings_follow_gymnasiums_sections_and_name_every_feature():
    sections = (
        "Description",
        "Action Space",
        "Observation Space",
        "Rewards",
        "Starting State",
        "Episode End",
        "Arguments",
        "Version History",
    )
    for cls in (VFTuneEnv, VFServoEnv):
        doc = cls.__doc__
        assert [doc.index(f"## {s}") for s in sections] == sorted(
            doc.index(f"## {s}") for s in sections
        )
    for name in SCENARIO_FEATURES:
        assert f"| {name} |" in VFTuneEnv.__doc__ or name.startswith("profile_")
    for name in B.OBS_DYNAMIC:
        assert f"| {name} |" in VFServoEnv.__doc__ or name.startswith("setting_")
    obs_size = {VFTuneEnv: len(SCENARIO_FEATURES), VFServoEnv: 37}
    for cls, n in obs_size.items():
        assert f"Box(-10, 10, ({n},), float32)" in cls.__doc__
    assert len(SERVO_FEATURES) == 37
