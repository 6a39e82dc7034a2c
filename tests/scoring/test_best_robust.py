""":func:`vfgym.scoring.best_robust`, the lazy check, picks what ranking every candidate's
:func:`vfgym.scoring.score_robust` score picks (feasible on every plant first, then the
least modelled cost), on random candidates, moves and plants."""

from __future__ import annotations

import numpy as np
import pytest

from vfgym import Settings
from vfgym.axis import Uncertainty, plant_design
from vfgym.moves.distribution import random_scenario
from vfgym.params import PAPER_PLANT
from vfgym.scoring import Move, best_robust, score_robust
from vfgym.space import from_action


def _ranked(cands, move, plants):
    scores = score_robust(cands, [move] * len(cands), plants)
    return min(range(len(cands)), key=lambda i: (not scores[i].feasible, scores[i].cost, i))


@pytest.mark.parametrize("seed", range(6))
def test_the_lazy_check_picks_as_ranking_every_score(seed):
    rng = np.random.default_rng(seed)
    move = Move.of(random_scenario(seed, "test"), PAPER_PLANT)
    # around a feasible setting, so that some hold on every plant and some do not
    near = rng.uniform(-0.25, 0.25, size=(12, 4)) + np.array([0.2, 0.2, 0.3, 0.9])
    cands = [from_action(np.clip(a, -1, 1)) for a in near] + [Settings()]
    wide = Uncertainty(inertia=(0.7, 1.4), coulomb_nm=(0.0, 0.01))
    for plants in ((), plant_design(wide, PAPER_PLANT)):
        for chunk in (1, 4, 50):
            got = best_robust(cands, move, plants, chunk=chunk)
            assert got == _ranked(cands, move, plants), (plants, chunk)


def test_one_robust_rule_evaluate_and_score_robust_agree():
    """The robust rule has one home (:func:`vfgym.scoring.robust_constraints`): the worst
    of each constraint over the modelled and the true plants, as an evaluation's
    ``robust_constraints`` reads it and as :func:`score_robust` ranks by, on random
    settings and moves (where the modelled plant is feasible; elsewhere score_robust does
    not run the plants, a pair that cannot turn feasible)."""
    from vfgym import PAPER_AXIS, evaluate

    rng = np.random.default_rng(5)
    cands = [from_action(a) for a in rng.uniform(-0.6, 0.9, size=(6, 4))]
    moves = [random_scenario(s, "test") for s in range(3)]
    plants = plant_design(Uncertainty(inertia=(0.8, 1.25)), PAPER_PLANT)
    ev = evaluate(cands, moves, axis=PAPER_AXIS, plants=plants)
    robust = ev.robust_constraints
    assert robust.shape == ev.constraints.shape
    pairs = [(c, s) for c in range(len(cands)) for s in range(len(moves))]
    scored = score_robust([cands[c] for c, _ in pairs],
                          [Move.of(moves[s], PAPER_PLANT) for _, s in pairs], plants)  # fmt: skip
    checked = 0
    for (c, s), r in zip(pairs, scored, strict=True):
        if r.feasible or bool(np.all(ev.constraints[c, s] <= 0.0)):
            np.testing.assert_array_equal(r.constraints, robust[c, s])
            checked += 1
    assert checked > 0
    assert (robust >= ev.constraints).all()
    assert (robust > ev.constraints).any()  # some setting breaks on a design plant only
