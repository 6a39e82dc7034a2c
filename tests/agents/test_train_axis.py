"""``vfgym train --axis FILE``: the environments get the axis through ``env_kwargs``, the
held-out validation moves come from its train move set, and ``predict --axis`` resolves
the axis's moves."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

pytest.importorskip("stable_baselines3")

from vfgym.agents import load_tuner, policy_settings
from vfgym.agents.hyperparams import HYPERPARAMS_DIR
from vfgym.agents.selection import VALIDATION_SEED0, validation_scenarios
from vfgym.axis import load_axis
from vfgym.cli import main
from vfgym.commands._common import load_settings
from vfgym.permove.supervised import PRETRAINED

REPO = Path(__file__).resolve().parents[2]
SMALL = {
    "plant": {"motor": {"inertia_ratio": 2.0}},
    "moves": {
        "train": {"random": {"count": 2, "distance_rad": [0.2, 1.0], "settle_s": 0.02}},
        "test": [{"name": "up", "profile": "trapezoid", "distance_rad": 1.5, "duration_s": 0.05}],
    },
}


def _own_model(runs: Path, name: str = "small") -> Path:
    """A settings model where ``vfgym fit --axis small.yaml --name small`` writes it (the
    shipped one's copy: a fit takes minutes)."""
    own = runs / "fit" / name / "settings_model.json"
    own.parent.mkdir(parents=True)
    own.write_bytes(PRETRAINED.read_bytes())
    return own


def test_train_on_an_axis_starts_from_the_axis_own_model_or_says_how_to_make_it(tmp_path, capsys):
    path = tmp_path / "small.yaml"
    path.write_text(yaml.safe_dump(SMALL))
    args = ["train", "--algo", "ppo", "--axis", str(path), "--runs-dir", str(tmp_path),
            "--name", "m", "--no-progress", "--hyperparams", "n_timesteps=32", "n_envs=4",
            "n_steps=8", "batch_size=16", "eval_freq=16", "n_eval_scenarios=2"]  # fmt: skip
    assert main(args) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "this axis's settings model" in err
    assert f"vfgym fit --axis {path} --name small" in err
    assert not (tmp_path / "train").exists()
    own = _own_model(tmp_path)
    assert main(args) == 0
    cfg = yaml.safe_load((tmp_path / "train" / "m" / "config.yaml").read_text())
    assert cfg["hyperparams"]["env_kwargs"]["residual_base"] == f"model:{own}"


def test_validation_moves_come_from_the_axis_train_set(tmp_path):
    path = tmp_path / "small.yaml"
    path.write_text(yaml.safe_dump(SMALL))
    axis = load_axis(path)
    got = validation_scenarios(3, str(path))
    assert got == [axis.moves.train.random.draw(VALIDATION_SEED0 + i, "train", axis.plant)
                   for i in range(3)]  # fmt: skip
    assert all(0.2 <= abs(s.distance_rad) <= 1.0 for s in got)


def test_cli_train_on_an_axis_then_predict_on_it(tmp_path, capsys):
    path = tmp_path / "small.yaml"
    path.write_text(yaml.safe_dump(SMALL))
    _own_model(tmp_path)
    args = ["train", "--algo", "ppo", "--axis", str(path), "--runs-dir", str(tmp_path)]
    args += ["--name", "t", "--no-progress", "--hyperparams-file",
             str(HYPERPARAMS_DIR / "ppo.yml"), "--hyperparams", "n_timesteps=32",
             "n_envs=4", "n_steps=8", "batch_size=16", "eval_freq=16",
             "n_eval_scenarios=2"]  # fmt: skip
    assert main(args) == 0
    run = tmp_path / "train" / "t"
    cfg = yaml.safe_load((run / "config.yaml").read_text())
    assert cfg["hyperparams"]["env_kwargs"]["axis"] == str(path)
    out = tmp_path / "s.yaml"
    capsys.readouterr()
    model = str(run / "best_model.zip")
    assert main(["predict", "--model", model, "--axis", str(path), "--scenario", "up",
                 "--out", str(out)]) == 0  # fmt: skip
    assert yaml.safe_load(capsys.readouterr().out)["scenario"] == "up"
    # the agent's own config names the axis: predicting without --axis resolves the same
    assert policy_settings(model)("up") == load_settings(str(out), load_axis(path))
    # as a tuner: quiet on a move like its training draws, one line on a longer one
    seen: list[str] = []
    tuner = load_tuner(model, path, warn=seen.append)
    tuner(load_axis(path).moves.train.random.draw(12345, "train", load_axis(path).plant))
    assert seen == []
    assert tuner("up") == load_settings(str(out), load_axis(path))
    assert len(seen) == 1 and "is outside its training moves (log_distance" in seen[0], seen
    # a bad axis file fails before a run folder is made
    bad = tmp_path / "bad.yaml"
    bad.write_text(yaml.safe_dump({"measures": {"in_position_counts": -1}}))
    bad_args = [str(bad) if a == str(path) else a for a in args]
    bad_args[bad_args.index("--runs-dir") + 1] = str(tmp_path / "x")
    capsys.readouterr()
    assert main(bad_args) == 2
    err = capsys.readouterr().err.strip()
    assert f"{bad}: measures.in_position_counts=-1 is out of range" in err
    assert not (tmp_path / "x").exists()


def test_train_on_an_axis_ends_with_fits_verdict(tmp_path, capsys):
    """The run's best model judged as ``vfgym fit`` judges its model: against the best
    fixed setting of a sweep on the axis's train moves, the paper's and the S-curve."""
    path = tmp_path / "small.yaml"
    path.write_text(yaml.safe_dump(SMALL))
    _own_model(tmp_path)
    args = ["train", "--algo", "ppo", "--axis", str(path), "--runs-dir", str(tmp_path),
            "--name", "v", "--no-progress", "--hyperparams", "n_timesteps=32", "n_envs=4",
            "n_steps=8", "batch_size=16", "eval_freq=16", "n_eval_scenarios=2"]  # fmt: skip
    assert main(args) == 0
    out = capsys.readouterr().out
    run = tmp_path / "train" / "v"
    text = (run / "verdict.txt").read_text()
    assert "axis small" in text and text.strip() in out
    summary = yaml.safe_load((run / "summary.yaml").read_text())
    labels = [r["controller"] for r in summary["verdict"]["controllers"]]
    assert labels[0] == "agent" and {"best-fixed", "paper", "scurve"} <= set(labels)
    assert set(summary["best_fixed"]) >= {"value_rad", "error_limit_rad", "k", "ts_over_tf"}


def test_residual_base_takes_a_settings_models_path(tmp_path):
    from vfgym.agents import CheckedBase, env_options
    from vfgym.moves.distribution import get_scenario
    from vfgym.params import PAPER_PLANT

    for spec in (str(PRETRAINED), f"model:{PRETRAINED}", f"model-lookup:{PRETRAINED}"):
        base = env_options({"residual_base": spec})["residual_base"]
        assert isinstance(base, CheckedBase)
    sc = get_scenario("test-3")
    lookup = env_options({"residual_base": f"model-lookup:{PRETRAINED}"})["residual_base"]
    shipped = env_options({"residual_base": "model-lookup"})["residual_base"]
    assert lookup(sc, PAPER_PLANT) == shipped(sc, PAPER_PLANT)
    with pytest.raises(ValueError, match=r"residual_base='model:nowhere\.json': nowhere\.json"):
        env_options({"residual_base": "model:nowhere.json"})


def test_validation_pairs_on_an_uncertain_axis_are_fixed_true_plants():
    from vfgym.agents.selection import validation_plants
    from vfgym.axis import NOMINAL

    axis = REPO / "experiments" / "axes" / "loads-uncertain.yaml"
    plants = validation_plants(8, str(axis))
    assert plants == validation_plants(8, load_axis(axis))  # every evaluation the same
    assert len(set(plants)) == 8 and all(0.8 <= p.inertia <= 1.25 for p in plants)
    assert validation_plants(3) == [NOMINAL] * 3


def test_eval_env_kwargs_are_what_validation_and_the_saved_agent_act_with(tmp_path):
    """``eval_env_kwargs`` over ``env_kwargs``: the validation env and the loaded agent's
    env take them (a one-decision agent trained without the shield, judged with it), the
    training env does not; a key the env does not take is refused before training."""
    from vfgym.agents import hyperparams as hp
    from vfgym.agents import load_agent, make_env
    from vfgym.agents.training import train

    kw = {"residual": True, "residual_base": "paper", "decision": "once", "interval_s": 0.001}
    over = {"n_timesteps": 16, "n_envs": 2, "n_steps": 8, "batch_size": 16, "eval_freq": 8,
            "n_eval_scenarios": 2, "env_kwargs": kw}  # fmt: skip
    over["eval_env_kwargs"] = {"shield": True}
    params = hp.load("ppo", "vfgym/VFServo-v0", HYPERPARAMS_DIR / "ppo.yml", over)
    train("ppo", "vfgym/VFServo-v0", params, tmp_path, progress=False, log=lambda m: None)
    agent = load_agent(tmp_path / "best_model.zip")
    assert agent.env_kwargs()["shield"] is True and "shield" not in kw
    env = make_env("vfgym/VFServo-v0", agent.env_kwargs()).unwrapped
    assert env.core.config.shield and env.decision.design  # the shield on, its plant known
    with pytest.raises(ValueError, match="unknown env_kwargs key"):
        hp.load("ppo", "vfgym/VFServo-v0", HYPERPARAMS_DIR / "ppo.yml",
                over | {"eval_env_kwargs": {"sheild": True}})  # fmt: skip
