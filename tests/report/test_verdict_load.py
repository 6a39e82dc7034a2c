"""The held-out verdict on a compliant axis reports the load: each controller's load move
time and residual vibration (in µm where the transmission states its travel, else in
encoder counts), and on how many moves the tuned setting's residual vibration is no larger
than each baseline's; its numbers are the report's, counted with numpy; a rigid axis's
verdict has none of it."""

from __future__ import annotations

import math

import numpy as np
import pytest

from vfgym import Settings
from vfgym.axis import axis_from_dict
from vfgym.report import format_verdict, held_out_verdict

TUNED = Settings(value_rad=0.75, error_limit_rad=0.66, k=2000.0, ts_over_tf=0.5)
MOVES = [
    {"name": "a", "profile": "step", "distance_rad": 1.5, "duration_s": 0.12},
    {"name": "b", "profile": "trapezoid", "distance_rad": -4.0, "duration_s": 0.15},
    {"name": "c", "profile": "scurve", "distance_rad": 6.0, "duration_s": 0.2},
    {"name": "d", "profile": "step", "distance_rad": -0.8, "duration_s": 0.1},
]


def axis(transmission):
    plant = {"motor": {"preset": "SGME-02A", "inertia_ratio": 0.5}}
    if transmission is not None:
        plant["transmission"] = transmission
    return axis_from_dict(
        {"name": "t", "plant": plant, "moves": {"train": MOVES[:1], "test": MOVES}}, "t"
    )


LINEAR = {"load_inertia_kgm2": 3e-5, "resonance_hz": 150.0, "damping_ratio": 0.05}


@pytest.mark.parametrize(
    ("travel", "unit", "key"),
    [(2.0, "µm", "load_residual_vibration_um"), (None, "counts", "load_residual_vibration_counts")],
)
def test_the_verdict_reports_the_loads_residual_vibration_and_move_time(travel, unit, key):
    ax = axis(LINEAR | ({} if travel is None else {"travel_mm_per_rad": travel}))
    v = held_out_verdict(TUNED, ax.scenarios("test"), axis=ax, across=False)
    assert v.residual_unit == unit
    tuned = v.report.column("tuned").values(key)
    assert np.all(np.isfinite(tuned)) and tuned.max() > 0.0
    for r in v.rows:
        col = v.report.column(r.label)
        mine = col.values(key)
        assert r.residual.mean == pytest.approx(float(np.mean(mine)), rel=1e-12)
        assert r.residual.median == pytest.approx(float(np.median(mine)), rel=1e-12)
        lmt = col.values("load_move_time_s")
        assert r.load_move_time.mean == pytest.approx(float(np.mean(lmt)), rel=1e-12)
        if r.label == "tuned":
            assert r.residual_no_larger is None
        else:
            assert r.residual_no_larger == (int((tuned <= mine).sum()), len(MOVES))
    lines = format_verdict(v).splitlines()
    at = next(i for i, x in enumerate(lines) if x.startswith("at the load"))
    assert f"residual vibration median [IQR] ({unit})" in lines[at + 1]
    sc = v.row("scurve")
    line = next(x for x in lines[at:] if x.startswith("scurve "))
    assert line.endswith(f"{sc.residual_no_larger[0]}/{sc.residual_no_larger[1]}")
    assert f"{1e3 * sc.load_move_time.mean:.3g}" in line
    d = v.to_dict()["controllers"]
    short = "um" if travel else "counts"
    assert d[0][f"residual_vibration_{short}"]["mean"] == v.rows[0].residual.mean
    assert d[-1]["residual_no_larger"] == list(v.rows[-1].residual_no_larger)


def test_a_rigid_axis_verdict_has_no_load_lines():
    ax = axis(None)
    v = held_out_verdict(TUNED, ax.scenarios("test"), axis=ax, across=False)
    assert v.residual_unit == ""
    assert all(r.residual is None and r.load_move_time is None for r in v.rows)
    assert "at the load" not in format_verdict(v)
    assert all(not any(k.startswith("residual") for k in d) for d in v.to_dict()["controllers"])
    assert not math.isnan(v.rows[0].cost.mean)
