"""A residual agent starts as its base, exactly: ``train`` zeroes the policy's action
output at creation, so the first evaluation (before any update) scores each validation
(move, true plant) pair as the base does; the zeroed layer still learns. A run where no
later model beats the start ships the start and says so in one line."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("stable_baselines3")

from vfgym import PAPER_SETTINGS, evaluate
from vfgym.agents import hyperparams as hp
from vfgym.agents import make_env
from vfgym.agents.selection import validation_plants, validation_scenarios, validation_size
from vfgym.agents.training import start_at_base, train
from vfgym.axis import load_axis

REPO = Path(__file__).resolve().parents[2]
AXIS = REPO / "experiments" / "axes" / "loads-uncertain.yaml"
ONE_EVAL = {  # one rollout of 2 x 16 steps: the only evaluation is the one before any update
    "n_envs": 2,
    "n_steps": 16,
    "batch_size": 32,
    "n_epochs": 1,
    "n_timesteps": 32,
    "eval_freq": 10_000,
    "n_eval_scenarios": 2,
    "n_eval_scenarios_uncertain": 3,
    "checkpoint_freq": 10_000,
    "policy_kwargs": {"net_arch": [8]},
}


@pytest.mark.parametrize("env_id", ["vfgym/VFServo-v0", "vfgym/VFTune-v0"])
def test_the_first_evaluation_costs_what_the_base_costs_on_each_validation_pair(env_id, tmp_path):
    """On the uncertain axis, with the paper's settings as the residual base: the first
    evaluation's cost on each of the ``n_eval_scenarios_uncertain`` validation pairs is
    ``evaluate``'s cost of the base on that move and true plant, to 1e-12; with no later
    evaluation, best_model.zip is the start and the log says so."""
    kw = {"residual": True, "residual_base": "paper", "axis": str(AXIS)}
    if "Servo" in env_id:
        kw["interval_s"] = 0.005
    params = hp.load("ppo", env_id, hp.HYPERPARAMS_DIR / "ppo.yml", ONE_EVAL | {"env_kwargs": kw})
    logs: list[str] = []
    train("ppo", env_id, params, tmp_path, seed=0, progress=False, log=logs.append)
    doc = json.loads((tmp_path / "best_model_costs.json").read_text())
    assert len(doc["cost"]) == 3  # the uncertain axis's count, not n_eval_scenarios
    axis = load_axis(AXIS)
    moves, plants = validation_scenarios(3, axis), validation_plants(3, axis)
    pairs = zip(doc["cost"], doc["feasible"], moves, plants, strict=True)
    for cost, feasible, move, plant in pairs:
        ev = evaluate(PAPER_SETTINGS, [move], axis=axis, plants=[plant]).across
        assert cost == pytest.approx(float(ev.cost[0].ravel()[0]), rel=0, abs=1e-12)
        assert feasible == bool(ev.feasible[0].ravel()[0])
    said = [m for m in logs if m.startswith("no later model beat the start")]
    assert len(said) == 1 and "its residual base itself" in said[0]


@pytest.mark.parametrize("algo", ["ppo", "sac", "td3"])
def test_the_shipped_vftune_start_is_what_vfgym_predict_gives(algo):
    """With the shipped hyperparameters a VFTune-v0 agent's base, hence its start, is the
    shipped settings model as ``vfgym predict`` uses it (its candidates checked on the
    move), setting for setting, on train and held-out moves."""
    from vfgym.moves.distribution import random_scenario
    from vfgym.permove import load_tuner

    env = make_env("vfgym/VFTune-v0", hp.load(algo, "vfgym/VFTune-v0")["env_kwargs"])
    predict = load_tuner(None)
    for sc in [random_scenario(3, "train"), *(random_scenario(i, "test") for i in range(4))]:
        assert env.unwrapped.config.base_settings(sc) == predict(sc), sc.name


def test_validation_size_is_larger_on_an_uncertain_axis():
    params = {"n_eval_scenarios": 32, "n_eval_scenarios_uncertain": 256}
    assert validation_size(params) == 32
    assert validation_size(params, str(AXIS)) == 256
    exact = REPO / "experiments" / "axes" / "loads.yaml"
    assert load_axis(exact).uncertainty.exact and validation_size(params, str(exact)) == 32
    shipped = hp.load("ppo", "vfgym/VFServo-v0")
    assert validation_size(shipped, str(AXIS)) == shipped["n_eval_scenarios_uncertain"] == 256
    assert validation_size({"n_eval_scenarios": 5}, str(AXIS)) == 5  # no key: the same count


def test_the_zeroed_policy_keeps_its_std_and_value_net_and_still_learns():
    """start_at_base touches only the action output: the std, the value net and the hidden
    layers are as made, so the zeroed layer's gradient (the hidden activations times the
    advantage) is not zero, and a few hundred PPO steps move it off zero."""
    import torch
    from stable_baselines3 import PPO

    env = make_env("vfgym/VFTune-v0", {"residual": True, "residual_base": "paper"})
    model = PPO("MlpPolicy", env, n_steps=64, batch_size=32, n_epochs=2, seed=0, device="cpu")
    before = {k: v.clone() for k, v in model.policy.state_dict().items()}
    start_at_base(model)
    after = model.policy.state_dict()
    for key, value in before.items():
        if key.startswith("action_net."):
            assert not torch.any(after[key])
        else:
            assert torch.equal(after[key], value), key
    model.learn(256)
    assert torch.any(model.policy.action_net.weight != 0)
    obs = np.zeros((1, *env.observation_space.shape), dtype=np.float32)
    assert np.any(model.predict(obs, deterministic=True)[0] != 0)
