"""mkdocs hooks (mkdocs.yml ``hooks:``): reference pages written from the code at build time.

Two markers, each alone on its line in a page:

- ``<!-- vfgym:help -->``: ``vfgym --help`` and every sub-command's ``--help``, as the
  installed command prints them (80 columns; a reST role in a description shown as the
  bare name), one section each;
- ``<!-- vfgym:axis-keys -->``: the axis file's keys, a table per dataclass (field, type,
  default, the docstring's description of it).

So the pages cannot fall behind the command line or the dataclasses.
"""

from __future__ import annotations

import contextlib
import dataclasses
import inspect
import io
import os
import re
from typing import Any

HELP = "<!-- vfgym:help -->"
AXIS_KEYS = "<!-- vfgym:axis-keys -->"


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

    subs = build_parser()._subparsers._group_actions[0].choices  # type: ignore[union-attr]
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
    from vfgym.moves.distribution import MoveDistribution
    from vfgym.axis import Uncertainty

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


def on_page_markdown(markdown: str, **kwargs: Any) -> str:
    if HELP in markdown:
        markdown = markdown.replace(HELP, help_markdown())
    if AXIS_KEYS in markdown:
        markdown = markdown.replace(AXIS_KEYS, axis_keys_markdown())
    return markdown
