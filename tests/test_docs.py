"""The documentation site builds with ``mkdocs build --strict`` (the ``docs`` extra).

Strict mode fails on any warning: a broken link between pages, a page missing from the
navigation, a docstring mkdocstrings cannot parse as numpydoc. The API pages must hold the
public functions with their parameters, rendered from the docstrings.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def test_mkdocs_build_strict(tmp_path: Path):
    pytest.importorskip("mkdocstrings", reason="the docs extra builds the documentation")
    site = tmp_path / "site"
    env = {**os.environ, "NO_MKDOCS_2_WARNING": "1"}
    done = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "-f", str(ROOT / "mkdocs.yml"),
         "-d", str(site)],
        cwd=ROOT, capture_output=True, text=True, timeout=600, env=env,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr[-4000:]
    scoring = (site / "api" / "scoring" / "index.html").read_text(encoding="utf-8")
    assert 'id="vfgym.scoring.evaluate"' in scoring
    assert "Parameters" in scoring and "Returns" in scoring
    for page in ("index", "axes", "model", "tuning", "agents", "results", "speed"):
        path = site / ("index.html" if page == "index" else f"{page}/index.html")
        assert path.is_file(), page
