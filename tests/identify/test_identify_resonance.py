"""A compliant transmission's resonance identified from the motor encoder's capture."""

from __future__ import annotations

import hashlib
from pathlib import Path

import numpy as np
import pytest

from vfgym.axis import PAPER_AXIS, load_axis
from vfgym.cli import main
from vfgym.identify.capture import read_capture
from vfgym.identify.model import Start, record_of, respond
from vfgym.identify.pipeline import identify_axis
from vfgym.identify.plan import RESONANCE_BURSTS, RESONANCE_MOVE, make_plan
from vfgym.identify.resonance_problem import (
    damping_ratio,
    resonance_segment,
    trimmed,
    with_resonance,
)
from vfgym.identify.simulated import record_capture
from vfgym.params import PAPER_SETTINGS

ROOT = Path(__file__).resolve().parents[2]
COMPLIANT = ROOT / "experiments" / "axes" / "belt-compliant.yaml"

RIGID_PLANS = {
    "paper": "6c3882b81e2db957236301c42202270feb49dc045a73d3b0129940150a067e7b",
    "belt": "3ecaab4cdbd3932519547f806de857f3ffc61dada70fb018844bc565b5889c35",
}
"""sha256 of the rigid axes' plan pulse trains before the resonance moves existed."""


@pytest.mark.parametrize("name", sorted(RIGID_PLANS))
def test_a_rigid_axis_plan_is_unchanged_bit_for_bit(name):
    axis = PAPER_AXIS if name == "paper" else load_axis(ROOT / "experiments/axes/belt.yaml")
    plan = make_plan(axis, PAPER_SETTINGS)
    assert RESONANCE_MOVE not in [m.name for m in plan.moves]
    assert hashlib.sha256(plan.pulses.tobytes()).hexdigest() == RIGID_PLANS[name]


def test_a_compliant_axis_plan_starts_with_the_bursts():
    plan = make_plan(load_axis(COMPLIANT), PAPER_SETTINGS)
    first = plan.moves[0]
    assert first.name == RESONANCE_MOVE
    assert len(first.moves) == RESONANCE_BURSTS
    assert sum(d for d, _ in first.moves) == 0.0  # ends where it began


def _capture(tmp_path, plant, plan):
    path = record_capture(plant, plan.pulses, tmp_path / "c.vcd", start_s=-0.05, rest_s=0.2,
                          length_s=0.25 + plan.duration_s + 0.1)  # fmt: skip
    return read_capture(path)


def test_a_50_hz_transmission_is_identified_within_5_percent(tmp_path):
    axis = load_axis(COMPLIANT)
    true = with_resonance(axis.plant, 50.0, 0.05)
    cap = _capture(tmp_path, true, make_plan(axis, PAPER_SETTINGS))
    ident, _, _ = identify_axis(axis, [cap], PAPER_SETTINGS, from_enable=True)
    res = ident.resonance
    assert res is not None and res.shown
    assert abs(res.resonance_hz / 50.0 - 1.0) <= 0.05
    written = ident.axis.plant
    assert abs(written.resonance_hz / 50.0 - 1.0) <= 0.05  # the axis holds it, not the nominal
    assert abs(damping_ratio(written) - 0.05) <= 0.02
    unc = ident.axis.uncertainty
    assert unc.stiffness is not None and unc.stiffness[0] < 1.0 < unc.stiffness[1]


def test_an_overdamped_transmission_is_refused_in_one_line(tmp_path, capsys):
    """A critically damped spring hardly rings: the capture cannot tell its resonance, and
    ``vfgym identify`` refuses in one line naming the transmission, writing nothing."""
    axis = load_axis(COMPLIANT)
    true = with_resonance(axis.plant, 60.0, 1.0)
    path = record_capture(true, make_plan(axis, PAPER_SETTINGS).pulses, tmp_path / "c.vcd",
                          start_s=-0.05, rest_s=0.2, length_s=3.9)  # fmt: skip
    out = tmp_path / "identified.yaml"
    args = ["identify", "--axis", str(COMPLIANT), "--capture", str(path), "--out", str(out)]
    assert main([*args, "--from-enable"]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err
    assert "transmission: the capture cannot tell the resonance" in err, err
    assert err.endswith("no axis written"), err
    assert not out.exists()


def test_a_trimmed_record_has_the_residuals_of_the_whole(tmp_path):
    """Cutting the rest before the first pulse (whole servo periods) changes no residual."""
    axis = load_axis(COMPLIANT)
    plan = make_plan(axis, PAPER_SETTINGS)
    rec = record_of(_capture(tmp_path, with_resonance(axis.plant, 80.0, 0.04), plan),
                    axis.plant, True)  # fmt: skip
    seg = resonance_segment(rec, 20_000)
    cut = trimmed(seg, axis.plant)
    assert cut.n_ticks < seg.n_ticks - 20_000  # the rest before the moves is gone
    for phase in (0, 33):
        start = Start(-0.4, phase)
        whole = seg.residuals(respond(seg, axis.plant, PAPER_SETTINGS, start))
        part = cut.residuals(respond(cut, axis.plant, PAPER_SETTINGS, start))
        np.testing.assert_array_equal(part, whole)
