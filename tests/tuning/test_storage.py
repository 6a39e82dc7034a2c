"""One storage parser: what a run folder recorded (config.yaml's storage) is parsed by
resolve_storage and found again by find_storage, which `vfgym plot history|pareto` uses."""

from __future__ import annotations

import shutil

import optuna
import pytest
import yaml

from vfgym import cli, tuning


@pytest.mark.parametrize("kind", ["sqlite", "journal"])
def test_a_recorded_storage_is_found_again_even_when_the_folder_moved(tmp_path, kind):
    run = tmp_path / "a"
    spec = tuning.resolve_storage(kind, run)
    study = optuna.create_study(study_name="s", storage=tuning.open_storage(spec))
    study.optimize(lambda t: t.suggest_float("x", 0.0, 1.0), n_trials=3)
    params = [t.params for t in study.trials]
    assert tuning.find_storage(spec.display, run) == spec  # as config.yaml records it
    assert tuning.find_storage(kind, run) == spec
    moved = tmp_path / "b"
    shutil.move(run, moved)
    found = tuning.find_storage(spec.display, moved)  # the old path is gone
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
        tuning.find_storage(text, tmp_path)
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


def test_the_claim_lock_file_is_removed_and_still_excludes(tmp_path):
    """A worker removes the lock file when it closes; a worker that locked the removed
    file must take the path's new one, so that two workers never hold the lock at once."""
    import threading

    from vfgym.tuning._storage import _FileLock

    base = str(tmp_path / "study.db")
    a, b = _FileLock(base), _FileLock(base)
    a.acquire()
    a.release()
    b.acquire()
    b.release()
    a.close()
    assert not (tmp_path / "study.db.vfgym-lock").exists()
    b.acquire()  # its descriptor is of the removed file
    c = _FileLock(base)
    got = threading.Event()
    t = threading.Thread(target=lambda: (c.acquire(), got.set()))
    t.start()
    assert not got.wait(0.5)  # b holds it: c waits
    b.release()
    assert got.wait(10)
    c.close()
    t.join()
    b.close()
    assert list(tmp_path.iterdir()) == []
