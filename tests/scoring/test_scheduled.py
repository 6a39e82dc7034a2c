"""Schedulers in :func:`vfgym.evaluate`: a controller that runs each move itself is scored
on the same (move, plant) pairs, by the same formula, as every other controller."""

from __future__ import annotations

import numpy as np
import pytest

from vfgym import Settings, evaluate
from vfgym.axis import PlantVariant
from vfgym.params import DEFAULT_MEASURES, PAPER_PLANT
from vfgym.plant import simulate
from vfgym.report import Candidate, compare
from vfgym.scoring import Move, Scheduler

HELD = Settings(value_rad=1.2, error_limit_rad=1.2, k=300.0)
PLANTS = (PlantVariant(inertia=1.1), PlantVariant(inertia=0.9, coulomb_offset_nm=0.002))
MOVES = ["paper-step", "short-move", "test-3"]


class Hold(Scheduler):
    """A scheduler that holds one setting through the move: its scores must be the
    setting's own, on the modelled plant and on each true plant."""

    def __init__(self, settings: Settings) -> None:
        self.settings = settings
        self.runs: list[tuple[str, PlantVariant]] = []

    def run_move(self, scenario, plant):
        self.runs.append((scenario.name, plant))
        mv = Move.of(scenario, PAPER_PLANT, plant)  # the true plant, the modelled command
        return simulate(mv.command, self.settings, mv.plant, measures=DEFAULT_MEASURES).metrics


def test_a_scheduler_holding_a_setting_scores_as_the_setting():
    hold = Hold(HELD)
    assert isinstance(hold, Scheduler)
    ev = evaluate([HELD, hold], MOVES, plants=PLANTS)
    np.testing.assert_allclose(ev.cost[1], ev.cost[0], rtol=1e-12)
    np.testing.assert_allclose(ev.constraints[1], ev.constraints[0], rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(ev.objectives[1], ev.objectives[0], rtol=1e-12, atol=1e-15)
    a = ev.across
    assert a is not None
    np.testing.assert_allclose(a.cost[1], a.cost[0], rtol=1e-12)
    np.testing.assert_array_equal(a.feasible[1], a.feasible[0])
    # each (move, plant) pair run once, the modelled plant first
    assert len(hold.runs) == len(MOVES) * (1 + len(PLANTS))
    assert {p for _, p in hold.runs[: len(MOVES)]} == {PlantVariant()}
    # a true plant changes the score: the scheduler was run on it
    assert not np.allclose(a.cost[1, 0], ev.cost[1])
    assert ev.chosen[0] == [HELD] * len(MOVES) and ev.chosen[1] == [None] * len(MOVES)


def test_compare_judges_a_scheduler_across_plants_in_its_one_call():
    rep = compare([Candidate("sched", policy=Hold(HELD))], ["paper"], MOVES, plants=PLANTS)
    ev = evaluate([HELD, "paper"], MOVES, plants=PLANTS)
    np.testing.assert_allclose(rep.column("sched").cost, ev.cost[0], rtol=1e-12)
    a = rep.across_of(["paper", "sched"])
    assert a is not None
    np.testing.assert_allclose(a.cost[1], ev.across.cost[0], rtol=1e-12)
    np.testing.assert_array_equal(a.cost[0], ev.across.cost[1])


def test_traces_are_kept_for_settings_not_for_a_scheduler():
    ev = evaluate([HELD, Hold(HELD)], ["short-move"], keep_traces=True)
    assert ev.traces[0][0] is not None and ev.traces[1][0] is None


class Broken(Scheduler):
    def run_move(self, scenario, plant):
        return {"cost": 1.0}


def test_a_scheduler_without_measures_is_one_line():
    with pytest.raises(ValueError, match="returned no measure"):
        evaluate(Broken(), ["short-move"])


def test_a_progress_bar_changes_no_number_and_counts_every_run(monkeypatch):
    """``progress=True`` splits the batch into calls of PROGRESS_CHUNK pairs and ticks
    per scheduler run: the same numbers, every (controller, move, plant) triple counted."""
    import tqdm as tqdm_module

    from vfgym.scoring import _evaluate

    seen = []

    class Counted(tqdm_module.tqdm):
        def update(self, n=1):
            seen.append(n)
            return super().update(n)

    monkeypatch.setattr(_evaluate, "tqdm", Counted)
    monkeypatch.setattr(_evaluate, "PROGRESS_CHUNK", 5)
    ctrls = [HELD, "paper", Hold(HELD)]
    triples = len(ctrls) * len(MOVES) * (1 + len(PLANTS))
    quiet = evaluate(ctrls, MOVES, plants=PLANTS)
    assert seen[0] == 2 * len(MOVES) * (1 + len(PLANTS))  # the fixed ones: one batched call
    assert sum(seen) == triples
    seen.clear()
    shown = evaluate(ctrls, MOVES, plants=PLANTS, progress=True)
    assert sum(seen) == triples and max(seen) == 5
    np.testing.assert_array_equal(shown.cost, quiet.cost)
    np.testing.assert_array_equal(shown.across.cost, quiet.across.cost)
