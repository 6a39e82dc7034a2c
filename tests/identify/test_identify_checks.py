"""What a capture must be before it is fitted: lost encoder edges and the axis's plan; and
a pulse the analyser saw that the drive did not get."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from capture_synth import draw_truth, identify_vcd, outside_block

from vfgym.axis import PAPER_AXIS
from vfgym.identify.checks import lost_edges, plan_match
from vfgym.identify.lines import Capture
from vfgym.identify.model import record_of
from vfgym.identify.plan import make_plan, moves_pulses
from vfgym.io.vcd import trace_edges, write_edges
from vfgym.params import PAPER_SETTINGS
from vfgym.plant import simulate

NOMINAL = PAPER_AXIS.plant
Q = NOMINAL.motor.count_rad
F = NOMINAL.tick_hz


def _capture(times_s: np.ndarray, counts: list[int]) -> Capture:
    return Capture("c", np.zeros(1), np.ones(1, np.int8), np.asarray(times_s, float),
                   np.asarray(counts, np.int64), 1.0, 1e-6, True)  # fmt: skip


def test_a_count_that_turns_back_at_speed_is_a_lost_edge_and_a_slow_turn_is_not():
    fast = 300.0 / Q  # counts a second at 300 rad/s
    t = np.arange(40) / fast
    # an edge lost on one line: a step back and a step on where steps on were due
    counts = [*range(1, 21), 19, *range(20, 39)]
    got = lost_edges(_capture(t, counts), NOMINAL)
    assert got.size == 1 and got[0] == t[20]
    # a real reversal: the motor slows to a stop half a count past its 20th edge, comes back
    a = 0.5 * NOMINAL.motor.peak_torque_nm / NOMINAL.motor.rotor_inertia_kgm2 / Q  # counts/s²
    up = 1.0 - np.sqrt(2.0 * (20.5 - np.arange(1, 21)) / a)  # edges 1..20 crossed going up
    down = 1.0 + np.sqrt(2.0 * (20.5 - np.arange(20, 0, -1)) / a)  # 20..1 going down
    turn = _capture(np.concatenate([up, down]), [*range(1, 21), *range(19, -1, -1)])
    assert lost_edges(turn, NOMINAL).size == 0


def _record(pulses: np.ndarray):
    tr = simulate(np.zeros(pulses.size), PAPER_SETTINGS, NOMINAL, pulses=pulses)
    e = trace_edges(tr, start_s=0.001)
    cap = Capture("c", e.pulse_s, e.pulse_sign, e.count_s, e.count, e.end_s, 1e-9, True)
    return record_of(cap, NOMINAL)


def test_the_plan_itself_one_pulse_more_a_plan_stopped_early_and_other_moves():
    plan = make_plan(PAPER_AXIS)
    full = np.concatenate([plan.pulses, np.zeros(4000, np.int8)])
    assert plan_match(_record(full), plan.pulses, F).kind == "plan"
    extra = full.copy()
    idle = int(np.flatnonzero(full == 0)[5000])
    extra[idle] = 1
    m = plan_match(_record(extra), plan.pulses, F)
    assert m.kind == "differs" and len(m.differ_s) == 1
    rec = _record(extra)
    assert abs(m.differ_s[0] - (idle + 0.5) / F + 0.001) < 1.0 / F  # its time in the capture
    half = full.copy()
    half[plan.pulses.size // 2 :] = 0
    m = plan_match(_record(half), plan.pulses, F)
    assert m.kind == "prefix" and m.pulses < m.plan_pulses
    assert "holds the first" in (m.note("c", "paper") or "") and rec.first_tick in (0, 1)
    other = np.concatenate([moves_pulses(plan.moves[::-1], NOMINAL), np.zeros(4000, np.int8)])
    assert plan_match(_record(other), plan.pulses, F).kind == "other"


def test_a_pulse_the_drive_did_not_get_is_fitted_away_with_the_plan(tmp_path):
    """The analyser shows one pulse more than the drive got (a glitch on the tick grid):
    the plan's train explains the count, is fitted, and the note says so."""
    plan = make_plan(PAPER_AXIS)
    rng = np.random.default_rng([4242, 1])
    truth = draw_truth(NOMINAL, rng, inertia_ratio=(4.0, 6.0), gain=1.03)
    rest = round(0.2 * F)
    train = np.concatenate([np.zeros(rest, np.int8), plan.pulses,
                            np.zeros(round(0.1 * F), np.int8)])  # fmt: skip
    tr = simulate(np.zeros(train.size), PAPER_SETTINGS, truth.plant, pulses=train)
    start = -0.03  # from before the drive's enable, as the procedure asks
    e = trace_edges(tr, start_s=start)
    rise = (rest // 2 + 0.5) / F - start  # a tick in the rest after the enable
    at = int(np.searchsorted(e.pulse_s, rise))
    e = replace(
        e,
        pulse_s=np.insert(e.pulse_s, at, rise),
        pulse_sign=np.insert(e.pulse_sign, at, 1),
        pulse_fall_s=np.insert(e.pulse_fall_s, at, rise + 0.5 / F),
        pulse_start_s=np.insert(e.pulse_start_s, at, rise - 0.5 / F),
    )
    path = write_edges(e, tmp_path / "extra.vcd", timescale="1 us")
    ident, _, matches = identify_vcd(path)
    assert matches[0].kind == "differs" and matches[0].fitted == "plan"
    assert ident.explained and outside_block(ident, truth) == []
    assert any("the plan's train explains the count better" in n for n in ident.notes)
