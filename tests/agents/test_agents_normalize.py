"""``normalize`` (VecNormalize saved beside the model and used to act), VecMonitor's episode
statistics, the held-out result a run ends with, and VFServo-v0 agents as schedulers in
``vfgym evaluate --model``."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import yaml

pytest.importorskip("stable_baselines3")

from vfgym.agents import Agent, load_agent, make_env, rollout_info, train, vecnormalize_path
from vfgym.agents import hyperparams as hp
from vfgym.cli import main

REPO = Path(__file__).resolve().parents[2]
TINY = {
    "n_envs": 2,
    "n_steps": 16,
    "batch_size": 32,
    "n_epochs": 1,
    "n_timesteps": 64,
    "eval_freq": 32,
    "n_eval_scenarios": 2,
    "checkpoint_freq": 32,
    "policy_kwargs": {"net_arch": [8]},
}


@pytest.fixture(scope="module")
def servo_run(tmp_path_factory):
    run = tmp_path_factory.mktemp("servo") / "run"
    run.mkdir()
    params = hp.load("ppo", "vfgym/VFServo-v0", hp.HYPERPARAMS_DIR / "ppo.yml", TINY)
    norm = params["normalize"]  # rl-zoo3's form: True, or VecNormalize's arguments
    assert (norm is True or norm["norm_obs"]) and params["env_kwargs"]["residual"] is True
    logs = []
    train("ppo", "vfgym/VFServo-v0", params, run, seed=0, progress=False, log=logs.append)
    return run, logs


def test_normalized_run_saves_its_statistics_and_acts_behind_them(servo_run):
    run, logs = servo_run
    for name in ("vecnormalize.pkl", "final_model_vecnormalize.pkl", "heldout.yaml"):
        assert (run / name).is_file(), name
    assert list((run / "checkpoints").glob("model_vecnormalize_*_steps.pkl"))
    agent = load_agent(run / "best_model.zip")
    assert agent.normalizer is not None and not agent.normalizer.training
    obs = np.full(agent.model.observation_space.shape, 0.5, dtype=np.float32)
    normed = agent.normalizer.normalize_obs(obs)
    assert not np.allclose(normed, obs)
    a1 = agent.act(obs)
    a2, _ = agent.model.predict(normed, deterministic=True)
    np.testing.assert_array_equal(a1, a2)
    held = yaml.safe_load((run / "heldout.yaml").read_text())
    assert held["moves"] == 2 and held["paper_cost"] > 0
    assert held["base"] == "its residual base (model)"  # judged against its own start
    assert any("held-out (2 test moves)" in line for line in logs)


def test_tensorboard_has_episode_returns(servo_run):
    run, _ = servo_run
    events = b"".join(p.read_bytes() for p in (run / "tb").rglob("events.out.tfevents.*"))
    assert b"rollout/ep_rew_mean" in events


def test_vecnormalize_path_names():
    assert vecnormalize_path("r/best_model.zip") == Path("r/vecnormalize.pkl")
    assert vecnormalize_path("r/final_model.zip") == Path("r/final_model_vecnormalize.pkl")
    assert vecnormalize_path("c/model_64_steps.zip") == Path("c/model_vecnormalize_64_steps.pkl")


def test_evaluate_runs_a_servo_agent_as_a_scheduler(servo_run, tmp_path, capsys):
    run, _ = servo_run
    args = ["evaluate", "--model", str(run / "best_model.zip"), "--scenarios",
            "paper-step,short-move", "--against", "paper", "--bootstrap", "10",
            "--runs-dir", str(tmp_path), "--name", "e"]  # fmt: skip
    assert main(args) == 0
    out = capsys.readouterr().out
    assert "agent:best_model" in out
    data = json.loads((tmp_path / "evaluate" / "e" / "results.json").read_text())
    rows = [r for r in data["per_scenario"] if r["controller"] == "agent:best_model"]
    agent = load_agent(run / "best_model.zip")
    env = make_env("vfgym/VFServo-v0", agent.env_kwargs())
    for r in rows:
        assert r["cost"] == rollout_info(agent, env, r["scenario"])["cost"]
    assert len(rows) == 2


def test_load_tuner_gives_a_servo_agent_as_a_scheduler_that_evaluate_judges(servo_run):
    from vfgym import evaluate
    from vfgym.agents import load_tuner
    from vfgym.axis import LOADS_AXIS, NOMINAL, PlantVariant
    from vfgym.scoring import Scheduler

    run, _ = servo_run
    sched = load_tuner(run / "best_model.zip", LOADS_AXIS)  # the axis it was trained on
    assert isinstance(sched, Scheduler) and sched.source.endswith("best_model.zip")
    heavy = PlantVariant(inertia=1.2)
    ev = evaluate(sched, ["short-move", "paper-step"], plants=[heavy])
    agent = load_agent(run / "best_model.zip")
    env = make_env("vfgym/VFServo-v0", agent.env_kwargs())
    for si, name in enumerate(["short-move", "paper-step"]):
        assert ev.cost[0, si] == rollout_info(agent, env, name, NOMINAL)["cost"]
        assert ev.across.cost[0, 0, si] == rollout_info(agent, env, name, heavy)["cost"]
    assert ev.across.cost[0, 0, 0] != ev.cost[0, 0]


def test_a_recurrent_agent_carries_its_memory_through_the_move():
    """``rollout_info`` passes a recurrent policy's LSTM state from each interval to the
    next (reset at the episode's start): the same move as a loop that does so by hand,
    and not the one of a policy that forgets at every interval."""
    from sb3_contrib import RecurrentPPO

    env = make_env("vfgym/VFServo-v0", {"residual": True, "residual_base": "paper"})
    model = RecurrentPPO("MlpLstmPolicy", env, seed=3, device="cpu")
    agent = Agent(model, {}, None, "vfgym/VFServo-v0")

    def by_hand(remember: bool) -> float:
        obs, _ = env.reset(options={"scenario": "paper-step"})
        state, start = None, True
        while True:
            kept = state if remember else None
            a, state = model.predict(obs, kept, np.array([start]), deterministic=True)
            obs, _, term, trunc, info = env.step(a)
            start = not remember
            if term or trunc:
                return info["cost"]

    got = rollout_info(agent, env, "paper-step")["cost"]
    assert got == by_hand(True)
    assert got != by_hand(False)


def test_predict_prints_a_servo_agents_schedule(servo_run, tmp_path, capsys):
    run, _ = servo_run
    out = tmp_path / "s.yaml"
    args = ["predict", "--model", str(run / "best_model.zip"), "--scenario", "short-move",
            "--out", str(out)]  # fmt: skip
    assert main(args) == 0
    doc = yaml.safe_load(out.read_text())
    assert doc["schedule"][0]["from_ms"] == 0.0
    times = [r["from_ms"] for r in doc["schedule"]]
    assert times == sorted(times) and len(set(times)) == len(times)
    agent = load_agent(run / "best_model.zip")
    env = make_env("vfgym/VFServo-v0", agent.env_kwargs())
    assert doc["cost"] == rollout_info(agent, env, "short-move")["cost"]
    assert main([*args[:-2], "--refine", "3"]) == 2
    assert "VFServo-v0 agent" in capsys.readouterr().err


@pytest.mark.parametrize("algo", ["ppo", "sac", "td3", "ppo_lstm"])
def test_a_residual_agent_starts_as_its_base(algo):
    from vfgym import PAPER_SETTINGS, evaluate
    from vfgym.agents.hyperparams import algo_class
    from vfgym.agents.training import start_at_base

    env = make_env("vfgym/VFServo-v0", {"residual": True, "residual_base": "paper"})
    policy = "MlpLstmPolicy" if algo == "ppo_lstm" else "MlpPolicy"
    model = algo_class(algo)(policy, env, seed=0, device="cpu")
    start_at_base(model)
    agent = Agent(model, {}, None, "vfgym/VFServo-v0")
    obs = np.random.default_rng(0).uniform(-3, 3, (4, *env.observation_space.shape))
    assert not np.any(agent.act(obs.astype(np.float32)))
    info = rollout_info(agent, env, "short-move")
    assert info["cost"] == evaluate(PAPER_SETTINGS, "short-move").cost[0, 0]


@pytest.mark.parametrize("algo", ["ppo", "sac", "td3"])
def test_a_residual_vftune_agent_starts_as_the_shipped_model(algo):
    """VFTune-v0 with residual actions on the shipped per-move model: the untrained agent's
    settings are the model's look-up (its best-ranked candidate, unchecked) on every move,
    and ``policy_settings`` reads them so (``model-lookup``)."""
    from dataclasses import replace

    from vfgym.agents import settings_policy
    from vfgym.agents.hyperparams import algo_class
    from vfgym.agents.training import start_at_base
    from vfgym.axis import LOADS_AXIS
    from vfgym.permove.supervised import load_settings_model

    kw = {"residual": True, "residual_base": "model-lookup"}
    env = make_env("vfgym/VFTune-v0", kw)
    model = algo_class(algo)("MlpPolicy", env, seed=0, device="cpu")
    start_at_base(model)
    agent = Agent(model, {"hyperparams": {"env_kwargs": kw}}, None, "vfgym/VFTune-v0")
    shipped = replace(load_settings_model(), check=0)
    pick = settings_policy(agent)
    for name in ("test-0", "test-1", "short-move"):  # on the envs' axis, as the env names them
        assert pick(name) == shipped.settings(LOADS_AXIS.scenario(name), LOADS_AXIS.plant)


@pytest.mark.parametrize("env_id", ["vfgym/VFServo-v0", "vfgym/VFTune-v0"])
def test_the_model_base_is_the_shipped_model_checked_on_the_move(env_id):
    """``residual_base: model`` is the shipped model as ``vfgym predict`` uses it (its
    candidates checked on the move): the zero action costs what ``evaluate`` gives for
    those settings, bit for bit; ``model-lookup`` is its best-ranked candidate, and on a
    move where the two differ the check's is no worse."""
    from dataclasses import replace

    from vfgym import evaluate
    from vfgym.agents import env_options
    from vfgym.axis import LOADS_AXIS as AXIS  # the envs' axis, on which they name the moves
    from vfgym.permove.supervised import load_settings_model

    shipped = load_settings_model()
    assert shipped.check > 1
    lookup = replace(shipped, check=0)
    kw = {"residual": True, "residual_base": "model"}
    env = make_env(env_id, {**kw, **({"interval_s": 0.005} if "Servo" in env_id else {})})
    differ = 0
    for name in ("test-0", "test-5", "test-10", "short-move"):
        sc = AXIS.scenario(name)
        checked = shipped.settings(sc, AXIS.plant)
        assert env_options(kw)["residual_base"](sc, AXIS.plant) == checked
        env.reset(options={"scenario": name})
        while True:
            _, _, term, trunc, info = env.step(np.zeros(4, dtype=np.float32))
            if term or trunc:
                break
        assert info["cost"] == evaluate(checked, sc, axis=AXIS).cost[0, 0]
        plain = evaluate(lookup.settings(sc, AXIS.plant), sc, axis=AXIS)
        if lookup.settings(sc, AXIS.plant) != checked:
            differ += 1
            assert (not plain.feasible[0, 0]) or info["cost"] <= plain.cost[0, 0]
    assert differ >= 2  # the check changed the pick on test-5 and test-10 at least
    with pytest.raises(ValueError, match="model-lookup"):
        env_options({"residual_base": "modle"})


def test_a_vftune_agent_is_a_residual_base_for_vfservo(tmp_path):
    """``residual_base: RUN/best_model.zip``: each move's base is the settings the VFTune-v0
    agent picks for it, so VFServo-v0's zero action costs what those settings cost."""
    from vfgym import evaluate
    from vfgym.agents import env_options, policy_settings
    from vfgym.axis import LOADS_AXIS

    params = hp.load("ppo", "vfgym/VFTune-v0", hp.HYPERPARAMS_DIR / "ppo.yml", TINY)
    train("ppo", "vfgym/VFTune-v0", params, tmp_path, seed=0, progress=False, log=lambda m: None)
    zip_path = str(tmp_path / "best_model.zip")
    kw = {"residual": True, "residual_base": zip_path, "interval_s": 0.005}
    env = make_env("vfgym/VFServo-v0", kw)
    pick = policy_settings(zip_path)
    for name in ("test-2", "short-move"):
        env.reset(options={"scenario": name})
        while True:
            _, _, term, trunc, info = env.step(np.zeros(4, dtype=np.float32))
            if term or trunc:
                break
        sc = LOADS_AXIS.scenario(name)  # the envs' axis names the move
        assert info["cost"] == evaluate(pick(name), sc, axis=LOADS_AXIS).cost[0, 0]
    with pytest.raises(ValueError, match="VFTune-v0 agent"):
        env_options({"residual_base": "nowhere.zip"})
