"""Arrival is part of the scoring path: a move that does not end in the in-position window
(a sine not followed) is infeasible, and costs more than any feasible run that arrives."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from vfgym import PAPER_SETTINGS, Measures, Settings, evaluate
from vfgym.moves.distribution import random_scenario
from vfgym.moves.scenarios import SCENARIOS, Scenario
from vfgym.scoring import CONSTRAINTS, DEFAULT_WEIGHTS, yardsticks
from vfgym.space import SPACE, from_action

NEVER_MOVES = Settings(value_rad=1e9, error_limit_rad=1e9)
"""The V-F controller with a value no error reaches: it emits no pulse."""
ARRIVAL = CONSTRAINTS.index("arrival")


def test_a_controller_that_never_moves_is_infeasible_and_costs_more_than_the_papers():
    ev = evaluate([NEVER_MOVES, PAPER_SETTINGS], list(SCENARIOS))
    for si, sc in enumerate(ev.scenarios):
        assert ev.metrics[0][si]["pulse_count"] == 0, sc.name
        assert not ev.feasible[0, si], sc.name
        assert ev.cost[0, si] > ev.cost[1, si], sc.name
    # it fails by arrival wherever the move does not end where it started
    ends_away = [not (sc.profile == "multi" and sc.command()[-1] == 0.0) for sc in ev.scenarios]
    assert ends_away.count(False) == 1  # multi-move returns to 0: its overshoot catches it
    for si, away in enumerate(ends_away):
        assert (ev.constraints[0, si, ARRIVAL] > 0.0) == away
    # heavy-load: 1,630 windows short, more than the paper's 92-window overshoot costs
    hl = [s.name for s in ev.scenarios].index("heavy-load")
    m = ev.metrics[0][hl]
    assert ev.constraints[0, hl, ARRIVAL] == pytest.approx(10.0 / m["window_rad"] - 1.0)
    assert not ev.feasible[1, hl] and ev.metrics[1][hl]["arrived"]


def test_point_to_point_arrival_is_settled_and_counts_windows_to_go():
    ev = evaluate([NEVER_MOVES, PAPER_SETTINGS, "scurve"], ["paper-step", "short-move"])
    for ci in range(3):
        for si in range(2):
            m = ev.metrics[ci][si]
            c = ev.constraints[ci, si, ARRIVAL]
            assert m["arrived"] == m["settled"] == (c <= 0.0)
            assert c == pytest.approx(abs(m["final_error_rad"]) / m["window_rad"] - 1.0)
    # the never-mover pays the fixed penalty and 0.1 per window still to go
    m, c = ev.metrics[0][0], ev.constraints[0, 0]
    w = DEFAULT_WEIGHTS
    expect = (
        m["move_time_s"] / m["ideal_time_s"] + w.unsettled + w.arrival * c[ARRIVAL]
    )  # no overshoot, no acceleration, no torque: it does not move
    assert ev.cost[0, 0] == pytest.approx(expect)


def test_a_zero_window_is_refused():
    """An in-position window of zero width has no meaning (every overshoot is infinitely
    many windows); the measures refuse it where it is made."""
    with pytest.raises(ValueError, match=r"in_position_counts=0.0 is out of range: allowed \(0"):
        Measures(in_position_counts=0.0)


def test_a_sine_arrives_when_followed_within_the_3db_bandwidth():
    """Tracking: RMS error ≤ 1/√2 of the reference's RMS (what not moving scores)."""
    sc = SCENARIOS["paper-sine"]
    ev = evaluate([NEVER_MOVES, PAPER_SETTINGS], [sc])
    cmd = sc.command()
    ref = math.sqrt(float(np.mean(cmd**2)))
    assert yardsticks(sc, sc.plant(), Measures()).reference_rms_rad == pytest.approx(ref)
    for ci in range(2):
        rms = ev.metrics[ci][0]["tracking_rms_rad"]
        assert ev.constraints[ci, 0, ARRIVAL] == pytest.approx(math.sqrt(2) * rms / ref - 1.0)
    # standing still: the error is the reference itself
    assert ev.constraints[0, 0, ARRIVAL] == pytest.approx(math.sqrt(2) - 1.0)
    assert not ev.metrics[0][0]["arrived"] and ev.metrics[1][0]["arrived"]
    assert ev.feasible[1, 0] and not ev.feasible[0, 0]


scenarios = st.one_of(
    st.builds(random_scenario, st.integers(0, 10_000), st.sampled_from(["train", "test"])),
    st.sampled_from([n for n, s in SCENARIOS.items() if s.duration_s <= 0.2]).map(
        SCENARIOS.__getitem__
    ),
    st.builds(
        lambda d, f: Scenario(
            name="sine", profile="sine", distance_rad=d, freq_hz=f, duration_s=0.1
        ),
        st.floats(0.5, 8.0),
        st.floats(5.0, 30.0),
    ),
)


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    sc=scenarios,
    acts=st.lists(
        st.lists(st.floats(-1.0, 1.0), min_size=len(SPACE), max_size=len(SPACE)),
        min_size=4,
        max_size=8,
    ),
)
def test_not_arriving_costs_more_than_any_feasible_run_that_arrives(sc, acts):
    ctrls = [NEVER_MOVES, PAPER_SETTINGS, "rule-of-thumb", *(from_action(a) for a in acts)]
    ev = evaluate(ctrls, [sc])
    arrived = np.array([row[0]["arrived"] for row in ev.metrics])
    cost, feas = ev.cost[:, 0], ev.feasible[:, 0]
    assert not arrived[0]  # the controller that never moves never gets there
    assert not np.any(feas & ~arrived)  # not arriving is infeasible
    if np.any(feas & arrived):
        assert cost[~arrived].min() > cost[feas & arrived].max()
