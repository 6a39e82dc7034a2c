"""Tests of the S-curve (MCX514 manual p.26) and fixed-frequency pulse sources.

Numbers are realistic for the paper's set-up: 140 kHz ticks, drive speeds up to
100 kpps, jerks giving moves of 1-100 ms.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st
from scipy.optimize import brentq

from vfgym.moves.pulse_sources import (
    ScurveProfile,
    fixed_frequency_pulses,
    scurve_counts,
    scurve_profile,
    scurve_pulses,
)
from vfgym.params import PAPER_PLANT

F = 140_000.0  # tick frequency, Hz (the paper's controller clock)

# Too short to reach DV: T = sqrt(99500/1e9) = 9.97 ms, 2*Pa = 2004 pulses > 600.
SHORT = dict(
    total_pulses=600,
    initial_speed_pps=500.0,
    drive_speed_pps=100_000.0,
    jerk_pps3=1e9,
    tick_hz=F,
)
# Reaches DV: 2*Pa = 2004 < 5000 pulses, about 70 ms.
LONG = dict(SHORT, total_pulses=5000)

PROPERTY = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def counts(train: np.ndarray) -> np.ndarray:
    """Cumulative pulse count at each tick boundary (entry i: pulses before tick i)."""
    return np.concatenate([[0], np.cumsum(train, dtype=np.int64)])


def window_counts(train: np.ndarray, w: int) -> np.ndarray:
    """Pulses in every window of w consecutive ticks."""
    c = counts(train)
    return c[w:] - c[:-w]


def both(**kw) -> tuple[ScurveProfile, np.ndarray]:
    return scurve_profile(**kw), scurve_pulses(**kw)


def ta_pa(sv: float, dv: float, jk: float) -> tuple[float, float]:
    """The manual's acceleration time and pulses when the move reaches drive speed."""
    root = math.sqrt((dv - sv) / jk)
    return 2.0 * root, (dv + sv) * root


def switch_time(sv: float, jk: float, total: int) -> float:
    """Independent solution of SV t + JK t^3 / 6 = P / 12 (rule of 1/12)."""
    return brentq(lambda t: sv * t + jk * t**3 / 6.0 - total / 12.0, 0.0, 10.0, xtol=1e-15)


# ---------------------------------------------------------------- shared checks


def assert_basic_train(train: np.ndarray, total: int) -> None:
    assert train.dtype == np.int8
    assert train.ndim == 1
    assert set(np.unique(train).tolist()) <= {0, 1}  # at most one pulse per tick, no minus
    assert int(train.sum()) == total


def assert_speed_limit(train: np.ndarray, dv: float, f: float) -> None:
    # p(t) rises by at most DV*w/f over w ticks; the window count is
    # round(p(b)) - round(p(a)) < p(b) - p(a) + 1, hence the +1: the two ends are each
    # rounded by up to half a pulse.
    for w in (1, 7, 70, 700, 7000):
        if w <= train.size:
            assert window_counts(train, w).max() <= dv * w / f + 1.0 + 1e-9, w


def assert_mirror_symmetric(train: np.ndarray) -> None:
    # Deceleration is the time mirror of acceleration, so pulse j (p passing j - 1/2) and
    # pulse P+1-j (p passing P - j + 1/2) sit at mirror times: their tick indices add up
    # to the same number within one tick. Equivalently, the train reversed matches the
    # original to within one tick.
    ticks = np.flatnonzero(train)
    if ticks.size == 0:
        return
    sums = ticks + ticks[::-1]
    assert sums.max() - sums.min() <= 1


def assert_matches_profile(prof: ScurveProfile, train: np.ndarray) -> None:
    # The count at every tick boundary is the exact position rounded to a whole pulse.
    c = counts(train)[: prof.n_ticks + 1]
    p = prof.position(prof.tick_times()[: c.size])
    assert np.all(np.abs(c - p) <= 0.5 + 1e-6)
    assert prof.position(prof.t_end) == prof.end_position
    assert prof.output_pulses == math.floor(prof.end_position + 0.5 + 1e-9)


def assert_profile_symmetric(prof: ScurveProfile) -> None:
    # The exact speed curve is its own mirror image: v(t_end - t) = v(t).
    t = np.linspace(0.0, prof.t_end, 4001)[1:-1]
    np.testing.assert_allclose(prof.speed(t), prof.speed(prof.t_end - t), rtol=1e-9)
    assert prof.t_end - prof.t_dec_start == pytest.approx(
        prof.t_acc_end, rel=1e-9, abs=1e-12 * prof.t_end
    )


# ---------------------------------------------------------------- S-curve: basics


@pytest.mark.parametrize("prevention", [True, False])
@pytest.mark.parametrize("case", [SHORT, LONG], ids=["short", "long"])
def test_exact_count_one_pulse_per_tick_and_profile(case, prevention):
    prof, train = both(**case, triangle_prevention=prevention)
    assert_basic_train(train, case["total_pulses"])
    assert train.size == prof.n_ticks == math.ceil(prof.t_end * F - 1e-6)
    assert prof.output_pulses == case["total_pulses"]
    assert_matches_profile(prof, train)


@pytest.mark.parametrize("prevention", [True, False])
@pytest.mark.parametrize("case", [SHORT, LONG], ids=["short", "long"])
def test_speed_never_above_drive_speed(case, prevention):
    prof, train = both(**case, triangle_prevention=prevention)
    assert_speed_limit(train, case["drive_speed_pps"], F)
    t = np.linspace(0.0, prof.t_end, 20001)
    assert prof.speed(t).max() <= case["drive_speed_pps"] * (1 + 1e-12)
    assert prof.speed(t[:-1]).min() >= case["initial_speed_pps"] * (1 - 1e-12)


def test_speed_limit_is_tight_when_cruising_at_drive_speed():
    # Cruising at DV, a window of w ticks holds DV*w/f pulses rounded either way.
    prof, train = both(**LONG)
    i0, i1 = math.ceil(prof.t_acc_end * F), math.floor(prof.t_dec_start * F)
    w = 140
    cruise = window_counts(train[i0:i1], w)
    assert cruise.min() >= math.floor(LONG["drive_speed_pps"] * w / F)
    assert cruise.max() <= math.ceil(LONG["drive_speed_pps"] * w / F)


@pytest.mark.parametrize("prevention", [True, False])
@pytest.mark.parametrize("case", [SHORT, LONG], ids=["short", "long"])
def test_acceleration_and_deceleration_symmetric(case, prevention):
    prof, train = both(**case, triangle_prevention=prevention)
    assert_mirror_symmetric(train)
    assert_profile_symmetric(prof)
    # Deceleration time and pulses equal the acceleration's.
    dec_pulses = prof.total_pulses - prof.position(prof.t_dec_start)
    assert dec_pulses == pytest.approx(prof.accel_pulses, rel=1e-9)


def test_dv_equal_to_tick_rate_keeps_one_pulse_per_tick():
    # DV = tick_hz: one pulse on every cruise tick, where rounding could give two.
    kw = dict(
        total_pulses=20_000,
        initial_speed_pps=1000.0,
        drive_speed_pps=F,
        jerk_pps3=2e10,
        tick_hz=F,
    )
    prof, train = both(**kw)
    assert_basic_train(train, 20_000)
    i0, i1 = math.ceil(prof.t_acc_end * F), math.floor(prof.t_dec_start * F)
    assert i1 - i0 > 10_000
    assert np.all(train[i0 + 1 : i1 - 1] == 1)


def test_constant_speed_when_initial_speed_equals_drive_speed():
    kw = dict(
        total_pulses=3000, initial_speed_pps=30_000.0, drive_speed_pps=30_000.0,
        jerk_pps3=1e9, tick_hz=F,
    )  # fmt: skip
    prof, train = both(**kw)
    assert_basic_train(train, 3000)
    assert prof.t_acc_end == 0.0 and prof.reached_drive_speed
    assert train.size == math.ceil(3000 / 30_000.0 * F - 1e-6)  # 100 ms
    np.testing.assert_array_equal(window_counts(train, 14), 3)  # 3.0 pulses per 14 ticks
    w = window_counts(train, 10)  # 2.14 pulses per 10 ticks
    assert w.min() == 2 and w.max() == 3


# ---------------------------------------------------------------- reaches drive speed


@pytest.mark.parametrize("prevention", [True, False])
@pytest.mark.parametrize(
    ("sv", "dv", "jk", "total"),
    [
        (500.0, 100_000.0, 1e9, 5000),  # ta = 20 ms
        (100.0, 50_000.0, 2e10, 2000),  # ta = 3.2 ms
        (5_000.0, 20_000.0, 6e7, 2000),  # ta = 31.6 ms, SV a quarter of DV
    ],
)
def test_reaching_drive_speed_matches_ta_and_pa(sv, dv, jk, total, prevention):
    kw = dict(
        total_pulses=total,
        initial_speed_pps=sv,
        drive_speed_pps=dv,
        jerk_pps3=jk,
        tick_hz=F,
        triangle_prevention=prevention,
    )
    prof, train = both(**kw)
    ta, pa = ta_pa(sv, dv, jk)
    assert prof.reached_drive_speed
    assert prof.t_acc_end == pytest.approx(ta, rel=1e-12)
    assert prof.t_acc_increase == pytest.approx(ta / 2, rel=1e-12)
    assert prof.peak_speed_pps == pytest.approx(dv, rel=1e-12)
    assert prof.accel_pulses == pytest.approx(pa, rel=1e-12)
    c = counts(train)
    # Tick boundary nearest ta: p is within DV/(2f) <= 1/2 pulse of Pa, and the count
    # within 1/2 of p, so within one pulse of Pa. Likewise for the deceleration.
    assert abs(c[round(ta * F)] - pa) <= 1.0
    assert abs((total - c[round(prof.t_dec_start * F)]) - pa) <= 1.0
    assert prof.t_end - prof.t_dec_start == pytest.approx(ta, rel=1e-9)
    # Peak acceleration sqrt(JK (DV - SV)) at ta/2, zero at ta: a smooth S-curve.
    assert prof.acceleration(ta / 2) == pytest.approx(math.sqrt(jk * (dv - sv)), rel=1e-9)
    assert abs(prof.acceleration(ta - 1e-12)) < 1e-2 * jk * 1e-6


# ---------------------------------------------------------------- rule of 1/12


def test_threshold_between_short_and_long_moves():
    sv, dv, jk = SHORT["initial_speed_pps"], SHORT["drive_speed_pps"], SHORT["jerk_pps3"]
    _, pa = ta_pa(sv, dv, jk)
    at = scurve_profile(**dict(SHORT, total_pulses=math.ceil(2 * pa)))
    below = scurve_profile(**dict(SHORT, total_pulses=math.floor(2 * pa)))
    assert at.reached_drive_speed and at.peak_speed_pps == pytest.approx(dv)
    assert not below.reached_drive_speed and below.peak_speed_pps < dv


def test_rule_of_one_twelfth_only_for_moves_that_cannot_reach_drive_speed():
    # SV = 20 kpps: P/12 is passed before the acceleration's natural switch at T, yet
    # 2 Pa <= P, so the move reaches DV with the plain S-curve: the rule only shapes
    # moves too short for DV (the manual's case), it does not slow long ones.
    kw = dict(SHORT, initial_speed_pps=20_000.0, total_pulses=3000)
    sv, dv, jk = kw["initial_speed_pps"], kw["drive_speed_pps"], kw["jerk_pps3"]
    ta, pa = ta_pa(sv, dv, jk)
    assert 2 * pa <= 3000 and switch_time(sv, jk, 3000) < ta / 2
    prof = scurve_profile(**kw)
    assert prof.reached_drive_speed
    assert prof.t_acc_increase == pytest.approx(ta / 2, rel=1e-12)
    assert prof.peak_speed_pps == pytest.approx(dv, rel=1e-12)


def test_train_builder_caps_rounding_to_one_pulse_per_tick():
    # Rounding at DV = tick_hz could in principle step the count by two in one tick; the
    # builder delays the extra pulse by a tick and extends the train if need be.
    from vfgym.moves.pulse_sources import _counts_of_train

    train = np.diff(_counts_of_train(np.array([0, 1, 3, 4, 5, 5, 5, 5]), 5, 5))
    np.testing.assert_array_equal(train, [1, 1, 1, 1, 1])
    train = np.diff(_counts_of_train(np.array([0, 2, 3, 4, 5, 5, 5, 5]), 4, 5))
    np.testing.assert_array_equal(train, [1, 1, 1, 1, 1])


@pytest.mark.parametrize("sv", [1.0, 500.0, 5_000.0])
def test_rule_of_one_twelfth_switch_time(sv):
    kw = dict(SHORT, initial_speed_pps=sv)
    prof, train = both(**kw)
    assert not prof.reached_drive_speed
    tau = switch_time(sv, kw["jerk_pps3"], kw["total_pulses"])
    assert prof.t_acc_increase == pytest.approx(tau, rel=1e-9)
    assert prof.t_acc_end == pytest.approx(2 * tau, rel=1e-9)
    # The pulse train: at the tick boundary nearest the switch, P/12 pulses are out.
    c = counts(train)
    assert abs(c[round(tau * F)] - kw["total_pulses"] / 12) <= 1.0
    # The acceleration is greatest at the switch: it rose before and falls after.
    a = prof.acceleration(np.array([0.5 * tau, tau, 1.5 * tau]))
    assert a[1] == pytest.approx(kw["jerk_pps3"] * tau, rel=1e-9)
    assert a[0] < a[1] and a[2] < a[1]
    assert prof.peak_speed_pps == pytest.approx(sv + kw["jerk_pps3"] * tau**2, rel=1e-9)


def test_no_corner_with_prevention_triangle_without():
    smooth = scurve_profile(**SHORT)
    tri = scurve_profile(**SHORT, triangle_prevention=False)
    dt = 1e-7  # s, well under a tick
    j = SHORT["jerk_pps3"]
    # With prevention the acceleration runs down to zero into the speed peak and up from
    # zero out of it: continuous, so no corner in the speed curve.
    a_in = smooth.acceleration(smooth.t_acc_end - dt)
    a_out = smooth.acceleration(smooth.t_dec_start + dt)
    assert 0.0 < a_in <= j * dt * 1.001
    assert -j * dt * 1.001 <= a_out < 0.0
    # Without prevention the deceleration starts while accelerating hard: a jump of 2a.
    assert tri.t_acc_end == tri.t_dec_start
    a_before = tri.acceleration(tri.t_dec_start - dt)
    a_after = tri.acceleration(tri.t_dec_start + dt)
    assert a_before > 5e6  # pps/s, against 0.1 pps/s for the smooth curve
    assert a_after == pytest.approx(-a_before, rel=1e-3)
    assert tri.peak_speed_pps > smooth.peak_speed_pps
    # Triangle: deceleration starts once half the pulses are out.
    assert tri.position(tri.t_dec_start) == pytest.approx(SHORT["total_pulses"] / 2, rel=1e-9)


@pytest.mark.parametrize("prevention", [True, False])
def test_corner_shows_in_the_pulse_train(prevention):
    # Second difference of pulse counts over three w-tick windows centred on the peak.
    # A smooth peak (acceleration through zero at jerk J) gives about -J (w/f)^3 = -8
    # pulses; a corner where acceleration jumps from +a to -a adds -1.5 a (w/f)^2, about
    # -47 here (a = 7.8e6 pps/s). Window rounding moves it by at most 4.
    prof, train = both(**SHORT, triangle_prevention=prevention)
    c = counts(train)
    ic = round(0.5 * (prof.t_acc_end + prof.t_dec_start) * F)
    w, h = 280, 140
    d2 = (c[ic - h] - c[ic - h - w]) - 2 * (c[ic + h] - c[ic - h]) + (c[ic + h + w] - c[ic + h])
    if prevention:
        assert abs(d2) <= 12
    else:
        assert d2 <= -40


def test_excess_pulses_form_a_plateau_at_the_peak():
    prof, train = both(**SHORT)
    sv, jk, total = SHORT["initial_speed_pps"], SHORT["jerk_pps3"], SHORT["total_pulses"]
    tau = switch_time(sv, jk, total)
    # Acceleration + deceleration use 2 (2 SV tau + JK tau^3) = P - 8 SV tau pulses;
    # the remaining 8 SV tau (26 here) come out at the peak speed.
    assert prof.plateau_pulses == pytest.approx(8 * sv * tau, rel=1e-9)
    assert prof.plateau_pulses > 20
    assert prof.t_dec_start - prof.t_acc_end == pytest.approx(
        8 * sv * tau / prof.peak_speed_pps, rel=1e-9
    )
    # The speed is constant at the peak across the plateau.
    t = np.linspace(prof.t_acc_end, prof.t_dec_start, 50, endpoint=False)
    np.testing.assert_array_equal(prof.speed(t), prof.peak_speed_pps)
    # In the pulse train, between the first and last whole ticks of the plateau.
    i0, i1 = math.ceil(prof.t_acc_end * F), math.floor(prof.t_dec_start * F)
    c = counts(train)
    assert abs((c[i1] - c[i0]) - prof.peak_speed_pps * (i1 - i0) / F) <= 1.0
    assert c[i1] - c[i0] >= 8 * sv * tau - 3


def test_plateau_vanishes_as_initial_speed_goes_to_zero():
    plateaus = [
        scurve_profile(**dict(SHORT, initial_speed_pps=sv)).plateau_pulses
        for sv in (5_000.0, 500.0, 50.0, 5.0, 0.5)
    ]
    assert all(a > b for a, b in itertools.pairwise(plateaus))
    assert plateaus[0] > 100
    assert plateaus[-1] < 0.05  # well under one pulse


# ---------------------------------------------------------------- decelerating stop


def test_stop_during_acceleration_increase_with_prevention():
    full = scurve_pulses(**LONG)
    stop = 300  # tick, 2.1 ms, before the switch at T = 9.97 ms
    prof, train = both(**LONG, stop_tick=stop)
    ts = stop / F
    sv, jk = LONG["initial_speed_pps"], LONG["jerk_pps3"]
    assert prof.stopped and not prof.reached_drive_speed
    assert prof.t_acc_increase == pytest.approx(ts)
    assert prof.t_acc_end == pytest.approx(2 * ts)
    assert prof.t_dec_start == pytest.approx(2 * ts)  # no plateau after a stop
    assert prof.peak_speed_pps == pytest.approx(sv + jk * ts**2)
    exact = 2 * (2 * sv * ts + jk * ts**3)  # pulses of the shortened S-curve
    assert prof.end_position == pytest.approx(exact)
    assert prof.output_pulses == round(exact) < LONG["total_pulses"]
    assert_basic_train(train, prof.output_pulses)
    assert train.size == prof.n_ticks == math.ceil(4 * stop - 1e-6)
    # Nothing changes before the stop is issued.
    np.testing.assert_array_equal(train[:stop], full[:stop])
    assert not np.array_equal(train[: 2 * stop], full[: 2 * stop])
    # Smooth: the acceleration passes through zero at the peak.
    dt = 1e-7
    assert 0 < prof.acceleration(2 * ts - dt) <= jk * dt * 1.001
    assert -jk * dt * 1.001 <= prof.acceleration(2 * ts + dt) < 0
    assert_profile_symmetric(prof)
    assert_matches_profile(prof, train)


def test_stop_during_acceleration_increase_without_prevention():
    stop = 300
    prof, train = both(**LONG, stop_tick=stop, triangle_prevention=False)
    ts = stop / F
    sv, jk = LONG["initial_speed_pps"], LONG["jerk_pps3"]
    exact = 2 * (sv * ts + jk * ts**3 / 6)
    assert prof.t_acc_end == pytest.approx(ts)
    assert prof.t_dec_start == pytest.approx(ts)
    assert prof.output_pulses == round(exact)
    assert_basic_train(train, prof.output_pulses)
    dt = 1e-7
    a_before = prof.acceleration(ts - dt)
    a_after = prof.acceleration(ts + dt)
    assert a_before == pytest.approx(jk * ts, rel=1e-3)
    assert a_after == pytest.approx(-jk * ts, rel=1e-3)  # the triangle's jump
    assert_profile_symmetric(prof)
    assert_matches_profile(prof, train)


def test_stop_during_acceleration_decrease_lets_acceleration_reach_zero():
    stop = round(0.015 * F)  # between T = 9.97 ms and ta = 19.9 ms
    full_prof = scurve_profile(**LONG)
    prof, train = both(**LONG, stop_tick=stop)
    assert full_prof.t_acc_increase < stop / F < full_prof.t_acc_end
    assert prof.t_acc_end == pytest.approx(full_prof.t_acc_end)
    assert prof.t_dec_start == prof.t_acc_end  # decelerate straight away
    assert prof.peak_speed_pps == pytest.approx(LONG["drive_speed_pps"])
    assert prof.output_pulses == round(2 * full_prof.accel_pulses)
    assert_basic_train(train, prof.output_pulses)
    assert_profile_symmetric(prof)
    assert_matches_profile(prof, train)


def test_stop_while_cruising_starts_the_mirrored_deceleration():
    full_prof, full = both(**LONG)
    stop = round(0.03 * F)
    prof, train = both(**LONG, stop_tick=stop)
    assert full_prof.t_acc_end < stop / F < full_prof.t_dec_start
    assert prof.reached_drive_speed
    assert prof.t_dec_start == pytest.approx(stop / F)
    assert prof.t_end - prof.t_dec_start == pytest.approx(full_prof.t_acc_end)
    assert_basic_train(train, prof.output_pulses)
    assert prof.output_pulses < LONG["total_pulses"]
    np.testing.assert_array_equal(train[:stop], full[:stop])


@pytest.mark.parametrize("when", [0.5, 0.99, 2.0])  # fraction of the way into deceleration
def test_stop_after_deceleration_began_changes_nothing(when):
    full_prof, full = both(**LONG)
    stop = math.ceil((full_prof.t_dec_start + when * full_prof.t_acc_end) * F)
    prof, train = both(**LONG, stop_tick=stop)
    assert not prof.stopped
    np.testing.assert_array_equal(train, full)


# ---------------------------------------------------------------- properties


@st.composite
def scurve_settings(draw):
    dv = draw(st.floats(1_000.0, F))
    sv = dv * draw(st.floats(1e-4, 1.0))
    ta = draw(st.floats(1e-3, 0.05))  # acceleration time if DV is reached, s
    jk = 4.0 * (dv - sv) / ta**2 if dv > sv else draw(st.floats(1e6, 1e11))
    total = draw(st.integers(1, max(1, int(dv * 0.08))))
    return dict(
        total_pulses=total,
        initial_speed_pps=sv,
        drive_speed_pps=dv,
        jerk_pps3=jk,
        tick_hz=F,
        triangle_prevention=draw(st.booleans()),
    )


@PROPERTY
@given(scurve_settings())
def test_property_count_speed_symmetry(kw):
    prof, train = both(**kw)
    assume(prof.n_ticks < 60_000)
    assert_basic_train(train, kw["total_pulses"])
    assert_speed_limit(train, kw["drive_speed_pps"], F)
    assert_mirror_symmetric(train)
    assert_matches_profile(prof, train)
    sv, dv, jk = kw["initial_speed_pps"], kw["drive_speed_pps"], kw["jerk_pps3"]
    ta, pa = ta_pa(sv, dv, jk)
    if kw["total_pulses"] >= 2 * pa:
        assert prof.reached_drive_speed
        assert prof.t_acc_end == pytest.approx(ta, rel=1e-9, abs=1e-15)
    else:
        # short of the drive speed; with SV within rounding of DV the peak rounds to DV
        assert prof.peak_speed_pps < dv or dv - sv <= 1e-12 * dv
        if kw["triangle_prevention"]:
            tau = switch_time(sv, jk, kw["total_pulses"])
            assert prof.t_acc_increase == pytest.approx(tau, rel=1e-7)
            assert abs(prof.acceleration(prof.t_acc_end - 1e-12)) <= jk * 1e-9
            assert prof.plateau_pulses == pytest.approx(8 * sv * tau, rel=1e-6, abs=1e-9)
        else:
            assert prof.t_acc_end == prof.t_dec_start


@PROPERTY
@given(scurve_settings(), st.floats(0.0, 1.2))
def test_property_decelerating_stop(kw, frac):
    full_prof, full = both(**kw)
    stop = max(1, math.ceil(frac * full_prof.n_ticks))
    prof, train = both(**kw, stop_tick=stop)
    assume(prof.n_ticks < 60_000)
    assert_basic_train(train, prof.output_pulses)
    assert prof.output_pulses <= kw["total_pulses"]
    assert_speed_limit(train, kw["drive_speed_pps"], F)
    assert_matches_profile(prof, train)
    assert_profile_symmetric(prof)
    assert prof.t_end <= full_prof.t_end * (1 + 1e-12)  # a stop never lengthens the move
    n = min(stop, train.size, full.size)
    np.testing.assert_array_equal(train[:n], full[:n])
    if stop / F >= full_prof.t_dec_start:
        np.testing.assert_array_equal(train, full)


# ---------------------------------------------------------------- bad input


@pytest.mark.parametrize(
    ("change", "name"),
    [
        ({"total_pulses": 0}, "total_pulses"),
        ({"total_pulses": -10}, "total_pulses"),
        ({"total_pulses": 2.5}, "total_pulses"),
        ({"total_pulses": float("nan")}, "total_pulses"),
        ({"jerk_pps3": 0.0}, "jerk_pps3"),
        ({"jerk_pps3": -1e9}, "jerk_pps3"),
        ({"jerk_pps3": float("nan")}, "jerk_pps3"),
        ({"drive_speed_pps": 400.0}, "drive_speed_pps"),  # below SV = 500
        ({"drive_speed_pps": 150_000.0}, "drive_speed_pps"),  # above tick_hz
        ({"drive_speed_pps": float("nan")}, "drive_speed_pps"),
        ({"initial_speed_pps": 0.0}, "initial_speed_pps"),
        ({"initial_speed_pps": -5.0}, "initial_speed_pps"),
        ({"initial_speed_pps": float("nan")}, "initial_speed_pps"),
        ({"tick_hz": 0.0}, "tick_hz"),
        ({"tick_hz": float("nan")}, "tick_hz"),
        ({"tick_hz": float("inf")}, "tick_hz"),
        ({"stop_tick": 0}, "stop_tick"),
        ({"stop_tick": 1.5}, "stop_tick"),
        ({"triangle_prevention": "yes"}, "triangle_prevention"),
    ],
)
@pytest.mark.parametrize("fn", [scurve_pulses, scurve_profile])
def test_bad_scurve_input_names_the_parameter(fn, change, name):
    kw = dict(SHORT, **change)
    with pytest.raises(ValueError, match=name) as info:
        fn(**kw)
    assert "allowed" in str(info.value)


def test_move_too_long_is_refused():
    with pytest.raises(ValueError, match="MAX_TICKS"):
        scurve_pulses(10**6, initial_speed_pps=1.0, drive_speed_pps=10.0, jerk_pps3=1.0, tick_hz=F)


# ---------------------------------------------------------------- fixed frequency


@pytest.mark.parametrize(("freq", "total"), [(F, 1000), (100_000.0, 777), (3_000.0, 50), (1.0, 1)])
def test_fixed_frequency_exact_count_and_spacing(freq, total):
    train = fixed_frequency_pulses(total, frequency_hz=freq, tick_hz=F)
    assert_basic_train(train, total)
    ticks = np.flatnonzero(train)
    np.testing.assert_array_equal(ticks, np.floor(np.arange(total) * F / freq).astype(int))
    assert train.size == ticks[-1] + 1
    if total > 1:
        gaps = np.diff(ticks)
        assert gaps.min() >= math.floor(F / freq) and gaps.max() <= math.ceil(F / freq)
    assert_speed_limit(train, freq, F)


def test_fixed_frequency_at_tick_rate_is_every_tick():
    np.testing.assert_array_equal(fixed_frequency_pulses(50, frequency_hz=F, tick_hz=F), 1)


@PROPERTY
@given(st.integers(1, 5000), st.floats(50.0, F))
def test_property_fixed_frequency(total, freq):
    assume(total * F / freq < 200_000)
    train = fixed_frequency_pulses(total, frequency_hz=freq, tick_hz=F)
    assert_basic_train(train, total)
    assert train[0] == 1 and train[-1] == 1
    assert_speed_limit(train, freq, F)


@pytest.mark.parametrize(
    ("change", "name"),
    [
        ({"total_pulses": 0}, "total_pulses"),
        ({"total_pulses": float("nan")}, "total_pulses"),
        ({"frequency_hz": 0.0}, "frequency_hz"),
        ({"frequency_hz": F + 1}, "frequency_hz"),
        ({"frequency_hz": float("nan")}, "frequency_hz"),
        ({"tick_hz": -1.0}, "tick_hz"),
    ],
)
def test_bad_fixed_frequency_input_names_the_parameter(change, name):
    kw = dict({"total_pulses": 100, "frequency_hz": 10_000.0, "tick_hz": F}, **change)
    with pytest.raises(ValueError, match=name):
        fixed_frequency_pulses(**kw)


@PROPERTY
@given(scurve_settings(), st.one_of(st.none(), st.floats(0.0, 1.2)))
def test_property_position_on_rising_times_is_position(kw, frac):
    """scurve_pulses reads positions through position_rising (phases as slices of rising
    times); it must equal position (masks over any times) bit for bit, also at the phase
    boundaries themselves and when a stop cuts the move short."""
    if frac is not None:
        kw = {**kw, "stop_tick": max(1, math.ceil(frac * scurve_profile(**kw).n_ticks))}
    prof = scurve_profile(**kw)
    assume(prof.n_ticks < 60_000)
    edges = [prof.t_acc_increase, prof.t_acc_end, prof.t_dec_start, prof.t_end]
    ticks = np.arange(prof.n_ticks + 9, dtype=np.float64) / prof.tick_hz
    t = np.sort(np.concatenate([ticks, np.array(edges), [s[0] for s in prof.segments]]))
    np.testing.assert_array_equal(prof.position_rising(t), prof.position(t))


@PROPERTY
@given(
    st.floats(0.01, 60.0),
    st.sampled_from([1.0, -1.0]),
    st.floats(50.0, 500.0),
    st.floats(2e3, 2e5),
    st.floats(0.001, 0.5),
)
def test_property_scurve_command_is_the_trains_running_count(dist, sign, v, a, dur):
    """The S-curve command reads the train's running count (scurve_counts) instead of
    summing the train again: the same numbers as the pulse train's cumulative sum held
    at its end, times ±δ (the command's definition, computed here the long way)."""
    from vfgym.moves import profiles

    delta = PAPER_PLANT.pulse_rad
    args = profiles.scurve_source_args(v, a, PAPER_PLANT.tick_hz, delta)
    total = round(dist / delta)
    assume(total >= 1)
    n = max(1, round(dur * PAPER_PLANT.tick_hz))
    train = scurve_pulses(total, **args)
    assume(train.size < 60_000)
    want = np.zeros(n)
    m = min(n, train.size)
    want[:m] = np.cumsum(train[:m], dtype=np.int64)
    want[m:] = want[m - 1]
    got = profiles.scurve(sign * dist, v, a, dur, PAPER_PLANT.tick_hz, delta)
    np.testing.assert_array_equal(got, math.copysign(delta, sign) * want)
    np.testing.assert_array_equal(np.diff(scurve_counts(scurve_profile(total, **args))), train)
