"""The cost judges the load where the plant states a transmission (docs/model.md §3.1, §6):
the load's move time, overshoot and arrival, not the motor's, and prices its residual
vibration; a rigid plant's score is the motor's, as before, with no residual term; and
evaluate (the batched one scoring path) gives simulate's measures and score on a
compliant plant."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from vfgym import (
    PAPER_AXIS,
    PAPER_PLANT,
    PAPER_SETTINGS,
    Settings,
    Transmission,
    evaluate,
    simulate,
)
from vfgym.moves.scenarios import SCENARIOS, Scenario
from vfgym.scoring import CostWeights, score, yardsticks

JM = PAPER_PLANT.motor.inertia_kgm2
COMPLIANT = PAPER_PLANT.replace(transmission=Transmission.from_resonance(JM, JM, 100.0, 0.05))
MOVE = SCENARIOS["short-move"]


def test_score_reads_the_loads_measures():
    tr = simulate(MOVE.command(COMPLIANT), PAPER_SETTINGS, COMPLIANT)
    m = tr.metrics
    s = score(m, MOVE, COMPLIANT, tr.measures)
    y = yardsticks(MOVE, COMPLIANT, tr.measures)
    assert y.load
    assert m["load_move_time_s"] > m["move_time_s"]  # the load settles later
    assert s.terms.main == m["load_move_time_s"] / y.ideal_time_s
    assert s.terms.overshoot == 0.1 * m["load_overshoot_rad"] / y.window_rad
    # the motor's measures alone would have cost less: the load's are what is judged
    motor_only = {k: v for k, v in m.items() if not k.startswith("load_")}
    rigid_view = score(motor_only, MOVE, COMPLIANT.replace(transmission=None), tr.measures)
    assert rigid_view.cost < s.cost


def test_the_loads_residual_vibration_is_priced_like_overshoot():
    """Ringing inside the window costs no move time; the residual term prices it, per
    in-position window of peak-to-peak vibration, at the weight of a window of overshoot."""
    tr = simulate(MOVE.command(COMPLIANT), PAPER_SETTINGS, COMPLIANT)
    m = dict(tr.metrics)
    y = yardsticks(MOVE, COMPLIANT, tr.measures)
    s = score(m, MOVE, COMPLIANT, tr.measures)
    assert m["load_residual_vibration_rad"] > 0.0
    assert s.terms.residual == 0.1 * m["load_residual_vibration_rad"] / y.window_rad
    assert s.cost == s.terms.running + s.terms.arrival + s.terms.residual
    m["load_residual_vibration_rad"] *= 3.0
    ringing = score(m, MOVE, COMPLIANT, tr.measures)
    assert ringing.cost - s.cost == pytest.approx(2.0 * s.terms.residual, rel=1e-12)
    assert ringing.terms.main == s.terms.main and ringing.feasible == s.feasible
    quiet = score(m, MOVE, COMPLIANT, tr.measures, CostWeights(residual=0.0))
    assert quiet.terms.residual == 0.0 and quiet.cost == s.terms.running + s.terms.arrival


def test_a_load_still_ringing_at_the_end_has_not_arrived():
    """The motor in position, the load not: the arrival term is charged."""
    tr = simulate(MOVE.command(COMPLIANT), PAPER_SETTINGS, COMPLIANT)
    y = yardsticks(MOVE, COMPLIANT, tr.measures)
    m = dict(tr.metrics)
    m["final_error_rad"] = 0.0
    m["load_final_error_rad"] = 3.0 * y.window_rad
    s = score(m, MOVE, COMPLIANT, tr.measures)
    assert not s.metrics["arrived"] and s.constraints[3] == pytest.approx(2.0)
    m["load_final_error_rad"], m["final_error_rad"] = 0.0, 3.0 * y.window_rad
    assert score(m, MOVE, COMPLIANT, tr.measures).metrics["arrived"]


def test_evaluate_on_a_compliant_plant_is_simulate_then_score():
    moves = [MOVE, Scenario(name="back", profile="trapezoid", distance_rad=-3.0, duration_s=0.1)]
    sets = [PAPER_SETTINGS, Settings(value_rad=0.5, error_limit_rad=0.4, k=1000.0)]
    ev = evaluate(sets, moves, axis=replace(PAPER_AXIS, plant=COMPLIANT))
    for i, s in enumerate(sets):
        for j, sc in enumerate(moves):
            plant = sc.plant(COMPLIANT)
            tr = simulate(sc.command(plant), s, plant)
            want = score(tr.metrics, sc, plant, tr.measures)
            assert ev.cost[i, j] == want.cost
            np.testing.assert_array_equal(ev.constraints[i, j], want.constraints)


def test_a_rigid_plant_is_judged_at_the_motor():
    tr = simulate(MOVE.command(PAPER_PLANT), PAPER_SETTINGS, PAPER_PLANT)
    y = yardsticks(MOVE, PAPER_PLANT, tr.measures)
    assert not y.load
    s = score(tr.metrics, MOVE, PAPER_PLANT, tr.measures)
    assert s.terms.main == tr.metrics["move_time_s"] / y.ideal_time_s
    assert s.terms.residual == 0.0  # no residual term without a transmission
    assert s.cost == s.terms.running + s.terms.arrival
