"""The acceleration constraint means what it says (docs/model.md §5.1): the V-F train's
position is not quantised, so its peak is the acceleration law's own; an external train's
window is the shortest whose one-pulse quantum is within the stated tolerance of the run's
own limit; and a feasible run never reports a peak above the limit by more than that
tolerance."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from vfgym import DEFAULT_MEASURES, PAPER_PLANT, Measures, evaluate, simulate
from vfgym.axis import PAPER_AXIS, load_axis
from vfgym.moves.distribution import scenario_set
from vfgym.plant.measures import accel_window_ticks
from vfgym.space import from_action

AXES = Path(__file__).resolve().parents[2] / "experiments" / "axes"
LOW_LIMIT = PAPER_PLANT.with_motor(accel_limit_rad_s2=25e3)  # a slow ball-screw axis


def shortest_window(plant, tol: float) -> int:
    """The oracle: count up from one tick to the first window whose quantum is within
    ``tol`` of the limit (no square root, no rounding)."""
    a, d, T = plant.motor.usable_accel_rad_s2, plant.pulse_rad, plant.tick_s
    w = 1
    while 2.0 * d / (w * T) ** 2 > tol * a:
        w += 1
    return w


@pytest.mark.parametrize(
    ("plant", "want"),
    [
        (PAPER_PLANT, 294),  # docs/model.md §5.1's table: 2.10 ms
        (PAPER_PLANT.with_motor(inertia_ratio=5.0), 633),  # heavy-load, 30 krad/s²: 4.52 ms
        (load_axis(AXES / "belt.yaml").plant, 1071),  # 10.5 krad/s²: 7.65 ms
        (LOW_LIMIT, None),
    ],
)
@pytest.mark.parametrize("tol_pct", [1.0, 0.25, 5.0])
def test_the_window_is_the_shortest_within_the_tolerance(plant, want, tol_pct):
    m = Measures(accel_tolerance_pct=tol_pct)
    w = accel_window_ticks(m, plant, external=True)
    assert w == max(140, shortest_window(plant, tol_pct / 100.0))
    if want is not None and tol_pct == 1.0:
        assert w == want
    assert accel_window_ticks(m, plant) == 140  # the V-F's: accel_window_s, 1 ms


def test_the_paper_settings_read_the_acceleration_law_exactly():
    """k = f²δ/a_motor (paper eq. 1): the V-F train's unquantised position accelerates at
    exactly the limit, where its pulse count over 1 ms read up to one quantum (6.1
    krad/s², 1.03 x) more."""
    m = evaluate(["paper"], ["paper-step"]).metrics[0][0]
    assert m["peak_accel_pulse_rad_s2"] == pytest.approx(140e3, rel=1e-12)
    assert m["accel_quantum_rad_s2"] == 0.0 and m["accel_window_s"] == pytest.approx(1e-3)


def test_the_window_follows_the_load():
    """The same axis with a heavier load has a lower limit, so a longer window."""
    ws = [
        accel_window_ticks(DEFAULT_MEASURES, PAPER_PLANT.with_motor(inertia_ratio=r), True)
        for r in (0.0, 1.0, 3.0, 5.0)
    ]
    assert ws == sorted(ws) and ws[0] < ws[-1]


def test_a_train_at_the_limit_reads_within_the_tolerance():
    """An external pulse train at exactly the limit (⌊a t²/2δ⌋ pulses, then at that speed)
    is accel-feasible; the same train at 1.03 x the limit is not (the old one-pulse
    allowance at 1 ms let 1.04 x through). The ramp lasts 12 ms, longer than the triangular weight's
    2w, so the window reads the ramp's own acceleration (on the bare paper motor no train
    accelerates that long: 140 krad/s² reaches the top pulse speed δ·f in 3.1 ms)."""
    for plant in (LOW_LIMIT, PAPER_PLANT.with_motor(inertia_ratio=5.0)):
        a = plant.motor.usable_accel_rad_s2
        assert 2 * accel_window_ticks(DEFAULT_MEASURES, plant, True) * plant.tick_s < 12e-3
        for scale, ok in ((1.0, True), (1.03, False)):
            n_ticks = 4200
            t = np.arange(1, n_ticks + 1) * plant.tick_s
            t_acc = 12e-3  # accelerate for 12 ms, then hold that speed
            x = np.where(t < t_acc, 0.5 * scale * a * t**2, 0.5 * scale * a * t_acc**2)
            x += np.where(t < t_acc, 0.0, scale * a * t_acc * (t - t_acc))
            n = np.floor(x / plant.pulse_rad).astype(np.int64)
            pulses = np.diff(np.concatenate([[0], n])).astype(np.int8)
            assert pulses.max() <= 1
            cmd = n * plant.pulse_rad
            m = simulate(cmd.astype(np.float64), plant=plant, pulses=pulses).metrics
            tol = DEFAULT_MEASURES.accel_tolerance_pct / 100.0
            assert (m["accel_ratio_pulse"] <= 1.0 + tol) == ok, (plant, scale, m)


@settings(max_examples=12, deadline=None)
@given(
    seed=st.integers(0, 2**31 - 1),
    low=st.booleans(),
    tol_pct=st.sampled_from([1.0, 0.5]),
)
def test_no_feasible_run_reports_a_peak_above_the_limit(seed, low, tol_pct):
    """Random settings on random moves of the paper's axis and of a 25 krad/s² one: every
    feasible run's peak is within the limit plus the tolerance, and the accel constraint
    is exactly ratio − 1 − tolerance."""
    rng = np.random.default_rng(seed)
    ctrls = [from_action(rng.uniform(-1.0, 1.0, 4)) for _ in range(6)]
    ctrls += ["paper", "rule-of-thumb", "scurve"]
    plant = LOW_LIMIT if low else PAPER_PLANT
    measures = Measures(accel_tolerance_pct=tol_pct)
    scens = scenario_set("test", 3, int(rng.integers(0, 1000)))
    ev = evaluate(ctrls, scens, axis=replace(PAPER_AXIS, plant=plant, measures=measures))
    tol = tol_pct / 100.0
    for i in range(len(ctrls)):
        for j in range(len(scens)):
            m = ev.metrics[i][j]
            if not isinstance(m, dict) or math.isnan(ev.cost[i, j]):
                continue
            assert ev.constraints[i, j, 0] == pytest.approx(m["accel_ratio_pulse"] - 1.0 - tol)
            limit = scens[j].plant(plant).motor.usable_accel_rad_s2
            assert m["accel_quantum_rad_s2"] <= tol * limit * (1.0 + 1e-12)
            assert (m["accel_quantum_rad_s2"] == 0.0) == (i < len(ctrls) - 1)  # scurve: counts
            if ev.feasible[i, j]:
                assert m["accel_ratio_pulse"] <= 1.0 + tol
