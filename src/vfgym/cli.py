"""The ``vfgym`` command line: one sub-command per module of :mod:`vfgym.commands`.

Each module there defines ``add_parser(subparsers)``, which adds its sub-command and sets
``func`` to the function that runs it (returning an exit code). Bad input — a
``ValueError`` raised anywhere — ends the command with a one-line error naming the
problem and exit status 2; an interrupt (Ctrl-C) exits with 130 after the command has
saved what it finished.
"""

from __future__ import annotations

import argparse
import importlib
import pkgutil
import sys

from vfgym import commands


def build_parser() -> argparse.ArgumentParser:
    """The parser with every sub-command found in :mod:`vfgym.commands`."""
    parser = argparse.ArgumentParser(
        prog="vfgym",
        description="Simulate, tune and evaluate a V-F transformation pulse-train "
        "position controller and the digital servo it drives.",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for info in sorted(pkgutil.iter_modules(commands.__path__), key=lambda m: m.name):
        if not info.name.startswith("_"):
            importlib.import_module(f"vfgym.commands.{info.name}").add_parser(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``vfgym`` console script."""
    from vfgym.io.runs import set_command_line

    parser = build_parser()
    args = parser.parse_args(argv)
    set_command_line(sys.argv[1:] if argv is None else argv)
    try:
        return int(args.func(args) or 0)
    except ValueError as exc:
        print(f"vfgym {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"vfgym {args.command}: interrupted; finished work is saved", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
