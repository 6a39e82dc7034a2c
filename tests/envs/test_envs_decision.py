"""VFServo-v0's one-decision mode (``decision="once"``): the episode is the per-interval
episode of the same schedule (the base for the hold, the ramp, the correction held), its
observation the hold's response as the per-interval env saw it, its reward the share of
the base's cost saved on the same (move, plant); the shield checks on design plants told
from the response, never on the true plant; the vector env and SB3's checker agree."""

from __future__ import annotations

import warnings
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.vector import AutoresetMode
from test_envs_vector import compare_runs

import vfgym.envs  # noqa: F401  (registers the envs)
from vfgym import load_axis
from vfgym.axis import NOMINAL, PlantVariant
from vfgym.envs._decision import (
    CALIBRATION_PLANTS,
    N_SIGNATURE,
    REWARD_SCALE,
    alike_plants,
    calibration_plants,
    check_plants,
    ramp_of,
)
from vfgym.envs.servo import VFServoEnv

AXIS = Path(__file__).resolve().parents[2] / "experiments" / "axes" / "loads-uncertain.yaml"
AXIS3 = AXIS.with_name("loads-uncertain-3.yaml")
SERVO = "vfgym/VFServo-v0"
ONCE = {"residual": True, "residual_scale": [1.0, 0.0, 1.0, 1.0], "decision": "once"}


def schedule(hold: int, ramp: int, action: np.ndarray, t: int) -> np.ndarray:
    """The per-interval actions of a decision: 0 for the hold, then the ramp, then held."""
    return np.zeros(4) if t < hold else action * min(1.0, (t - hold + 1) / ramp)


def interval_episode(env: VFServoEnv, options: dict, hold: int, ramp: int, action) -> tuple:
    """(the first ``hold`` observations, the end's info) of the per-interval env."""
    obs, t, seen = None, 0, []
    env.reset(options=options)
    while True:
        obs, _, term, trunc, info = env.step(schedule(hold, ramp, np.asarray(action, float), t))
        t += 1
        if t <= hold:
            seen.append(obs[:N_SIGNATURE])
        if term or trunc:
            return np.concatenate(seen), info


@pytest.mark.parametrize(("hold_s", "x"), [(0.002, -1.0), (0.003, -0.7)])
def test_a_decision_is_the_per_interval_episode_of_its_schedule(hold_s, x):
    kw = {**ONCE, "axis": str(AXIS), "interval_s": 0.001}
    once = VFServoEnv(**kw, hold_s=hold_s)
    every = VFServoEnv(**{**kw, "decision": "interval"})
    hold = round(hold_s / 1e-3)
    rng = np.random.default_rng(3)
    for k in range(4):
        options = {"scenario_seed": 40 + k, "plant": PlantVariant(inertia=0.8 + 0.15 * k)}
        obs, _ = once.reset(options=options)
        intervals = -(-once.episode.command.size // 140)
        ramp = ramp_of(x, intervals - hold)
        assert ramp == 1 + round((x + 1) / 2 * (intervals - hold - 1))
        assert obs.shape == once.observation_space.shape == (hold * N_SIGNATURE + 4 + 19,)
        action = np.r_[rng.uniform(-0.3, 0.3, 4), x].astype(np.float32)
        _, reward, term, trunc, info = once.step(action)
        assert term and not trunc and info["ramp"] == ramp
        action = action[:4]
        seen, ref = interval_episode(every, options, hold, ramp, action)
        _, base = interval_episode(every, options, hold, ramp, np.zeros(4))
        assert np.array_equal(obs[: hold * N_SIGNATURE], seen)
        assert info["cost"] == ref["cost"] and info["feasible"] == ref["feasible"]
        assert info["base_cost"] == base["cost"] and not info["shielded"]
        penalty = 5.0 if base["feasible"] and not ref["feasible"] else 0.0
        expected = REWARD_SCALE * (base["cost"] - ref["cost"]) / base["cost"] - penalty
        assert reward == pytest.approx(expected, rel=1e-12, abs=1e-12)
        assert np.array_equal(obs[hold * N_SIGNATURE : hold * N_SIGNATURE + 4], obs[-23:-19])
        with pytest.raises(gym.error.ResetNeeded):
            once.step(np.zeros(5, np.float32))


def test_the_zero_action_is_the_base_exactly():
    env = VFServoEnv(**ONCE, axis=str(AXIS), interval_s=0.001)
    for k in range(3):
        env.reset(seed=k)
        _, reward, _, _, info = env.step(np.r_[np.zeros(4), k - 1.0].astype(np.float32))
        assert reward == 0.0 and info["cost"] == info["base_cost"]


def test_a_move_over_within_the_hold_decides_nothing():
    env = VFServoEnv(**ONCE, interval_s=0.001, hold_s=0.1)
    env.reset(seed=0)
    assert env.decision.ended_in_hold is not None  # this move settles within 100 ms
    _, reward, terminated, _, info = env.step(np.array([0.1, 0, 0.1, 0.1, 0.5], np.float32))
    assert reward == 0.0 and terminated and info["cost"] == info["base_cost"]
    assert not info["shielded"] and not np.any(info["correction"])


def test_the_shield_checks_the_told_plants_and_never_the_true_one():
    """Whether a correction is shielded is what its runs on the told design plant, its
    neighbours, the plants between and the in-range grid's plants told as it say, against
    the base's, as the per-interval env gives them: the same for two true plants told
    alike, whatever they give."""
    axis = load_axis(AXIS)
    kw = {**ONCE, "axis": axis, "interval_s": 0.001}
    env = VFServoEnv(**kw, shield=True)
    every = VFServoEnv(**{**kw, "decision": "interval"})
    design = tuple(axis.design_plants())
    hold = 2
    rng = np.random.default_rng(0)
    shielded = kept = 0
    for k in range(6):
        seed = 7 + k
        sigs = [interval_episode(every, {"scenario_seed": seed, "plant": p}, hold, 1,
                                 np.zeros(4))[0] for p in design]  # fmt: skip
        true = PlantVariant(inertia=float(rng.uniform(0.8, 1.25)))
        obs, _ = env.reset(options={"scenario_seed": seed, "plant": true})
        ramp = ramp_of(-0.8, -(-env.episode.command.size // 140) - hold)

        def told_as(sig: np.ndarray, sigs: list = sigs) -> int:
            return int(np.argmin([np.sum((s - sig) ** 2) for s in sigs]))

        told = told_as(obs[: hold * N_SIGNATURE])
        grid = [q for q in calibration_plants(design, CALIBRATION_PLANTS) if told_as(
            interval_episode(every, {"scenario_seed": seed, "plant": q}, hold, 1,
                             np.zeros(4))[0]) == told]  # fmt: skip
        checks = [design[told], *check_plants(design, told, 2, 2)]
        dc = env.decision  # the grid's plants it checks besides: those the oracle tells alike
        assert dc._told_as(env.episode, dc._move_cache(env.episode), told) == [
            q for q in grid if q not in checks
        ]
        action = rng.uniform(-0.6, 0.6, 4).astype(np.float32)
        breaks = False
        for p in [*checks, *grid]:
            opts = {"scenario_seed": seed, "plant": p}
            _, cand = interval_episode(every, opts, hold, ramp, action)
            _, base = interval_episode(every, opts, hold, ramp, np.zeros(4))
            breaks = breaks or (base["feasible"] and not cand["feasible"])
        _, reward, _, _, info = env.step(np.r_[action, -0.8].astype(np.float32))
        assert info["told_plant"] == design[told] and info["ramp"] == ramp
        assert info["shielded"] == breaks
        if breaks:
            assert info["cost"] == info["base_cost"] and reward == 0.0
        shielded += breaks
        kept += not breaks
    assert shielded and kept  # both seen


def shield_and_oracle(axis_file: Path, **options) -> tuple:
    """(a shielded one-decision env, the per-interval env as its oracle, the design
    plants) on an axis, 1 ms intervals."""
    axis = load_axis(axis_file)
    kw = {**ONCE, "axis": axis, "interval_s": 0.001}
    every = VFServoEnv(**{**kw, "decision": "interval"})
    return VFServoEnv(**kw, shield=True, **options), every, tuple(axis.design_plants())


def test_a_gentler_shield_runs_the_first_halving_that_breaks_no_checked_plant():
    """With ``shield_gentler=g`` a correction that breaks a limit the base holds on a
    checked plant is tried halved, quartered ... g times on the same plants, and the first
    that breaks none runs on the true plant (the base where none does): each checked
    against the per-interval env's episodes of the same schedules."""
    env, every, design = shield_and_oracle(AXIS, shield_gentler=2)
    hold = 2
    rng = np.random.default_rng(3)
    seen = set()
    for k in range(5):
        seed = 40 + k
        true = PlantVariant(inertia=float(rng.uniform(0.8, 1.25)))
        env.reset(options={"scenario_seed": seed, "plant": true})
        ramp = ramp_of(-0.9, -(-env.episode.command.size // 140) - hold)
        dc = env.decision
        told = dc.told()
        plants = [design[told], *check_plants(design, told, 2, 2)]
        plants += dc._told_as(env.episode, dc._move_cache(env.episode), told)
        action = rng.uniform(-0.9, 0.9, 4).astype(np.float32).astype(np.float64)
        base_ok = {}
        for p in plants:
            opts = {"scenario_seed": seed, "plant": p}
            base_ok[p] = interval_episode(every, opts, hold, ramp, np.zeros(4))[1]["feasible"]
        ran = None  # the halvings: the first that breaks no limit the base holds
        for i in range(3):
            tried = action * 0.5**i
            ends = [interval_episode(every, {"scenario_seed": seed, "plant": p}, hold, ramp,
                                     tried)[1] for p in plants if base_ok[p]]  # fmt: skip
            if all(e["feasible"] for e in ends):
                ran = i
                break
        opts = {"scenario_seed": seed, "plant": true}
        want = np.zeros(4) if ran is None else action * 0.5**ran
        _, expect = interval_episode(every, opts, hold, ramp, want)
        info = env.step(np.r_[action, -0.9].astype(np.float32))[4]
        assert info["cost"] == expect["cost"] and info["shielded"] == (ran != 0)
        seen.add(ran)
    assert seen & {1, 2}, seen  # a halving run (besides the whole or the base)


def hold_signature(env: VFServoEnv, options: dict, hold: int) -> np.ndarray:
    """The per-interval env's first ``hold`` observations' dynamic features, the base held."""
    env.reset(options=options)
    return np.concatenate([env.step(np.zeros(4))[0][:N_SIGNATURE] for _ in range(hold)])


def test_alike_plants_are_every_combination_of_ends_and_own_values():
    design = tuple(load_axis(AXIS3).design_plants())
    for i, count in ((0, 2**3 - 1), (len(design) - 1, 3**3 - 1)):  # a corner, a point inside
        out = alike_plants(design, i)
        assert len(out) == len(set(out)) == count and design[i] not in out
        for k in ("inertia", "torque_per_count", "load_offset_nm"):
            ends = {min(getattr(p, k) for p in design), max(getattr(p, k) for p in design)}
            assert {getattr(q, k) for q in out} == ends | {getattr(design[i], k)}


def test_the_shield_checks_the_plants_the_hold_cannot_tell_from_the_told_one():
    """With three uncertain quantities a 2 ms hold tells the inertia, hardly the drive's
    gain or a load torque: the shield also checks the told design plant with those at
    their ranges' ends (those told as it), each against the per-interval env's episodes;
    on some moves only such a plant breaks the correction."""
    env, every, design = shield_and_oracle(AXIS3)
    hold = 2
    rng = np.random.default_rng(5)
    seen = set()
    for k in range(8):
        seed = 60 + k
        sigs = [hold_signature(every, {"scenario_seed": seed, "plant": p}, hold) for p in design]

        def told_as(p: PlantVariant, seed: int = seed, sigs: list = sigs) -> int:
            sig = hold_signature(every, {"scenario_seed": seed, "plant": p}, hold)
            return int(np.argmin([np.sum((s - sig) ** 2) for s in sigs]))

        true = draw_plant_3(rng)
        env.reset(options={"scenario_seed": seed, "plant": true})
        told = told_as(true)
        dc = env.decision
        held = dc._move_cache(env.episode)
        alike = [q for q in alike_plants(design, told) if told_as(q) == told]
        assert dc.told() == told and dc._alike(env.episode, held, told) == alike
        others = [design[told], *check_plants(design, told, 2, 2)]
        others += dc._told_as(env.episode, held, told)
        ramp = ramp_of(-0.8, -(-env.episode.command.size // 140) - hold)
        action = rng.uniform([-0.3, -0.3, 0.0, 0.0], 0.9).astype(np.float32)  # k, Ts/Tf up

        def breaks(plants: list, action=action, seed: int = seed, ramp: int = ramp) -> bool:
            for p in plants:
                opts = {"scenario_seed": seed, "plant": p}
                _, cand = interval_episode(every, opts, hold, ramp, action)
                _, base = interval_episode(every, opts, hold, ramp, np.zeros(4))
                if base["feasible"] and not cand["feasible"]:
                    return True
            return False

        by_others = breaks(others, action)
        for _ in range(3):  # toward the edge the told plant's checks allow
            if not by_others:
                break
            action = (action / 2).astype(np.float32)
            by_others = breaks(others, action)
        by_alike = not by_others and breaks([q for q in alike if q not in others], action)
        _, _, _, _, info = env.step(np.r_[action, -0.8].astype(np.float32))
        assert info["shielded"] == (by_others or by_alike)
        seen.add((by_others, by_alike))
    assert (False, True) in seen, seen  # a correction only a plant alike breaks


def draw_plant_3(rng: np.random.Generator) -> PlantVariant:
    """A true plant drawn uniformly in loads-uncertain-3's ranges."""
    return PlantVariant(
        inertia=float(rng.uniform(0.8, 1.25)),
        torque_per_count=float(rng.uniform(0.85, 1.15)),
        load_offset_nm=float(rng.uniform(-0.003, 0.003)),
    )


def test_the_vector_env_equals_single_envs_and_sb3_accepts_it():
    kw = {**ONCE, "seed_range": (0, 20), "interval_s": 0.001, "hold_s": 0.002}
    for mode in (AutoresetMode.NEXT_STEP, AutoresetMode.SAME_STEP):
        assert compare_runs(SERVO, 3, 4, mode, **kw) >= 6
    shielded = {"axis": str(AXIS3), "tell": True, "shield": True, "shield_gentler": 2}
    assert compare_runs(SERVO, 3, 3, AutoresetMode.NEXT_STEP, **kw, **shielded) >= 3
    check_env = pytest.importorskip("stable_baselines3.common.env_checker").check_env
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_env(gym.make(SERVO, **kw).unwrapped, warn=True)


def test_told_features_are_the_responses_difference_and_the_nearest_design_plants():
    """``tell=True``: after the move's features, the hold's response minus the modelled
    plant's (the per-interval env's, on the same move), then the nearest design plant's
    inertia over the design's range in [-1, 1], then a blend of the three nearest."""
    axis = load_axis(AXIS)
    env = VFServoEnv(**ONCE, axis=axis, interval_s=0.001, tell=True)
    every = VFServoEnv(**{**ONCE, "decision": "interval"}, axis=axis, interval_s=0.001)
    design = tuple(axis.design_plants())
    lo, hi = min(p.inertia for p in design), max(p.inertia for p in design)
    n = 2 * N_SIGNATURE
    assert env.observation_space.shape == (2 * n + 4 + 19 + 2,)
    for k, f in enumerate((0.8, 0.95, 1.12, 1.25)):
        options = {"scenario_seed": 5 + k, "plant": PlantVariant(inertia=f)}
        obs, _ = env.reset(options=options)
        nominal = interval_episode(every, {**options, "plant": NOMINAL}, 2, 1, np.zeros(4))[0]
        sigs = [interval_episode(every, {**options, "plant": p}, 2, 1, np.zeros(4))[0]
                for p in design]  # fmt: skip
        d = [np.linalg.norm(s - obs[:n]) for s in sigs]
        assert np.allclose(obs[n + 23 : 2 * n + 23], obs[:n] - nominal, atol=1e-6)
        told = 2 * (design[int(np.argmin(d))].inertia - lo) / (hi - lo) - 1
        assert obs[-2] == pytest.approx(told, abs=1e-6)
        assert -1.0 <= obs[-1] <= 1.0 and abs(obs[-1] - (2 * (f - lo) / (hi - lo) - 1)) < 0.3
        _, _, _, _, info = env.step(np.array([1, 0, -1, 0, -1], np.float32))
        assert not info["shielded"] and "told_plant" not in info  # telling is not shielding


def test_on_an_exact_axis_the_shield_checks_the_modelled_plant():
    """The plant known exactly: a correction that breaks a limit the base holds on it is
    replaced by the base; one that does not is run."""
    env = VFServoEnv(**ONCE, shield=True, interval_s=0.001)
    every = VFServoEnv(**{**ONCE, "decision": "interval"}, interval_s=0.001)
    seen = set()
    for k, x in enumerate([[1, 0, -1, 0, -1], [0.05, 0, 0.05, 0.05, 0]] * 3):
        options = {"scenario_seed": 12 + k}
        env.reset(options=options)
        action = np.asarray(x, np.float32)
        _, _, _, _, info = env.step(action)
        ramp = ramp_of(action[4], -(-env.episode.command.size // 140) - 2)
        _, cand = interval_episode(every, options, 2, ramp, action[:4].astype(float))
        _, base = interval_episode(every, options, 2, ramp, np.zeros(4))
        breaks = base["feasible"] and not cand["feasible"]
        assert info["shielded"] == breaks and info["told_plant"].nominal
        assert info["cost"] == (base["cost"] if breaks else cand["cost"])
        seen.add(breaks)
    assert seen == {True, False}


def test_bad_decision_actions_name_themselves():
    env = VFServoEnv(**ONCE)
    env.reset(seed=0)
    with pytest.raises(ValueError, match="ramp entry must be a number in"):
        env.step(np.array([0, 0, 0, 0, 1.5], np.float32))
    with pytest.raises(ValueError, match="5 numbers"):
        env.step(np.zeros(4, np.float32))
    with pytest.raises(ValueError, match=r"action=\[2.0, 0.0, 0.0, 0.0\] is out of range"):
        env.step(np.array([2, 0, 0, 0, 0], np.float32))


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"decision": "sometimes"}, "decision='sometimes'"),
        ({"decision": "once"}, "decision='once' needs residual=True"),
        ({**ONCE, "hold_s": 0.0025, "interval_s": 0.001}, "hold_s=0.0025 is not allowed"),
        ({**ONCE, "hold_s": 0.2, "interval_s": 0.001}, "hold_s=0.2 is not allowed"),
        ({"shield": True, "axis": str(AXIS), "residual": True}, "shield=True is not allowed"),
        ({**ONCE, "shield": 1, "axis": str(AXIS)}, "shield=1 must be a bool"),
        ({**ONCE, "shield_gentler": 1}, "shield_gentler=1 is not allowed here"),
        ({**ONCE, "shield": True, "shield_gentler": -1}, "shield_gentler=-1"),
        ({**ONCE, "shield": True, "shield_gentler": 9}, "shield_gentler=9"),
        ({**ONCE, "shield": True, "shield_gentler": 1.5}, "shield_gentler=1.5"),
        ({"tell": True, "residual": True}, "tell=True is not allowed"),
    ],
)
def test_bad_decision_arguments_name_themselves(kwargs, message):
    with pytest.raises(ValueError, match=message):
        VFServoEnv(**kwargs)
    with pytest.raises(ValueError, match="render_mode='rgb_array' is not allowed"):
        VFServoEnv(**ONCE, render_mode="rgb_array")
