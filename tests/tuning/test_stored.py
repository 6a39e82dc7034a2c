"""How a sweep's trials store their results (vfgym.tuning._stored): one user attribute
and one constraints attribute a trial; studies made before that read and resumed as they
are."""

from __future__ import annotations

import optuna
import pytest

from vfgym import space, tuning
from vfgym.report._sweep_figures import objective_points
from vfgym.scoring import CONSTRAINTS, OBJECTIVES
from vfgym.tuning._stored import FORMAT, FORMAT_KEY, RESULT_ATTR, named_constraints
from vfgym.tuning._study import META_KEY, study_meta

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


@pytest.mark.parametrize(
    "user_attrs",
    [
        {RESULT_ATTR: RESULT | {"settings": {}}},  # format 2
        {**RESULT, "settings": {}},  # format 1: a user attribute a part
    ],
    ids=["result", "parts"],
)
def test_both_formats_read_as_the_same_result(user_attrs):
    res = tuning.stored_result(_trial(user_attrs))
    want = tuning.StoredResult({}, 2.5, (-0.1, 0.2, -0.3, -0.4), False, (0.0, 1.5, 0.2), None)
    assert res == want
    assert res.arrives  # arrival, the last constraint, is met
    cached = _trial(user_attrs | {"cached_from": 3} if "cost" in user_attrs else user_attrs)
    if "cost" in user_attrs:
        assert tuning.stored_result(cached).cached_from == 3
    assert tuning.stored_result(_trial({"settings": {}})) is None


def test_named_constraints_reads_the_list_and_the_named_form():
    values = [-0.1, 0.2, -0.3, -0.4]
    as_list = _trial({}, {"constraints": values})
    named = _trial({}, {f"constraints:{n}": v for n, v in zip(CONSTRAINTS, values, strict=True)})
    assert named_constraints(as_list) == named_constraints(named)
    assert named_constraints(as_list) == dict(zip(CONSTRAINTS, values, strict=True))


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
    assert created and study.user_attrs[FORMAT_KEY] == FORMAT
    tuning.run_worker(cfg, spec, "s")
    done = study.get_trials(states=(optuna.trial.TrialState.COMPLETE,))
    assert len(done) == 6
    for t in done:
        assert set(t.user_attrs) <= {RESULT_ATTR, "baseline", tuning.WORKER_ATTR}
        assert set(t.user_attrs[RESULT_ATTR]) <= {"settings", "cost", "constraints", "feasible",
                                                  "objectives", "cached_from"}  # fmt: skip
        assert [k for k in t.system_attrs if k.startswith("constraints")] == ["constraints"]
        res = tuning.stored_result(t)
        assert res.cost == t.value and len(res.objectives) == len(OBJECTIVES)
        assert tuning.trial_settings(t) == space.settings_from_dict(res.settings)
        assert res.feasible == all(c <= 0.0 for c in res.constraints)
        assert list(t.constraints.values()) == list(res.constraints)
    # The trials CSV keeps a column a part, whatever the format.
    path = tuning.write_trials_csv(study, tmp_path / "trials.csv")
    header = path.read_text().splitlines()[0].split(",")
    cols = {f"user_attrs_{k}" for k in ("cost", "feasible", "constraints", "settings")}
    assert cols <= set(header)
    assert f"user_attrs_{RESULT_ATTR}" not in header
    # The figures read the objectives from the result.
    names, vals, _, _ = objective_points(study)
    assert names == list(OBJECTIVES) and vals.shape == (6, 3)


def test_a_study_made_before_the_format_goes_on_in_its_own(tmp_path):
    """A study without the format attribute (made by an earlier vfgym) is resumed writing
    its results a part an attribute and its constraints by name, so that every trial of
    it has the same constraint keys (Optuna's GP sampler requires it)."""
    cfg = _config(tmp_path, 4)
    spec = tuning.resolve_storage(cfg.storage, tmp_path)
    storage = tuning.open_storage(spec)
    study = optuna.create_study(study_name="s", storage=storage)
    from dataclasses import asdict

    study.set_user_attr(META_KEY, asdict(study_meta(cfg, cfg.scenario_list())))
    study.enqueue_trial(tuning.baseline_params(cfg.laws))
    tuning.run_worker(cfg, spec, "s")
    done = study.get_trials(states=(optuna.trial.TrialState.COMPLETE,))
    assert len(done) == 4 and FORMAT_KEY not in study.user_attrs
    for t in done:
        assert RESULT_ATTR not in t.user_attrs and "cost" in t.user_attrs
        assert "settings" in t.user_attrs
        keys = sorted(k for k in t.system_attrs if k.startswith("constraints"))
        assert keys == sorted(f"constraints:{n}" for n in CONSTRAINTS)
        assert tuning.stored_result(t).cost == t.value
    assert tuning.best_trial(study) is not None


@pytest.mark.filterwarnings("ignore:Heartbeat of storage")
def test_trials_made_meanwhile_are_read_back_and_the_compass_plans_again(tmp_path):
    """The compass's trials are made with the numbers it planned; when another trial was
    made meanwhile (outside the claim lock), the batch's numbers are read back from the
    storage and the next plan reads the study again."""
    from vfgym.tuning._batch import one_write

    cfg = _config(tmp_path, 4)
    spec = tuning.resolve_storage(cfg.storage, tmp_path)
    storage = tuning.open_storage(spec)
    study, _ = tuning.create_or_load(storage, "s", cfg, cfg.scenario_list())
    study.ask()  # the first warm start, taken
    study.ask()  # the second
    sampler = tuning.make_sampler(cfg, 0, cfg.scenario_list(), storage)
    study = optuna.load_study(study_name="s", storage=storage, sampler=sampler)
    maker = one_write(sampler, storage, storage.get_study_id_from_name("s"), FORMAT)
    assert maker is not None
    first, _ = maker.make(study, True, cfg.laws)
    study.ask()  # another worker's trial, made between the two
    second, _ = maker.make(study, False, cfg.laws)
    planned = [first.number, second.number]
    maker.check([first, second])
    stored = [storage.get_trial(m.trial_id).number for m in (first, second)]
    assert [first.number, second.number] == stored and stored != planned
    third, _ = maker.make(study, False, cfg.laws)  # planned from the study again
    assert storage.get_trial(third.trial_id).number == third.number


@pytest.mark.parametrize(
    ("names", "fmt", "keys"),
    [
        (CONSTRAINTS, 2, ["constraints"]),  # one list, in CONSTRAINTS' order
        (CONSTRAINTS, 1, [f"constraints:{n}" for n in CONSTRAINTS]),  # a study made before
        (("edge",), 2, ["constraints:edge"]),  # other names: each by name
    ],
    ids=["list", "format-1", "other-names"],
)
def test_constraint_writes_by_format_and_names(names, fmt, keys):
    from vfgym.tuning._stored import constraint_writes

    values = {n: -0.5 * i for i, n in enumerate(names)}
    writes = constraint_writes(values, fmt)
    assert [k for k, _ in writes] == keys
    flat = [x for _, v in writes for x in (v if isinstance(v, list) else [v])]
    assert flat == list(values.values())
