"""What an axis does not know exactly: its ``uncertainty:`` block, the true plants within
it, and every verdict judged across them.

The true plants are checked against plants built by hand from the physics (the drive's
K3 as set for the modelled plant, the total inertia scaled), and the across-plants
results against separate evaluations of each true plant."""

from __future__ import annotations

import itertools
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st

from vfgym import PAPER_AXIS, Settings, cli, evaluate, load_axis
from vfgym.axis import (
    EXACT,
    NOMINAL,
    PlantVariant,
    Uncertainty,
    axis_digest,
    axis_from_dict,
    axis_to_dict,
    draw_plants,
    plant_design,
    sensitivity_variants,
)
from vfgym.report import axis_verdict, format_verdict
from vfgym.tuning._objective import aggregate

AXES = Path(__file__).resolve().parents[2] / "experiments" / "axes"
# the main job's tuned setting (README): feasible on the 32 test moves as modelled
TUNED = Settings(value_rad=0.882, error_limit_rad=0.872, k=430.9, ts_over_tf=1.0)
FULL = Uncertainty(
    inertia=(0.8, 1.25),
    coulomb_nm=(0.0, 0.002),
    viscous_nm_s_rad=(0.0, 1e-5),
    load_torque_nm=(-0.001, 0.001),
    torque_per_count=(0.9, 1.1),
)


@pytest.mark.parametrize(
    ("block", "needle"),
    [
        ({"inertia": [1.25, 0.8]}, "uncertainty.inertia=[1.25, 0.8] is reversed"),
        ({"inertia": [0, 1.2]}, "uncertainty.inertia[0]=0 is out of range: allowed [0.05, 20]"),
        ({"inertia": [-1, 1.2]}, "uncertainty.inertia[0]=-1 is out of range"),
        ({"torque_per_count": [0.9, 50]}, "uncertainty.torque_per_count[1]=50 is out of range"),
        ({"inertia": 1.1}, "uncertainty.inertia=1.1 is not allowed: give [low, high]"),
        ({"inertia": [1, 2, 3]}, "uncertainty.inertia=[1, 2, 3] is not allowed"),
        ({"inertia": ["a", 1]}, "uncertainty.inertia[0]='a' must be a real number"),
        ({"mass": [1, 2]}, "uncertainty.mass=[1, 2] is not a key of vfgym.Uncertainty"),
        ({"coulomb_nm": [-0.1, 0.1]}, "uncertainty.coulomb_nm[0]=-0.1 is out of range"),
        ({"coulomb_nm": [0, 2.5]}, "the motor cannot move its load"),
        ({"load_torque_nm": [-1.0, 1.95]}, "the motor cannot move its load"),
        ({"viscous_nm_s_rad": [0, 1.0]}, "uncertainty.viscous_nm_s_rad=[0.0, 1.0] is out of"),
        ([0.8, 1.2], "uncertainty=[0.8, 1.2] is not allowed: give a mapping"),
    ],
)
def test_a_bad_range_is_one_line_naming_file_key_and_range(tmp_path, capsys, block, needle):
    f = tmp_path / "ax.yaml"
    f.write_text(yaml.safe_dump({"uncertainty": block}))
    with pytest.raises(ValueError, match=r"ax\.yaml: ") as exc:
        load_axis(f)
    assert needle in str(exc.value) and "\n" not in str(exc.value)
    code = cli.main(["simulate", "--axis", str(f), "--scenario", "short-move"])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and needle in err


def test_an_axis_file_with_uncertainty_round_trips_and_an_exact_one_keeps_its_digest():
    axis = load_axis(AXES / "loads-uncertain.yaml")
    assert axis.uncertainty == Uncertainty(inertia=(0.8, 1.25))
    assert axis_from_dict(axis_to_dict(axis)) == axis
    full = replace(PAPER_AXIS, uncertainty=FULL)
    assert axis_from_dict(axis_to_dict(full)) == full
    # without the block nothing changes: the record (and so every digest) is as before
    assert "uncertainty" not in axis_to_dict(PAPER_AXIS)
    assert axis_digest(full) != axis_digest(PAPER_AXIS)
    assert EXACT.exact and not FULL.exact and PAPER_AXIS.design_plants() == ()


@settings(max_examples=40, deadline=None)
@given(
    f=st.floats(0.05, 20.0),
    g=st.floats(0.05, 20.0),
    ratio=st.floats(0.0, 8.0),
    follows=st.booleans(),
)
def test_a_true_plant_keeps_the_modelled_drive_gain_and_scales_the_inertia(f, g, ratio, follows):
    model = PAPER_AXIS.plant.with_motor(inertia_ratio=ratio).with_servo(follows_load=follows)
    true = PlantVariant(inertia=f, torque_per_count=g).apply(model)
    assert math.isclose(true.motor.inertia_kgm2, f * model.motor.inertia_kgm2, rel_tol=1e-12)
    assert math.isclose(true.torque_per_count_nm, g * model.torque_per_count_nm, rel_tol=1e-12)
    assert true.motor.usable_accel_rad_s2 == min(
        model.motor.accel_limit_rad_s2, model.motor.peak_torque_nm / true.motor.inertia_kgm2
    )
    assert NOMINAL.apply(model) is model


def test_the_design_holds_every_corner_and_stratified_draws_inside():
    plant = PAPER_AXIS.plant
    design = plant_design(FULL, plant, drawn=6, seed=3)
    assert len(design) == 2**5 + 6
    ranges = FULL.ranges()
    corners = {
        (j, c, b, lt, k) for j, c, b, lt, k in itertools.product(*[ranges[n] for n in ranges])
    }
    got = {
        (v.inertia, v.coulomb_offset_nm, v.viscous_offset_nm_s_rad, v.load_offset_nm,
         v.torque_per_count)
        for v in design[:32]
    }  # fmt: skip
    assert got == corners
    inner = np.array([v.inertia for v in design[32:]])
    lo, hi = ranges["inertia"]
    assert np.all((inner > lo) & (inner < hi))
    # one draw in each sixth of the range (a Latin hypercube)
    assert sorted(np.floor((inner - lo) / (hi - lo) * 6).astype(int)) == list(range(6))
    assert plant_design(FULL, plant, drawn=6, seed=3) == design
    assert plant_design(FULL, plant, drawn=6, seed=4) != design


def test_held_out_plants_are_drawn_within_the_ranges_from_their_seed():
    unc = Uncertainty(inertia=(0.8, 1.25), coulomb_nm=(0.001, 0.003))
    plant = PAPER_AXIS.plant
    a = draw_plants(unc, plant, 50, seed=7)
    assert a == draw_plants(unc, plant, 50, seed=7) != draw_plants(unc, plant, 50, seed=8)
    assert all(0.8 <= v.inertia <= 1.25 and 0.001 <= v.coulomb_offset_nm <= 0.003 for v in a)
    assert draw_plants(EXACT, plant, 50, seed=7) == sensitivity_variants()
    assert [v.inertia for v in sensitivity_variants()] == [0.95, 1.05]


def test_across_plants_equals_each_true_plant_evaluated_on_its_own():
    """The batched call's (controller, plant, move) results are those of evaluating each
    true plant by hand: a plant with the modelled K3 fixed and the inertia scaled."""
    moves = PAPER_AXIS.scenarios("test")[:6]
    plants = (PlantVariant(inertia=1.1), PlantVariant(inertia=0.9, torque_per_count=1.05))
    ev = evaluate([TUNED, "paper"], moves, plants=plants, plant_seed=1)
    assert ev.across is not None and ev.across.cost.shape == (2, 2, 6)
    for p, v in enumerate(plants):
        for s, sc in enumerate(moves):
            model = sc.plant(PAPER_AXIS.plant)
            by_hand = model.with_motor(
                rotor_inertia_kgm2=model.motor.rotor_inertia_kgm2 * v.inertia
            ).with_servo(
                follows_load=False,
                torque_per_count_nm=model.torque_per_count_nm * v.torque_per_count,
            )
            # the paper's baseline is set for the modelled plant, not the true one
            one = evaluate([TUNED, "paper"], [replace(sc, inertia_ratio=0.0)],
                           axis=replace(PAPER_AXIS, plant=by_hand))  # fmt: skip
            resolved = ev.across.cost[:, p, s]
            assert np.allclose(one.cost[:, 0], resolved, rtol=1e-12, atol=0), (p, s)
    # the modelled plant's arrays are what they are without plants
    alone = evaluate([TUNED, "paper"], moves)
    assert np.array_equal(alone.cost, ev.cost)


def test_the_issues_measurement_the_main_job_setting_breaks_at_5_percent_more_inertia():
    """The figures the uncertainty was asked for: the tuned setting rides its limits."""
    test = PAPER_AXIS.scenarios("test")
    feasible = {}
    for f in (1.02, 1.05, 1.10, 1.25):
        ev = evaluate([TUNED, "paper"], test, plants=[PlantVariant(inertia=f)])
        assert ev.across is not None
        feasible[f] = [ev.across.summary(c).feasible for c in (0, 1)]
    assert feasible == {1.02: [29, 32], 1.05: [14, 32], 1.10: [8, 32], 1.25: [3, 32]}


def test_a_robust_objective_is_infeasible_when_one_design_plant_is():
    test = PAPER_AXIS.scenarios("test")[:8]
    nominal = aggregate(evaluate([TUNED], test))
    robust = aggregate(evaluate([TUNED], test, plants=[PlantVariant(inertia=1.25)]))
    assert nominal.feasible[0] and not robust.feasible[0]
    assert robust.cost[0] == nominal.cost[0]  # the cost is the modelled plant's
    assert np.all(robust.constraints[0] >= nominal.constraints[0])


def test_every_verdict_shows_the_plants_or_the_sensitivity_line():
    v = axis_verdict(TUNED, PAPER_AXIS)
    text = format_verdict(v)
    assert "sensitivity (the axis states no uncertainty)" in text
    assert v.to_dict()["plants"]["controllers"][0]["feasible_per_plant"] == [32, 14]
    axis = replace(load_axis(AXES / "loads-uncertain.yaml"), name="lu")
    v = axis_verdict(TUNED, axis)
    text = format_verdict(v)
    assert "across 16 plants drawn within the axis's uncertainty (plant seed 20261204)" in text
    summary = v.to_dict()["plants"]
    assert summary["seed"] == 20261204 and len(summary["plants"]) == 16
    assert {r["controller"] for r in summary["controllers"]} == {r.label for r in v.rows}


def test_evaluate_takes_plants_and_a_seed(tmp_path, capsys):
    best = tmp_path / "best.yaml"
    best.write_text(yaml.safe_dump({"settings": {
        "value_rad": TUNED.value_rad, "error_limit_rad": TUNED.error_limit_rad,
        "k": TUNED.k, "ts_over_tf": TUNED.ts_over_tf}}))  # fmt: skip
    argv = ["evaluate", "--settings", str(best), "--against", "paper", "--runs-dir",
            str(tmp_path / "runs"), "--axis", str(AXES / "loads-uncertain.yaml")]  # fmt: skip
    assert cli.main([*argv, "--plants", "3", "--plant-seed", "5", "--name", "a"]) == 0
    out = capsys.readouterr().out
    assert "across 3 plants drawn within the axis's uncertainty (plant seed 5)" in out
    assert cli.main([*argv, "--plants", "3", "--plant-seed", "6", "--name", "b"]) == 0
    assert capsys.readouterr().out != out
    code = cli.main(["evaluate", "--settings", str(best), "--plants", "4"])
    err = capsys.readouterr().err
    assert code == 2 and "--plants=4 is ignored: axis paper states no uncertainty" in err


def test_evaluate_takes_an_axis_a_plant_count_and_any_tuner():
    from vfgym import load_tuner

    axis = load_axis(AXES / "loads-uncertain.yaml")
    test = axis.scenarios("test")[:5]
    tuner = load_tuner(None, axis)  # the shipped settings model, on this axis
    ev = evaluate([TUNED, tuner, "paper"], test, axis=axis, plants=4, plant_seed=9)
    assert ev.across is not None and ev.across.seed == 9 and len(ev.across.plants) == 4
    assert ev.across.plants == draw_plants(axis.uncertainty, axis.plant, 4, 9)
    by_hand = evaluate([tuner(sc) for sc in test], test, axis=axis, plants=ev.across.plants)
    assert by_hand.across is not None
    assert np.array_equal(ev.cost[1], np.diag(by_hand.cost))
    assert np.array_equal(ev.across.cost[1], by_hand.across.cost[np.arange(5), :, np.arange(5)].T)
    exact = evaluate([TUNED], PAPER_AXIS.scenarios("test")[:3], axis=PAPER_AXIS, plants=2)
    assert exact.across is not None and exact.across.seed is None
    assert [p.inertia for p in exact.across.plants] == [0.95, 1.05]
    with pytest.raises(TypeError, match="plant"):  # the axis is the one problem argument
        evaluate([TUNED], test, axis=axis, plant=PAPER_AXIS.plant.with_motor(inertia_ratio=1))
