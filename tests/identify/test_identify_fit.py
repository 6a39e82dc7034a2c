"""The estimator on captures of plants drawn at random, recorded as a 1 MHz analyser would,
through ``vfgym identify``'s own path (:func:`vfgym.identify.pipeline.identify_axis`)."""

from __future__ import annotations

import re
from dataclasses import replace

import numpy as np
import pytest
from capture_synth import capture_vcd, draw_truth, identify_vcd, outside_block

from vfgym.axis import PAPER_AXIS
from vfgym.identify.capture import read_capture
from vfgym.identify.fit import PARAMS, QUANTISATION_FLOOR
from vfgym.identify.model import record_of
from vfgym.identify.plan import make_plan, moves_pulses
from vfgym.identify.written import EXPLAINED

NOMINAL = PAPER_AXIS.plant
RATED = NOMINAL.motor.rated_torque_nm
SEED = 31_415  # the drawn plants' stream (the benchmark draws from another)


@pytest.fixture(scope="module")
def plan():
    return make_plan(PAPER_AXIS)


@pytest.mark.parametrize(
    ("case", "ratio", "gain"), [("heavy", (4.0, 8.0), 0.93), ("light", (0.0, 0.8), 1.07)]
)
def test_a_drawn_plant_is_identified_within_the_goals(plan, tmp_path, case, ratio, gain):
    """A drive whose gain is off: where the torque saturates the gain is measured, else the
    estimates and the block span the gain's prior (±10 %) and hold the true plant."""
    rng = np.random.default_rng([SEED, len(case)])
    truth = draw_truth(NOMINAL, rng, inertia_ratio=ratio, gain=gain)
    path = capture_vcd(truth.plant, plan.pulses, tmp_path / f"{case}.vcd", rng, from_enable=True)
    ident, _, matches = identify_vcd(path)
    assert matches[0].kind == "plan"
    assert ident.explained, ident.notes
    result = ident.fit
    for name in ("coulomb_nm", "viscous_nm_s_rad", "load_torque_nm"):
        assert result.estimate(name).excited, name
    assert outside_block(ident, truth) == []
    g = result.estimate("torque_per_count")
    if case == "heavy":  # the reversals saturate the torque: J and K3 separate
        assert g.excited and g.value == pytest.approx(gain, rel=0.02)
        assert result.estimate("inertia").value == pytest.approx(truth.inertia, rel=0.02)
        assert ident.profile is None
        lo, hi = ident.axis.uncertainty.torque_per_count
        assert hi / lo < 1.01
        for name in ("coulomb_nm", "load_torque_nm"):
            assert abs(result.estimate(name).value - truth.value(name)) <= 0.01 * RATED
    else:  # they do not: the ratios to the gain are known, the gain within its prior
        assert not g.excited and g.value == 1.0 and (g.low, g.high) == (0.9, 1.1)
        assert ident.profile is not None and ident.profile.prior == (0.9, 1.1)
        assert ident.axis.uncertainty.torque_per_count == (0.9, 1.1)
        j = result.estimate("inertia")
        assert j.value == pytest.approx(truth.inertia / gain, rel=0.01)  # J/K3 as set
        assert j.low <= truth.inertia <= j.high and j.high / j.low > 1.2
        line = [n for n in ident.notes if n.startswith("torque_per_count: not separated")]
        assert len(line) == 1 and "inertia/gain = " in line[0] and "[0.9, 1.1]" in line[0]
        for name in ("coulomb_nm", "load_torque_nm"):
            e = result.estimate(name)
            assert e.low <= truth.value(name) <= e.high, name
    # the identified axis simulates as the fit at the gain as set did
    fit1 = ident.profile.fits[1] if ident.profile is not None else result
    assert ident.axis.plant.motor.inertia_kgm2 == pytest.approx(
        fit1.plant.motor.inertia_kgm2, rel=1e-12
    )
    assert ident.axis.plant.torque_per_count_nm == pytest.approx(
        fit1.plant.torque_per_count_nm, rel=1e-12
    )


def test_a_load_torque_is_not_seen_when_the_capture_starts_with_the_axis_held(plan, tmp_path):
    """A light axis never reaches its torque limit: below it a load torque only adds to the
    error the servo holds, so a capture started after the enable cannot show it."""
    rng = np.random.default_rng([SEED, 5])
    truth = draw_truth(NOMINAL, rng, inertia_ratio=(0.0, 0.8))
    path = capture_vcd(truth.plant, plan.pulses, tmp_path / "h.vcd", rng, from_enable=False)
    ident, _, _ = identify_vcd(path, from_enable=False)
    result = ident.fit
    assert ident.profile is not None and ident.profile.fits[1].saturated_s == 0.0
    load = result.estimate("load_torque_nm")
    assert not load.excited and load.value == load.nominal
    lines = [n for n in ident.notes if n.startswith("load_torque_nm: not excited")]
    assert len(lines) == 1 and "before enabling the drive" in lines[0], ident.notes
    # the rest is still identified, and the truth lies within the block
    assert ident.profile.fits[1].estimate("inertia").value == pytest.approx(truth.inertia, rel=0.02)
    assert abs(result.estimate("coulomb_nm").value - truth.coulomb_nm) <= 0.01 * RATED
    assert outside_block(ident, truth) == []


def test_an_enable_within_the_capture_is_recognised_by_the_sag(plan, tmp_path):
    """Without --from-enable: the axis sagging under a load before the first pulse."""
    rng = np.random.default_rng([SEED, 10])
    truth = draw_truth(NOMINAL, rng, inertia_ratio=(0.0, 1.0))
    assert abs(truth.load_torque_nm) > truth.coulomb_nm + 0.005 * RATED  # it sags
    path = capture_vcd(truth.plant, plan.pulses, tmp_path / "e.vcd", rng, from_enable=True)
    rec = record_of(read_capture(path), NOMINAL)
    assert rec.enabled and rec.sag_counts != 0
    assert rec.first_sample > 0  # the sag's samples, at an unknown instant, are left out
    with pytest.raises(ValueError, match="starts inside a move"):  # said to start held
        record_of(read_capture(path), NOMINAL, False)


def _subset(plan, keep):
    moves = tuple(sc for sc in plan.moves if keep(sc.name))
    return moves_pulses(moves, NOMINAL)


@pytest.mark.parametrize(
    ("keep", "missing", "why"),
    [
        (lambda n: n.endswith("-fwd"), ["coulomb_nm"], "one direction only"),
        (lambda n: n.startswith("identify-speed2"), ["viscous_nm_s_rad"], "fewer than two"),
        (
            lambda n: n.startswith("identify-step"),
            ["coulomb_nm", "viscous_nm_s_rad", "load_torque_nm"],
            "no constant-speed",
        ),
    ],
    ids=["one-direction", "one-speed", "no-cruise"],
)
def test_what_the_moves_do_not_excite_is_left_nominal_and_said(plan, tmp_path, keep, missing, why):
    rng = np.random.default_rng([SEED, 7])
    truth = draw_truth(NOMINAL, rng, inertia_ratio=(2.0, 6.0))
    path = capture_vcd(truth.plant, _subset(plan, keep), tmp_path / "c.vcd", rng, from_enable=True)
    ident, _, matches = identify_vcd(path)
    assert matches[0].kind != "plan"
    assert any("is not the plan of axis paper" in n for n in ident.notes), ident.notes
    result = ident.fit
    for name in missing:
        e = result.estimate(name)
        assert not e.excited and e.value == pytest.approx(e.nominal, abs=1e-12), name
        assert e.low < e.value or e.high > e.value  # a wide range, not a point
        lines = [n for n in ident.notes if n.startswith(f"{name}: not excited")]
        assert len(lines) == 1 and why in lines[0], ident.notes
    for name in set(PARAMS) - set(missing) - {"torque_per_count"}:
        assert result.estimate(name).excited, name


def test_a_wrong_motor_preset_is_refused_with_its_cause(plan, tmp_path):
    """A slower motor than the axis file's: it cannot follow the fast moves."""
    rng = np.random.default_rng([SEED, 11])
    truth = draw_truth(NOMINAL, rng, inertia_ratio=(1.0, 3.0))
    rpm = 2 * np.pi / 60
    other = replace(
        truth.plant.motor,
        knee_speed_rad_s=2000 * rpm,
        max_speed_rad_s=3000 * rpm,
        torque_at_max_speed_nm=0.5,
    )
    path = capture_vcd(replace(truth.plant, motor=other), plan.pulses, tmp_path / "w.vcd", rng,
                       from_enable=True)  # fmt: skip
    ident, _, _ = identify_vcd(path)
    assert not ident.explained
    fit1 = ident.profile.fits[1] if ident.profile is not None else ident.fit
    assert fit1.residual_rms_counts > EXPLAINED * QUANTISATION_FLOOR
    line = [n for n in ident.notes if n.startswith("the model does not explain")]
    assert len(line) == 1 and "plant.motor.preset" in line[0], ident.notes


def test_a_wrong_gear_is_named(plan, tmp_path):
    rng = np.random.default_rng([SEED, 13])
    truth = draw_truth(NOMINAL, rng, inertia_ratio=(0.0, 2.0))
    geared = truth.plant.with_servo(gear=2)
    keep = _subset(plan, lambda n: n.startswith("identify-speed1"))
    ident, _, _ = identify_vcd(capture_vcd(geared, keep, tmp_path / "g.vcd", rng, from_enable=True))
    assert not ident.explained
    m = re.match(
        r"the gear: the capture moves ([0-9.]+) encoder counts per pulse", ident.cause or ""
    )
    assert m is not None, ident.cause
    assert float(m.group(1)) == pytest.approx(2.0, rel=0.02)
