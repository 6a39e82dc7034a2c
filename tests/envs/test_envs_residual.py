"""VFServo-v0's residual actions: an offset from a base setting, the zero action holding the
base exactly (the paper's, fixed tuned settings, or a per-move model's)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from vfgym import LOADS_AXIS, PAPER_PLANT, PAPER_SETTINGS, Settings, evaluate
from vfgym.envs.servo import ServoConfig, VFServoEnv
from vfgym.envs.vector import VFServoVectorEnv
from vfgym.space import SPACE, Relative, from_action, to_action

ZERO = np.zeros(4, dtype=np.float32)
TUNED = Settings(value_rad=0.7, error_limit_rad=1.3, k=37.0, ts_over_tf=0.31)


def episode_cost(env: VFServoEnv, action, **reset_kw) -> tuple[float, float]:
    """(the episode's cost, its return) with a constant action."""
    env.reset(**reset_kw)
    total = 0.0
    while True:
        _, r, term, trunc, info = env.step(action)
        total += r
        if term or trunc:
            return info["cost"], total


@pytest.mark.parametrize("scenario", ["paper-step", "reversal", "train-5"])
def test_zero_residual_reproduces_the_paper_settings_bit_for_bit(scenario):
    cost, ret = episode_cost(VFServoEnv(scenario, residual=True), ZERO)
    assert cost == evaluate(PAPER_SETTINGS, scenario, axis=LOADS_AXIS).cost[0, 0]
    assert ret == pytest.approx(-cost, rel=1e-9, abs=1e-12)


def test_zero_residual_reproduces_a_tuned_base_and_a_per_move_base():
    cost, _ = episode_cost(VFServoEnv("short-move", residual=True, residual_base=TUNED), ZERO)
    assert cost == evaluate(TUNED, "short-move").cost[0, 0]
    seen = []

    def per_move(scenario, plant):
        seen.append(scenario.name)
        assert plant == PAPER_PLANT  # the env's plant, before the move's load
        return TUNED.replace(k=20.0 * (1.0 + scenario.inertia_ratio))

    env = VFServoEnv(residual=True, residual_base=per_move)
    for seed in (3, 4):
        cost, _ = episode_cost(env, ZERO, options={"scenario_seed": seed})
        sc = env.episode.scenario
        assert sc.name == seen[-1]
        assert cost == evaluate(per_move(sc, PAPER_PLANT), sc).cost[0, 0]
    assert seen[0] != seen[-1]


def test_vector_env_takes_the_same_residual_steps():
    env = VFServoEnv("paper-step", residual=True)
    venv = VFServoVectorEnv(2, "paper-step", residual=True)
    venv.reset(seed=0)
    env.reset(seed=0)
    act = np.array([0.3, -0.2, 0.5, -1.0], dtype=np.float32)
    for _ in range(5):
        o1, r1, *_ = env.step(act)
        o2, r2, *_ = venv.step(np.stack([act, act]))
        assert r2[0] == r1 and np.array_equal(o2[1], o1)


def test_residual_offset_moves_the_relative_coordinates_by_the_scale():
    """An action a moves space.Relative's log coordinates (value, L/value, k, Ts/Tf) by
    scale × a × half each axis's width from the base's; the observation shows the settings
    in force as the search space's unit coordinates."""
    env = VFServoEnv("paper-step", residual=True, residual_scale=0.5)
    env.reset()
    a = np.array([0.4, -0.6, 1.0, 0.0])
    obs, *_ = env.step(a)
    rel = Relative(PAPER_SETTINGS.k)
    s = rel.from_log(rel.to_log(PAPER_SETTINGS) + 0.5 * a * Relative.widths() / 2.0)
    from vfgym.envs import _batch as B
    from vfgym.plant import _layout as L

    w = env._w
    assert w[B.W_PRM + L.P_VALUE] == pytest.approx(s.value_rad, rel=1e-12)
    assert w[B.W_PRM + L.P_LIMIT] == pytest.approx(s.error_limit_rad, rel=1e-12)
    assert w[B.W_PRM + L.P_VALUE] / w[B.W_PRM + L.P_STEP] == pytest.approx(s.k, rel=1e-12)
    assert w[B.W_PRM + L.P_A] == PAPER_SETTINGS.ts_over_tf  # a zero offset: the base exactly
    np.testing.assert_allclose(obs[14:18], to_action(s), atol=1e-6)
    assert len(SPACE) == 4


@settings(max_examples=200, deadline=None)
@given(
    base=st.lists(st.floats(-1.0, 1.0), min_size=4, max_size=4),
    act=st.lists(st.floats(-1.0, 1.0), min_size=4, max_size=4),
    scale=st.lists(st.sampled_from([0.0, 0.1, 0.25, 1.0, 2.0]), min_size=4, max_size=4),
)
def test_the_compiled_residual_mapping_is_relatives_offset(base, act, scale):
    """map_action (compiled) against space.Relative (an independent oracle): the offset in
    Relative's coordinates, clipped to the space; a zero offset keeps a setting bit for bit
    (L: unless the value moved); L = value stays so bit for bit."""
    from vfgym.envs import _batch as B

    b = from_action(np.array(base))
    a, sc = np.array(act), np.array(scale)
    unit = np.zeros(4)
    row = np.array([getattr(b, f) for f in B.SETTING_FIELDS])
    got = B.map_action(a, B.space_table(), True, sc, row, unit)
    rel = Relative(1.0)
    want = rel.from_log(rel.to_log(b) + sc * a * Relative.widths() / 2.0)
    for g, f in zip(got, B.SETTING_FIELDS, strict=True):
        assert g == pytest.approx(getattr(want, f), rel=1e-12)
    held = sc * a == 0.0
    for i in (0, 2, 3):
        if held[i]:
            assert got[i] == row[i]
    if held[0] and held[1]:
        assert got[1] == row[1]
    np.testing.assert_allclose(
        unit, [d.to_unit(g) for d, g in zip(SPACE, got, strict=True)], atol=1e-12
    )
    b2 = b.replace(error_limit_rad=b.value_rad)
    row2 = np.array([getattr(b2, f) for f in B.SETTING_FIELDS])
    v, lim, *_ = B.map_action(a, B.space_table(), True, sc * [1, 0, 1, 1], row2, unit)
    assert lim == v


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"residual": 1}, "residual"),
        ({"residual_scale": 0.0}, "residual_scale"),
        ({"residual_scale": 2.5}, "residual_scale"),
        ({"residual_base": "paper"}, "residual_base"),
    ],
)
def test_bad_residual_arguments_name_themselves(kwargs, name):
    with pytest.raises(ValueError, match=name):
        ServoConfig(**kwargs)


RIDGE = Settings(value_rad=0.6, error_limit_rad=0.6, k=40.0, ts_over_tf=0.5)


def test_l_keeps_the_bases_ratio_to_the_value_bit_for_bit():
    env = VFServoEnv("paper-step", residual=True, residual_base=RIDGE)
    env.reset()
    from vfgym.envs import _batch as B
    from vfgym.plant import _layout as L

    env.step(np.array([0.37, 0.0, -0.2, 0.1]))
    w = env._w
    assert w[B.W_PRM + L.P_VALUE] != RIDGE.value_rad
    assert w[B.W_PRM + L.P_LIMIT] == w[B.W_PRM + L.P_VALUE]


def test_a_zero_scale_holds_its_setting_at_the_base():
    env = VFServoEnv(
        "paper-step", residual=True, residual_base=TUNED, residual_scale=(0.5, 0.0, 0.5, 0.0)
    )
    env.reset()
    from vfgym.envs import _batch as B
    from vfgym.plant import _layout as L

    env.step(np.array([0.4, -0.9, 1.0, 0.8]))
    w = env._w
    ratio = w[B.W_PRM + L.P_LIMIT] / w[B.W_PRM + L.P_VALUE]  # L/value held, not L
    assert ratio == pytest.approx(TUNED.error_limit_rad / TUNED.value_rad, rel=1e-12)
    assert w[B.W_PRM + L.P_A] == TUNED.ts_over_tf
    assert w[B.W_PRM + L.P_VALUE] != TUNED.value_rad


@pytest.mark.parametrize("scale", [(0.1, 0.2, 0.3), (0.1, 0.2, 0.3, 2.5), (0.1, -0.1, 0.2, 0.2)])
def test_bad_per_setting_scales_name_themselves(scale):
    with pytest.raises(ValueError, match="residual_scale"):
        ServoConfig(residual_scale=scale)


def test_vftune_residual_zero_action_is_the_base_and_matches_vfservo():
    from vfgym.envs.tune import VFTuneEnv
    from vfgym.envs.vector import VFTuneVectorEnv

    kw = {"residual": True, "residual_base": TUNED}
    env = VFTuneEnv("short-move", **kw)
    obs, _ = env.reset()
    assert obs.shape == (23,) and env.observation_space.shape == (23,)
    np.testing.assert_array_equal(obs[-4:], to_action(TUNED))
    _, r, *_ = env.step(ZERO)
    assert -r == evaluate(TUNED, "short-move").cost[0, 0]
    # a nonzero action: the settings VFServo-v0's compiled mapping holds for a whole move
    a = np.array([0.3, -0.4, 0.5, -0.6])
    s = env.settings_of(a)
    servo = VFServoEnv("short-move", **kw)
    servo.reset()
    from vfgym.envs import _batch as B
    from vfgym.plant import _layout as L

    servo.step(a)
    w = servo._w
    assert (s.value_rad, s.error_limit_rad) == (w[B.W_PRM + L.P_VALUE], w[B.W_PRM + L.P_LIMIT])
    assert s.ts_over_tf == w[B.W_PRM + L.P_A]
    # the vector env: the same observations and rewards
    venv = VFTuneVectorEnv(2, "short-move", **kw)
    vobs, _ = venv.reset(seed=0)
    np.testing.assert_array_equal(vobs[0], obs)
    env.reset()
    _, r1, *_ = env.step(a)
    _, r2, *_ = venv.step(np.stack([a, ZERO]))
    assert r2[0] == r1 and -r2[1] == evaluate(TUNED, "short-move").cost[0, 0]


def test_vftune_violation_penalty_lowers_only_an_infeasible_moves_reward():
    from vfgym.envs.tune import TuneConfig, VFTuneEnv
    from vfgym.envs.vector import VFTuneVectorEnv

    hot = Settings(value_rad=1.0, error_limit_rad=1.0, k=1.0, ts_over_tf=0.25)  # k 1: too fast
    plain = VFTuneEnv("paper-step", residual=True, residual_base=hot)
    env = VFTuneEnv("paper-step", residual=True, residual_base=hot, violation_penalty=2.0)
    venv = VFTuneVectorEnv(1, "paper-step", residual=True, residual_base=hot, violation_penalty=2.0)
    for e in (plain, env):
        e.reset()
    venv.reset(seed=0)
    _, r0, *_, info0 = plain.step(ZERO)
    _, r1, *_, info1 = env.step(ZERO)
    _, rv, *_ = venv.step(ZERO[None])
    assert not info1["feasible"] and info1["cost"] == info0["cost"] == -r0
    assert r1 == r0 - 2.0 and rv[0] == r1
    ok = VFTuneEnv("paper-step", violation_penalty=2.0)
    ok.reset()
    _, r, *_, info = ok.step(to_action(PAPER_SETTINGS))
    assert info["feasible"] and r == -info["cost"]  # the paper's settings: feasible there
    with pytest.raises(ValueError, match="violation_penalty"):
        TuneConfig(violation_penalty=-1.0)
