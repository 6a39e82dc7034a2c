"""The servo follows its load: K3 scales with the total inertia, so a loaded loop keeps the
bare loop's natural frequency and damping (the patent's continuous model); the switch
``Servo.follows_load=False`` restores the drive tuned for the bare motor."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from helpers import linear_plant
from scipy import signal

from vfgym import PAPER_PLANT, Settings, evaluate, simulate
from vfgym.axis import PAPER_AXIS
from vfgym.moves.baselines import usable_accel
from vfgym.params import DEFAULT_MEASURES

F = PAPER_PLANT.tick_hz


def loop(plant):
    """ωn and ζ of the patent's continuous loop: ωn² = K3·K4, ζ = K2·ωn/2."""
    k4 = plant.motor.counts_per_rev / (2 * math.pi) / plant.motor.inertia_kgm2
    wn = math.sqrt(plant.torque_per_count_nm * k4)
    return wn, plant.servo.speed_gain_b * plant.sample_s * wn / 2


@pytest.mark.parametrize("ratio", [0.0, 1.0, 3.0, 5.0, 12.5])
def test_the_loaded_loop_keeps_the_bare_natural_frequency_and_damping(ratio):
    bare = loop(PAPER_PLANT)
    loaded = PAPER_PLANT.with_motor(inertia_ratio=ratio)
    assert loaded.torque_per_count_nm == pytest.approx(5.3e-4 * (1 + ratio), rel=1e-15)
    assert loop(loaded) == pytest.approx(bare, rel=1e-12)
    assert bare[1] == pytest.approx(0.8, abs=0.01)  # docs/reference/axis.md's ζ = 0.8
    mistuned = loaded.with_servo(follows_load=False)
    assert mistuned.torque_per_count_nm == 5.3e-4
    wn, zeta = loop(mistuned)
    assert wn == pytest.approx(bare[0] / math.sqrt(1 + ratio), rel=1e-12)
    assert zeta == pytest.approx(bare[1] / math.sqrt(1 + ratio), rel=1e-12)


def small_step(plant, a=0.25, gear_pulses=16, seconds=0.12):
    ext = np.zeros(int(seconds * F), dtype=np.int8)
    ext[:gear_pulses] = 1
    return simulate(np.cumsum(ext) * plant.pulse_rad, Settings(ts_over_tf=a), plant, pulses=ext)


def test_a_loaded_step_follows_the_bare_continuous_model_and_the_switch_does_not():
    """Against patent Fig. 7's G(s) for the bare loop (as the linear-regime test of the
    plant does): the loaded loop that follows its load matches it; the mis-tuned one
    matches G(s) with ωn/sqrt(1 + ratio) instead."""
    gear, npulse, ratio, wn, b, ns, a = 64, 16, 3.0, 150.0, 200.0, 7, 0.25
    bare = linear_plant(gear, ns, b, wn)
    ts = bare.sample_s
    k2, tf = b * ts, ts / a

    def model(w):
        return signal.lti([tf, 1.0], [tf / w**2, 1.0 / w**2, k2 + tf, 1.0])

    results = {}
    for follows in (True, False):
        pl = bare.with_motor(inertia_ratio=ratio).with_servo(follows_load=follows)
        tr = small_step(pl, a, npulse)
        counts = tr.motor_rad / pl.motor.count_rad / (gear * npulse)
        _, y_bare = signal.step(model(wn), T=tr.time_s)
        _, y_slow = signal.step(model(wn / math.sqrt(1 + ratio)), T=tr.time_s)
        results[follows] = (np.abs(counts - y_bare).max(), np.abs(counts - y_slow).max())
    assert results[True][0] <= 0.005 < 3 * 0.005 < results[True][1]
    assert results[False][1] <= 0.01 < 3 * 0.01 < results[False][0]


def test_a_loaded_step_overshoots_as_the_bare_motor_does():
    """The paper's plant, a 64-count step (no torque saturation): the same overshoot on
    any load while the servo follows it; the mis-tuned drive overshoots far more."""
    bare = small_step(PAPER_PLANT).metrics
    assert 0.0 < bare["overshoot_counts"] < 8.0
    for ratio in (1.0, 3.0, 5.0):
        loaded = PAPER_PLANT.with_motor(inertia_ratio=ratio)
        m = small_step(loaded).metrics
        assert m["overshoot_counts"] == pytest.approx(bare["overshoot_counts"], rel=1e-6)
        assert m["move_time_s"] == pytest.approx(bare["move_time_s"], abs=2 / F)
        mis = small_step(loaded.with_servo(follows_load=False)).metrics
        assert mis["overshoot_counts"] > 2.0 * bare["overshoot_counts"] + 1.0


# Golden numbers: `vfgym.evaluate(["paper", "rule-of-thumb"], ["heavy-load"])` before the
# servo followed its load (commit 97f06c6), its measures printed in full.
BEFORE = {
    "paper": {
        "overshoot_counts": 2901.9276016084386,
        "move_time_s": 0.20092857142857143,
        "peak_torque_nm": 1.91,
        "torque_limit_time_s": 0.026514285714285712,
        "peak_following_error_counts": 6031.0,
        "peak_speed_rad_s": 471.3040038477132,
        "final_error_rad": 0.0006207258373702729,
        "pulse_count": 3315,
    },
    "rule-of-thumb": {
        "overshoot_counts": 822.3419591944221,
        "move_time_s": 0.18302857142857143,
        "peak_torque_nm": 1.7321575796067532,
        "torque_limit_time_s": 0.0,
        "peak_following_error_counts": 4908.0,
        "peak_speed_rad_s": 411.0842054886809,
        "final_error_rad": 0.003090576232867903,
        "pulse_count": 3265,
    },
}


def test_the_switch_restores_the_drive_tuned_for_the_bare_motor():
    mistuned = PAPER_PLANT.with_servo(follows_load=False)
    ev = evaluate(
        ["paper", "rule-of-thumb"], ["heavy-load"], axis=replace(PAPER_AXIS, plant=mistuned)
    )
    for ci, name in enumerate(BEFORE):
        m = ev.metrics[ci][0]
        for key, value in BEFORE[name].items():
            assert m[key] == value, (name, key)
    # and by default the same move arrives as the bare motor's step would
    ev = evaluate(["rule-of-thumb"], ["heavy-load"])
    m = ev.metrics[0][0]
    assert m["settled"] and m["overshoot_counts"] < 8.0 and ev.feasible[0, 0]


def test_every_limit_is_the_loaded_motors_usable_acceleration():
    """Peak torque over total inertia, capped by the stated limit (140 krad/s²)."""
    for ratio, want in ((0.0, 140e3), (0.2, 140e3), (3.0, 1.91 / 4.24e-5), (5.0, 1.91 / 6.36e-5)):
        plant = PAPER_PLANT.with_motor(inertia_ratio=ratio)
        assert plant.motor.usable_accel_rad_s2 == pytest.approx(want, rel=1e-12)
        assert usable_accel(plant) == plant.motor.usable_accel_rad_s2
    ev = evaluate(["paper"], ["heavy-load"])
    m = ev.metrics[0][0]
    limit = 1.91 / 6.36e-5  # 30 krad/s²
    assert m["accel_ratio_pulse"] == pytest.approx(m["peak_accel_pulse_rad_s2"] / limit)
    tol = DEFAULT_MEASURES.accel_tolerance_pct / 100.0
    assert ev.constraints[0, 0, 0] == pytest.approx(m["accel_ratio_pulse"] - 1.0 - tol)
    # an axis that states a lower limit is held to it
    capped = PAPER_PLANT.with_motor(accel_limit_rad_s2=50e3)
    assert capped.motor.usable_accel_rad_s2 == 50e3
