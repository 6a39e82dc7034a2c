"""Robust per-move optima and the settings model on an axis with uncertainty: what they
call feasible is feasible on every plant of the axis's design, checked by evaluating the
chosen settings on each design plant on its own."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from vfgym import evaluate, load_axis
from vfgym.axis import Uncertainty
from vfgym.permove.optima import OptimumSearch, move_optima

AXES = Path(__file__).resolve().parents[2] / "experiments" / "axes"
SEARCH = OptimumSearch(points=3, rounds=3, keep=2)


def test_robust_optima_are_feasible_on_every_design_plant_and_cost_no_less():
    axis = load_axis(AXES / "paper.yaml")
    axis = replace(axis, uncertainty=Uncertainty(inertia=(0.85, 1.2)))
    design = axis.design_plants()
    moves = axis.scenarios("test")[:4]
    kw = {"plant": axis.plant, "measures": axis.measures}
    nominal = move_optima(moves, SEARCH, **kw)
    robust = move_optima(moves, SEARCH, **kw, plants=design)
    assert any(not np.isclose(a.cost, b.cost) for a, b in zip(nominal, robust, strict=True))
    for o_n, o_r, sc in zip(nominal, robust, moves, strict=True):
        assert o_r.feasible
        ev = evaluate([o_r.settings, o_n.settings], [sc], axis=axis, plants=design)
        assert ev.across is not None
        assert ev.across.feasible[0].all() and ev.feasible[0, 0]
        assert o_r.cost >= o_n.cost - 1e-12  # a constrained optimum costs no less
        if not ev.across.feasible[1].all():  # the nominal optimum breaks on a design plant
            assert o_r.settings != o_n.settings


def test_fit_best_fixed_is_the_sweep_with_as_many_trials(tmp_path):
    """The fit's best fixed setting is what ``vfgym sweep`` finds with as many trials on
    the same axis: the same warm starts, sampler and feasibility (the design included)."""
    from vfgym import cli
    from vfgym.commands._common import load_settings
    from vfgym.permove.fit import best_fixed

    path = tmp_path / "lu.yaml"
    path.write_text((AXES / "loads-uncertain.yaml").read_text())
    axis = load_axis(path)
    got = best_fixed(axis.scenarios("train"), axis, 12)
    assert cli.main(["sweep", "--config", str(AXES.parent / "quick.yaml"), "--axis", str(path),
                     "--trials", "12", "--study", "s", "--runs-dir", str(tmp_path),
                     "--no-progress"]) == 0  # fmt: skip
    assert got == load_settings(str(tmp_path / "sweep" / "s" / "best.yaml"), axis)


def test_an_oracles_optima_are_each_true_plants_own():
    """``true_plants``: each move optimised as it runs on its true plant, so the optimum's
    cost is its cost there, and no more than the modelled plant's optimum costs there."""
    from vfgym.axis import PlantVariant

    axis = load_axis(AXES / "paper.yaml")
    moves = axis.scenarios("test")[:3]
    heavy = [PlantVariant(inertia=1.25)] * len(moves)
    oracle = move_optima(moves, SEARCH, true_plants=heavy)
    nominal = move_optima(moves, SEARCH)
    for o, n, sc in zip(oracle, nominal, moves, strict=True):
        ev = evaluate([o.settings, n.settings], [sc], plants=heavy[:1])
        assert ev.across.cost[0, 0, 0] == o.cost and o.feasible == ev.across.feasible[0, 0, 0]
        if ev.across.feasible[1, 0, 0]:
            assert o.cost <= ev.across.cost[1, 0, 0] + 1e-12
    assert any(o.settings != n.settings for o, n in zip(oracle, nominal, strict=True))
