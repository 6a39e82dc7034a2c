"""stable-baselines3 agents: tiny training runs of every algorithm on both envs, save/load,
determinism, resuming, and hyperparameter checks before training."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

pytest.importorskip("stable_baselines3")

from vfgym.agents import hyperparams as hp
from vfgym.agents import load_model, policy_settings
from vfgym.agents.training import train
from vfgym.axis import PAPER_AXIS
from vfgym.cli import main
from vfgym.commands._common import load_settings

REPO = Path(__file__).resolve().parents[2]
TINY = {
    "ppo": {"n_envs": 4, "n_steps": 16, "batch_size": 32, "n_epochs": 1},
    "sac": {"n_envs": 2, "learning_starts": 16, "batch_size": 16, "buffer_size": 1000},
    "td3": {"n_envs": 2, "learning_starts": 16, "batch_size": 16, "buffer_size": 1000},
    "ppo_lstm": {"n_envs": 4, "n_steps": 16, "batch_size": 32, "n_epochs": 1},
}


def tiny(algo: str, env_id: str, **extra) -> dict:
    over = TINY[algo] | {
        "n_timesteps": 64,
        "eval_freq": 10_000,
        "n_eval_scenarios": 2,
        "checkpoint_freq": 32,
        "policy_kwargs": {"net_arch": [16, 16]},
    }
    return hp.load(algo, env_id, hp.HYPERPARAMS_DIR / f"{algo}.yml", over | extra)


@pytest.mark.parametrize(
    ("algo", "env_id"),
    [(a, e) for a in ("ppo", "sac", "td3") for e in ("vfgym/VFTune-v0", "vfgym/VFServo-v0")]
    + [("ppo_lstm", "vfgym/VFServo-v0")],
)
def test_each_algorithm_trains_saves_loads_and_predicts_the_same(algo, env_id, tmp_path):
    run = tmp_path / "run"
    run.mkdir()
    model = train(algo, env_id, tiny(algo, env_id), run, seed=1, progress=False)
    for name in ("final_model.zip", "best_model.zip", "config.yaml", "evaluations.csv"):
        assert (run / name).is_file(), name
    assert any((run / "checkpoints").glob("model_*_steps.zip"))
    assert any((run / "tb").iterdir())
    loaded, cfg = load_model(run / "final_model.zip")
    assert cfg["algo"] == algo and cfg["env"] == env_id
    obs = np.random.default_rng(0).uniform(-1, 1, (5, *model.observation_space.shape))
    a1, _ = model.predict(obs.astype(np.float32), deterministic=True)
    a2, _ = loaded.predict(obs.astype(np.float32), deterministic=True)
    np.testing.assert_array_equal(a1, a2)


def test_same_seed_same_first_evaluation(tmp_path):
    firsts = []
    for i in range(2):
        run = tmp_path / f"r{i}"
        run.mkdir()
        train(
            "ppo",
            "vfgym/VFTune-v0",
            tiny("ppo", "vfgym/VFTune-v0", eval_freq=32),
            run,
            seed=7,
            progress=False,
        )
        firsts.append((run / "evaluations.csv").read_text().splitlines()[1:3])
    assert firsts[0] == firsts[1]


def test_a_run_started_again_continues_from_its_last_checkpoint(tmp_path, capsys):
    run = tmp_path / "run"
    run.mkdir()
    params = tiny("ppo", "vfgym/VFTune-v0")
    train("ppo", "vfgym/VFTune-v0", params, run, seed=3, progress=False)
    params = params | {"n_timesteps": 128}
    model = train("ppo", "vfgym/VFTune-v0", params, run, seed=3, progress=False)
    assert "continuing" in capsys.readouterr().out
    assert model.num_timesteps == 128
    steps = sorted(int(p.stem.split("_")[1]) for p in (run / "checkpoints").glob("model_*.zip"))
    assert steps[-1] == 128 and 64 in steps


def test_an_interrupt_saves_a_checkpoint_first(tmp_path, monkeypatch):
    from stable_baselines3 import PPO

    run = tmp_path / "run"
    run.mkdir()
    calls = {"n": 0}
    real = PPO.train

    def interrupted(self):
        calls["n"] += 1
        if calls["n"] == 1:  # after the first rollout of 64 steps
            raise KeyboardInterrupt
        return real(self)

    monkeypatch.setattr(PPO, "train", interrupted)
    params = tiny("ppo", "vfgym/VFTune-v0", checkpoint_freq=10_000, n_timesteps=128)
    with pytest.raises(KeyboardInterrupt):
        train("ppo", "vfgym/VFTune-v0", params, run, seed=0, progress=False)
    saved = [p.name for p in (run / "checkpoints").glob("model_*_steps.zip")]
    assert saved == ["model_64_steps.zip"], "the interrupt did not save what it had"
    monkeypatch.setattr(PPO, "train", real)
    model = train("ppo", "vfgym/VFTune-v0", params, run, seed=0, progress=False)
    assert model.num_timesteps == 128


def test_cli_train_then_predict_gives_a_settings_file_evaluate_reads(tmp_path, capsys):
    code = main(
        [
            "train",
            "--algo",
            "ppo",
            "--env",
            "vfgym/VFTune-v0",
            "--runs-dir",
            str(tmp_path),
            "--name",
            "t",
            "--no-progress",
            "--hyperparams-file",
            str(hp.HYPERPARAMS_DIR / "ppo.yml"),
            "--hyperparams",
            "n_timesteps=32",
            "n_envs=4",
            "n_steps=8",
            "batch_size=16",
            "eval_freq=16",
            "n_eval_scenarios=2",
        ]
    )
    assert code == 0
    run = tmp_path / "train" / "t"
    assert (run / "command.txt").read_text().startswith("vfgym ")
    out = tmp_path / "s.yaml"
    capsys.readouterr()
    assert (
        main(
            [
                "predict",
                "--model",
                str(run / "best_model.zip"),
                "--scenario",
                "test-3",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    printed = yaml.safe_load(capsys.readouterr().out)
    s = load_settings(str(out), PAPER_AXIS)
    assert printed["settings"]["k"] == s.k
    # without --axis, predict's axis is the default problem's (the paper's), on which the
    # agent picks for the move named test-3 there
    assert policy_settings(run / "best_model.zip", PAPER_AXIS)("test-3") == s


@pytest.mark.parametrize(
    ("content", "match"),
    [
        ({"vfgym/VFTune-v0": {"n_envs": 2, "learning_rat": 0.1}}, "unknown key 'learning_rat'"),
        ({"vfgym/VFTune-v0": {"n_steps": "many"}}, "n_steps='many' has the wrong type"),
        ({"vfgym/VFTune-v0": {"n_envs": 0}}, "n_envs=0 is out of range"),
        (
            {"vfgym/VFTune-v0": {"policy_kwargs": {"net_arch": [8], "activation_fn": "sine"}}},
            "activation_fn='sine'",
        ),
        ({"vfgym/Other-v0": {}}, "unknown environment id"),
        (
            {"vfgym/VFTune-v0": {"policy": "MlpLstmPolicy"}},
            "policy='MlpLstmPolicy' is not allowed for ppo: give MlpPolicy",
        ),
        ({"vfgym/VFTune-v0": {"policy": "CnnPolicy"}}, "policy='CnnPolicy'"),
    ],
)
def test_bad_hyperparameter_files_fail_before_training(tmp_path, content, match, capsys):
    f = tmp_path / "ppo.yml"
    f.write_text(yaml.safe_dump(content))
    code = main(
        [
            "train",
            "--algo",
            "ppo",
            "--runs-dir",
            str(tmp_path / "runs"),
            "--hyperparams-file",
            str(f),
        ]
    )
    err = capsys.readouterr().err
    assert code == 2 and match in err and err.count("\n") == 1
    assert not (tmp_path / "runs").exists()  # nothing started


def test_unknown_algorithm_and_bad_override(tmp_path, capsys):
    assert main(["train", "--algo", "dqn", "--runs-dir", str(tmp_path)]) == 2
    assert "algo='dqn' is not known" in capsys.readouterr().err
    assert (
        main(["train", "--algo", "ppo", "--runs-dir", str(tmp_path), "--hyperparams", "gamma"]) == 2
    )
    assert "key=value" in capsys.readouterr().err


def test_train_threads_sets_torch_and_numba_and_records_them(tmp_path):
    """``vfgym train --threads N`` (default 1) sets torch's and numba's threads, and the
    run's config.yaml records them."""
    import numba
    import torch

    before = torch.get_num_threads(), numba.get_num_threads()
    base = ["train", "--algo", "ppo", "--runs-dir", str(tmp_path), "--no-progress"]
    over = ["--hyperparams", "n_timesteps=16", "n_envs=2", "n_steps=8", "batch_size=16"]
    over += ["eval_freq=16", "n_eval_scenarios=1"]
    try:
        torch.set_num_threads(2)
        numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
        assert main([*base, "--name", "one", *over]) == 0  # the default
        assert (torch.get_num_threads(), numba.get_num_threads()) == (1, 1)
        assert yaml.safe_load((tmp_path / "train/one/config.yaml").read_text())["threads"] == 1
        n = numba.config.NUMBA_NUM_THREADS
        assert main([*base, "--name", "all", "--threads", str(n), *over]) == 0
        assert (torch.get_num_threads(), numba.get_num_threads()) == (n, n)
        assert yaml.safe_load((tmp_path / "train/all/config.yaml").read_text())["threads"] == n
    finally:
        torch.set_num_threads(before[0])
        numba.set_num_threads(before[1])


def test_a_working_folders_own_hyperparameter_file_is_read_before_the_shipped_one(
    tmp_path, monkeypatch
):
    monkeypatch.chdir(tmp_path)
    assert hp.default_file("ppo") == hp.HYPERPARAMS_DIR / "ppo.yml"
    assert hp.load("ppo", "vfgym/VFTune-v0")["gamma"] == 0.0  # the shipped file's
    own = tmp_path / "agents" / "hyperparams" / "ppo.yml"
    own.parent.mkdir(parents=True)
    own.write_text("vfgym/VFTune-v0:\n  gamma: 0.5\n")
    assert hp.default_file("ppo") == Path("agents/hyperparams/ppo.yml")
    assert hp.load("ppo", "vfgym/VFTune-v0")["gamma"] == 0.5


@pytest.mark.parametrize(
    ("ratio", "scale", "warns"),
    [
        (True, [0.25, 0.0, 0.25, 0.25], False),  # the shipped files': the same actions
        (True, [0.25, 0.25, 0.25, 0.25], True),  # L/value's offset over another range
        (False, [0.25, 0.0, 0.25, 0.25], True),  # L alone, not L/value
    ],
)
def test_a_run_saved_with_residual_ratio_loads_and_says_when_its_actions_changed(
    tmp_path, ratio, scale, warns
):
    """Runs saved when residual actions had a ``residual_ratio`` option load (the option
    dropped: actions are always offsets of L/value now), one line where L's actions
    changed meaning."""
    import warnings

    from vfgym.agents.loaded import make_env, run_config
    from vfgym.permove import TunerWarning

    kw = {"residual": True, "residual_ratio": ratio, "residual_scale": scale}
    cfg = {"algo": "ppo", "env": "vfgym/VFTune-v0", "hyperparams": {"env_kwargs": kw}}
    (tmp_path / "config.yaml").write_text(yaml.safe_dump(cfg))
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        got = run_config(tmp_path / "best_model.zip")
    env_kwargs = got["hyperparams"]["env_kwargs"]
    assert "residual_ratio" not in env_kwargs
    make_env("vfgym/VFTune-v0", env_kwargs)  # the env takes what is left
    lines = [str(w.message) for w in seen if issubclass(w.category, TunerWarning)]
    assert len(lines) == int(warns) and all("\n" not in ln for ln in lines)
