"""Options and helpers shared by several sub-commands."""

from __future__ import annotations

import argparse
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from vfgym._validate import check_int, check_real
from vfgym.io.runs import read_yaml
from vfgym.moves.baselines import Baseline
from vfgym.params import Settings
from vfgym.space import NAMES, settings_from_dict

if TYPE_CHECKING:
    from vfgym.axis import Axis


class Interrupted(KeyboardInterrupt):
    """An interrupt (Ctrl-C) caught by a command that saved its work; the message says
    where it is and how to continue (:func:`vfgym.cli.main` prints it, exit status 130)."""


def load_settings(path: str, axis: Axis) -> Settings:
    """Settings from a YAML file: a mapping of the tuned settings, or one under the key
    ``settings`` (as ``best.yaml`` of a sweep and ``vfgym predict`` write). Any problem
    raises a one-line ``ValueError`` that names the file. A ``best.yaml`` tuned for
    another machine than the axis they are used on (its ``machine``) is noted in one line
    (:class:`~vfgym.axis.AxisNote`)."""
    try:
        data = read_yaml(path)
        _note_machine(path, data, axis)
        if isinstance(data, dict) and "settings" in data:
            data = data["settings"]
            if not isinstance(data, dict):
                raise ValueError(
                    f"settings={data!r} is not allowed: give a mapping of "
                    f"{', '.join(NAMES)} (and accel_law)"
                )
        return settings_from_dict(data, source=path)
    except ValueError as exc:
        msg = str(exc)
        raise ValueError(msg if msg.startswith(str(path)) else f"{path}: {msg}") from None


def _note_machine(path: str, data: Any, axis: Axis) -> None:
    import warnings

    from vfgym.axis import AxisNote, machine_digest

    if not isinstance(data, dict) or not isinstance(data.get("machine"), str):
        return
    if data["machine"] != machine_digest(axis):
        warnings.warn(
            f"{path}: tuned on axis {data.get('axis') or 'paper'}, used on axis {axis.name} with "
            "another plant, measures or uncertainty: its verdict does not carry over; tune "
            "for this axis (vfgym sweep --axis FILE)",
            AxisNote,
            stacklevel=3,
        )


def controller_from_args(args: argparse.Namespace, axis: Axis) -> Any:
    """The controller named by --settings FILE or --baseline NAME (default: paper), on
    ``axis`` (:func:`load_settings`)."""
    if getattr(args, "settings", None):
        return load_settings(args.settings, axis)
    return Baseline(getattr(args, "baseline", None) or "paper")


def warn_line(command: str) -> Callable[[str], None]:
    """A warning printer for a sub-command: one line on stderr, ``vfgym COMMAND:
    warning: ...``."""
    import sys

    def warn(message: str) -> None:
        print(f"vfgym {command}: warning: {message}", file=sys.stderr, flush=True)

    return warn


def whole(lo: int | None = None, hi: int | None = None) -> Callable[[str], int]:
    """argparse type: a whole number in ``[lo, hi]``, checked by
    :func:`vfgym._validate.check_int` (so ``1e3`` is 1000 and ``2.5`` is refused)."""

    def parse(text: str) -> int:
        try:
            return check_int("", text, lo, hi, text=True)
        except ValueError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None

    parse.__name__ = "whole number"
    return parse


def real(
    lo: float | None = None, hi: float | None = None, *, lo_open: bool = False
) -> Callable[[str], float]:
    """argparse type: a finite real number in the interval, checked by
    :func:`vfgym._validate.check_real` (``nan`` and ``inf`` are refused)."""

    def parse(text: str) -> float:
        try:
            return check_real("", text, lo, hi, lo_open=lo_open, text=True)
        except ValueError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None

    parse.__name__ = "real number"
    return parse


positive_int = whole(1)
"""argparse type: a whole number ≥ 1."""
SEED = whole(0, 2**32 - 1)
"""argparse type of a seed (numpy's and torch's range)."""


AXIS_HELP = (
    "an axis file (e.g. experiments/axes/belt.yaml): its plant, measures and train/test "
    "moves (default: the paper's axis, experiments/axes/paper.yaml)"
)


def add_axis_option(p: argparse.ArgumentParser) -> None:
    """The ``--axis FILE`` option every command takes."""
    p.add_argument("--axis", metavar="FILE.yaml", help=AXIS_HELP)


def axis_from_args(args: argparse.Namespace) -> Axis:
    """The :class:`~vfgym.axis.Axis` of ``--axis FILE`` (a bad file: one-line
    ``ValueError`` naming it), or the paper's axis without the option (the default
    problem, :data:`vfgym.PAPER_AXIS`)."""
    from vfgym.axis import PAPER_AXIS, load_axis

    path = getattr(args, "axis", None)
    return load_axis(path) if path else PAPER_AXIS


def scenario_from_args(args: argparse.Namespace, axis: Axis) -> Any:
    """``--scenario NAME`` on the axis (its listed moves, the named scenarios, or
    ``<split>-<seed>`` of its random moves)."""
    return axis.scenario(args.scenario)
