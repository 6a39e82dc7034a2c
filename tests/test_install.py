"""vfgym still imports and simulates from a read-only install with nowhere to cache."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

import vfgym

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
