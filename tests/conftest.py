"""Shared test set-up. The tests mirror the packages of ``src/vfgym`` (``plant/``,
``moves/``, ``scoring/``, ``tuning/``, ``report/``, ``io/``, ``envs/``, ``permove/``, ``agents/``,
``commands/``); ``helpers.py`` holds shared plants and ``oracles.py`` the independent
oracles (both importable from any test, see ``pythonpath`` in ``pyproject.toml``)."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

os.environ.setdefault("MPLBACKEND", "Agg")  # figures are drawn off-screen

REPO = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="session")
def repo_root() -> Path:
    """The repository's root folder (experiments/, agents/, README.md)."""
    return REPO
