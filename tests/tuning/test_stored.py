"""How a sweep's trials store their results (vfgym.tuning._objective): one user attribute
and one constraints attribute a trial, the one format of a study."""

from __future__ import annotations

import optuna

from vfgym import space, tuning
from vfgym.report._sweep_figures import objective_points
from vfgym.scoring import CONSTRAINTS, OBJECTIVES
from vfgym.tuning._compass import _constraint_name
from vfgym.tuning._objective import RESULT_ATTR
from vfgym.tuning._results import write_trials_csv
from vfgym.tuning._workers import WORKER_ATTR

RESULT = {
    "cost": 2.5,
    "constraints": [-0.1, 0.2, -0.3, -0.4],
    "feasible": False,
    "objectives": [0.0, 1.5, 0.2],
}


def _trial(user_attrs: dict, system_attrs: dict | None = None) -> optuna.trial.FrozenTrial:
    return optuna.trial.create_trial(
        params=tuning.baseline_params(("rise",)),
        distributions=space.distributions(),
        value=2.5,
        user_attrs=user_attrs,
        system_attrs=system_attrs or {},
    )


def test_a_stored_result_reads_back():
    res = tuning.stored_result(_trial({RESULT_ATTR: RESULT | {"settings": {}}}))
    want = tuning.StoredResult({}, 2.5, (-0.1, 0.2, -0.3, -0.4), False, (0.0, 1.5, 0.2), None)
    assert res == want
    assert res.arrives  # arrival, the last constraint, is met
    cached = _trial({RESULT_ATTR: RESULT | {"settings": {}, "cached_from": 3}})
    assert tuning.stored_result(cached).cached_from == 3
    assert tuning.stored_result(_trial({RESULT_ATTR: {"settings": {}}})) is None
    # Results are read from the one attribute only: parts stored apart are not a result.
    assert tuning.stored_result(_trial({**RESULT, "settings": {}})) is None


def test_the_constraints_list_reads_back_by_name():
    values = [-0.1, 0.2, -0.3, -0.4]
    as_list = _trial({}, {"constraints": values})
    named = {_constraint_name(k): v for k, v in as_list.constraints.items()}
    assert named == dict(zip(CONSTRAINTS, values, strict=True))


def _config(tmp_path, trials: int) -> tuning.SweepConfig:
    return tuning.SweepConfig.resolve(
        {"scenarios": ["short-move"], "trials": trials, "seed": 0, "plots": False,
         "runs_dir": str(tmp_path)},
        {},
    )  # fmt: skip


def test_a_new_study_stores_each_result_in_one_attribute_each(tmp_path):
    cfg = _config(tmp_path, 6)
    spec = tuning.resolve_storage(cfg.storage, tmp_path)
    study, created = tuning.create_or_load(tuning.open_storage(spec), "s", cfg, cfg.scenario_list())
    assert created
    tuning.run_worker(cfg, spec, "s")
    done = study.get_trials(states=(optuna.trial.TrialState.COMPLETE,))
    assert len(done) == 6
    for t in done:
        assert set(t.user_attrs) <= {RESULT_ATTR, "baseline", WORKER_ATTR}
        assert set(t.user_attrs[RESULT_ATTR]) <= {"settings", "cost", "constraints", "feasible",
                                                  "objectives", "cached_from"}  # fmt: skip
        assert [k for k in t.system_attrs if k.startswith("constraints")] == ["constraints"]
        res = tuning.stored_result(t)
        assert res.cost == t.value and len(res.objectives) == len(OBJECTIVES)
        assert tuning.trial_settings(t) == space.settings_from_dict(res.settings)
        assert res.feasible == all(c <= 0.0 for c in res.constraints)
        assert list(t.constraints.values()) == list(res.constraints)
    # The trials CSV keeps a column a part, whatever the format.
    path = write_trials_csv(study, tmp_path / "trials.csv")
    header = path.read_text().splitlines()[0].split(",")
    cols = {f"user_attrs_{k}" for k in ("cost", "feasible", "constraints", "settings")}
    assert cols <= set(header)
    assert f"user_attrs_{RESULT_ATTR}" not in header
    # The figures read the objectives from the result.
    names, vals, _, _ = objective_points(study)
    assert names == list(OBJECTIVES) and vals.shape == (6, 3)
