"""The ``vfgym`` command line: one sub-command per module of :mod:`vfgym.commands`.

Each module there defines ``add_parser(subparsers)``, which adds its sub-command and sets
``func`` to the function that runs it (returning an exit code).

:func:`main` is the one place where failures become exit statuses. Every expected failure
ends with one line on stderr, ``vfgym COMMAND: error: ...``, naming what failed and what
is allowed, and exit status 2:

- bad input: a usage error (argparse) or a ``ValueError`` raised by a check anywhere
  (:mod:`vfgym._validate`, the config dataclasses, settings files, ...);
- a file that cannot be read or written (``OSError``: a missing folder, a file in the way,
  no permission, a read-only file system, a full disk);
- a closed output pipe (``vfgym ... | head -1``): the command still finishes its work,
  the output printed after the reader left is dropped;
- an optional package that is not installed (the agents or postgres extra).

An interrupt (Ctrl-C) exits with 130 after the command has saved what it finished. Any
other exception is a bug in vfgym: its traceback is printed, with a line asking to report
it, and the exit status is 1.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import os
import pkgutil
import re
import sys
import traceback
import warnings
from typing import Any, NoReturn

from vfgym import commands

EXTRAS = {
    "stable_baselines3": "agents",
    "torch": "agents",
    "tensorboard": "agents",
    "psycopg": "postgres",
    "psycopg2": "postgres",
}
"""Optional packages and the extra of ``pyproject.toml`` that installs each."""
ISSUES_HINT = (
    "this is a bug in vfgym, not in your input: please report it with the command line "
    "and the traceback above"
)


class Parser(argparse.ArgumentParser):
    """argparse's parser with one-line usage errors (exit status 2), reported by the
    sub-command they concern; :attr:`subcommands` holds the sub-commands' parsers by name
    (:func:`build_parser` fills it)."""

    subcommands: dict[str, argparse.ArgumentParser]

    def parse_args(self, args: Any = None, namespace: Any = None) -> Any:  # type: ignore[override]
        ns, extras = self.parse_known_args(args, namespace)
        if extras:
            sub = getattr(self, "subcommands", {})
            owner = sub.get(getattr(ns, "command", None) or "", self)
            owner.error(f"unrecognized arguments: {' '.join(extras)}")
        return ns

    def error(self, message: str) -> NoReturn:
        # a value refused by a vfgym check reads as everywhere else: --opt='v' is ...
        m = re.match(r"^argument ([^:/ ]+)[^:]*: ('.*)$", message)
        if m:
            message = f"{m.group(1)}={m.group(2)}"
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def _version() -> str:
    """The installed package's version (its metadata, as ``pip show vfgym`` gives it)."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("vfgym")
    except PackageNotFoundError:  # run from a source tree that was never installed
        return "unknown (not installed)"


def build_parser() -> Parser:
    """The parser with every sub-command found in :mod:`vfgym.commands` (by name in its
    :attr:`Parser.subcommands`)."""
    parser = Parser(
        prog="vfgym",
        description="Simulate, tune and evaluate a V-F transformation pulse-train "
        "position controller and the digital servo it drives.",
    )
    parser.add_argument(
        "--version", action="version", version=f"%(prog)s {_version()}",
        help="print the installed vfgym's version and exit",
    )  # fmt: skip
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for info in sorted(pkgutil.iter_modules(commands.__path__), key=lambda m: m.name):
        if not info.name.startswith("_"):
            importlib.import_module(f"vfgym.commands.{info.name}").add_parser(sub)
    parser.subcommands = dict(sub.choices)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``vfgym`` console script; returns the exit status.

    Parameters
    ----------
    argv
        The arguments after ``vfgym`` (default: ``sys.argv[1:]``).

    Returns
    -------
    int
        0 on success, 2 for bad input or a file, pipe or package problem (one line on
        stderr), 130 after an interrupt, 1 for a bug (with its traceback).
    """
    from vfgym.axis import AxisNote
    from vfgym.io.runs import set_command_line

    guard = _StdoutGuard(sys.stdout)
    sys.stdout = guard
    notes: list[str] = []
    show = warnings.showwarning

    def keep(message: Any, category: type[Warning], *rest: Any, **kw: Any) -> None:
        if issubclass(category, AxisNote):
            notes.append(str(message))
        else:
            show(message, category, *rest, **kw)

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("always", AxisNote)
            warnings.showwarning = keep
            code = _run(argv, guard)
        if code == 0:  # a note after the output, and none after an error's one line
            for note in dict.fromkeys(notes):
                _error_line(f"vfgym: note: {note}")
    finally:
        sys.stdout = guard.stream
        set_command_line(None)
    return code


def _run(argv: list[str] | None, guard: _StdoutGuard) -> int:
    from vfgym.commands._common import Interrupted
    from vfgym.io.runs import set_command_line

    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # --help, or a usage error already printed in one line
        guard.flush()
        return exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 2)
    set_command_line(sys.argv[1:] if argv is None else argv)
    name = f"vfgym {args.command}"
    try:
        code = int(args.func(args) or 0)
        guard.flush()
        if guard.broken:
            _error_line(
                f"{name}: error: the output pipe was closed early (e.g. by `| head`): the "
                "printed output after that was dropped, the command itself finished; "
                "redirect to a file (> out.txt) to keep all of it"
            )
            return 2
        return code
    except KeyboardInterrupt as exc:
        detail = str(exc) if isinstance(exc, Interrupted) else ""
        _error_line(f"{name}: interrupted" + (f": {detail}" if detail else ""))
        return 130
    except OSError as exc:
        _error_line(f"{name}: error: {_os_message(exc, args)}")
        return 2
    except ValueError as exc:
        _error_line(f"{name}: error: {_one_line(str(exc))}")
        return 2
    except ImportError as exc:
        extra = EXTRAS.get((exc.name or "").split(".")[0])
        if extra is None:
            return _bug(name)
        _error_line(
            f"{name}: error: {exc.name} is not installed; it comes with the {extra} extra: "
            f'pip install -c constraints.txt -e ".[{extra}]"'
        )
        return 2
    except Exception:
        return _bug(name)


class _StdoutGuard:
    """stdout for the length of a command: once its reader has gone (a closed pipe,
    ``vfgym sweep ... | head -1``), further output is dropped instead of raising
    ``BrokenPipeError`` wherever the command happens to print, so the command finishes
    its work (run folders, studies) the same whatever the reader's timing; :func:`main`
    then reports the closed pipe in one line. The file descriptor is pointed at
    /dev/null, as the Python documentation recommends, so that the interpreter's flush at
    exit does not fail again."""

    def __init__(self, stream: Any) -> None:
        self.stream = stream
        self.broken = False

    def write(self, text: str) -> int:
        if not self.broken:
            try:
                return self.stream.write(text)
            except BrokenPipeError:
                self._close()
        return len(text)

    def flush(self) -> None:
        if not self.broken:
            try:
                self.stream.flush()
            except BrokenPipeError:
                self._close()

    def _close(self) -> None:
        self.broken = True
        try:
            fd = self.stream.fileno()
        except (AttributeError, OSError, ValueError):  # a captured stdout (tests)
            return
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, fd)
        os.close(devnull)

    def __getattr__(self, name: str) -> Any:
        return getattr(self.stream, name)


def _bug(name: str) -> int:
    traceback.print_exc()
    _error_line(f"{name}: {ISSUES_HINT}")
    return 1


def _error_line(text: str) -> None:
    with contextlib.suppress(OSError):  # stderr closed as well: nothing left to tell
        print(text, file=sys.stderr, flush=True)


def _one_line(text: str) -> str:
    return " ".join(text.split()) or "bad input"


def _os_message(exc: OSError, args: argparse.Namespace) -> str:
    """``OPTION: PATH: reason; what is allowed`` for a failed file operation."""
    from vfgym._validate import describe_os_error

    option = _option_for_path(vars(args), exc.filename)
    head = f"{option}: " if option else ""
    hint = (
        "; give a path in a folder you can write"
        if exc.filename is not None
        else "; check the paths given"
    )
    return _one_line(f"{head}{describe_os_error(exc)}{hint}")


def _option_for_path(values: dict[str, Any], filename: Any) -> str | None:
    """The option whose path value is, contains or lies in ``filename`` (the longest), or
    names the file a temporary file beside it stands for (``.NAME.tmp``)."""
    if filename is None:
        return None
    target = os.path.abspath(os.fsdecode(filename))
    best: tuple[int, str] | None = None
    for dest, value in values.items():
        items = value if isinstance(value, list) else [value]
        for item in items:
            if not isinstance(item, str) or not item or dest in ("command", "kind"):
                continue
            v = os.path.abspath(item)
            related = (
                target == v
                or target.startswith(v + os.sep)
                or v.startswith(target + os.sep)
                or (
                    os.path.dirname(target) == os.path.dirname(v)
                    and os.path.basename(target).startswith(f".{os.path.basename(v)}.")
                )
            )
            if related and (best is None or len(v) > best[0]):
                best = (len(v), "--" + dest.replace("_", "-"))
    return best[1] if best else None


if __name__ == "__main__":
    sys.exit(main())
