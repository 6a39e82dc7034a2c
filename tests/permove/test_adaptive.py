"""The scheduler that watches the response: on each design plant it is never worse than the
base it holds first; it is deterministic; bad options name themselves."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from vfgym import PAPER_AXIS, evaluate, load_axis
from vfgym.permove import load_settings_model
from vfgym.permove.adaptive import AdaptiveOptions, EstimatingScheduler

AXIS = Path(__file__).resolve().parents[2] / "experiments" / "axes" / "loads-uncertain.yaml"
FAST = AdaptiveOptions(evals=12, neighbours=1, probes=1)


@pytest.fixture(scope="module")
def setup():
    axis = load_axis(AXIS)
    sched = EstimatingScheduler(axis, load_settings_model(), FAST)
    return axis, sched, axis.scenarios("test")[:2]


def test_on_each_design_plant_it_is_never_worse_than_its_base(setup):
    axis, sched, moves = setup
    for sc in moves:
        table = sched.table(sc)
        plants = list(sched.design)
        base = evaluate(table.base, [sc], axis=axis, plants=plants).across
        mine = evaluate(sched, [sc], axis=axis, plants=plants).across
        for i in range(len(plants)):
            b = (bool(base.feasible[0, i, 0]), -float(base.cost[0, i, 0]))
            m = (bool(mine.feasible[0, i, 0]), -float(mine.cost[0, i, 0]))
            assert m >= (b[0], b[1] - 1e-12), (sc.name, plants[i], m, b)
        assert any(c.ramp > 0 and np.any(c.action != 0.0) for c in table.continuations)


def test_it_is_deterministic(setup):
    """Two schedulers of the same options make the same tables and the same verdict."""
    axis, sched, moves = setup
    sc, plants = moves[0], list(sched.design[:3])
    again = EstimatingScheduler(axis, load_settings_model(), FAST)
    for x, y in zip(sched.table(sc).continuations, again.table(sc).continuations, strict=True):
        assert np.array_equal(x.action, y.action) and x.ramp == y.ramp
    a = evaluate(sched, [sc], axis=axis, plants=plants).across
    b = evaluate(again, [sc], axis=axis, plants=plants).across
    assert np.array_equal(a.cost, b.cost)


def test_an_exact_axis_is_refused():
    with pytest.raises(ValueError, match="states no uncertainty"):
        EstimatingScheduler(PAPER_AXIS, load_settings_model())


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"hold_ms": 0.0}, "hold_ms"),
        ({"hold_ms": 80.0}, "hold_ms"),
        ({"interval_ms": 0.01}, "interval_ms"),
        ({"evals": 0}, "evals"),
        ({"sigma": 0.0}, "sigma"),
        ({"neighbours": -1}, "neighbours"),
        ({"probes": -1}, "probes"),
        ({"seed": -2}, "seed"),
    ],
)
def test_bad_options_name_themselves(kwargs, name):
    with pytest.raises(ValueError, match=name):
        AdaptiveOptions(**kwargs)
