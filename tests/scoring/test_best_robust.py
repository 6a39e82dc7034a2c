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
    for plants in ((), plant_design(wide, PAPER_PLANT.motor)):
        for chunk in (1, 4, 50):
            got = best_robust(cands, move, plants, chunk=chunk)
            assert got == _ranked(cands, move, plants), (plants, chunk)
