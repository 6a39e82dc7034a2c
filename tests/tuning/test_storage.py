"""One storage parser: what a run folder recorded (config.yaml's storage) is parsed by
resolve_storage and found again by find_storage, which `vfgym plot history|pareto` uses."""

from __future__ import annotations

import os
import shutil

import optuna
import pytest
import yaml

from vfgym import cli, tuning
from vfgym.tuning._storage import find_storage


@pytest.mark.parametrize("kind", ["sqlite", "journal"])
def test_a_recorded_storage_is_found_again_even_when_the_folder_moved(tmp_path, kind):
    run = tmp_path / "a"
    spec = tuning.resolve_storage(kind, run)
    study = optuna.create_study(study_name="s", storage=tuning.open_storage(spec))
    study.optimize(lambda t: t.suggest_float("x", 0.0, 1.0), n_trials=3)
    params = [t.params for t in study.trials]
    assert find_storage(spec.display, run) == spec  # as config.yaml records it
    assert find_storage(kind, run) == spec
    moved = tmp_path / "b"
    shutil.move(run, moved)
    found = find_storage(spec.display, moved)  # the old path is gone
    assert found.kind == kind and found.path == str(
        (moved / run.joinpath(spec.path).name).resolve()
    )
    again = optuna.load_study(study_name="s", storage=tuning.open_storage(found))
    assert [t.params for t in again.trials] == params


@pytest.mark.parametrize(
    ("text", "needle"),
    [
        ("postgresql://me:***@db/opt", "password is masked"),
        ("sqlite:////nowhere/study.db", "no sqlite file"),
        ("/nowhere/journal.log", "no journal file"),
        ("redis://h", "is not allowed"),
        ("sqlite://", "is not allowed"),
    ],
)
def test_find_storage_bad_input(tmp_path, text, needle):
    with pytest.raises(ValueError, match="storage=") as e:
        find_storage(text, tmp_path)
    assert needle in str(e.value) and "\n" not in str(e.value)


def test_plot_reads_a_journal_sweep_and_names_a_missing_storage(tmp_path, capsys):
    argv = ["sweep", "--scenarios", "short-move", "--trials", "3", "--storage", "journal",
            "--runs-dir", str(tmp_path), "--study", "j", "--no-progress", "--no-plots"]  # fmt: skip
    assert cli.main(argv) == 0
    run = tmp_path / "sweep" / "j"
    assert yaml.safe_load((run / "config.yaml").read_text())["storage"] == str(run / "journal.log")
    out = tmp_path / "h.png"
    assert cli.main(["plot", "history", "--sweep", str(run), "--out", str(out), "--dpi", "30"]) == 0
    assert out.stat().st_size > 1000
    capsys.readouterr()
    bad = ["plot", "history", "--sweep", str(run), "--storage", "sqlite:////nowhere/x.db"]
    assert cli.main([*bad, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert "/nowhere/x.db: no such file" in err and "\n" not in err


RACE = """
import sys, time
from vfgym import cli  # imported before the moment, so that both start at once
at = float(sys.argv[1])
time.sleep(max(0.0, at - time.time()))
sys.exit(cli.main(sys.argv[2:]))
"""


PG_URL = os.environ.get("VFGYM_TEST_POSTGRES_URL")


@pytest.mark.parametrize(
    "kind",
    [
        "sqlite",
        "journal",
        pytest.param(
            "postgresql",
            marks=pytest.mark.skipif(not PG_URL, reason="VFGYM_TEST_POSTGRES_URL is not set"),
        ),
    ],
)
def test_two_sweeps_started_at_the_same_moment_on_a_new_study_both_run(tmp_path, kind):
    """Both processes create the storage's tables and the study at once: neither fails
    (Optuna's table creation races: "table studies already exists"), the warm starts are
    enqueued once, and the study ends with the trials asked for."""
    import subprocess
    import sys
    import time
    import uuid
    from collections import Counter
    from pathlib import Path

    src = str(Path(__file__).resolve().parents[2] / "src")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([src, os.environ.get("PYTHONPATH", "")]))
    store = {"sqlite": f"sqlite:///{tmp_path}/s.db", "journal": f"journal:{tmp_path}/s.log"}
    store["postgresql"] = str(PG_URL)
    name = f"race-{uuid.uuid4().hex[:10]}"  # new, also on a shared server
    argv = ["sweep", "--runs-dir", str(tmp_path), "--study", name, "--storage", store[kind],
            "--scenarios", "short-move", "--trials", "8", "--no-plots",
            "--no-progress"]  # fmt: skip
    at = str(time.time() + 6.0)
    run = [sys.executable, "-c", RACE, at, *argv]
    pipe = subprocess.PIPE
    procs = [subprocess.Popen(run, env=env, text=True, stdout=pipe, stderr=pipe) for _ in range(2)]
    outs = [p.communicate(timeout=300) for p in procs]
    assert [p.returncode for p in procs] == [0, 0], [err for _, err in outs]
    spec = tuning.resolve_storage(store[kind], tmp_path)
    study = optuna.load_study(study_name=name, storage=tuning.open_storage(spec))
    states = Counter(t.state for t in study.trials)
    assert states[optuna.trial.TrialState.COMPLETE] == 8
    assert set(states) <= {optuna.trial.TrialState.COMPLETE, optuna.trial.TrialState.PRUNED}
    baselines = [t.user_attrs["baseline"] for t in study.trials if "baseline" in t.user_attrs]
    assert sorted(baselines) == ["paper", "rule-of-thumb"]


POP = """
import json, sys, time
import optuna
from vfgym import tuning
optuna.logging.set_verbosity(optuna.logging.ERROR)
spec = tuning.StorageSpec(*sys.argv[1:4])
study = optuna.load_study(study_name="pop", storage=tuning.open_storage(spec))
time.sleep(max(0.0, float(sys.argv[4]) - time.time()))
print(json.dumps([study.ask().number for _ in range(int(sys.argv[5]))]))
"""


@pytest.mark.parametrize("kind", ["sqlite", "journal"])
def test_two_workers_never_pop_the_same_enqueued_trial(tmp_path, kind):
    """SQLite has no row locks: a worker reading a waiting trial's state and another writing
    it between the read and the write both ran it (optuna/optuna#4002). Two processes ask
    150 trials each from 300 enqueued at the same moment; each is handed out once."""
    import json
    import subprocess
    import sys
    import time
    from pathlib import Path

    spec = tuning.resolve_storage(kind, tmp_path)
    study = optuna.create_study(study_name="pop", storage=tuning.open_storage(spec))
    for i in range(300):
        study.enqueue_trial({"x": float(i)})
    src = str(Path(__file__).resolve().parents[2] / "src")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([src, os.environ.get("PYTHONPATH", "")]))
    at = str(time.time() + 4.0)
    run = [sys.executable, "-c", POP, spec.kind, spec.url, spec.path or "", at, "150"]
    pipe = subprocess.PIPE
    procs = [subprocess.Popen(run, env=env, text=True, stdout=pipe, stderr=pipe) for _ in range(2)]
    outs = [p.communicate(timeout=300) for p in procs]
    assert [p.returncode for p in procs] == [0, 0], [err for _, err in outs]
    a, b = (json.loads(out) for out, _ in outs)
    assert set(a).isdisjoint(b)
    assert sorted(a + b) == list(range(300))


FAIL_ALL = """
import copy, json, sys, time
import optuna
from vfgym import tuning
from vfgym.tuning._workers import _fail_and_retry
optuna.logging.set_verbosity(optuna.logging.ERROR)
spec = tuning.StorageSpec(*sys.argv[1:4])
study = optuna.load_study(study_name="dead", storage=tuning.open_storage(spec))
running = [copy.deepcopy(t) for t in study.get_trials(deepcopy=False)]
time.sleep(max(0.0, float(sys.argv[4]) - time.time()))
print(json.dumps([t.number for t in running if _fail_and_retry(study, t)]))
"""


@pytest.mark.parametrize("kind", ["sqlite", "journal"])
def test_two_workers_never_retry_the_same_dead_trial(tmp_path, kind):
    """Two workers that take the same running trials as dead at the same moment: each trial
    is failed by one of them only, and enqueued again once (on SQLite, without row locks,
    both read "running" before either wrote "failed" unless the state change is atomic)."""
    import json
    import subprocess
    import sys
    import time
    from collections import Counter
    from pathlib import Path

    spec = tuning.resolve_storage(kind, tmp_path)
    study = optuna.create_study(study_name="dead", storage=tuning.open_storage(spec))
    for _ in range(150):
        study.ask({"x": optuna.distributions.FloatDistribution(0.0, 1.0)})
    src = str(Path(__file__).resolve().parents[2] / "src")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([src, os.environ.get("PYTHONPATH", "")]))
    at = str(time.time() + 4.0)
    run = [sys.executable, "-c", FAIL_ALL, spec.kind, spec.url, spec.path or "", at]
    pipe = subprocess.PIPE
    procs = [subprocess.Popen(run, env=env, text=True, stdout=pipe, stderr=pipe) for _ in range(2)]
    outs = [p.communicate(timeout=300) for p in procs]
    assert [p.returncode for p in procs] == [0, 0], [err for _, err in outs]
    a, b = (json.loads(out) for out, _ in outs)
    assert set(a).isdisjoint(b) and sorted(a + b) == list(range(150))
    trials = optuna.load_study(study_name="dead", storage=tuning.open_storage(spec)).trials
    retried = Counter(t.system_attrs.get("failed_trial") for t in trials[150:])
    assert retried == Counter(range(150))
