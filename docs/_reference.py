"""The reference pages' tables written from the code, into the pages themselves, so that
they read in the repository as on the site:

- ``docs/reference/commands.md``, between ``<!-- vfgym:help:begin -->`` and
  ``<!-- vfgym:help:end -->``: ``vfgym --help`` and every sub-command's ``--help``, as
  the installed command prints them (80 columns; a reST role in a description shown as
  the bare name), one section each;
- ``docs/reference/axis.md``, between ``<!-- vfgym:axis-keys:begin -->`` and
  ``<!-- vfgym:axis-keys:end -->``: the axis file's keys, a table per dataclass (field,
  default, the docstring's description of it).

    python docs/_reference.py            # rewrite the blocks from the code
    python docs/_reference.py --check    # exit 1 (and show the difference) if a page differs

``tests/test_docs.py`` runs the check, so the pages cannot fall behind the command line or
the dataclasses.
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import difflib
import inspect
import io
import os
import re
import sys
from pathlib import Path
from typing import Any

DOCS = Path(__file__).resolve().parent
BLOCKS = {"help": DOCS / "reference" / "commands.md", "axis-keys": DOCS / "reference" / "axis.md"}
"""Each generated block's name and the page it is in."""


def _help_text(argv: list[str]) -> str:
    from vfgym.cli import build_parser

    old = os.environ.get("COLUMNS")
    os.environ["COLUMNS"] = "80"
    try:
        out = io.StringIO()
        with contextlib.redirect_stdout(out), contextlib.suppress(SystemExit):
            build_parser().parse_args([*argv, "--help"])
        # a module docstring's reST role, as ``--help`` prints it, reads as the bare name here
        return re.sub(
            r":(?:class|func|meth|attr|data|mod):`~?([^`]+)`", r"\1", out.getvalue()
        ).rstrip()
    finally:
        if old is None:
            os.environ.pop("COLUMNS", None)
        else:
            os.environ["COLUMNS"] = old


def help_markdown() -> str:
    """``vfgym --help`` and each sub-command's, as Markdown sections."""
    from vfgym.cli import build_parser

    subs = build_parser().subcommands
    parts = ["## vfgym", "", "```text", _help_text([]), "```", ""]
    for name in sorted(subs):
        parts += [f"## vfgym {name}", "", "```text", _help_text([name]), "```", ""]
    return "\n".join(parts)


def _described(cls: type) -> dict[str, str]:
    """The numpydoc ``Parameters`` of ``cls``'s docstring: name -> description (one line)."""
    doc = inspect.getdoc(cls) or ""
    m = re.search(r"^Parameters\n-+\n(.*?)(?:^\S[^\n]*\n-+\n|\Z)", doc, flags=re.S | re.M)
    found: dict[str, str] = {}
    if not m:
        return found
    name = None
    for line in m.group(1).splitlines():
        head = re.match(r"^(\w+(?:, \w+)*)\s*(?::.*)?$", line)
        if head and not line.startswith(" "):
            name = head.group(1)
            for each in name.split(", "):
                found[each] = ""
        elif name and line.strip():
            for each in name.split(", "):
                found[each] = (found[each] + " " + line.strip()).strip()
    return found


def _default(f: dataclasses.Field) -> str:
    if f.default is not dataclasses.MISSING:
        value: Any = f.default
    elif f.default_factory is not dataclasses.MISSING:
        value = f.default_factory()
    else:
        return "required"
    if dataclasses.is_dataclass(value):
        return f"{type(value).__name__}(…)"
    return f"`{value!r}`"


def _cell(text: str) -> str:
    text = re.sub(r":(?:class|func|meth|attr|data|mod):`~?([^`]+)`", r"`\1`", text)
    return text.replace("``", "`").replace("|", "\\|")


def axis_keys_markdown() -> str:
    """A table of keys for each dataclass an axis file is written in."""
    import vfgym
    from vfgym.axis import Uncertainty
    from vfgym.moves.distribution import MoveDistribution

    where = [
        ("plant", vfgym.Plant),
        ("plant: motor", vfgym.Motor),
        ("plant: servo", vfgym.Servo),
        ("plant: transmission", vfgym.Transmission),
        ("measures", vfgym.Measures),
        ("moves: train / test, each move", vfgym.Scenario),
        ("moves: train / test, random", MoveDistribution),
        ("uncertainty", Uncertainty),
    ]
    parts = []
    for key, cls in where:
        desc = _described(cls)
        parts += [f"### `{key}`: `{cls.__module__}.{cls.__name__}`", ""]
        parts += ["| key | default | what it is |", "| --- | --- | --- |"]
        for f in dataclasses.fields(cls):
            if not f.init:
                continue
            parts.append(f"| `{f.name}` | {_cell(_default(f))} | {_cell(desc.get(f.name, ''))} |")
        parts.append("")
    return "\n".join(parts)


def generated(name: str) -> str:
    """The text of block ``name`` as the code makes it."""
    return {"help": help_markdown, "axis-keys": axis_keys_markdown}[name]()


def with_block(page: str, name: str, text: str) -> str:
    """``page`` with block ``name`` replaced by ``text`` (the markers kept)."""
    begin, end = f"<!-- vfgym:{name}:begin -->", f"<!-- vfgym:{name}:end -->"
    head, sep, rest = page.partition(begin + "\n")
    _, sep2, tail = rest.partition(end)
    if not sep or not sep2:
        raise ValueError(f"the page has no {begin} ... {end} block")
    return f"{head}{begin}\n{text.rstrip()}\n{end}{tail}"


def main(argv: list[str] | None = None) -> int:
    """Rewrite (or ``--check``) every block; the exit status is 1 where a page differs."""
    ap = argparse.ArgumentParser(description="write the reference pages' generated blocks")
    ap.add_argument("--check", action="store_true", help="only compare; exit 1 on a difference")
    args = ap.parse_args(argv)
    differ = 0
    for name, path in BLOCKS.items():
        old = path.read_text(encoding="utf-8")
        new = with_block(old, name, generated(name))
        if new == old:
            continue
        differ = 1
        if args.check:
            sys.stdout.writelines(difflib.unified_diff(
                old.splitlines(True), new.splitlines(True), str(path), "from the code", n=1
            ))  # fmt: skip
        else:
            path.write_text(new, encoding="utf-8")
            print(f"wrote {path}")
    return differ if args.check else 0


if __name__ == "__main__":
    sys.exit(main())
