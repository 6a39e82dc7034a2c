"""Every failure a user can cause ends in one line: a table of bad inputs over every
sub-command, each asserting exit status 2, exactly one line on stderr (naming the
problem) and no traceback. Most run in-process through ``vfgym.cli.main``; the closed
pipe and the interrupt run as real processes. Also: a real bug keeps its traceback, and
the quiet surprises of issue 15 (a missing storage folder, a refused run recorded, a
study asked for fewer trials than it has) are gone."""

from __future__ import annotations

import errno
import importlib.util
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import yaml

from vfgym.cli import main
from vfgym.permove import PRETRAINED

HAS_SB3 = importlib.util.find_spec("stable_baselines3") is not None
REPO = Path(__file__).resolve().parents[2]
LU = REPO / "experiments" / "axes" / "loads-uncertain.yaml"
GOOD = {"value_rad": 0.7, "error_limit_rad": 0.7, "k": 350.0, "ts_over_tf": 0.25}


@pytest.fixture
def ws(tmp_path, monkeypatch):
    """A working folder with the files the bad inputs point at; the cwd for the run."""
    (tmp_path / "afile").write_text("a file where a folder is expected\n")
    (tmp_path / "adir").mkdir()
    (tmp_path / "bin.yaml").write_bytes(b"\x00\xff\xfe\x01 binary \x89PNG")
    (tmp_path / "list.yaml").write_text("settings: [1, 2, 3]\n")
    (tmp_path / "good.yaml").write_text(yaml.safe_dump({"settings": GOOD}))
    (tmp_path / "nan.yaml").write_text("value_rad: .nan\n")
    for algo, tiny in TINY.items():  # if a check let a case through, it trains 64 steps
        (tmp_path / f"{algo}.yml").write_text(yaml.safe_dump({"vfgym/VFTune-v0": tiny}))
    for name, text in BAD_FILES.items():
        (tmp_path / name).write_text(text)
    sweep = tmp_path / "runs" / "sweep" / "s"
    sweep.mkdir(parents=True)
    (sweep / "config.yaml").write_text("command: sweep\nstudy: s\nstorage: sqlite\n")
    monkeypatch.chdir(tmp_path)
    return tmp_path


RUN = {"n_envs": 2, "n_timesteps": 64, "eval_freq": 64, "n_eval_scenarios": 1}
TINY = {
    "ppo": {**RUN, "n_steps": 32, "batch_size": 32, "n_epochs": 1},
    "sac": {**RUN, "learning_starts": 16, "batch_size": 16, "buffer_size": 1000},
}
TRAIN = ["train", "--hyperparams-file", "ppo.yml"]
SAC = ["train", "--algo", "sac", "--hyperparams-file", "sac.yml"]
SWEEP = ["sweep", "--scenarios", "short-move", "--trials", "2", "--no-progress"]

# files of values that cannot mean anything (issue 21), written into `ws`
BAD_FILES = {
    "ip0.yaml": "measures: {in_position_counts: 0}\n",
    "ip1e9.yaml": "measures: {in_position_counts: 1e9}\n",
    "iplong.yaml": "measures: {in_position_counts: 2000}\n",  # wider than a 0.2 rad move
    "tick.yaml": "plant: {tick_hz: 1e12}\n",
    "slow.yaml": "plant: {tick_hz: 10}\n",
    "motorkey.yaml": "motor: {inertia_ratio: 2}\n",
    "ratio.yaml": "plant: {motor: {inertia_ratio: 1e4}}\n",
    "held.yaml": "plant: {motor: {coulomb_nm: 1.5, load_torque_nm: 0.5}}\n",
    "viscous.yaml": "plant: {motor: {viscous_nm_s_rad: 0.1}}\n",
    "rated.yaml": "plant: {motor: {rated_torque_nm: 5.0}}\n",
    "ns.yaml": "plant: {servo: {sample_ticks: 7000}}\n",
    "ns70.yaml": "plant: {servo: {sample_ticks: '70'}}\n",
    "yes.yaml": "plant: {servo: {follows_load: 'yes'}}\n",
    "steady.yaml": "measures: {steady_window_s: 0.5}\nmoves: {train: [{name: a, "
    "profile: step, distance_rad: 1.0, duration_s: 0.1}]}\n",
    "plots.yaml": "plots: 'yes'\n",
    "workers.yaml": "workers: '2'\n",
    "str.yaml": "value_rad: '1.5'\n",
    # a limit in the wrong unit, on an axis whose listed moves it would make too short
    "slip.yaml": "plant: {motor: {accel_limit_rad_s2: 30}}\nmoves: {train: [{name: a, "
    "profile: step, distance_rad: 6.0, duration_s: 0.3}]}\n",
}

# (argv, a piece of the one line that must name the problem); paths are relative to `ws`
CASES = [
    # simulate
    (["simulate", "--scenario", "mars"], "scenario='mars'"),
    (["simulate", "--settings", "bin.yaml"], "bin.yaml: not a text file"),
    (["simulate", "--settings", "list.yaml"], "list.yaml: settings=[1, 2, 3] is not allowed"),
    (["simulate", "--settings", "missing.yaml"], "missing.yaml: no such file"),
    (["simulate", "--settings", "adir"], "adir: is a folder"),
    (["simulate", "--settings", "nan.yaml"], "value_rad=nan"),
    (["simulate", "--baseline", "pid"], "baseline='pid'"),
    (["simulate", "--settings", "/dev/null"], "/dev/null: not a regular file"),
    (["simulate", "--settings", "good.yaml", "--baseline", "paper"], "not allowed with"),
    (["simulate", "--storage", "x"], "unrecognized arguments: --storage x"),
    (["nosuch"], "invalid choice: 'nosuch'"),
    (
        ["identify", "--axis", "missing.yaml", "--capture", "c.vcd", "--out", "o.yaml"],
        "missing.yaml: no such file",
    ),
    # identify: never replace a user's file; a prior on the drive's gain in range
    (["identify", "--capture", "c.vcd", "--out", "afile"], "--out='afile' is not allowed: the"),
    (
        ["identify", "--axis", "good.yaml", "--capture", "c.vcd", "--out", "good.yaml"],
        "it is the --axis file, an input",
    ),
    (["identify", "--capture", "afile", "--out", "afile"], "--out='afile' is not allowed"),
    (["identify", "--capture", "c.vcd", "--out", "o.yaml", "--gain-prior", "2"], "--gain-prior=2"),
    (["identify", "--capture", "c.vcd", "--out", "o.yaml", "--true-axis", "t.yaml"], "--plan"),
    (["identify", "--plan", "--out", "afile"], "is a file: with --plan give a folder"),
    # sweep
    ([*SWEEP, "--runs-dir", "afile/runs"], "afile is a file"),
    ([*SWEEP, "--sampler", "grid", "--grid-points", "1"], "grid_points=1 is out of range"),
    ([*SWEEP, "--grid-points", "2.5"], "grid_points=2.5"),
    ([*SWEEP, "--storage", "sqlite:///nowhere/dir/x.db"], "folder"),
    ([*SWEEP, "--storage", "journal:afile/j.log"], "afile is a file"),
    ([*SWEEP, "--study", "../.."], "study='../..'"),
    ([*SWEEP, "--trials", "0"], "trials=0 is out of range"),
    ([*SWEEP, "--timeout", "nan"], "timeout=nan"),
    ([*SWEEP, "--workers", "0"], "workers=0"),
    ([*SWEEP, "--config", "bin.yaml"], "bin.yaml: not a text file"),
    ([*SWEEP, "--config", "list.yaml"], "unknown key(s) settings"),
    ([*SWEEP, "--storage", "journal:bin.yaml"], "bin.yaml' cannot be opened"),
    # issue 21: every axis, plant and measures value in a range that means something
    ([*SWEEP, "--axis", "ip0.yaml"], "ip0.yaml: measures.in_position_counts=0 is out of range"),
    (["simulate", "--axis", "ip1e9.yaml"], "in_position_counts=1000000000.0 is out of range"),
    (["simulate", "--axis", "iplong.yaml"], "below the shortest move (moves.train.random"),
    (["simulate", "--axis", "tick.yaml"], "plant.tick_hz=1000000000000.0 is out of range"),
    (["simulate", "--axis", "slow.yaml"], "plant.tick_hz=10 is out of range: allowed [1000"),
    (["simulate", "--axis", "motorkey.yaml"], "allowed name, description, plant, measures"),
    (["simulate", "--axis", "ratio.yaml"], "plant.motor.inertia_ratio=10000.0 is out of range"),
    (["simulate", "--axis", "held.yaml"], "the motor cannot move its load"),
    (["simulate", "--axis", "viscous.yaml"], "plant.motor.viscous_nm_s_rad=0.1 is out of range"),
    (["simulate", "--axis", "rated.yaml"], "plant.motor.rated_torque_nm=5.0 is out of range"),
    (["simulate", "--axis", "ns.yaml"], "plant.servo.sample_ticks=7000 is out of range"),
    (["simulate", "--axis", "ns70.yaml"], "sample_ticks='70' must be one of the whole numbers"),
    (["simulate", "--axis", "yes.yaml"], "follows_load='yes' must be true or false"),
    (["simulate", "--axis", "steady.yaml"], "steady_window_s=0.5 is out of range"),
    (["simulate", "--axis", "slip.yaml"], "accel_limit_rad_s2=30 is out of range: the motor's"),
    # issue 21: one strictness: a string is not a number, a bool is true or false
    ([*SWEEP, "--config", "plots.yaml"], "plots='yes' must be true or false"),
    ([*SWEEP, "--config", "workers.yaml"], "workers='2' must be one of the whole numbers"),
    (["simulate", "--settings", "str.yaml"], "value_rad='1.5' must be a real number"),
    # issue 21: storage URLs SQLAlchemy does not take for SQLite or PostgreSQL
    ([*SWEEP, "--storage", "mysql://u:secret@h/db"], "SQLite or PostgreSQL"),
    ([*SWEEP, "--storage", "postgresql+asyncpg://u:secret@h/db"], "asynchronous"),
    ([*SWEEP, "--storage", "postgresql://u:secret@h:70000/db"], "port 70000 is out of range"),
    ([*SWEEP, "--storage", "postgres://u:secret@h/db"], "postgresql://"),
    ([*SWEEP, "--storage", "sqlite:///:memory:"], "in-memory"),
    # issue 21: an explicit output's missing folder is refused, not made
    (["export", "--format", "vcd", "--out", "nowhere/dir/x.vcd"], "folder nowhere/dir does"),
    (["export", "--format", "csv", "--out", "/proc/version"], "--out: /proc/version: "),
    (["plot", "scurve", "--out", "nowhere/d.png"], "folder nowhere does not exist"),
    (["predict", "--out", "nowhere/s.yaml"], "folder nowhere does not exist"),
    (["evaluate", "--settings", "good.yaml", "--runs-dir", "nowhere/runs"], "folder nowhere"),
    ([*SWEEP, "--runs-dir", "nowhere/runs"], "folder nowhere does not exist"),
    (["grid", "--points", "2", "--runs-dir", "nowhere/runs"], "folder nowhere does not exist"),
    # grid
    (["grid", "--name", "../..", "--points", "2"], "name='../..'"),
    (["grid", "--points", "1"], "points=1 is out of range"),
    (["grid", "--refine", "-1"], "refine=-1"),
    (["grid", "--runs-dir", "afile", "--points", "2"], "afile"),
    (["grid", "--config", "missing.yaml"], "missing.yaml: no such file"),
    # evaluate
    (["evaluate", "--settings", "good.yaml", "--name", "../../out"], "--name='../../out'"),
    (["evaluate", "--settings", "good.yaml", "--runs-dir", "afile"], "afile is a file"),
    (["evaluate", "--settings", "good.yaml", "--count", "0"], "--count='0' is out of range"),
    (["evaluate", "--settings", "good.yaml", "--seed", "-1"], "--seed='-1' is out of range"),
    (["evaluate", "--settings", "good.yaml", "--bootstrap", "nan"], "--bootstrap='nan'"),
    (["evaluate", "--settings", "list.yaml"], "list.yaml: settings=[1, 2, 3]"),
    (["evaluate", "--model", "missing.zip"], "missing.zip: no such file"),
    (["evaluate"], "nothing to evaluate"),
    (["evaluate", "--adaptive", "missing.json"], "--adaptive missing.json: no such file"),
    (["evaluate", "--adaptive", str(PRETRAINED)], "states no uncertainty"),
    (
        ["evaluate", "--adaptive", "good.yaml", "--axis", str(LU)],
        "--adaptive good.yaml: not a vfgym settings model",
    ),  # a settings file, not a model
    (
        ["evaluate", "--settings", "good.yaml", "--plants", "1000000"],
        "--plants='1000000' is out of range: allowed whole numbers in [1, 1000]",
    ),
    # plot
    (["plot", "scurve", "--short-rad", "-1"], "--short-rad='-1' is out of range"),
    (["plot", "scurve", "--short-rad", "nan"], "--short-rad='nan' is out of range"),
    (["plot", "scurve", "--long-rad", "inf"], "--long-rad='inf'"),
    (["plot", "response", "--out", "afile/d.png"], "afile is a file"),
    (["plot", "response", "--out", "adir"], "give a .png file"),
    (["plot", "response", "--out", "x.jpg"], "give a .png file"),
    (["plot", "frequency", "--dpi", "0"], "--dpi='0' is out of range"),
    (["plot", "history"], "needs --sweep"),
    (["plot", "history", "--sweep", "runs/sweep/s", "--storage", "sqlite:///gone.db"], "gone.db"),
    (["plot", "pareto", "--sweep", "no/such/folder"], "no such folder"),
    (["plot", "compare", "--against", "paper"], "only the controller itself"),
    (["plot", "response", "--scenario", "paper-sine", "--baseline", "scurve"], "does not apply"),
    (["plot", "spiral"], "invalid choice: 'spiral'"),
    # export
    (["export", "--format", "vcd", "--out", "afile/e.vcd"], "afile is a file"),
    (["export", "--format", "csv", "--out", "adir"], "adir is a folder"),
    (["export", "--format", "wav"], "invalid choice: 'wav'"),
    (["export", "--format", "csv", "--out", ""], "--out='' is not allowed"),
    (["export"], "required: --format"),
    (["export", "--format", "csv", "--decimation", "0"], "--decimation='0'"),
    (["export", "--format", "vcd", "--decimation", "2"], "not allowed for vcd"),
    (["export", "--format", "vcd", "--timescale", "7 ns"], "timescale"),
    (["export", "--format", "vcd", "--settings", "bin.yaml"], "bin.yaml"),
    (["export", "--format", "csv", "--out", "afile"], "--out='afile' is not allowed: the file"),
    (["export", "--format", "vcd", "--settings", "good.yaml", "--out", "good.yaml"], "an input"),
    # train (checked before anything trains)
    ([*TRAIN, "--algo", "ppo", "--name", "../../x"], "--name='../../x'"),
    ([*TRAIN, "--algo", "ppo", "--hyperparams", "gamma=2"], "gamma=2 is out of range"),
    ([*TRAIN, "--algo", "ppo", "--hyperparams", "learning_rate=0"], "learning_rate=0"),
    ([*TRAIN, "--algo", "ppo", "--hyperparams", "n_timesteps=0"], "n_timesteps=0"),
    ([*TRAIN, "--algo", "ppo", "--hyperparams", "n_envs=2.5"], "n_envs=2.5"),
    ([*TRAIN, "--algo", "ppo", "--hyperparams", "gae_lambda=-0.1"], "gae_lambda=-0.1"),
    ([*TRAIN, "--algo", "ppo", "--hyperparams", "gamma"], "give key=value"),
    ([*TRAIN, "--algo", "ppo", "--hyperparams", "env_kwargs={foo: 1}"], "env_kwargs key(s) foo"),
    ([*TRAIN, "--algo", "ppo", "--seed", "-1"], "--seed='-1' is out of range"),
    ([*TRAIN, "--algo", "ppo", "--hyperparams", "env_kwargs={split: x}"], "split='x'"),
    ([*TRAIN, "--algo", "ppo", "--runs-dir", "afile"], "afile is a file"),
    ([*TRAIN, "--algo", "ppo", "--threads", "0"], "--threads='0' is out of range: allowed whole"),
    ([*TRAIN, "--algo", "ppo", "--threads", "1.5"], "--threads='1.5' is not allowed: whole"),
    ([*TRAIN, "--algo", "ppo", "--threads", "999"], "--threads='999' is out of range"),
    (["train", "--algo", "ppo", "--hyperparams-file", "bin.yaml"], "bin.yaml: not a text file"),
    (["train", "--algo", "dqn"], "algo='dqn' is not known"),
    ([*TRAIN, "--algo", "ppo", "--env", "vfgym/Nope-v0"], "env='vfgym/Nope-v0'"),
    ([*SAC, "--hyperparams", "tau=0"], "tau=0 is out of range"),
    ([*SAC, "--hyperparams", "ent_coef=auto_-1"], "ent_coef"),
    ([*SAC, "--hyperparams", "train_freq=[4, hours]"], "train_freq='hours'"),
    # predict
    (["predict", "--model", "missing.zip"], "missing.zip: no such file"),
    (["predict", "--model", "missing.zip", "--out", "afile/s.yaml"], "afile is a file"),
    (["predict", "--model", "missing.zip", "--scenario", "mars"], "scenario='mars'"),
    (["predict", "--model", "missing.json"], "missing.json: no such file"),
    (["predict", "--model", "good.yaml"], "not a vfgym settings model"),
    (["predict", "--model", "bin.yaml"], "not a vfgym settings model"),
    (["predict", "--refine", "0"], "--refine='0' is out of range"),
    (["predict", "--refine", "-3"], "--refine='-3' is out of range"),
    (["predict", "--refine", "2.5"], "--refine='2.5' is not allowed"),
    (["predict", "--refine", "many"], "--refine='many' must be"),
    (["predict", "--refine", "nan"], "--refine='nan' is not allowed"),
    (["predict", "--refine", "3", "--seed", "-1"], "--seed='-1' is out of range"),
    (["fit"], "the following arguments are required: --axis"),
    (["fit", "--axis", "missing.yaml"], "missing.yaml"),
    (
        ["fit", "--axis", str(REPO / "experiments/axes/belt.yaml"), "--moves", "7"],
        "--moves='7' is out of range",
    ),
    (
        ["fit", "--axis", str(REPO / "experiments/axes/belt.yaml"), "--runs-dir", "afile"],
        "afile is a file",
    ),
]


def _id(case) -> str:
    """The case's arguments without the shared prefixes (TRAIN, SAC, SWEEP)."""
    argv = case[0]
    for prefix in (TRAIN, SAC, SWEEP):
        if argv[: len(prefix)] == prefix:
            argv = [prefix[0], *argv[len(prefix) :]]
    return " ".join(argv)


@pytest.mark.parametrize(("argv", "needle"), CASES, ids=[_id(c) for c in CASES])
def test_bad_input_is_one_line_with_status_2(ws, capsys, argv, needle):
    if argv[0] == "train" and not HAS_SB3:
        pytest.skip("needs the agents extra")
    code = main(argv)
    out, err = capsys.readouterr()
    assert code == 2, (out, err)
    assert err.endswith("\n") and err.count("\n") == 1, err
    assert "Traceback" not in err and "Traceback" not in out
    assert err.startswith(f"vfgym {argv[0]}: error: " if argv[0] != "nosuch" else "vfgym: error:")
    assert needle in err, err
    assert "secret" not in err and ".tmp" not in err  # no password, no temporary file
    assert not (ws / "runs" / argv[0]).exists() or argv[0] == "sweep"
    assert not list((ws / "runs" / "sweep").glob("sweep-*"))  # no run folder was made
    assert not (ws / "nowhere").exists()  # the missing folder was not created
    assert not [p for p in ws.rglob("*") if ".tmp" in p.name or "-lock" in p.name]


def test_the_corpus_covers_every_subcommand():
    from vfgym.cli import build_parser

    commands = set(build_parser().subcommands)
    covered = {argv[0] for argv, _ in CASES}
    assert commands <= covered
    assert len(CASES) >= 40


def test_yaml_numbers_in_any_notation(ws):
    """``1e3`` is a number wherever a number is expected (PyYAML alone reads a string)."""
    from vfgym import tuning
    from vfgym.io.runs import read_yaml

    (ws / "c.yaml").write_text("trials: 1e3\ntimeout: 2.5E+1\nscenarios: paper-step\n")
    cfg = tuning.SweepConfig.resolve(read_yaml(ws / "c.yaml"), {}, source="c.yaml")
    assert (cfg.trials, cfg.timeout) == (1000, 25.0)
    (ws / "s.yaml").write_text("value_rad: 7e-1\nk: 3.5e2\n")
    assert main(["simulate", "--settings", "s.yaml", "--scenario", "short-move"]) == 0
    if HAS_SB3:
        from vfgym.agents import hyperparams as hp

        over = hp.parse_overrides(["n_timesteps=1e3", "learning_rate=3e-4"])
        params = hp.load("ppo", "vfgym/VFTune-v0", hp.HYPERPARAMS_DIR / "ppo.yml", over)
        assert params["n_timesteps"] == 1000 and isinstance(params["n_timesteps"], int)
        assert params["learning_rate"] == 3e-4


@pytest.mark.parametrize(
    ("argv", "drawn"),
    [
        (["compare"], {"paper", "rule-of-thumb"}),
        (["compare", "--settings", "paper.yaml"], {"paper.yaml", "paper"}),
        (["frequency"], {"paper", "fixed-frequency"}),
        (["frequency", "--baseline", "fixed-frequency"], {"fixed-frequency", "paper"}),
    ],
)
def test_plot_defaults_draw_two_distinct_controllers(ws, argv, drawn):
    """``plot compare`` on its defaults drew the paper against itself (issue 15): the
    default --against is the first of the kind's defaults that is not the controller, and
    a settings file named like a baseline keeps its path as its label."""
    from vfgym.cli import build_parser
    from vfgym.commands.plot import build_figure

    (ws / "paper.yaml").write_text(yaml.safe_dump({"settings": GOOD}))
    fig = build_figure(build_parser().parse_args(["plot", *argv]))
    labels = {lab for ax in fig.axes for lab in ax.get_legend_handles_labels()[1]}
    assert {lab.split(" (cost ")[0] for lab in labels if " (cost " in lab} == drawn


def test_an_unwritable_output_found_late_is_still_one_line(ws, capsys, monkeypatch):
    """The safety net in cli.main: an OSError after the early checks (a full disk while
    saving) names the option and the path in one line."""
    from matplotlib.figure import Figure

    def full(self, path, **kw):
        raise OSError(errno.ENOSPC, "No space left on device", str(path))

    monkeypatch.setattr(Figure, "savefig", full)
    (ws / "figs").mkdir()
    assert main(["plot", "scurve", "--out", "figs/s.png"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert err.startswith("vfgym plot: error: --out: ") and "no space left" in err


def test_a_read_only_folder_is_refused_before_any_work(ws, capsys):
    if shutil.which("mount") is None or os.geteuid() != 0:
        pytest.skip("needs root and mount(8) to make a read-only bind mount")
    src, ro = ws / "src", ws / "ro"
    src.mkdir()
    ro.mkdir()
    if subprocess.run(["mount", "--bind", str(src), str(ro)], capture_output=True).returncode:
        pytest.skip("cannot bind-mount here")
    try:
        remount = ["mount", "-o", "remount,bind,ro", str(ro)]
        if subprocess.run(remount, capture_output=True).returncode:
            pytest.skip("cannot remount read-only here")
        for argv in (
            ["plot", "scurve", "--out", "ro/s.png"],
            ["export", "--format", "csv", "--out", "ro/x.csv"],
            [*SWEEP, "--runs-dir", "ro/runs"],
        ):
            assert main(argv) == 2
            err = capsys.readouterr().err
            assert err.count("\n") == 1 and "read-only file system" in err, err
    finally:
        subprocess.run(["umount", str(ro)], capture_output=True)


def test_a_bug_keeps_its_traceback_and_asks_to_report_it(ws, capsys, monkeypatch):
    import vfgym.commands.simulate as sim

    def broken(args):
        raise TypeError("an internal mistake")

    monkeypatch.setattr(sim, "run", broken)  # add_parser binds it when main builds the parser
    assert main(["simulate"]) == 1
    err = capsys.readouterr().err
    assert "Traceback" in err and "TypeError: an internal mistake" in err
    assert err.strip().splitlines()[-1].startswith("vfgym simulate: this is a bug in vfgym")


def _sweep_quietly(*args):
    return main([*SWEEP, "--no-plots", "--runs-dir", "runs", *args])


def test_an_evaluation_name_in_use_by_another_job_is_kept_unless_forced(ws, capsys):
    """``evaluate --name`` never replaces another job's run folder silently: the same job
    again is fine, another is refused in one line (the folder as it was), ``--force``
    replaces it."""
    job = ["evaluate", "--settings", "good.yaml", "--scenarios", "short-move", "--against",
           "paper", "--bootstrap", "10", "--name", "e"]  # fmt: skip
    assert main(job) == 0
    run = ws / "runs" / "evaluate" / "e"
    assert main(job) == 0  # the same job again
    before = {p.name: p.read_bytes() for p in run.iterdir()}
    capsys.readouterr()
    other = [*job[:-2], "--scenarios", "paper-step", "--name", "e"]
    assert main(other) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--name='e' is in use" in err[0] and "--force" in err[0]
    assert {p.name: p.read_bytes() for p in run.iterdir()} == before
    assert main([*other, "--force"]) == 0
    assert yaml.safe_load((run / "config.yaml").read_text())["scenario_names"] == ["paper-step"]


def test_a_refused_sweep_leaves_its_run_folder_as_it_was(ws, capsys):
    assert _sweep_quietly("--study", "r1") == 0
    run = ws / "runs" / "sweep" / "r1"
    before = {p.name: p.read_bytes() for p in (run / "command.txt", run / "config.yaml")}
    capsys.readouterr()
    assert _sweep_quietly("--study", "r1", "--scenarios", "paper-step") == 2
    assert "already optimises scenarios" in capsys.readouterr().err
    assert {p.name: p.read_bytes() for p in (run / "command.txt", run / "config.yaml")} == before
    assert (run / "command.txt").read_text().count("\n") == 1

    # asked for fewer trials than the study has: said so, not "2/1"
    assert _sweep_quietly("--study", "r1", "--trials", "1") == 0
    out = capsys.readouterr().out
    assert "2 trials done, --trials 1 asked: nothing to run" in out
    assert "2/1" not in out


def test_explicit_storage_file_needs_an_existing_folder(ws, capsys):
    """``sqlite:///FILE`` in an existing folder works; a missing folder is not made."""
    (ws / "db").mkdir()
    assert _sweep_quietly("--study", "st", "--storage", f"sqlite:///{ws}/db/x.db") == 0
    assert (ws / "db" / "x.db").is_file()
    capsys.readouterr()
    assert _sweep_quietly("--study", "st2", "--storage", f"sqlite:///{ws}/no/dir/x.db") == 2
    err = capsys.readouterr().err
    assert f"folder {ws}/no/dir does not exist" in err and not (ws / "no").exists()
    assert not (ws / "runs" / "sweep" / "st2").exists()


def _env() -> dict[str, str]:
    env = dict(os.environ)
    src = str(REPO / "src")
    env["PYTHONPATH"] = src + os.pathsep + env.get("PYTHONPATH", "")
    env["MPLBACKEND"] = "Agg"
    return env


def _vfgym(*args: str) -> list[str]:
    return [sys.executable, "-c", "import sys; from vfgym.cli import main; sys.exit(main())", *args]


def test_a_closed_pipe_is_one_line_and_the_sweep_still_finishes(tmp_path):
    """``vfgym sweep ... | head -1``: the reader is gone before the sweep prints; the sweep
    still runs its trials and writes its run folder, then says in one line that the
    pipe was closed (no BrokenPipeError traceback, also not at the interpreter's exit)."""
    r, w = os.pipe()
    os.close(r)  # no reader at all: every write to stdout fails with EPIPE
    try:
        p = subprocess.run(
            _vfgym("sweep", "--scenarios", "short-move", "--trials", "2", "--no-progress",
                   "--no-plots", "--runs-dir", str(tmp_path), "--study", "piped"),
            stdout=w, stderr=subprocess.PIPE, text=True, env=_env(), timeout=300,
        )  # fmt: skip
    finally:
        os.close(w)
    assert p.returncode == 2, p.stderr
    assert p.stderr.count("\n") == 1 and "Traceback" not in p.stderr, p.stderr
    assert "output pipe was closed" in p.stderr
    assert (tmp_path / "sweep" / "piped" / "best.yaml").is_file()


@pytest.mark.parametrize(
    "argv",
    [
        ["sweep", "--scenarios", "paper-step", "--trials", "5000", "--no-progress", "--no-plots",
         "--study", "ctrl-c"],
        ["grid", "--scenarios", "paper-step", "--points", "20", "--refine", "0", "--batch", "64",
         "--no-progress"],
    ],
    ids=["sweep", "grid"],
)  # fmt: skip
def test_an_interrupt_is_one_line_with_status_130(tmp_path, argv):
    # Ctrl-C reaches the command as from a terminal: a test run started in the background
    # of a script (`pytest &`) has SIGINT ignored, and a child inherits that and keeps it
    # (the grid, which sets no handler of its own, then ran to its end).
    p = subprocess.Popen(
        _vfgym(*argv, "--runs-dir", str(tmp_path)),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=_env(),
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    try:
        assert p.stdout.readline().startswith(f"vfgym {argv[0]}:")  # the header: it runs
        time.sleep(1.5)
        p.send_signal(signal.SIGINT)
        out, err = p.communicate(timeout=120)
    finally:
        if p.poll() is None:
            p.kill()
    assert p.returncode == 130, (err, out[-400:])
    # (on a cold numba cache the first use says once that it compiles: not the interrupt's)
    err = "".join(ln for ln in err.splitlines(True) if not ln.startswith("vfgym: compiling"))
    assert err.count("\n") == 1 and "Traceback" not in err, err
    assert err.startswith(f"vfgym {argv[0]}: interrupted")


# every URL form SQLAlchemy takes for PostgreSQL (issue 21): read, kept as given, the
# password masked; no server is needed to tell that it is accepted
PG_URLS = [
    "postgresql://u:secret@host/db?sslmode=require",
    "postgresql://u@[::1]:5432/db",
    "postgresql:///db",  # a Unix socket, the default user
    "postgresql://u:secret@/db?host=/var/run/postgresql",
    "postgresql+psycopg://u:secret@host:5433/db",
    "postgresql+psycopg2://u:secret@host/db",
    "postgresql://host/db",  # the default user
    "postgresql://u:p%40ss@host/db",  # an escaped @ in the password
]


@pytest.mark.parametrize("url", PG_URLS)
def test_every_postgresql_url_sqlalchemy_takes_is_accepted(tmp_path, url):
    from sqlalchemy.engine import make_url

    from vfgym import tuning

    spec = tuning.resolve_storage(url, tmp_path)
    assert spec.kind == "postgresql" and spec.path is None
    assert make_url(spec.url) == make_url(url)  # the same database, options and all
    assert "secret" not in spec.display and "p%40ss" not in spec.display
    if make_url(url).password is not None:
        assert ":***@" in spec.display


@pytest.mark.parametrize(
    "url",
    [
        "postgresql://u:secret@127.0.0.1:1/db?sslmode=require",
        "postgresql://u:secret@[::1]:1/db",
        "postgresql://u:secret@/db?host=/nonexistent-socket-folder",
    ],
)
def test_a_postgresql_url_is_taken_up_to_the_server(ws, capsys, url):
    """Accepted, not refused: the sweep tries the server (none listens there) and says so
    in one line, the password masked; nothing is left behind."""
    assert _sweep_quietly("--study", "pg", "--storage", url) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    assert "is not allowed" not in err and "secret" not in err
    assert "cannot be opened" in err or "needs a database driver" in err, err
    assert not (ws / "runs" / "sweep" / "pg").exists()


@pytest.mark.parametrize(
    "url",
    ["sqlite:///db/x.db", "sqlite+pysqlite:///db/y.db", "sqlite:///{ws}/db/z.db?timeout=30"],
)
def test_every_sqlite_file_url_runs_a_sweep_and_leaves_no_lock(ws, capsys, url):
    (ws / "db").mkdir()
    assert _sweep_quietly("--study", "q", "--storage", url.format(ws=ws)) == 0
    capsys.readouterr()
    assert len(list((ws / "db").glob("*.db"))) == 1
    assert not list(ws.rglob("*vfgym-lock")), list(ws.rglob("*vfgym-lock"))


def test_the_default_storage_leaves_no_lock_file_in_the_run_folder(ws, capsys):
    assert _sweep_quietly("--study", "nolock") == 0
    run = ws / "runs" / "sweep" / "nolock"
    assert (run / "study.db").is_file() and not (run / "study.db.vfgym-lock").exists()


WEAK = "plant: {motor: {inertia_ratio: 5.0, accel_limit_rad_s2: 100000.0}}\n"


def test_a_motor_too_weak_for_its_limit_gets_a_note_naming_the_limit_it_uses(ws, capsys):
    """1.91 N·m over 6 rotor inertias gives 30 krad/s², not the stated 100: one note line
    after the output; an error on that axis is still one line."""
    (ws / "weak.yaml").write_text(WEAK)
    assert main(["simulate", "--axis", "weak.yaml", "--scenario", "short-move"]) == 0
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("vfgym: note: weak.yaml: plant.motor: ")
    assert "accel_limit_rad_s2 = 100 krad/s²" in err and "held to 30.03 krad/s²" in err
    (ws / "weak2.yaml").write_text(WEAK)
    assert main(["simulate", "--axis", "weak2.yaml", "--scenario", "mars"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "scenario='mars'" in err
    (ws / "strong.yaml").write_text("plant: {motor: {accel_limit_rad_s2: 100000.0}}\n")
    assert main(["simulate", "--axis", "strong.yaml", "--scenario", "short-move"]) == 0
    assert capsys.readouterr().err == ""
