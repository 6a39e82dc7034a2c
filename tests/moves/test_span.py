""":class:`vfgym.moves.features.MoveSpan`: what a set of moves asks of a plant, and what of
another move lies outside it (the held-out verdict's extrapolation warning)."""

from __future__ import annotations

import math

import pytest

from vfgym import PAPER_PLANT, Scenario
from vfgym.moves.features import SPAN_MARGINS, MoveSpan, peak_speed_rad_s


def step(d: float, ratio: float = 0.0) -> Scenario:
    return Scenario(name=f"s{d}", profile="step", distance_rad=d, duration_s=0.5,
                    inertia_ratio=ratio)  # fmt: skip


def test_the_speed_a_move_asks_for_is_its_triangle_peak_or_the_top_speed():
    limit = PAPER_PLANT.motor.usable_accel_rad_s2
    assert peak_speed_rad_s(step(0.5), PAPER_PLANT) == pytest.approx(math.sqrt(0.5 * limit))
    assert peak_speed_rad_s(step(40.0), PAPER_PLANT) == PAPER_PLANT.pulse_top_speed_rad_s


def test_a_move_is_outside_only_beyond_the_margin_of_each_end():
    span = MoveSpan.of([step(1.0), step(4.0, ratio=1.0)], PAPER_PLANT)
    assert span.lows[0] == 1.0 and span.highs[0] == 4.0 and span.highs[2] == 1.0
    inside = 4.0 * (1 + SPAN_MARGINS[0]) * 0.99
    assert span.outside(step(inside), PAPER_PLANT) == []
    assert span.outside(step(4.0 * (1 + SPAN_MARGINS[0]) * 1.01), PAPER_PLANT) == [
        "distance 5.05 rad (tuned on 1 to 4)"
    ]
    heavy = span.outside(step(4.0, ratio=3.0), PAPER_PLANT)
    assert heavy == ["inertia_ratio 3 rotor inertias of load (tuned on 0 to 1)"]
    short = span.outside(step(0.3), PAPER_PLANT)  # shorter, and slower at its peak
    assert [p.split()[0] for p in short] == ["distance", "speed"]
