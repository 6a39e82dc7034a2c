"""The compass sampler's search steps (no simulation: synthetic observations)."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import pytest

from vfgym.tuning._model import Observation


def _run(options, seed: int, trials: int):
    """A compass study on a synthetic cost falling along u0 + u1 behind the edge
    u1 − u0 ≤ 0.05 (unit coordinates of :class:`vfgym.space.Relative`)."""
    import optuna

    from vfgym import space
    from vfgym.params import Settings
    from vfgym.tuning._compass import CompassSampler
    from vfgym.tuning._objective import set_constraints

    rel = space.Relative(430.0)
    storage = optuna.storages.InMemoryStorage()
    sampler = CompassSampler(rel, seed=seed, options=options, storage=storage)
    study = optuna.create_study(sampler=sampler, storage=storage)
    study.enqueue_trial({"value_rad": 1.0, "error_limit_rad": 1.0, "k": 430.0, "ts_over_tf": 0.25})

    def objective(trial: optuna.Trial) -> float:
        s = space.suggest(trial)
        u = rel.to_unit(Settings(**{d.name: getattr(s, d.name) for d in space.SPACE}))
        set_constraints(trial, {"edge": float(u[1] - u[0] - 0.05)})
        return float(np.exp(2.0 - (u[0] + u[1]) + (u[2] - 0.5) ** 2 + (u[3] - 0.8) ** 2))

    optuna.logging.set_verbosity(optuna.logging.WARNING)
    study.optimize(objective, n_trials=trials)
    return study


def test_each_drawn_trial_records_its_generation_and_a_seed_draws_the_same_trials():
    # The generations are on the trials (a resumed or shared study continues the search).
    from vfgym.tuning._compass import ATTR, CompassOptions

    first = _run(CompassOptions(), seed=2, trials=40)
    again = _run(CompassOptions(), seed=2, trials=40)
    assert [(t.params, t.value) for t in first.trials] == [
        (t.params, t.value) for t in again.trials
    ]
    drawn = [t for t in first.trials if "fixed_params" not in t.system_attrs]
    assert all(ATTR in t.system_attrs for t in drawn)
    assert {"init", "compass"} <= {t.system_attrs[ATTR]["mode"] for t in drawn}


def test_diagonal_polls_move_value_and_the_limit_ratio_together():
    # The fifth poll direction keeps L/value² (the tail's deceleration at top speed) fixed:
    # log value and log L/value move by the same step, k and Ts/Tf not at all.
    from vfgym import space
    from vfgym.tuning._compass import ATTR, CompassOptions

    study = _run(CompassOptions(), seed=0, trials=40)
    lo, hi = space.Relative(430.0).bounds()[:2].T
    by_number = {t.number: t.params for t in study.trials}
    diag = [
        t for t in study.trials if t.system_attrs.get(ATTR, {}).get("role", "")[:7] == "axis:4:"
    ]
    assert len(diag) >= 4
    checked = 0
    for t in diag:
        p, c = t.params, by_number[t.system_attrs[ATTR]["centre"]]
        dv = np.log(p["value_rad"] / c["value_rad"])
        dr = np.log(p["error_limit_rad"] / p["value_rad"] / (c["error_limit_rad"] / c["value_rad"]))
        x = np.log([p["value_rad"], p["error_limit_rad"] / p["value_rad"]])
        if (
            np.any(x <= lo + 1e-9)
            or np.any(x >= hi - 1e-9)
            or not 0.05 < p["error_limit_rad"] < 10.0
        ):
            continue  # a poll clipped to the search box moves one coordinate only
        checked += 1
        assert abs(dv) > 0.01 and dv == pytest.approx(dr, abs=1e-9)
        assert p["k"] == pytest.approx(c["k"]) and p["ts_over_tf"] == pytest.approx(c["ts_over_tf"])
    assert checked >= 2


@pytest.mark.parametrize(
    ("moved", "mode"),
    [
        (True, "compass"),  # a compass that moved goes on past its budget
        (False, "model"),  # one that did not move stops at its budget
    ],
)
def test_a_moving_compass_goes_on_past_its_budget(moved, mode):
    from vfgym import space
    from vfgym.tuning._compass import ATTR, CompassOptions, CompassSampler

    opts = CompassOptions(compass_trials=8)
    sampler = CompassSampler(space.Relative(430.0), seed=0, options=opts)
    mid = sampler._lo + 0.5 * sampler._span
    ok = np.array([-1.0])
    obs = [Observation(0, mid, "rise", 1.0, 0.0, True, ok)]
    for i in range(8):  # one generation of axis polls, the first better if the compass moved
        x = mid + (1 if i % 2 == 0 else -1) * opts.step0 * np.eye(4)[i // 2]
        cost = 0.9 if (moved and i == 0) else 1.1
        obs.append(Observation(i + 1, x, "rise", cost, 0.0, True, ok))
    tags = [
        {"gen": 3, "mode": "compass", "role": f"axis:{i // 2}:{1 if i % 2 == 0 else -1:+d}",
         "centre": 0, "steps": [opts.step0] * 4, "since": 0}
        for i in range(8)
    ]  # fmt: skip
    tagged = [_Trial(i + 1, {ATTR: t}) for i, t in enumerate(tags)]
    plan = sampler._generation(obs, tagged, 3)
    assert plan[0]["tag"]["mode"] == mode


@pytest.mark.parametrize(
    ("cons", "expected"),
    [
        # each broken constraint alone; one never broken is left out
        ([[-1.0, 0.5, -2.0], [0.2, -0.5, -1.0]], [[-1.0, 0.2], [0.5, -0.5]]),
        # none broken: no feasibility model
        ([[-1.0, -0.5], [-0.2, 0.0]], []),
    ],
)
def test_constraint_targets(cons, expected):
    from vfgym.tuning._model import _constraint_models

    got = _constraint_models(np.array(cons))
    assert [list(c) for _, c in got] == expected


def test_one_feasibility_model_per_broken_constraint():
    from vfgym.tuning._model import _fit

    x = np.random.default_rng(3).uniform(0.0, 1.0, (30, 4))
    obs = []
    for i, u in enumerate(x):
        g = np.array([u[0] - 0.7, 0.3 - u[1], -1.0])  # the third never broken
        v = float(np.maximum(g, 0.0).sum())
        obs.append(Observation(i, u, "rise", float(1.0 + u @ u), v, v <= 0.0, g))
    assert len(_fit(x, obs, 0.0).cgps) == 2


class _Trial(NamedTuple):
    number: int
    system_attrs: dict


@pytest.mark.parametrize(
    ("cost", "far", "mode"),
    [
        (1.05, True, "compass"),  # another basin's point nearly as good: searched
        (1.2, True, "model"),  # too much worse: the model again
        (1.05, False, "model"),  # near the centre: its basin, already searched
        (0.9, False, "model"),  # better: the centre, and (steps converged) the model from it
    ],
)
def test_a_model_point_of_another_basin_gets_a_compass(cost, far, mode):
    from vfgym import space
    from vfgym.tuning._compass import ATTR, CompassOptions, CompassSampler

    opts = CompassOptions()
    sampler = CompassSampler(space.Relative(430.0), seed=0, options=opts)
    mid = sampler._lo + 0.5 * sampler._span
    away = mid + np.array([1.0, -1.0, 0.0, 0.0]) * (3.0 if far else 1.0) * opts.step0
    obs = [
        Observation(0, mid, "rise", 1.0, 0.0, True, np.array([-1.0])),
        Observation(1, away, "rise", cost, 0.0, True, np.array([-1.0])),
        Observation(2, mid + 0.1, "rise", 5.0, 0.0, True, np.array([-1.0])),
    ]
    # The compass before the model converged (steps below resume_floor): with steps left
    # it would go on from the centre whatever the model found.
    tag = {"gen": 4, "mode": "model", "role": "model", "centre": 0, "steps": [0.02] * 4,
           "since": 0}  # fmt: skip
    tagged = [_Trial(n, {ATTR: tag}) for n in (1, 2)]
    plan = sampler._generation(obs, tagged, 4)
    assert plan[0]["tag"]["mode"] == mode
    if mode == "compass" or cost < 1.0:
        assert plan[0]["tag"]["centre"] == 1


@pytest.mark.parametrize(
    ("steps", "mode"),
    [
        (0.2, "compass"),  # cut short by its budget: the compass goes on, same steps
        (0.05, "compass"),  # below min_step, above resume_floor: goes on too
        (0.02, "model"),  # below resume_floor: converged, the model again
    ],
)
def test_a_compass_cut_short_goes_on_after_a_model_batch(steps, mode):
    from vfgym import space
    from vfgym.tuning._compass import ATTR, CompassOptions, CompassSampler

    opts = CompassOptions()
    sampler = CompassSampler(space.Relative(430.0), seed=0, options=opts)
    mid = sampler._lo + 0.5 * sampler._span
    ok = np.array([-1.0])
    obs = [Observation(0, mid, "rise", 1.0, 0.0, True, ok)]
    obs += [Observation(n, mid + 0.3 * n, "rise", 2.0, 0.0, True, ok) for n in (1, 2)]
    tag = {"gen": 6, "mode": "model", "role": "model", "centre": 0, "steps": [steps] * 4,
           "since": 0}  # fmt: skip
    plan = sampler._generation(obs, [_Trial(n, {ATTR: tag}) for n in (1, 2)], 6)
    assert {p["tag"]["mode"] for p in plan} == {mode}
    if mode == "compass":
        assert plan[0]["tag"]["centre"] == 0 and plan[0]["tag"]["steps"] == [steps] * 4
        moved = [np.abs(p["x"] - mid).max() for p in plan]
        assert np.allclose(moved, steps)
