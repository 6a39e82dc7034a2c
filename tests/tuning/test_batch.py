"""A worker's batch: a planned batch created while it is simulated, and what a failure or
an interrupt at each point of that leaves behind."""

from __future__ import annotations

import signal
import threading

import optuna
import pytest

from vfgym import space, tuning
from vfgym.tuning import _batch
from vfgym.tuning._objective import Objective
from vfgym.tuning._workers import DeferredInterrupt

pytestmark = pytest.mark.filterwarnings("ignore:Heartbeat of storage")
COMPLETE, FAIL, WAITING = (optuna.trial.TrialState[s] for s in ("COMPLETE", "FAIL", "WAITING"))


def _sweep(tmp_path, trials: int) -> tuple[tuning.SweepConfig, object, optuna.Study]:
    cfg = tuning.SweepConfig.resolve(
        {"scenarios": ["short-move"], "trials": trials, "seed": 0, "plots": False,
         "runs_dir": str(tmp_path)},
        {},
    )  # fmt: skip
    spec = tuning.resolve_storage(cfg.storage, tmp_path)
    study, _ = tuning.create_or_load(tuning.open_storage(spec), "s", cfg, cfg.scenario_list())
    return cfg, spec, study


def test_a_planned_batch_is_created_while_it_is_simulated(tmp_path, monkeypatch):
    """The compass's trials are created by the work handed to the simulation (none exists
    before it starts, all of them once it ends), and each result records its own
    trial's number."""
    cfg, spec, study = _sweep(tmp_path, 24)
    seen: list[tuple[int, int]] = []  # (trials before the work, after it)
    score_many = Objective.score_many

    def spy(self, settings, while_running=None):
        if while_running is None:
            return score_many(self, settings)
        before = len(study.get_trials(deepcopy=False))

        def work() -> None:
            while_running()
            seen.append((before, len(study.get_trials(deepcopy=False))))

        return score_many(self, settings, work)

    monkeypatch.setattr(Objective, "score_many", spy)
    tuning.run_worker(cfg, spec, "s")
    done = study.get_trials(states=(COMPLETE,))
    # The first batch, with the warm starts waiting, is claimed before it is simulated.
    first = len(done) - sum(after - before for before, after in seen)
    assert len(done) == 24 and len(seen) >= 2 and all(a > b for b, a in seen)
    assert 2 < first <= 8, seen
    for t in done:  # each trial holds its own settings' result
        assert tuning.trial_settings(t) == space.settings_from_dict(
            tuning.stored_result(t).settings
        )


def test_a_trial_made_meanwhile_renumbers_the_batch_before_its_results(tmp_path, monkeypatch):
    """Another trial made between the plan and the creation (outside the claim lock):
    the batch's trials are read back with their numbers before the results name them."""
    cfg, spec, study = _sweep(tmp_path, 12)
    score_many = Objective.score_many
    intruded: list[int] = []

    def intrude(self, settings, while_running=None):
        if while_running is not None and not intruded:
            intruded.append(study.ask().number)
            study.tell(intruded[0], state=FAIL)
        return score_many(self, settings, while_running)

    monkeypatch.setattr(Objective, "score_many", intrude)
    report = tuning.run_worker(cfg, spec, "s")
    done = study.get_trials(states=(COMPLETE,))
    assert intruded and len(done) == 12
    # The worker names the trials it ran by their stored numbers, not the planned ones
    # (the intruder took one of those).
    assert sorted(report.trials) == sorted(t.number for t in done)
    assert intruded[0] not in report.trials
    for t in done:
        assert tuning.trial_settings(t) == space.settings_from_dict(
            tuning.stored_result(t).settings
        )


def test_results_name_the_numbers_the_work_beside_the_simulation_gave():
    """``numbers`` as a callable is read after ``while_running`` (which may renumber the
    trials): a later copy of a setting names the trial that simulated it."""
    from vfgym.params import Settings

    obj = Objective(tuning.SweepConfig().scenario_list()[:1], ("ramp",), "cost")
    numbers = [5, 6]
    a, b = Settings(), Settings(k=300.0)
    obj.results(None, lambda: list(numbers), [a, b], lambda: numbers.__setitem__(0, 7))
    (copy,) = obj.results(None, [9], [a])
    assert copy.attrs["cached_from"] == 7


@pytest.mark.parametrize("before_work", [True, False], ids=["before-creation", "after"])
def test_a_failing_simulation_fails_what_it_made_and_frees_the_lock(
    tmp_path, monkeypatch, before_work
):
    """A simulation failing before the trials are created leaves none (the sampler plans
    again); failing after, fails them; either way the claim lock is free and the next
    worker completes the sweep."""
    cfg, spec, study = _sweep(tmp_path, 12)
    score_many = Objective.score_many

    def broken(self, settings, while_running=None):
        if while_running is None:
            return score_many(self, settings)
        if not before_work:
            while_running()
        raise RuntimeError("kernel")

    monkeypatch.setattr(Objective, "score_many", broken)
    with pytest.raises(RuntimeError, match="kernel"):
        tuning.run_worker(cfg, spec, "s")
    states = [t.state for t in study.get_trials(deepcopy=False)]
    assert optuna.trial.TrialState.RUNNING not in states
    assert (FAIL in states) is not before_work
    monkeypatch.undo()
    done = threading.Event()
    worker = threading.Thread(target=lambda: (tuning.run_worker(cfg, spec, "s"), done.set()))
    worker.start()
    worker.join(timeout=120)  # a lock left held would block it
    assert done.is_set()
    assert len(study.get_trials(states=(COMPLETE,))) == 12


def test_an_interrupt_is_held_back_inside_an_allowed_block_where_held():
    with DeferredInterrupt() as interrupts:
        with interrupts.allowed():
            with interrupts.held():
                signal.raise_signal(signal.SIGINT)  # held: no raise here
            assert interrupts.open and interrupts.pending
            with pytest.raises(KeyboardInterrupt):
                signal.raise_signal(signal.SIGINT)  # allowed again: raised at once
        with pytest.raises(KeyboardInterrupt):
            interrupts.check()  # the one held back


def test_once_calls_at_most_once():
    calls: list[int] = []
    f = _batch.once(lambda: calls.append(1))
    f()
    f()
    assert calls == [1]
