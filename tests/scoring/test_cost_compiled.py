"""The compiled copy of the cost (the VFServo-v0 env's running cost) against the scoring
path's :func:`vfgym.scoring.score`: on random loop states, plants, windows, weights,
bounds and scenarios, and on simulated moves, the compiled terms at the end of a move are
``score``'s terms one by one (``score`` adds the arrival term, in one place), and
``violated`` is "a running constraint > 0"."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from vfgym import PAPER_PLANT, Measures, Transmission
from vfgym.moves.distribution import random_scenario
from vfgym.moves.scenarios import SCENARIOS, Scenario
from vfgym.plant import _kernel as K
from vfgym.plant import _layout as L
from vfgym.plant import command_end_s, pack
from vfgym.plant.measures import from_acc
from vfgym.scoring import (
    Bounds,
    CostWeights,
    arrival_constraint,
    arrival_term,
    residual_term,
    score,
    yardsticks,
)
from vfgym.scoring import _cost_compiled as CC
from vfgym.space import SPACE, from_action

SHORT = [n for n, s in SCENARIOS.items() if s.duration_s <= 0.2]

scenarios = st.one_of(
    st.sampled_from(SHORT).map(SCENARIOS.__getitem__),
    st.builds(random_scenario, st.integers(0, 10_000), st.sampled_from(["train", "test"])),
    st.builds(
        lambda d, f, t: Scenario(
            name="sine", profile="sine", distance_rad=d, freq_hz=f, duration_s=t
        ),
        st.floats(0.2, 8.0) | st.floats(-8.0, -0.2),
        st.floats(5.0, 40.0),
        st.floats(0.03, 0.12),
    ),
)


def _base(ns: int, lines: int, hz: float | None):
    """The paper's plant with another servo period and encoder; with a transmission (the
    load judged) at ``hz`` unless None."""
    plant = PAPER_PLANT.with_servo(sample_ticks=ns).with_motor(encoder_lines=lines)
    if hz is None:
        return plant
    jm = plant.motor.inertia_kgm2
    return plant.replace(transmission=Transmission.from_resonance(jm, jm, hz, 0.05))


bases = st.builds(
    _base,
    st.sampled_from([35, 70, 140]),
    st.sampled_from([2048, 4096]),
    st.sampled_from([None, None, 150.0, 400.0]),
)
measures = st.one_of(
    st.builds(
        Measures,
        in_position_counts=st.sampled_from([0.5, 1.0, 8.0, 40.0]),
        accel_window_s=st.sampled_from([5e-4, 1e-3, 2e-3]),
    ),
    st.builds(Measures, in_position_pct=st.floats(0.1, 5.0)),
)
weight = st.floats(0.0, 10.0)
weights = st.builds(
    CostWeights,
    time=weight,
    tracking=weight,
    overshoot=weight,
    accel=weight,
    torque=weight,
    unsettled=weight,
    arrival=weight,
    residual=weight,
)
bounds = st.builds(
    Bounds, overshoot_windows=st.floats(0.0, 5.0), torque_limit_time_s=st.floats(0, 0.01)
)
actions = st.lists(st.floats(-1.0, 1.0), min_size=len(SPACE), max_size=len(SPACE))


def check_against_score(stt, prm, scenario, plant, meas, w, b) -> None:
    """The compiled cost on loop state ``stt`` at the end of the move against ``score`` on
    the measures the same state decodes to."""
    cmd = scenario.command(plant)
    n = cmd.size
    acc = np.zeros(L.N_ACC)
    K.finish(stt, acc, n, prm)
    m = from_acc(acc, plant, meas, float(cmd[-1]), command_end_s(cmd, plant.tick_hz))
    s = score(m, scenario, plant, meas, w, b)
    k = CC.constants(yardsticks(scenario, plant, meas), n, w, b)

    assert CC.cost_terms(stt, prm, k) == tuple(s.terms[:4])
    assert CC.running_cost(stt, prm, k) == s.terms.running
    # the end-of-move terms, each added in one place: the arrival term, and the load's
    # residual vibration where a transmission is stated (none on a rigid plant)
    y = yardsticks(scenario, plant, meas)
    c_arr = arrival_constraint(m, y)
    assert s.terms.arrival == arrival_term(c_arr, w)
    assert s.terms.residual == residual_term(m, y, w)
    if plant.transmission is None:
        assert s.terms.residual == 0.0
    assert s.cost == CC.running_cost(stt, prm, k) + arrival_term(c_arr, w) + residual_term(m, y, w)
    assert CC.running_constraints(stt, prm, k) == tuple(s.constraints[:3])
    assert s.constraints[3] == c_arr
    assert CC.violated(stt, prm, k) == bool(np.any(s.constraints[:3] > 0.0))


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    sc=scenarios,
    base=bases,
    meas=measures,
    w=weights,
    b=bounds,
    data=st.data(),
)
def test_compiled_cost_equals_score_term_by_term_on_random_states(sc, base, meas, w, b, data):
    plant = sc.plant(base)
    cmd = sc.command(plant)
    n = cmd.size
    target = float(cmd[-1])
    prm = pack(from_action(np.zeros(len(SPACE))), plant, meas, target, n)
    accw = int(prm[L.P_ACC_W])
    win = yardsticks(sc, plant, meas).window_rad
    stt = np.zeros(L.N_STATE)
    stt[L.S_LOM] = data.draw(st.integers(-1, n - 1), "last tick out of the window")
    stt[L.S_OVM] = data.draw(st.floats(0.0, 3.0) | st.sampled_from([0.0, win]), "overshoot")
    stt[L.S_D2MX] = data.draw(st.integers(0, 4 * accw), "peak second difference")
    stt[L.S_SAT] = data.draw(st.integers(0, n), "ticks at the torque limit")
    stt[L.S_TSQM] = data.draw(st.floats(0.0, 100.0 * n), "sum of squared tracking error")
    stt[L.S_THETA] = target + data.draw(
        st.floats(-3.0, 3.0) | st.sampled_from([0.0, win, -win]), "final error"
    )
    if plant.transmission is not None:  # the load's measures, which the cost judges
        stt[L.S_LOL] = data.draw(st.integers(-1, n - 1), "the load's last tick out")
        stt[L.S_OVL] = data.draw(st.floats(0.0, 3.0) | st.sampled_from([0.0, win]), "its overshoot")
        stt[L.S_TSQL] = data.draw(st.floats(0.0, 100.0 * n), "its squared tracking error")
        stt[L.S_TWIST] = (
            stt[L.S_THETA]
            - target
            - data.draw(st.floats(-3.0, 3.0) | st.sampled_from([0.0, win, -win]), "its final error")
        )
    check_against_score(stt, prm, sc, plant, meas, w, b)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(sc=scenarios, base=bases, meas=measures, w=weights, b=bounds, a=actions)
def test_compiled_cost_equals_score_term_by_term_on_simulated_moves(sc, base, meas, w, b, a):
    plant = sc.plant(base)
    cmd = sc.command(plant)
    prm = pack(from_action(np.array(a)), plant, meas, float(cmd[-1]), cmd.size)
    stt = np.zeros(L.N_STATE)
    ring = np.zeros(K.ring_size(prm))
    K.init_state(prm, stt, ring)
    K.run_segment(cmd, np.zeros(0, np.int8), prm, stt, ring, cmd.size, np.zeros((L.N_ROWS, 0)), 1)
    check_against_score(stt, prm, sc, plant, meas, w, b)


def test_the_compiled_constants_are_read_from_the_scoring_inputs():
    """Each slot of the constants row holds the yardstick, weight or bound it names."""
    sc, meas = SCENARIOS["paper-sine"], Measures(in_position_counts=3.0, accel_tolerance_pct=0.7)
    plant = sc.plant()
    y = yardsticks(sc, plant, meas)
    w = CostWeights(*(float(i + 2) for i in range(len(CostWeights.__dataclass_fields__))))
    b = Bounds(overshoot_windows=0.5, torque_limit_time_s=1e-3)
    k = CC.constants(y, 42, w, b)
    expect = {
        CC.K_TICKS: 42,
        CC.K_IDEAL: y.ideal_time_s,
        CC.K_WIN: y.window_rad,
        CC.K_LIMIT: y.accel_limit_rad_s2,
        CC.K_TRACKING: 1.0,
        CC.K_TRK_SCALE: y.tracking_scale_rad,
        CC.K_W_TIME: w.time,
        CC.K_W_TRACK: w.tracking,
        CC.K_W_OV: w.overshoot,
        CC.K_W_ACC: w.accel,
        CC.K_W_TQ: w.torque,
        CC.K_B_OV: b.overshoot_windows,
        CC.K_B_TQ: b.torque_limit_time_s,
        CC.K_ACC_TOL: y.accel_tolerance,
        CC.K_LOAD: 0.0,
    }
    assert y.accel_tolerance == pytest.approx(0.007)
    assert sorted(expect) == list(range(CC.N_CONST))
    for slot, value in expect.items():
        assert k[slot] == value, slot


def test_the_compiled_cost_judges_the_load_where_a_transmission_is_stated():
    """On a compliant plant the load rings after the motor is in position: the compiled
    cost, as ``score``, reads the load's move time, not the motor's, and differs from what
    the motor's would give."""
    sc = SCENARIOS["short-move"]
    plant = _base(70, 2048, 100.0)
    cmd = sc.command(plant)
    prm = pack(from_action(np.zeros(len(SPACE))), plant, Measures(), float(cmd[-1]), cmd.size)
    stt = np.zeros(L.N_STATE)
    K.init_state(prm, stt, np.zeros(K.ring_size(prm)))
    ring = np.zeros(K.ring_size(prm))
    K.run_segment(cmd, np.zeros(0, np.int8), prm, stt, ring, cmd.size, np.zeros((L.N_ROWS, 0)), 1)
    y = yardsticks(sc, plant, Measures())
    assert y.load and stt[L.S_LOL] > stt[L.S_LOM]
    k = CC.constants(y, cmd.size, CostWeights(), Bounds())
    assert k[CC.K_LOAD] == 1.0
    main = CC.cost_terms(stt, prm, k)[0]
    assert main == (stt[L.S_LOL] + 1.0) * plant.tick_s / y.ideal_time_s
    check_against_score(stt, prm, sc, plant, Measures(), CostWeights(), Bounds())
