"""A compliant axis: ``plant.transmission`` read from an axis file (its fields, or a
resonance and a damping ratio), as strictly as every other key, written back and read
equal; a rigid axis's record and digest unchanged; stiffness, damping and the load's
friction ranges in ``uncertainty:`` and the true plants they give; and the shipped
compliant axis."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
import yaml

from vfgym import Transmission
from vfgym.axis import (
    PlantVariant,
    Uncertainty,
    axis_digest,
    axis_from_dict,
    axis_to_dict,
    load_axis,
    machine_digest,
    plant_design,
)

REPO = Path(__file__).resolve().parents[2]
BELT = REPO / "experiments" / "axes" / "belt-compliant.yaml"

PLANT = {"motor": {"preset": "SGME-02A", "inertia_ratio": 0.5}}
FIELDS = {"load_inertia_kgm2": 3.0e-5, "stiffness_nm_rad": 1.0, "damping_nm_s_rad": 0.002}


def axis_with(transmission=None, uncertainty=None):
    plant = dict(PLANT) | ({} if transmission is None else {"transmission": transmission})
    data = {"name": "t", "plant": plant}
    if uncertainty is not None:
        data["uncertainty"] = uncertainty
    return axis_from_dict(data, "t")


def test_the_issues_example_reads_into_a_transmission():
    ax = axis_with(FIELDS)
    assert ax.plant.transmission == Transmission(3.0e-5, 1.0, 0.002)
    assert ax.plant.resonance_hz == pytest.approx(49.4, abs=0.05)  # "about 49 Hz here"


def test_a_resonance_and_damping_ratio_convert_on_the_motors_inertia():
    ax = axis_with({"load_inertia_kgm2": 3.0e-5, "resonance_hz": 49.37, "damping_ratio": 0.05})
    jm = ax.plant.motor.inertia_kgm2
    tr = ax.plant.transmission
    assert ax.plant.resonance_hz == pytest.approx(49.37, rel=1e-12)
    mu = jm * 3e-5 / (jm + 3e-5)
    assert tr.damping_nm_s_rad == pytest.approx(2 * 0.05 * mu * 2 * math.pi * 49.37, rel=1e-12)
    assert tr.stiffness_nm_rad == pytest.approx(1.0, rel=2e-4)


@pytest.mark.parametrize(
    ("transmission", "needle"),
    [
        ({"load_inertia_kgm2": 3e-5, "stiffnes_nm_rad": 1.0}, "plant.transmission.stiffnes_nm_rad"),
        ({"load_inertia_kgm2": 3e-5}, "stiffness_nm_rad"),
        ({"load_inertia_kgm2": -1.0, "stiffness_nm_rad": 1.0}, "plant.transmission.load_inertia"),
        (FIELDS | {"resonance_hz": 50.0}, "plant.transmission.stiffness_nm_rad=1.0 is not allowed"),
        ({"load_inertia_kgm2": 3e-5, "damping_ratio": 0.1}, "plant.transmission.resonance_hz"),
        ({"load_inertia_kgm2": 3e-5, "resonance_hz": "50"}, "plant.transmission.resonance_hz"),
        ({"load_inertia_kgm2": 3e-5, "resonance_hz": 50, "damping_ratio": 2}, "damping_ratio"),
        ({"load_inertia_kgm2": 3e-5, "resonance_hz": 2e4}, "plant.transmission.stiffness_nm_rad"),
        ([1, 2], "plant.transmission"),
    ],
)
def test_a_bad_transmission_is_one_line_naming_its_key(transmission, needle):
    with pytest.raises(ValueError, match=needle.replace(".", r"\.")) as exc:
        axis_with(transmission)
    assert "\n" not in str(exc.value)


def test_a_compliant_axis_round_trips_and_a_rigid_one_keeps_its_record():
    ax = axis_with(FIELDS | {"travel_mm_per_rad": 2.865})
    d = axis_to_dict(ax)
    assert d["plant"]["transmission"]["stiffness_nm_rad"] == 1.0
    assert axis_from_dict(yaml.safe_load(yaml.safe_dump(d)), "t") == ax
    rigid = axis_with()
    assert "transmission" not in axis_to_dict(rigid)["plant"]
    assert machine_digest(rigid) != machine_digest(ax)
    assert axis_digest(rigid) != axis_digest(ax)


def test_stiffness_and_damping_ranges_give_true_plants():
    ax = axis_with(FIELDS, {"stiffness": [0.7, 1.3], "damping": [0.5, 2.0], "inertia": [0.9, 1.1]})
    design = plant_design(ax.uncertainty, ax.plant)
    assert len(design) == 8 + 6
    corner = PlantVariant(inertia=1.1, stiffness=0.7, damping=2.0)
    assert corner in design
    true = corner.apply(ax.plant)
    tr = true.transmission
    assert tr.stiffness_nm_rad == pytest.approx(0.7)
    assert tr.damping_nm_s_rad == pytest.approx(0.004)
    assert tr.load_inertia_kgm2 == pytest.approx(3.3e-5)  # the inertia factor: the whole load
    assert true.motor.inertia_kgm2 == pytest.approx(1.1 * ax.plant.motor.inertia_kgm2)
    assert true.torque_per_count_nm == ax.plant.torque_per_count_nm  # the drive as set
    assert corner.label() == "J×1.1 K_S×0.7 c_S×2"
    assert Uncertainty(stiffness=(0.5, 1.0)).to_dict() == {"stiffness": [0.5, 1.0]}


def test_a_load_friction_range_gives_true_plants_around_the_modelled_one():
    ax = axis_with(FIELDS | {"load_coulomb_nm": 0.01}, {"load_coulomb_nm": [0.004, 0.03]})
    assert ax.uncertainty.to_dict() == {"load_coulomb_nm": [0.004, 0.03]}
    assert axis_from_dict(axis_to_dict(ax), "t") == ax
    design = ax.design_plants()
    true = sorted(v.apply(ax.plant).transmission.load_coulomb_nm for v in design)
    assert true[0] == pytest.approx(0.004) and true[-1] == pytest.approx(0.03)
    assert all(0.004 - 1e-15 <= c <= 0.03 + 1e-15 for c in true)
    v = PlantVariant(load_coulomb_offset_nm=-0.006)
    assert v.label() == "τc_L-0.006"
    assert v.apply(ax.plant).transmission.load_coulomb_nm == pytest.approx(0.004)
    assert v.apply(ax.plant).motor == ax.plant.motor  # the motor's own friction untouched
    assert repr(PlantVariant(inertia=1.1)) == (
        "PlantVariant(inertia=1.1, coulomb_offset_nm=0.0, viscous_offset_nm_s_rad=0.0, "
        "load_offset_nm=0.0, torque_per_count=1.0)"
    )  # a rigid axis's variants read (and digest) as before


@pytest.mark.parametrize(
    ("transmission", "uncertainty", "needle"),
    [
        (None, {"load_coulomb_nm": [0.0, 0.01]}, "uncertainty.load_coulomb_nm"),
        (FIELDS, {"load_coulomb_nm": [-0.01, 0.01]}, r"uncertainty.load_coulomb_nm\[0\]"),
        (FIELDS, {"load_coulomb_nm": [0.0, 50.0]}, r"uncertainty.load_coulomb_nm=.*peak_torque"),
        (None, {"stiffness": [0.8, 1.2]}, "uncertainty.stiffness"),
        (None, {"damping": [0.8, 1.2]}, "uncertainty.damping"),
        (FIELDS, {"stiffness": [0.8, 30.0]}, r"uncertainty.stiffness\[1\]"),
        (
            {"load_inertia_kgm2": 3e-5, "resonance_hz": 11e3},
            {"stiffness": [1, 2]},
            "stiffness=.*resonance",
        ),
    ],
)
def test_transmission_ranges_are_checked_with_the_axis(transmission, uncertainty, needle):
    with pytest.raises(ValueError, match=needle):
        axis_with(transmission, uncertainty)
    with pytest.raises(ValueError, match="no transmission"):
        PlantVariant(stiffness=1.1).apply(axis_with().plant)
    with pytest.raises(ValueError, match="no transmission"):
        PlantVariant(load_coulomb_offset_nm=0.01).apply(axis_with().plant)


def test_the_shipped_compliant_axis():
    """experiments/axes/belt-compliant.yaml: a belt stage whose first resonance is one a
    real one has (tens of Hz), its load ringing after the motor is in position."""
    ax = load_axis(BELT)
    tr = ax.plant.transmission
    assert tr is not None and tr.travel_mm_per_rad is not None
    assert 20.0 <= ax.plant.resonance_hz <= 150.0
    assert ax.scenarios("train") and ax.scenarios("test")
