"""Every sampler through the sweep's worker: the same seed with one worker gives the same
trials twice; a sweep whose first trials are all infeasible ends with a feasible best and
never reports an infeasible one as best once a feasible one exists."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import optuna
import pytest

from vfgym import tuning
from vfgym.params import Settings
from vfgym.scoring import evaluate
from vfgym.tuning._study import SAMPLER_NEEDS

# Infeasible on short-move (the pulse train's acceleration over the limit) and cheaper than
# any feasible setting of a short sweep (cost 5.19 at k = 54; found by a random scan).
CHEAP_BUT_TOO_FAST = Settings(
    value_rad=0.277763948606789,
    error_limit_rad=0.09707742204314096,
    k=54.057381349313445,
    ts_over_tf=0.9112492013983532,
)
EARLY = [dataclasses.replace(CHEAP_BUT_TOO_FAST, k=k) for k in (54.057381349313445, 40.0, 30.0)]
EARLY += [dataclasses.replace(s, ts_over_tf=0.7) for s in EARLY]


def _samplers() -> list:
    out = []
    for name in tuning.SAMPLERS:
        needs = SAMPLER_NEEDS.get(name, ())
        slow = name == "gp"  # a trial takes seconds: fewer of them
        out.append(pytest.param(name, 10 if slow else 24, id=name, marks=_needs(needs)))
    return out


def _needs(modules: tuple[str, ...]) -> list:
    import importlib.util

    missing = [m for m in modules if importlib.util.find_spec(m) is None]
    return [pytest.mark.skip(reason=f"needs {missing}")] if missing else []


def _config(tmp_path: Path, sampler: str, trials: int, seed: int) -> tuning.SweepConfig:
    return tuning.SweepConfig(
        scenarios="short-move",
        sampler=sampler,
        objective="cost",
        trials=trials,
        seed=seed,
        grid_points=3,
        storage=f"sqlite:///{tmp_path}/study.db",
        progress=False,
        plots=False,
    )


def _run(tmp_path: Path, sampler: str, trials: int, seed: int) -> list[tuple]:
    tmp_path.mkdir(parents=True, exist_ok=True)
    cfg = _config(tmp_path, sampler, trials, seed)
    spec = tuning.resolve_storage(cfg.storage, tmp_path)
    tuning.create_or_load(tuning.open_storage(spec), "s", cfg, cfg.scenario_list())
    tuning.run_worker(cfg, spec, "s")
    study = optuna.load_study(study_name="s", storage=tuning.open_storage(spec))
    return [(t.number, t.params, t.value, t.state) for t in study.get_trials(deepcopy=False)]


@pytest.mark.parametrize(("sampler", "trials"), _samplers())
def test_same_seed_one_worker_gives_the_same_trials_twice(tmp_path, sampler, trials):
    a = _run(tmp_path / "a", sampler, trials, seed=3)
    b = _run(tmp_path / "b", sampler, trials, seed=3)
    assert len(a) == trials and a == b
    if sampler != "grid":  # the grid's order is the seed's, its points are not
        c = _run(tmp_path / "c", sampler, trials, seed=4)
        assert [t[1] for t in a] != [t[1] for t in c]


@pytest.mark.parametrize(("sampler", "trials"), _samplers())
def test_early_infeasible_trials_never_make_the_best(tmp_path, sampler, trials):
    scen = _config(tmp_path, sampler, trials, 0).scenario_list()
    ev = evaluate(EARLY, scen)
    assert (np.nanmax(ev.constraints, axis=(1, 2)) > 0).all()  # every early one infeasible

    cfg = _config(tmp_path, sampler, trials + len(EARLY), seed=0)
    spec = tuning.resolve_storage(cfg.storage, tmp_path)
    study = optuna.create_study(study_name="s", storage=tuning.open_storage(spec))
    for s in EARLY:  # in place of the warm starts (the paper's is feasible here)
        study.enqueue_trial(tuning.baseline_params(cfg.laws, s))
    seen: list[tuple[bool, bool]] = []

    def look(st: optuna.Study) -> None:
        done = st.get_trials(deepcopy=False, states=(optuna.trial.TrialState.COMPLETE,))
        best = tuning.best_trial(st)
        any_feasible = any(_feasible(t) for t in done)
        seen.append((any_feasible, best is not None and _feasible(best)))

    tuning.run_worker(cfg, spec, "s", on_trial=look)
    done = study.get_trials(deepcopy=False, states=(optuna.trial.TrialState.COMPLETE,))
    assert len(done) == trials + len(EARLY)
    assert not any(_feasible(t) for t in done[: len(EARLY)])
    assert all(best_ok for any_ok, best_ok in seen if any_ok)
    best = tuning.best_trial(study)
    assert best is not None and _feasible(best), sampler
    assert best.number >= len(EARLY)


def test_compass_k_reference_is_the_loaded_motors_usable_k():
    """The compass searches k relative to the loaded motor's usable acceleration's k (the
    rule of thumb's), not the stated limit's: on heavy-load (5 rotor inertias) ≈ 4.7x it."""
    from vfgym.moves.baselines import rule_of_thumb
    from vfgym.params import paper_k, usable_k
    from vfgym.tuning._study import relative_space

    (heavy,) = tuning.SweepConfig(scenarios="heavy-load").scenario_list()
    plant = heavy.plant()
    rel = relative_space([heavy])
    assert rel.k_ref == pytest.approx(usable_k(plant)) == pytest.approx(rule_of_thumb(plant).k)
    assert rel.k_ref == pytest.approx(
        paper_k(plant) * plant.motor.accel_limit_rad_s2 / plant.motor.usable_accel_rad_s2
    )
    assert rel.k_ref > 4.0 * paper_k(plant)
    (step,) = tuning.SweepConfig(scenarios="paper-step").scenario_list()
    assert relative_space([step]).k_ref == pytest.approx(paper_k(step.plant()))  # bare motor
    # A set's reference: the geometric mean over its plants.
    both = relative_space([heavy, step]).k_ref
    assert both == pytest.approx((usable_k(plant) * paper_k(step.plant())) ** 0.5)


def test_the_compass_needs_the_studys_storage():
    cfg = tuning.SweepConfig(scenarios="paper-step")
    with pytest.raises(ValueError, match="storage"):
        tuning.make_sampler(cfg, 0)
    storage = optuna.storages.InMemoryStorage()
    assert tuning.make_sampler(cfg, 0, storage=storage).storage is storage


def _feasible(trial: optuna.trial.FrozenTrial) -> bool:
    res = tuning.stored_result(trial)
    return res is not None and res.feasible
