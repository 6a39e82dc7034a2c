"""vfgym still imports and simulates from a read-only install with nowhere to cache."""

from __future__ import annotations

import os
import shutil
import site
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

import vfgym
from vfgym.agents import hyperparams as hp

SCRIPT = (
    "import vfgym, vfgym.plant._jit as J; "
    "tr = vfgym.simulate(vfgym.step_command(10.0, 14000)); "
    "print(J.CACHE, tr.metrics['pulse_count'], tr.metrics['move_time_s'])"
)


def _ro_mount(src: Path, dst: Path) -> bool:
    dst.mkdir(parents=True, exist_ok=True)
    ok = subprocess.run(["mount", "--bind", str(src), str(dst)], capture_output=True).returncode
    if ok != 0:
        return False
    if (
        subprocess.run(["mount", "-o", "remount,bind,ro", str(dst)], capture_output=True).returncode
        != 0
    ):
        subprocess.run(["umount", str(dst)], capture_output=True)
        return False
    return True


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="uses a read-only bind mount")
def test_read_only_install_without_any_cache_dir_still_works(tmp_path):
    if shutil.which("mount") is None or os.geteuid() != 0:
        pytest.skip("needs root and mount(8) to make a read-only bind mount")
    pkg = tmp_path / "pkg"
    shutil.copytree(
        Path(vfgym.__file__).parent, pkg / "vfgym", ignore=shutil.ignore_patterns("__pycache__")
    )
    home = tmp_path / "home"
    home.mkdir()
    ro_pkg, ro_home = tmp_path / "ro_pkg", tmp_path / "ro_home"
    if not _ro_mount(pkg, ro_pkg):
        pytest.skip("cannot make a read-only bind mount here")
    try:
        if not _ro_mount(home, ro_home):
            pytest.skip("cannot make a read-only bind mount here")
        try:
            env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
            env |= {
                "HOME": str(ro_home),
                "XDG_CACHE_HOME": str(ro_home / ".cache"),
                "PYTHONPATH": str(ro_pkg),
            }
            out = subprocess.run(
                [sys.executable, "-c", SCRIPT],
                env=env,
                cwd=tmp_path,
                capture_output=True,
                text=True,
                timeout=300,
            )
            assert out.returncode == 0, out.stderr
            m = vfgym.simulate(vfgym.step_command(10.0, 14000)).metrics
            # no cache, and the same answer as this process's cached kernel
            assert out.stdout.split() == ["False", str(m["pulse_count"]), str(m["move_time_s"])]
        finally:
            subprocess.run(["umount", str(ro_home)], capture_output=True)
    finally:
        subprocess.run(["umount", str(ro_pkg)], capture_output=True)


def _installed_venv(tmp_path: Path) -> Path:
    """A venv with vfgym installed from a copy of this source tree (a wheel, not
    editable); the rest of its packages (setuptools, torch, ...) are this interpreter's."""
    src = Path(__file__).resolve().parents[1]
    tree = tmp_path / "tree"
    skip = shutil.ignore_patterns("__pycache__", "*.egg-info", "*.nbi", "*.nbc")
    shutil.copytree(src / "src", tree / "src", ignore=skip)
    for name in ("pyproject.toml", "README.md"):
        shutil.copy(src / name, tree / name)
    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True)
    (site_dir,) = venv.glob("lib/python*/site-packages")
    # paths only: the .pth files of those folders (this checkout's editable hook) stay unread
    (site_dir / "outer.pth").write_text("\n".join(site.getsitepackages()) + "\n")
    pip = [str(venv / "bin" / "python"), "-m", "pip", "install", "--no-deps"]
    pip += ["--no-build-isolation", "--no-index", "-q", str(tree)]
    out = subprocess.run(pip, capture_output=True, text=True, env=_clean_env(), timeout=600)
    assert out.returncode == 0, out.stderr
    return venv


def _clean_env() -> dict[str, str]:
    return {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="a POSIX venv layout")
def test_a_wheel_install_trains_with_the_shipped_hyperparameters_and_predicts(tmp_path):
    pytest.importorskip("stable_baselines3")
    venv = _installed_venv(tmp_path)
    work = tmp_path / "elsewhere"
    work.mkdir()
    exe = str(venv / "bin" / "vfgym")

    def vfgym_cli(*args: str) -> str:
        out = subprocess.run([exe, *args], cwd=work, capture_output=True, text=True,
                             env=_clean_env(), timeout=900)  # fmt: skip
        assert out.returncode == 0, out.stderr
        return out.stdout

    where = subprocess.run(
        [str(venv / "bin" / "python"), "-c", "import vfgym; print(vfgym.__file__)"],
        cwd=work, capture_output=True, text=True, env=_clean_env(),
    )  # fmt: skip
    assert Path(where.stdout.strip()).is_relative_to(venv), where  # the installed copy
    vfgym_cli("train", "--algo", "ppo", "--runs-dir", "runs", "--name", "t", "--no-progress",
              "--hyperparams", "n_timesteps=32", "n_envs=4", "n_steps=8", "batch_size=16",
              "eval_freq=16", "n_eval_scenarios=2")  # fmt: skip
    cfg = yaml.safe_load((work / "runs/train/t/config.yaml").read_text())
    assert cfg["hyperparams"]["gamma"] == hp.load("ppo", "vfgym/VFTune-v0")["gamma"]
    agent = yaml.safe_load(vfgym_cli("predict", "--model", "runs/train/t/best_model.zip"))
    shipped = yaml.safe_load(vfgym_cli("predict", "--scenario", "short-move"))
    assert agent["scenario"] == "paper-step" and set(agent["settings"]) >= {"value_rad", "k"}
    assert shipped["scenario"] == "short-move" and shipped["source"].startswith("pretrained")
