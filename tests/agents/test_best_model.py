"""Which evaluation's model becomes a run's best (vfgym.agents.selection.beats): a later
model must beat the best by more than the validation scenarios' spread."""

from __future__ import annotations

import numpy as np
import pytest

from vfgym.agents.selection import SIGNIFICANCE, beats, best_is_start, best_so_far

BEST = np.array([2.0, 3.0, 4.0, 5.0, 2.5, 3.5, 4.5, 1.5])


@pytest.mark.parametrize(
    ("costs", "wins"),
    [
        (BEST * 0.99, True),  # 1 % lower on every scenario: no spread, a real gain
        (BEST, False),  # the same model again
        (BEST * 1.01, False),  # worse
        # lower on average by 0.05, but by +-1 scenario by scenario: noise
        (BEST + np.array([1, -1, 1, -1, 1, -1, 1, -1.4]), False),
        # lower by 0.3 on average, with a spread of 0.2: clear
        (BEST - 0.3 + np.array([0.2, -0.2, 0.2, -0.2, 0.2, -0.2, 0.2, -0.2]), True),
    ],
    ids=["uniform", "same", "worse", "noise", "clear"],
)
def test_a_later_model_replaces_the_best_only_beyond_the_spread(costs, wins):
    assert beats(costs, BEST) is wins


def test_the_first_evaluation_is_the_best_and_the_margin_is_in_standard_errors():
    assert beats(BEST, None)
    diff = np.array([0.1, -0.05, 0.1, -0.05, 0.1, -0.05, 0.1, -0.05])  # mean 0.025
    se = diff.std(ddof=1) / np.sqrt(len(diff))
    z_at = diff.mean() / se
    assert beats(BEST - diff, BEST, z=0.9 * z_at) and not beats(BEST - diff, BEST, z=1.1 * z_at)
    assert SIGNIFICANCE > 0


def test_a_cheaper_model_feasible_on_fewer_pairs_never_replaces_the_best():
    """A model cheaper on the validation pairs because it breaks a limit on some true
    plants does not replace the best (the base, feasible on the axis's design)."""
    ok = np.ones(len(BEST), bool)
    broke = ok.copy()
    broke[3] = False
    assert beats(BEST * 0.9, BEST, feasible=ok, best_feasible=ok)
    assert not beats(BEST * 0.9, BEST, feasible=broke, best_feasible=ok)
    assert beats(BEST * 0.9, BEST, feasible=ok, best_feasible=broke)  # more feasible: fine
    assert beats(BEST * 0.9, BEST)  # feasibility not known: the costs decide


def test_feasibility_is_compared_pair_by_pair_not_by_count():
    """A model feasible on as many pairs as the best, but not on the same ones (it breaks
    a limit on a pair where the best holds), never replaces it, however much cheaper."""
    best_ok = np.ones(len(BEST), bool)
    best_ok[0] = False
    swapped = np.ones(len(BEST), bool)
    swapped[5] = False  # as many feasible pairs, one of them where the best broke a limit
    assert int(swapped.sum()) == int(best_ok.sum())
    assert not beats(BEST * 0.5, BEST, feasible=swapped, best_feasible=best_ok)
    assert beats(BEST * 0.5, BEST, feasible=best_ok, best_feasible=best_ok)


def test_best_is_start_reads_whether_a_later_evaluation_was_shipped(tmp_path):
    assert not best_is_start(tmp_path)  # no evaluation yet
    head = "timesteps,mean_cost,median_cost,best\n"
    (tmp_path / "evaluations.csv").write_text(head + "16,3.0,3.0,1\n20016,2.9,2.9,0\n")
    assert best_is_start(tmp_path)
    (tmp_path / "evaluations.csv").write_text(head + "16,3.0,3.0,1\n20016,2.9,2.9,1\n")
    assert not best_is_start(tmp_path)


def test_a_continued_run_keeps_its_best_and_its_costs(tmp_path):
    assert best_so_far(tmp_path) == (float("inf"), None, None)
    (tmp_path / "evaluations.csv").write_text(
        "timesteps,mean_cost,median_cost,best\n0,3.0,3.0,1\n100,2.9,2.9,0\n200,2.95,2.9,1\n"
    )
    mean, costs, ok = best_so_far(tmp_path)
    assert mean == 2.95 and costs is None and ok is None  # from before the costs were kept
    (tmp_path / "best_model_costs.json").write_text("[2.9, 3.0]")
    mean, costs, ok = best_so_far(tmp_path)
    assert mean == 2.95 and costs.tolist() == [2.9, 3.0] and ok is None
    (tmp_path / "best_model_costs.json").write_text(
        '{"cost": [2.9, 3.0], "feasible": [true, false]}'
    )
    mean, costs, ok = best_so_far(tmp_path)
    assert costs.tolist() == [2.9, 3.0] and ok.tolist() == [True, False]


def test_a_run_folder_is_continued_only_on_the_same_problem(tmp_path):
    """A run folder holding a run with other env arguments (another axis, base or
    interval) is refused in one line naming the keys, never continued as this one."""
    import yaml

    from vfgym.agents.training import check_same_run

    kw = {"axis": "experiments/axes/loads-uncertain.yaml", "residual": True}
    doc = {"algo": "ppo", "env": "vfgym/VFServo-v0", "seed": 0, "hyperparams": {"env_kwargs": kw}}
    (tmp_path / "config.yaml").write_text(yaml.safe_dump(doc | {"observation": "drive"}))
    check_same_run(tmp_path, "ppo", "vfgym/VFServo-v0", 0, dict(kw))  # the same: continued
    with pytest.raises(ValueError, match=r"other env_kwargs \(axis: axis='experiments/axes/"):
        check_same_run(tmp_path, "ppo", "vfgym/VFServo-v0", 0, kw | {"axis": "b.yaml"})
    with pytest.raises(ValueError, match="seed=0, not 1"):
        check_same_run(tmp_path, "ppo", "vfgym/VFServo-v0", 1, kw)
    (tmp_path / "config.yaml").write_text(yaml.safe_dump(doc))  # before the drive's observation
    with pytest.raises(ValueError, match="continuous angle, speed and torque; it is now what"):
        check_same_run(tmp_path, "ppo", "vfgym/VFServo-v0", 0, dict(kw))


def test_a_servo_agent_trained_on_the_simulators_state_is_refused_in_one_line(tmp_path):
    """A VFServo-v0 run saved when its observation held the continuous angle, speed and
    torque (no ``observation: drive`` in its config) is refused, in one line; a VFTune-v0
    run, whose observation did not change, is not."""
    import yaml

    from vfgym.agents import load_agent

    (tmp_path / "best_model.zip").write_bytes(b"not read")
    for env, refused in (("vfgym/VFServo-v0", True), ("vfgym/VFTune-v0", False)):
        doc = {"algo": "ppo", "env": env, "seed": 0, "hyperparams": {}}
        (tmp_path / "config.yaml").write_text(yaml.safe_dump(doc))
        with pytest.raises(ValueError) as err:
            load_agent(tmp_path / "best_model.zip")
        message = str(err.value)
        assert ("train it again" in message) == refused and "\n" not in message


def test_a_gain_below_the_least_share_never_replaces_the_best():
    """0.1 % cheaper on every pair (no spread: far beyond 2 standard errors) is below the
    least gain; 0.6 % is not."""
    assert not beats(BEST * 0.999, BEST)
    assert beats(BEST * 0.994, BEST)
    assert beats(BEST * 0.999, BEST, min_gain=0.0)
