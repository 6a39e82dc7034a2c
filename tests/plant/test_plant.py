"""The servo, motor and encoder: the patent's numbers, an independent G(s) oracle, exact
motor integration, invariants, and the compiled kernel against the plain-Python reference."""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers import linear_plant
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy import signal

from vfgym import (
    DEFAULT_MEASURES,
    PAPER_PLANT,
    PAPER_SETTINGS,
    PAPER_TICK_HZ,
    Measures,
    Motor,
    Plant,
    Servo,
    Settings,
    simulate,
    step_command,
)
from vfgym.plant import _kernel as K
from vfgym.plant import _layout as L
from vfgym.plant import pack
from vfgym.plant.reference import DigitalServo, MotorLoad, reference_run

F = PAPER_TICK_HZ
T = 1.0 / F


# --- the patent's worked numbers (gear 1, Ts = 5 ms, B = 4) ------------------------------


@pytest.fixture(scope="module")
def patent_run():
    # gear 1 as in the patent: one command pulse is one encoder count
    count_rad = 2 * math.pi / 8192
    pl = Plant(
        pulse_rad=count_rad,
        servo=Servo(gear=1, sample_ticks=700, speed_gain_b=4.0, torque_per_count_nm=2e-5),
        motor=Motor(),
    ).with_sample_period(5e-3)
    n = int(1.0 * F)
    ext = np.zeros(n, dtype=np.int8)
    ext[::140] = 1  # 1000 pulses/s
    tr = simulate(np.cumsum(ext) * count_rad, PAPER_SETTINGS, pl, pulses=ext)
    return pl, tr


def test_patent_speed_counter_averages_5_counts_times_4_is_20(patent_run):
    pl, tr = patent_run
    x = tr.speed_count[int(0.5 * F) :: pl.servo.sample_ticks]  # latched values, steady state
    assert x.mean() == pytest.approx(20.0, abs=0.5)
    assert set(np.unique(x)) <= {16.0, 20.0, 24.0}  # ±1 count of jitter shows as ±4


def test_patent_following_error_20_and_kv_50(patent_run):
    pl, tr = patent_run
    pc = tr.position_counter[int(0.5 * F) :]
    assert pc.mean() == pytest.approx(20.0, abs=1.0)
    assert 1000.0 / pc.mean() == pytest.approx(50.0, rel=0.05)
    assert pl.servo_kv == pytest.approx(50.0)  # Kv = 1/(B·Ts)


def test_patent_filter_at_20_with_input_24_outputs_21():
    servo = DigitalServo(
        pack(
            PAPER_SETTINGS,
            PAPER_PLANT.with_servo(sample_ticks=1, speed_gain_b=4.0),
            DEFAULT_MEASURES,
            0.0,
            1,
        )
    )
    servo.y = 20.0
    servo.tick(0, 6)  # 6 counts in the sample: x = 4·6 = 24
    assert servo.x == 24.0
    assert servo.y == 21.0  # a quarter of the change (A = Ts/Tf = 1/4)


def test_filter_equation_holds_at_every_sample_in_the_kernel(patent_run):
    pl, tr = patent_run
    ns = pl.servo.sample_ticks
    x = tr.speed_count[ns - 1 :: ns]
    y = tr.feedback_counts[ns - 1 :: ns]
    a = PAPER_SETTINGS.ts_over_tf
    np.testing.assert_array_equal(y[1:], y[:-1] + a * (x[1:] - y[:-1]))
    # without the filter the feedback jumps by the full ±4; with A = 1/4 by a quarter of it
    steady = slice(len(x) // 2, None)
    assert np.abs(np.diff(x[steady])).max() == 4.0
    assert np.abs(np.diff(y[steady])).max() <= 0.25 * 8.0 + 1e-9


# --- linear regime against patent Fig. 7's closed loop ------------------------------------


@pytest.mark.parametrize(
    ("a", "ns", "b", "wn", "tol"),
    [
        (0.1, 7, 200.0, 150.0, 0.005),
        (0.25, 7, 200.0, 150.0, 0.005),
        (1.0, 7, 200.0, 150.0, 0.005),
        (0.25, 7, 100.0, 300.0, 0.008),
        (0.25, 70, 20.0, 150.0, 0.008),
        (0.1, 70, 20.0, 150.0, 0.015),
    ],
)
def test_linear_step_response_matches_patent_closed_loop(a, ns, b, wn, tol):
    """G(s) = 1/(s²/(K1K3K4) + (K2/K1)·s/(Tf·s+1) + 1), K1 = 1, K2 = B·Ts, Tf = Ts/A,
    computed by scipy.signal. Tolerance (fraction of the step): 0.5 % with Ts = 50 µs;
    up to 1.5 % at Ts = 0.5 ms, where the sampled speed counter's delay (≈ Ts) and the
    discrete filter (pole 1 − A rather than e^(−A)) part from the continuous model."""
    gear, npulse = 64, 16
    pl = linear_plant(gear, ns, b, wn)
    n = int(0.12 * F)
    ext = np.zeros(n, dtype=np.int8)
    ext[:npulse] = 1
    tr = simulate(np.cumsum(ext) * pl.pulse_rad, Settings(ts_over_tf=a), pl, pulses=ext)
    ts = pl.sample_s
    k2, tf = b * ts, ts / a
    w = pl.servo.torque_per_count_nm * pl.motor.counts_per_rev / (2 * math.pi)
    w /= pl.motor.inertia_kgm2
    g = signal.lti([tf, 1.0], [tf / w, 1.0 / w, k2 + tf, 1.0])
    _, y = signal.step(g, T=tr.time_s)
    counts = tr.motor_rad / pl.motor.count_rad / (gear * npulse)
    assert np.abs(counts - y).max() <= tol
    # and the oracle is not trivially satisfied: a wrong gain is caught
    g_wrong = signal.lti([tf, 1.0], [tf / (2 * w), 1.0 / (2 * w), k2 + tf, 1.0])
    _, y_wrong = signal.step(g_wrong, T=tr.time_s)
    assert np.abs(counts - y_wrong).max() > 3 * tol


# --- motor block against closed forms --------------------------------------------------------


def motor_block(**motor) -> MotorLoad:
    pl = PAPER_PLANT.with_motor(**motor)
    return MotorLoad(pack(PAPER_SETTINGS, pl, DEFAULT_MEASURES, 0.0, 1))


def test_motor_constant_torque_no_friction_is_a_parabola():
    m = motor_block()
    J = PAPER_PLANT.motor.inertia_kgm2
    for _ in range(1000):
        m.tick(0.5)
    t = 1000 * T
    assert m.omega == pytest.approx(0.5 / J * t, rel=1e-12)
    assert m.theta == pytest.approx(0.5 / J * t * t / 2, rel=1e-9)


def test_motor_viscous_matches_exponential():
    b = 2e-4
    m = motor_block(viscous_nm_s_rad=b)
    J = PAPER_PLANT.motor.inertia_kgm2
    a = b / J
    for _ in range(2000):
        m.tick(0.3)
    t = 2000 * T
    w = 0.3 / b * (1 - math.exp(-a * t))
    th = 0.3 / b * (t - (1 - math.exp(-a * t)) / a)
    assert m.omega == pytest.approx(w, rel=1e-10)
    assert m.theta == pytest.approx(th, rel=1e-8)


def test_motor_coulomb_stops_exactly_and_sticks():
    tc = 0.05
    m = motor_block(coulomb_nm=tc)
    J = PAPER_PLANT.motor.inertia_kgm2
    m.omega = 100.0
    t_stop = 100.0 * J / tc  # 21.2 ms
    for _ in range(int(0.05 * F)):
        m.tick(0.0)
    assert m.omega == 0.0
    assert m.theta == pytest.approx(100.0 * t_stop / 2, rel=1e-9)
    th = m.theta
    for _ in range(1000):
        m.tick(0.9 * tc)  # below the breakaway torque: stays put
    assert (m.theta, m.omega) == (th, 0.0)
    m.tick(2 * tc)  # above it: moves
    assert m.omega > 0.0


def test_load_torque_pulls_back_a_stalled_motor():
    m = motor_block(load_torque_nm=0.2)
    m.tick(0.0)
    assert m.omega < 0.0


# --- invariants, determinism, the reference -----------------------------------------------------


def test_position_counter_is_gear_times_pulses_minus_encoder_counts_every_tick():
    pl = PAPER_PLANT.with_motor(coulomb_nm=0.02, viscous_nm_s_rad=1e-5)
    tr = simulate(step_command(10.0, 20_000), PAPER_SETTINGS, pl)
    counts = np.floor(tr.motor_rad / pl.motor.count_rad)
    seen = np.concatenate([[0.0], counts[:-1]])  # the servo sees last tick's count
    np.testing.assert_array_equal(tr.position_counter, pl.servo.gear * tr.pulse_count - seen)


def test_negated_command_gives_mirrored_pulses():
    a = simulate(step_command(3.0, 20_000))
    b = simulate(step_command(-3.0, 20_000))
    np.testing.assert_array_equal(b.pulse_count, -a.pulse_count)


def test_same_inputs_same_outputs():
    pl = PAPER_PLANT.with_motor(coulomb_nm=0.03, inertia_ratio=2.0)
    a = simulate(step_command(5.0, 30_000), PAPER_SETTINGS, pl)
    b = simulate(step_command(5.0, 30_000), PAPER_SETTINGS, pl)
    np.testing.assert_array_equal(a.acc, b.acc)
    np.testing.assert_array_equal(a.motor_rad, b.motor_rad)


def test_decimated_trace_is_a_subsample_and_measures_are_unchanged():
    full = simulate(step_command(2.0, 7000))
    dec = simulate(step_command(2.0, 7000), decimation=7)
    np.testing.assert_array_equal(dec.motor_rad, full.motor_rad[6::7])
    np.testing.assert_array_equal(dec.time_s, full.time_s[6::7])
    np.testing.assert_array_equal(dec.acc, full.acc)


def kernel_and_reference(cmd, settings_, plant, ext=None):
    n = len(cmd)
    use_ext = ext is not None
    ext_arr = np.zeros(0, np.int8) if ext is None else ext
    prm = pack(settings_, plant, Measures(accel_window_s=50 * T), float(cmd[-1]), n, use_ext)
    acc = K.new_acc()
    rec = np.empty((L.N_ROWS, n))
    K.run_one(cmd, ext_arr, prm, acc, rec, 1)
    acc_ref, rec_ref = reference_run(cmd, ext_arr, prm)
    return acc, rec, acc_ref, rec_ref


command_shape = st.sampled_from(["step", "sine", "ramp", "multi"])


def make_command(shape: str, amp: float, n: int, freq: float) -> np.ndarray:
    t = np.arange(n) * T
    if shape == "step":
        return np.full(n, amp)
    if shape == "sine":
        return amp * np.sin(2 * np.pi * freq * t)
    if shape == "ramp":
        return amp * np.minimum(t / (0.6 * t[-1]), 1.0)
    c = np.full(n, amp)
    c[n // 3 :] = -0.5 * amp
    c[2 * n // 3 :] = 0.25 * amp
    return c


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    shape=command_shape,
    amp=st.floats(0.01, 8.0),
    sign=st.sampled_from([1.0, -1.0]),
    freq=st.floats(5.0, 200.0),
    value=st.floats(0.05, 2.0),
    limit=st.floats(0.05, 2.0),
    k=st.floats(1.0, 3000.0),
    a=st.floats(0.01, 1.0),
    law=st.sampled_from(["rise", "slew"]),
    ratio=st.floats(0.0, 5.0),
    viscous=st.sampled_from([0.0, 1e-5, 3e-3]),
    coulomb=st.sampled_from([0.0, 0.01, 0.2]),
    load=st.sampled_from([0.0, 0.05, -0.3]),
    ns=st.integers(1, 200),
    gear=st.integers(1, 8),
)
def test_kernel_matches_reference_bit_for_bit(
    shape, amp, sign, freq, value, limit, k, a, law, ratio, viscous, coulomb, load, ns, gear
):
    n = 2500
    cmd = sign * make_command(shape, amp, n, freq)
    s = Settings(value_rad=value, error_limit_rad=limit, k=k, ts_over_tf=a, accel_law=law)
    pl = PAPER_PLANT.with_motor(
        inertia_ratio=ratio, viscous_nm_s_rad=viscous, coulomb_nm=coulomb, load_torque_nm=load
    ).with_servo(sample_ticks=ns, gear=gear)
    acc, rec, acc_ref, rec_ref = kernel_and_reference(cmd, s, pl)
    np.testing.assert_array_equal(rec, rec_ref)
    np.testing.assert_array_equal(acc, acc_ref)


@settings(max_examples=20, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), coulomb=st.sampled_from([0.0, 0.05]))
def test_kernel_matches_reference_with_external_pulses(seed, coulomb):
    rng = np.random.default_rng(seed)
    ext = rng.choice(np.array([-1, 0, 1], dtype=np.int8), size=3000, p=[0.2, 0.5, 0.3])
    cmd = np.cumsum(ext) * PAPER_PLANT.pulse_rad
    pl = PAPER_PLANT.with_motor(coulomb_nm=coulomb)
    acc, rec, acc_ref, rec_ref = kernel_and_reference(cmd, PAPER_SETTINGS, pl, ext)
    np.testing.assert_array_equal(rec, rec_ref)
    np.testing.assert_array_equal(acc, acc_ref)


def test_batch_kernel_equals_single_runs():
    cmds = [step_command(3.0, 4000), -step_command(1.0, 3000)]
    plants = [PAPER_PLANT, PAPER_PLANT.with_motor(coulomb_nm=0.05, inertia_ratio=1.0)]
    sets = [PAPER_SETTINGS, Settings(value_rad=0.5, error_limit_rad=0.4, k=100.0)]
    flat = np.concatenate(cmds)
    off = np.array([0, len(cmds[0]), len(flat)], dtype=np.int64)
    ext_off = np.zeros(2, dtype=np.int64)
    runs = [(j, s) for j in range(2) for s in sets]
    prm = np.stack(
        [pack(s, plants[j], DEFAULT_MEASURES, float(cmds[j][-1]), len(cmds[j])) for j, s in runs]
    )
    acc = K.new_acc(len(runs))
    idx = np.array([j for j, _ in runs])
    K.run_batch(flat, off, idx, np.zeros(0, np.int8), ext_off, np.zeros_like(idx), prm, acc)
    for r, (j, s) in enumerate(runs):
        np.testing.assert_array_equal(acc[r], simulate(cmds[j], s, plants[j]).acc)


# --- bad input -----------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("make", "name"),
    [
        (lambda: Settings(value_rad=0.0), "value_rad"),
        (lambda: Settings(error_limit_rad=-1.0), "error_limit_rad"),
        (lambda: Settings(k=0.99), "k"),
        (lambda: Settings(ts_over_tf=0.0), "ts_over_tf"),
        (lambda: Settings(ts_over_tf=1.5), "ts_over_tf"),
        (lambda: Settings(accel_law="fast"), "accel_law"),
        (lambda: Servo(sample_ticks=2.5), "sample_ticks"),
        (lambda: Servo(gear=0), "gear"),
        (lambda: Servo(speed_gain_b=-4.0), "speed_gain_b"),
        (lambda: PAPER_PLANT.with_sample_period(1.0e-5), "sample_period_s"),
        (lambda: Motor(rotor_inertia_kgm2=0.0), "rotor_inertia_kgm2"),
        (lambda: Motor(inertia_ratio=-1.0), "inertia_ratio"),
        (lambda: Motor(coulomb_nm=float("nan")), "coulomb_nm"),
        (lambda: Motor(max_speed_rad_s=10.0), "max_speed_rad_s"),
        (lambda: Plant(tick_hz=0.0), "tick_hz"),
        (lambda: simulate(np.array([1.0, np.inf])), "command_rad"),
        (lambda: simulate(np.ones(5), decimation=0), "decimation"),
        (lambda: simulate(np.ones(5), pulses=np.full(5, 2, np.int8)), "pulses"),
    ],
)
def test_bad_input_names_parameter_value_and_range(make, name):
    with pytest.raises(ValueError, match=name) as info:
        make()
    assert "allowed" in str(info.value) or "must" in str(info.value)


def test_sample_period_in_seconds():
    assert PAPER_PLANT.with_sample_period(5e-3).servo.sample_ticks == 700


def test_segments_with_the_same_parameters_equal_one_run():
    """The stateful kernel (online tuning steps 140 ticks at a time) continues exactly."""
    pl = PAPER_PLANT.with_motor(coulomb_nm=0.01, inertia_ratio=1.5)
    cmd = step_command(4.0, 9000)
    prm = pack(PAPER_SETTINGS, pl, DEFAULT_MEASURES, 4.0, cmd.size)
    whole = simulate(cmd, PAPER_SETTINGS, pl)
    st = np.empty(L.N_STATE)
    ring = np.empty(K.ring_size(prm))
    K.init_state(prm, st, ring)
    rec = np.empty((L.N_ROWS, cmd.size))
    for start in range(0, cmd.size, 140):
        stop = min(cmd.size, start + 140)
        K.run_segment(cmd, np.zeros(0, np.int8), prm, st, ring, stop, rec[:, start:stop], 1)
    acc = K.new_acc()
    K.finish(st, acc, cmd.size, prm)
    np.testing.assert_array_equal(acc, whole.acc)
    np.testing.assert_array_equal(rec[L.R_THETA], whole.motor_rad)


def test_encoder_count_is_the_exact_quotient_where_the_reciprocal_rounds_across_a_count():
    """The kernel guesses floor(θ/q) as floor(θ·(1/q)) and checks it with the quotient:
    at θ = 0.3, q = 0.1 the product rounds up to 3.0 while θ/q is 2.9999999999999996.
    A motor held by Coulomb friction at θ = 0.3 must read count 2, every tick."""
    theta, q = 0.3, 0.1
    assert math.floor(theta * (1.0 / q)) == 3 and math.floor(theta / q) == 2
    pl = PAPER_PLANT.with_motor(coulomb_nm=1.5)  # below the peak torque: it can move
    cmd = np.zeros(5)
    prm = pack(PAPER_SETTINGS, pl, DEFAULT_MEASURES, 0.0, cmd.size)
    prm[L.P_COUNT_RAD] = q
    st = np.empty(L.N_STATE)
    ring = np.empty(K.ring_size(prm))
    K.init_state(prm, st, ring)
    st[L.S_THETA] = theta
    rec = np.empty((L.N_ROWS, cmd.size))
    for i in range(cmd.size):  # tick by tick: the count after each one
        K.run_segment(cmd, np.zeros(0, np.int8), prm, st, ring, i + 1, rec[:, i : i + 1], 1)
        assert st[L.S_THETA] == theta
        assert st[L.S_C] == 2
