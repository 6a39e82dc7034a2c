"""optuna-dashboard opens a finished sweep's run folder as it is (README, "Looking at results").

A 4-trial sweep writes ``study.db``; ``optuna-dashboard sqlite:///…/study.db`` (the
README's command line) serves it on a free 127.0.0.1 port, and the study is read back
through the dashboard's HTTP API: its name, its direction, its trials and their values as
the study itself stores them. The server is stopped at the end; every wait is bounded.
"""

from __future__ import annotations

import json
import shutil
import socket
import subprocess
import sys
import time
import urllib.error
import urllib.request
from pathlib import Path

import optuna
import pytest

from vfgym.cli import main

ROOT = Path(__file__).resolve().parents[1]
# the console script installed beside this Python (a venv's bin/), else the one on PATH
_BESIDE = Path(sys.executable).parent / "optuna-dashboard"
DASHBOARD = str(_BESIDE) if _BESIDE.is_file() else shutil.which("optuna-dashboard")
START_S = 60.0  # the server's start-up, bounded


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _get(url: str) -> dict:
    with urllib.request.urlopen(url, timeout=10) as r:
        return json.loads(r.read().decode("utf-8"))


@pytest.mark.skipif(DASHBOARD is None, reason="optuna-dashboard is in the test extra")
def test_dashboard_reads_a_finished_sweep(tmp_path: Path, monkeypatch: pytest.MonkeyPatch):
    monkeypatch.chdir(ROOT)
    runs = tmp_path / "runs"
    rc = main(["sweep", "--config", "experiments/quick.yaml", "--trials", "4",
               "--study", "dash", "--runs-dir", str(runs)])  # fmt: skip
    assert rc == 0
    db = runs / "sweep" / "dash" / "study.db"
    study = optuna.load_study(study_name="dash", storage=f"sqlite:///{db}")
    stored = sorted((t.number, t.value) for t in study.trials)
    assert len(stored) == 4

    port = _free_port()
    server = subprocess.Popen(
        [DASHBOARD, f"sqlite:///{db}", "--host", "127.0.0.1", "--port", str(port), "--quiet"],
        stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
    )  # fmt: skip
    base = f"http://127.0.0.1:{port}"
    try:
        deadline = time.monotonic() + START_S
        while True:
            try:
                listing = _get(f"{base}/api/studies")
                break
            except (urllib.error.URLError, ConnectionError):
                assert server.poll() is None, server.stderr.read().decode()[-2000:]
                assert time.monotonic() < deadline, f"no answer on {base} in {START_S} s"
                time.sleep(0.5)
        (summary,) = listing["study_summaries"]
        assert summary["study_name"] == "dash"
        assert summary["directions"] == ["minimize"]
        detail = _get(f"{base}/api/studies/{summary['study_id']}")
        served = sorted((t["number"], t["values"][0]) for t in detail["trials"])
        assert [n for n, _ in served] == [n for n, _ in stored]
        assert [v for _, v in served] == pytest.approx([v for _, v in stored])
        assert detail["best_trials"][0]["values"][0] == pytest.approx(study.best_value)
    finally:
        server.terminate()
        try:
            server.wait(timeout=10)
        except subprocess.TimeoutExpired:
            server.kill()
            server.wait(timeout=10)
