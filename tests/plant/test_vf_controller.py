"""The V-F controller against the paper's numbers and docs/model.md §1's consequences."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from vfgym import PAPER_K, PAPER_PULSE_RAD, PAPER_TICK_HZ, step_command, vf_pulses

F = PAPER_TICK_HZ
DELTA = PAPER_PULSE_RAD
T = 1.0 / F
LIMIT = 140e3


def paper_step(n_ticks: int = 60_000, **kw) -> np.ndarray:
    args = {"value_rad": 1.0, "error_limit_rad": 1.0, "k": PAPER_K} | kw
    return vf_pulses(step_command(10.0, n_ticks), **args)


def window_accel(n: np.ndarray, w: int) -> np.ndarray:
    """Pulse-train acceleration over a window of w ticks: second difference of counts
    (the train was at rest before tick 0)."""
    n = np.concatenate([np.zeros(2 * w, dtype=n.dtype), n])
    return (n[2 * w :] - 2 * n[w:-w] + n[: -2 * w]) * DELTA / (w * T) ** 2


def test_paper_constants():
    assert pytest.approx(429.5, abs=0.05) == DELTA * F  # v_max, the paper's "430 rad/s"
    assert pytest.approx(429.5, abs=0.05) == PAPER_K  # k = f²δ / 140e3


def test_paper_step_ramps_over_about_k_ticks_then_one_pulse_per_tick():
    p = paper_step()
    # first tick from which 20 consecutive ticks all carry a pulse: the end of the ramp
    run = np.convolve(p == 1, np.ones(20, dtype=int), mode="valid")
    full = int(np.flatnonzero(run == 20)[0])
    assert 0.9 * PAPER_K <= full <= 1.1 * PAPER_K
    # no pulse at all in the first ticks: the error starts from 0 and rises by value/k
    assert p[:20].sum() == 0
    # cruising at one pulse per tick: v = δ·f = 429.5 rad/s
    n = np.cumsum(p)
    cruise = n[full + 100 : full + 1100]
    assert cruise[-1] - cruise[0] == 999
    assert (cruise[-1] - cruise[0]) * DELTA / (999 * T) == pytest.approx(429.5, abs=0.05)


@pytest.mark.parametrize("w", [50, 100, 200, 400])
def test_paper_step_rise_acceleration_within_limit_to_one_pulse(w):
    p = paper_step()
    n = np.cumsum(p).astype(np.int64)
    a = window_accel(n[: 4 * int(PAPER_K)], w)
    quantum = 2 * DELTA / (w * T) ** 2  # each window count is off by less than one pulse
    assert a.max() <= LIMIT + quantum
    if w >= 100 and 2 * w <= PAPER_K:  # the limit is used, not merely respected
        assert a.max() >= 0.9 * LIMIT


def test_paper_step_without_acceleration_law_exceeds_limit():
    # k = 1: the error may jump to L in one tick (eq. 1's uncontrolled acceleration)
    n = np.cumsum(paper_step(k=1.0)).astype(np.int64)
    assert window_accel(n[:4000], 100).max() > 4 * LIMIT  # v_max/(wT) = 601 krad/s²


def test_paper_step_ends_at_3259_or_3260_and_never_overshoots_by_more_than_one_pulse():
    p = paper_step(200_000)
    n = np.cumsum(p)
    assert n[-1] in (3259, 3260)
    assert pytest.approx(3259.5, abs=0.01) == 10.0 / DELTA
    assert n.max() <= 3260  # one pulse past 10 rad at most
    assert n.max() * DELTA - 10.0 < DELTA
    # after the move it dithers between the two pulses that bracket 10 rad
    assert set(np.unique(n[-50_000:])) <= {3259, 3260}


def test_error_limit_above_value_winds_up_and_overshoots():
    n_ok = np.cumsum(paper_step(100_000))
    n_wind = np.cumsum(paper_step(100_000, error_limit_rad=3.0))
    assert n_ok.max() <= 3260
    assert n_wind.max() >= 3260 + 50  # sum wound up while saturated
    assert n_wind.max() * DELTA - 10.0 > 0.15


@pytest.mark.parametrize("m", [2, 3, 4, 8])
def test_error_limit_value_over_m_gives_one_pulse_per_m_ticks(m):
    value = 1.0
    p = paper_step(60_000, value_rad=value, error_limit_rad=value / m, k=1.0)
    ticks = np.flatnonzero(p)
    gaps = np.diff(ticks[10:200])  # well inside the saturated stretch
    assert math.ceil(value / (value / m)) == m
    assert np.all(gaps == m)


def test_error_limit_below_value_caps_speed_at_limit_over_value_pulses_per_tick():
    # value/L not whole: intervals alternate between floor and ceil of value/L
    p = paper_step(60_000, error_limit_rad=0.3, k=1.0)
    ticks = np.flatnonzero(p)[10:500]
    gaps = np.diff(ticks)
    assert set(np.unique(gaps)) == {3, 4}
    rate = (len(ticks) - 1) / (ticks[-1] - ticks[0])
    assert rate == pytest.approx(0.3, rel=0.01)


@pytest.mark.parametrize("value", [0.5, 1.0, 2.0])
def test_tail_gain_is_delta_over_value_times_tick(value):
    """Unsaturated, the pulse speed is Kv·e with Kv = δ/(value·T): regress windowed pulse
    speed on the windowed mean error over the tail."""
    p = paper_step(300_000, value_rad=value, error_limit_rad=value)
    n = np.cumsum(p)
    err = 10.0 - np.concatenate([[0], n[:-1]]) * DELTA  # error seen at each tick
    start = int(np.flatnonzero(err <= 0.5 * value)[0])
    stop = int(np.flatnonzero(err <= 0.02 * value)[0])
    w = 20
    edges = np.arange(start, stop - w, w)
    speed = (n[edges + w - 1] - n[edges - 1]) * DELTA / (w * T)
    mean_err = np.array([err[a : a + w].mean() for a in edges])
    kv = float(speed @ mean_err / (mean_err @ mean_err))
    assert kv == pytest.approx(DELTA / (value * T), rel=0.01)


def test_slew_law_limits_deceleration_and_overshoots():
    # at twice the paper's k the slew-limited error lags the true one on the way down
    k = 2 * PAPER_K
    rise = np.cumsum(paper_step(100_000, k=k))
    slew = np.cumsum(paper_step(100_000, k=k, accel_law="slew"))
    assert rise.max() <= 3260
    assert slew.max() > 3260 + 50
    # on the rise the two laws are the same
    k = int(PAPER_K)
    np.testing.assert_array_equal(rise[:k], slew[:k])


@settings(max_examples=40, deadline=None)
@given(
    amp=st.floats(-30, 30).filter(lambda a: abs(a) > 1e-3),
    shape=st.sampled_from(["step", "sine", "ramp"]),
    value=st.floats(0.05, 3.0),
    limit=st.floats(0.05, 3.0),
    k=st.floats(1.0, 2000.0),
    law=st.sampled_from(["rise", "slew"]),
)
def test_negated_command_gives_negated_pulses(amp, shape, value, limit, k, law):
    t = np.arange(5000) * T
    cmd = {
        "step": np.full(t.size, amp),
        "sine": amp * np.sin(2 * np.pi * 50 * t),
        "ramp": amp * t / t[-1],
    }[shape]
    kw = {"value_rad": value, "error_limit_rad": limit, "k": k, "accel_law": law}
    p = vf_pulses(cmd, **kw)
    q = vf_pulses(-cmd, **kw)
    np.testing.assert_array_equal(q, -p)
    assert p.dtype == np.int8
    assert set(np.unique(p)) <= {-1, 0, 1}
    np.testing.assert_array_equal(vf_pulses(cmd, **kw), p)  # same inputs, same outputs


@pytest.mark.parametrize(
    ("kw", "name"),
    [
        ({"value_rad": 0.0}, "value_rad"),
        ({"value_rad": -1.0}, "value_rad"),
        ({"error_limit_rad": 0.0}, "error_limit_rad"),
        ({"k": 0.5}, "k"),
        ({"k": float("nan")}, "k"),
        ({"accel_law": "jerk"}, "accel_law"),
        ({"pulse_rad": -1.0}, "pulse_rad"),
    ],
)
def test_bad_settings_name_the_parameter(kw, name):
    args = {"value_rad": 1.0, "error_limit_rad": 1.0, "k": 10.0} | kw
    with pytest.raises(ValueError, match=name):
        vf_pulses(np.ones(10), **args)


@pytest.mark.parametrize("bad", [float("nan"), float("inf"), -float("inf")])
def test_non_finite_command_is_refused(bad):
    cmd = np.ones(10)
    cmd[3] = bad
    with pytest.raises(ValueError, match=r"command_rad\[3\].*finite"):
        vf_pulses(cmd, value_rad=1.0, error_limit_rad=1.0, k=10.0)
