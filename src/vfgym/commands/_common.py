"""Options and helpers shared by several sub-commands."""

from __future__ import annotations

import argparse
from typing import Any

from vfgym.io.runs import read_yaml
from vfgym.moves.baselines import Baseline
from vfgym.params import Settings
from vfgym.space import settings_from_dict


def load_settings(path: str) -> Settings:
    """Settings from a YAML file: a mapping of the tuned settings, or one under the key
    ``settings`` (as ``best.yaml`` of a sweep and ``vfgym predict`` write)."""
    data = read_yaml(path)
    if isinstance(data, dict) and "settings" in data and isinstance(data["settings"], dict):
        data = data["settings"]
    return settings_from_dict(data, source=path)


def controller_from_args(args: argparse.Namespace) -> Any:
    """The controller named by --settings FILE or --baseline NAME (default: paper)."""
    if getattr(args, "settings", None):
        return load_settings(args.settings)
    return Baseline(getattr(args, "baseline", None) or "paper")


def positive_int(text: str) -> int:
    """argparse type: a whole number ≥ 1."""
    try:
        n = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None
    if n < 1:
        raise argparse.ArgumentTypeError(f"{n} is out of range: allowed whole numbers >= 1")
    return n
