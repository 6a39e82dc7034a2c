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


AXIS_HELP = (
    "an axis file (e.g. experiments/axes/belt.yaml): its plant, measures and train/test "
    "moves (default: the paper's axis, experiments/axes/paper.yaml)"
)


def add_axis_option(p: argparse.ArgumentParser) -> None:
    """The ``--axis FILE`` option every command takes."""
    p.add_argument("--axis", metavar="FILE.yaml", help=AXIS_HELP)


def axis_from_args(args: argparse.Namespace) -> Any:
    """The :class:`~vfgym.moves.axis.Axis` of ``--axis FILE`` (a bad file: one-line
    ``ValueError`` naming it), or ``None`` without the option (the paper's axis, as
    before axes existed)."""
    from vfgym.moves.axis import load_axis

    path = getattr(args, "axis", None)
    return load_axis(path) if path else None


def scenario_from_args(args: argparse.Namespace, axis: Any) -> Any:
    """``--scenario NAME`` on the axis (its listed moves, the named scenarios, or
    ``<split>-<seed>`` of its random moves), or as :func:`vfgym.get_scenario` without one."""
    from vfgym.moves.scenarios import get_scenario

    return get_scenario(args.scenario) if axis is None else axis.scenario(args.scenario)
