"""vfgym.plant.simulate_train: an external train from another state of rest, as the
identification simulates a capture (the motor anywhere within a count, the servo's sample
clock at any phase), checked against simulate and the plain-Python reference."""

from __future__ import annotations

import numpy as np
import pytest

from vfgym.axis import PlantVariant
from vfgym.params import PAPER_PLANT, PAPER_SETTINGS, Settings
from vfgym.plant import pack, reference, simulate, simulate_train

RATED = PAPER_PLANT.motor.rated_torque_nm
PLANT = PlantVariant(
    inertia=2.5, coulomb_offset_nm=0.02 * RATED, load_offset_nm=-0.03 * RATED
).apply(PAPER_PLANT)


def _train(n: int = 6000) -> np.ndarray:
    """Rest, a burst forward at half the pulse rate, a burst back at full rate, rest."""
    p = np.zeros(n, dtype=np.int8)
    p[500:2500:2] = 1
    p[3000:4000] = -1
    return p


def test_the_defaults_are_simulate_with_an_external_train():
    p = _train()
    a = simulate(np.zeros(p.size), PAPER_SETTINGS, PLANT, pulses=p, decimation=3)
    b = simulate_train(p, PAPER_SETTINGS, PLANT, decimation=3)
    np.testing.assert_array_equal(a.motor_rad, b.motor_rad)
    np.testing.assert_array_equal(a.torque_nm, b.torque_nm)
    np.testing.assert_array_equal(a.acc, b.acc)
    assert b.external and b.decimation == 3


def test_a_servo_phase_is_the_state_after_as_many_idle_ticks():
    """Without a load nothing moves at rest, so k idle ticks first only advance the clock."""
    plant = PlantVariant(inertia=2.5, coulomb_offset_nm=0.02 * RATED).apply(PAPER_PLANT)
    p = _train()
    for k in (1, 37, plant.servo.sample_ticks - 1):
        a = simulate(np.zeros(p.size + k), PAPER_SETTINGS, plant, pulses=np.r_[np.zeros(k), p])
        b = simulate_train(p, PAPER_SETTINGS, plant, servo_phase_ticks=k)
        np.testing.assert_array_equal(a.motor_rad[k:], b.motor_rad)
        np.testing.assert_array_equal(a.servo_error_counts[k:], b.servo_error_counts)


def test_a_start_within_the_count_and_a_phase_match_the_reference(monkeypatch):
    """The plain-Python reference, its motor and servo started in the same state."""
    frac, phase = 0.6875, 23
    q = PLANT.motor.count_rad

    class Motor(reference.MotorLoad):
        def __init__(self, prm):
            super().__init__(prm)
            self.theta = frac * q

    class Servo(reference.DigitalServo):
        def __init__(self, prm):
            super().__init__(prm)
            self.ticks_in_sample = phase

    monkeypatch.setattr(reference, "MotorLoad", Motor)
    monkeypatch.setattr(reference, "DigitalServo", Servo)
    p = _train()
    settings = Settings(ts_over_tf=0.3)
    prm = pack(settings, PLANT, simulate_train(p[:1], settings, PLANT).measures, 0.0, p.size, True)
    _, rows = reference.reference_run(np.zeros(p.size), p, prm)
    tr = simulate_train(p, settings, PLANT, start_count=frac, servo_phase_ticks=phase)
    np.testing.assert_array_equal(tr.motor_rad, rows[2])
    np.testing.assert_array_equal(tr.torque_nm, rows[4])
    assert tr.motor_rad[0] >= frac * q - 1e-12  # at rest, the load held by the friction
    # and it is not the start from 0
    assert not np.array_equal(simulate_train(p, settings, PLANT).motor_rad, rows[2])


@pytest.mark.parametrize(
    ("kw", "name"),
    [
        ({"start_count": 1.0}, "start_count"),
        ({"start_count": -0.1}, "start_count"),
        ({"servo_phase_ticks": PAPER_PLANT.servo.sample_ticks}, "servo_phase_ticks"),
        ({"servo_phase_ticks": -1}, "servo_phase_ticks"),
    ],
)
def test_a_start_out_of_its_range_is_refused_by_name(kw, name):
    with pytest.raises(ValueError, match=name):
        simulate_train(_train(), PAPER_SETTINGS, PAPER_PLANT, **kw)
