"""`vfgym sweep` across processes (each worker Optuna's ``study.optimize``): workers sharing
one study end with exactly the trials asked for; a worker killed with SIGKILL mid-trial
loses nothing (its trial is failed by Optuna's heartbeat, or on a journal by its dead
process, and retried); an interrupted sweep keeps every finished trial and continues where
it stopped. On the journal, SQLite and — when ``VFGYM_TEST_POSTGRES_URL`` names a server
(``.ci/postgres.sh`` starts one) — PostgreSQL."""

from __future__ import annotations

import dataclasses
import os
import random
import signal
import subprocess
import sys
import threading
import time
import uuid
from collections import Counter
from pathlib import Path

import optuna
import pytest
import yaml

from vfgym import tuning
from vfgym.tuning._workers import DeferredInterrupt

SRC = Path(__file__).resolve().parents[2] / "src"
PG_URL = os.environ.get("VFGYM_TEST_POSTGRES_URL")
needs_pg = pytest.mark.skipif(
    not PG_URL, reason="VFGYM_TEST_POSTGRES_URL is not set (source .ci/postgres.sh to start one)"
)
COMPLETE = optuna.trial.TrialState.COMPLETE
RUNNING = optuna.trial.TrialState.RUNNING
FAIL = optuna.trial.TrialState.FAIL
WAITING = optuna.trial.TrialState.WAITING
PRUNED = optuna.trial.TrialState.PRUNED


def storage_param(kind: str):
    return pytest.param(kind, marks=needs_pg) if kind == "postgresql" else kind


def storage_arg(kind: str) -> str:
    return PG_URL if kind == "postgresql" else kind  # type: ignore[return-value]


def cmd(tmp_path: Path, study: str, kind: str, *args: str) -> list[str]:
    return [
        sys.executable, "-m", "vfgym.cli", "sweep", "--runs-dir", str(tmp_path), "--study", study,
        "--storage", storage_arg(kind), "--scenarios", "short-move", "--no-progress",
        "--no-plots", *args,
    ]  # fmt: skip


def env() -> dict[str, str]:
    e = dict(os.environ)
    e["PYTHONPATH"] = os.pathsep.join([str(SRC), e.get("PYTHONPATH", "")]).rstrip(os.pathsep)
    e["MPLBACKEND"] = "Agg"
    return e


def start(argv: list[str]) -> subprocess.Popen:
    return subprocess.Popen(argv, env=env(), stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)  # fmt: skip


def load(tmp_path: Path, study: str, kind: str, timeout: float = 60.0) -> optuna.Study:
    spec = tuning.resolve_storage(storage_arg(kind), tmp_path / "sweep" / study)
    deadline = time.monotonic() + timeout
    while True:
        try:
            return optuna.load_study(study_name=study, storage=tuning.open_storage(spec))
        except (KeyError, ValueError):
            if time.monotonic() > deadline:
                raise
            time.sleep(0.1)


def wait_complete(study: optuna.Study, n: int, proc: subprocess.Popen, timeout=60.0) -> None:
    deadline = time.monotonic() + timeout
    while len(study.get_trials(deepcopy=False, states=(COMPLETE,))) < n:
        assert proc.poll() is None, proc.communicate()
        assert time.monotonic() < deadline, "the sweep made no progress"
        time.sleep(0.05)


def name(kind: str) -> str:
    return f"{kind[:2]}-{uuid.uuid4().hex[:10]}"  # unique on a shared server


@pytest.mark.parametrize(
    ("kind", "n"), [("journal", 60), pytest.param("postgresql", 60, marks=needs_pg)]
)
def test_three_workers_share_one_study_and_end_with_exactly_the_trials_asked(tmp_path, kind, n):
    study_name = name(kind)
    p = subprocess.run(
        cmd(tmp_path, study_name, kind, "--workers", "3", "--trials", str(n)),
        env=env(), capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert p.returncode == 0, p.stderr
    study = load(tmp_path, study_name, kind)
    states = Counter(t.state for t in study.trials)
    # Two workers starting a trial at the same moment for the last place: the later one
    # is pruned (rare); nothing else is left besides the trials asked for.
    assert states[COMPLETE] == n and set(states) <= {COMPLETE, PRUNED}
    done = sorted(t.number for t in study.trials if t.state == COMPLETE)
    summary = yaml.safe_load((tmp_path / "sweep" / study_name / "summary.yaml").read_text())
    reports = summary["workers"]
    assert len(reports) == 3 and all(r["exit"] == 0 and r["stopped"] == "done" for r in reports)
    ran = [i for r in reports for i in r["trials"]]
    assert sorted(ran) == done  # each trial run by exactly one worker
    workers = {t.user_attrs["worker"] for t in study.trials}
    assert len(workers) >= 2  # shared (a worker may start after the others are done)
    assert f"{n}/{n} completed trials" in p.stdout


def _kill_mid_trial(study: optuna.Study, proc: subprocess.Popen, timeout=60.0) -> tuple[int, int]:
    """Freeze a worker that is inside a trial, check the trial is still running, kill it."""
    parent = proc.pid
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        assert proc.poll() is None, "the sweep ended before a worker was caught in a trial"
        for t in study.get_trials(deepcopy=False, states=(RUNNING,)):
            worker = t.user_attrs.get("worker")
            if not worker:
                continue
            pid = int(worker.split("/")[1])
            if pid == parent:
                continue
            os.kill(pid, signal.SIGSTOP)
            if study.get_trials(deepcopy=False)[t.number].state == RUNNING:
                os.kill(pid, signal.SIGKILL)
                return t.number, pid
            os.kill(pid, signal.SIGCONT)
        time.sleep(0.02)
    raise AssertionError("no worker was caught inside a trial")


@pytest.mark.parametrize(
    ("kind", "n"),
    [("sqlite", 14), ("journal", 40), pytest.param("postgresql", 14, marks=needs_pg)],
)
def test_worker_killed_mid_trial_loses_nothing(tmp_path, kind, n):
    study_name = name(kind)
    args = ("--workers", "3", "--trials", str(n), "--heartbeat", "1", "--grace", "2")
    p = start(cmd(tmp_path, study_name, kind, *args))
    study = load(tmp_path, study_name, kind)
    wait_complete(study, 3, p)
    victim, _ = _kill_mid_trial(study, p)
    kept = {t.number: t.values for t in study.get_trials(deepcopy=False, states=(COMPLETE,))}
    out, err = p.communicate(timeout=180)
    assert p.returncode == 0, err
    final = load(tmp_path, study_name, kind)
    trials = final.trials
    # The killed worker's trial failed (and, on a loaded machine, maybe a live worker's
    # whose heartbeat came late: that worker goes on); each is retried exactly once.
    failed = [t.number for t in trials if t.state == FAIL]
    assert victim in failed
    for number in failed:
        retries = [t for t in trials if t.system_attrs.get("failed_trial") == number]
        assert len(retries) == 1 and retries[0].state == COMPLETE
        # Settings chosen before the kill are kept; the rest are drawn when it runs again.
        assert trials[number].params.items() <= retries[0].params.items()
    states = Counter(t.state for t in trials)
    assert states[COMPLETE] == n and states[FAIL] == len(failed)
    assert set(states) <= {COMPLETE, FAIL, PRUNED}
    for n, values in kept.items():  # nothing a worker finished is lost
        assert trials[n].state == COMPLETE and trials[n].values == values
    summary = yaml.safe_load((tmp_path / "sweep" / study_name / "summary.yaml").read_text())
    assert sorted(r["exit"] for r in summary["workers"]) == [-9, 0, 0]
    assert set(failed) <= set(summary["retried"])
    assert "failed trials retried" in out


@pytest.mark.parametrize("kind", ["sqlite", "journal"])
def test_interrupted_sweep_continues_where_it_stopped(tmp_path, kind):
    p = start(cmd(tmp_path, "r", kind, "--trials", "2000"))
    study = load(tmp_path, "r", kind)
    wait_complete(study, 6, p)
    p.send_signal(signal.SIGINT)
    _, err = p.communicate(timeout=60)
    assert p.returncode == 130, err
    assert "--study r" in err and err.strip().splitlines()[-1].startswith("vfgym sweep: inter")
    study = load(tmp_path, "r", kind)
    states = Counter(t.state for t in study.trials)
    k = states[COMPLETE]
    assert 6 <= k < 2000 and states[RUNNING] == 0
    # The interrupted trial (if the interrupt came during one) is failed and enqueued
    # again once; nothing else is left behind.
    assert states[FAIL] == states[WAITING] <= 1
    retried = sorted(t.system_attrs["failed_trial"] for t in study.trials if t.state == WAITING)
    assert retried == sorted(t.number for t in study.trials if t.state == FAIL)
    kept = {t.number: t.values for t in study.trials if t.state == COMPLETE}
    run_dir = tmp_path / "sweep" / "r"
    assert (run_dir / "trials.csv").read_text().count("\n") == len(study.trials) + 1

    more = max(4, states[WAITING])  # enough for every retry (they run first)
    q = subprocess.run(cmd(tmp_path, "r", kind, "--trials", str(k + more)), env=env(),
                       capture_output=True, text=True, timeout=300)  # fmt: skip
    assert q.returncode == 0, q.stderr
    assert f"(continued: {k}/{k + more} trials done)" in q.stdout
    final = load(tmp_path, "r", kind)
    assert Counter(t.state for t in final.trials)[COMPLETE] == k + more
    for n, values in kept.items():
        assert final.trials[n].state == COMPLETE and final.trials[n].values == values
    for t in final.trials:
        if t.state == FAIL:
            (again,) = [u for u in final.trials if u.system_attrs.get("failed_trial") == t.number]
            assert again.state == COMPLETE and t.params.items() <= again.params.items()
    assert len((run_dir / "command.txt").read_text().splitlines()) == 2


@pytest.mark.parametrize("kind", ["sqlite", "journal"])
def test_an_interrupt_at_any_moment_leaves_a_clean_study(tmp_path, kind):
    """Ctrl-C at many random moments of a worker's loop (evaluation, Optuna's storage
    writes, waiting): each time the worker stops with KeyboardInterrupt and nothing else,
    no trial is left running, completed trials are kept, and what waits is a warm start
    not yet run or the one retry of the interrupted trial."""
    cfg = tuning.SweepConfig(scenarios="short-move", trials=100_000, seed=3, storage=kind)
    spec = tuning.resolve_storage(kind, tmp_path)
    scenarios = cfg.scenario_list()
    tuning.create_or_load(tuning.open_storage(spec), "s", cfg, scenarios)
    # the moments span a worker's start and its first trials: three times what a worker
    # takes, uninterrupted, to finish two trials here (on a loaded machine its start alone
    # can exceed a fixed window, and then no trial would ever complete)
    timing = dataclasses.replace(cfg, trials=2)
    tuning.create_or_load(tuning.open_storage(spec), "timing", timing, scenarios)
    start = time.perf_counter()
    tuning.run_worker(timing, spec, "timing")
    window = max(0.15, 3.0 * (time.perf_counter() - start))
    rng = random.Random(0)
    main = threading.get_ident()
    kept: dict[int, list[float]] = {}
    for _ in range(30):
        delay = rng.uniform(0.0, window)
        timer = threading.Timer(delay, signal.pthread_kill, (main, signal.SIGINT))
        timer.start()
        try:
            with pytest.raises(KeyboardInterrupt):
                tuning.run_worker(cfg, spec, "s")
        finally:
            timer.cancel()
        study = optuna.load_study(study_name="s", storage=tuning.open_storage(spec))
        trials = study.get_trials(deepcopy=False)
        states = Counter(t.state for t in trials)
        assert states[RUNNING] == 0, (delay, states)
        failed = [
            t.system_attrs["failed_trial"]
            for t in trials
            if t.state == WAITING and "failed_trial" in t.system_attrs
        ]
        assert len(failed) == len(set(failed)), (delay, failed)
        for t in trials:
            if t.state == WAITING and "baseline" not in t.user_attrs:
                assert trials[t.system_attrs["failed_trial"]].state == FAIL, (delay, t.number)
        for n, values in kept.items():
            assert trials[n].state == COMPLETE and trials[n].values == values
        kept = {t.number: t.values for t in trials if t.state == COMPLETE}
    assert len(kept) >= 10, window


def test_an_interrupt_is_held_back_outside_an_allowed_block():
    with DeferredInterrupt() as interrupts:
        signal.raise_signal(signal.SIGINT)  # held: no raise here
        assert interrupts.pending
        with pytest.raises(KeyboardInterrupt), interrupts.allowed():
            pass  # the one held back, raised on entering
        with pytest.raises(KeyboardInterrupt), interrupts.allowed():
            signal.raise_signal(signal.SIGINT)  # allowed: raised at once
        assert not interrupts.pending and not interrupts.open
