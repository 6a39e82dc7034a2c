"""The trace CSV: a rigid plant's columns as they always were; where the plant states a
transmission, the load's columns after them (its angle and speed at the motor shaft, and
its position in mm of travel where the transmission states it), read back bit for bit;
and ``vfgym export --format csv`` on a compliant axis writes them."""

from __future__ import annotations

import csv
from dataclasses import replace
from pathlib import Path

import numpy as np

from vfgym import PAPER_PLANT, simulate
from vfgym.axis import load_axis
from vfgym.cli import main
from vfgym.io.trace_csv import LOAD_FIELDS, TRACE_FIELDS, write_trace_csv

REPO = Path(__file__).resolve().parents[2]
BELT = REPO / "experiments" / "axes" / "belt-compliant.yaml"


def read(path: Path) -> tuple[list[str], dict[str, np.ndarray]]:
    with open(path, newline="", encoding="utf-8") as f:
        rows = list(csv.reader(f))
    head = rows[0]
    cols = {h: np.array([r[i] for r in rows[1:]]) for i, h in enumerate(head)}
    return head, cols


def compliant_trace(plant, decimation=7):
    move = load_axis(BELT).scenario("jog-20mm")
    loaded = move.plant(plant)
    return simulate(move.command(loaded), plant=loaded, decimation=decimation)


def test_a_rigid_trace_keeps_its_columns(tmp_path):
    tr = simulate(np.linspace(0.0, 0.5, 700), plant=PAPER_PLANT)
    head, _ = read(write_trace_csv(tr, tmp_path / "rigid.csv"))
    assert tuple(head) == TRACE_FIELDS


def test_a_compliant_trace_adds_the_loads_columns(tmp_path):
    plant = load_axis(BELT).plant
    tr = compliant_trace(plant)
    head, cols = read(write_trace_csv(tr, tmp_path / "belt.csv"))
    assert tuple(head) == TRACE_FIELDS + LOAD_FIELDS
    load = cols["load_rad"].astype(float)
    np.testing.assert_array_equal(load, tr.load_rad)  # 17 digits: bit for bit
    np.testing.assert_array_equal(cols["load_speed_rad_s"].astype(float), tr.load_speed_rad_s)
    mm = cols["load_mm"].astype(float)
    np.testing.assert_array_equal(mm, tr.load_rad * plant.transmission.travel_mm_per_rad)
    assert not np.array_equal(load, cols["motor_rad"].astype(float))  # the load, not the motor
    # without travel_mm_per_rad the load stays in rad at the motor shaft only
    bare = plant.replace(transmission=replace(plant.transmission, travel_mm_per_rad=None))
    head, _ = read(write_trace_csv(compliant_trace(bare), tmp_path / "bare.csv"))
    assert tuple(head) == (*TRACE_FIELDS, "load_rad", "load_speed_rad_s")


def test_export_writes_the_loads_columns_on_a_compliant_axis(tmp_path):
    out = tmp_path / "jog.csv"
    code = main(["export", "--axis", str(BELT), "--scenario", "jog-20mm", "--format", "csv",
                 "--out", str(out), "--decimation", "50"])  # fmt: skip
    assert code == 0
    head, cols = read(out)
    assert "load_mm" in head
    # the carriage ends within the in-position window of the 7 rad (20.05 mm) jog
    assert abs(float(cols["load_mm"][-1]) - 7.0 * 2.865) < 0.05
