"""A Griffe extension for the API pages: the docstrings' reST roles become links.

The docstrings cross-reference in Sphinx's way, ``:class:`Settings```,
``:func:`~vfgym.evaluate```, ``:meth:`Plant.whole_ticks```. mkdocstrings renders
Markdown, where such a role would show as it is written. Before the docstrings are parsed,
each role is replaced by a mkdocs-autorefs cross-reference to the object it names,
resolved in the scope of the documented object (its members, its module's imports, its
parents), else by a name unique in the package. The reference is *optional*: a target the
site does not render (a private helper, matplotlib) shows as code, without a link and
without a warning. ``~`` shows the last part of the name only, as in Sphinx, and
``:func:`text <target>``` shows ``text``.

Loaded by mkdocs.yml (``plugins: mkdocstrings: handlers: python: options: extensions``);
the docstrings in ``src/`` stay as they are.
"""

from __future__ import annotations

import html
import re
from typing import Any

import griffe

ROLE = re.compile(
    r":(?:py:)?(?P<role>class|func|meth|attr|data|mod|obj|exc|const|type)"
    r":`(?P<body>[^`]+)`"
)


def _paths(obj: griffe.Object, index: dict[str, set[str]]) -> None:
    """Every object's path by its short name (aliases left out)."""
    for member in obj.members.values():
        if member.is_alias:
            continue
        index.setdefault(member.name, set()).add(member.path)
        _paths(member, index)


def _resolve(obj: griffe.Object, target: str, index: dict[str, set[str]]) -> str:
    """The full path of ``target`` as named in ``obj``'s docstring (the name itself when
    it cannot be told)."""
    target = target.lstrip(".")
    head, _, rest = target.partition(".")
    try:
        path = obj.resolve(head)
        return f"{path}.{rest}" if rest else path
    except Exception:
        pass
    if "." in target:
        return target  # a full path already (vfgym.x.y), or an outside one (warnings.warn)
    found = index.get(target, set())
    return next(iter(found)) if len(found) == 1 else target


def _canonical(pkg: griffe.Object, path: str) -> str:
    """Where the object at ``path`` is defined (``vfgym.Motor.x`` -> ``vfgym.params.Motor.x``),
    which is where the API pages render it; ``path`` itself outside the package."""
    head, _, rest = path.partition(".")
    if head != pkg.name or not rest:
        return path
    try:
        return pkg[rest].canonical_path
    except Exception:
        return path


def convert(text: str, obj: griffe.Object, index: dict[str, set[str]]) -> str:
    """``text`` with every reST role replaced by an optional autorefs reference."""

    def link(m: re.Match[str]) -> str:
        body = m["body"].strip()
        explicit = re.fullmatch(r"(?P<title>.+?)\s*<(?P<target>[^>]+)>", body)
        if explicit:
            title, target = explicit["title"], explicit["target"]
        else:
            target = body.lstrip("~!")
            title = target.rsplit(".", 1)[-1] if body.startswith("~") else target.lstrip(".")
        path = _canonical(obj.package, _resolve(obj, target.lstrip("~!"), index))
        return (
            f'<autoref identifier="{html.escape(path)}" class="role" optional>'
            f"<code>{html.escape(title)}</code></autoref>"
        )

    return ROLE.sub(link, text)


class ReSTRoles(griffe.Extension):
    """Replaces reST roles in every docstring of a loaded package (see the module)."""

    def on_package(self, *, pkg: griffe.Module, **kwargs: Any) -> None:
        index: dict[str, set[str]] = {}
        _paths(pkg, index)
        self._walk(pkg, index)

    # older Griffe versions name the same event ``on_package_loaded``; the
    # conversion is idempotent (no role is left), so a Griffe calling both is fine
    on_package_loaded = on_package

    def _walk(self, obj: griffe.Object, index: dict[str, set[str]]) -> None:
        if obj.docstring is not None:
            new = convert(obj.docstring.value, obj, index)
            if new != obj.docstring.value:
                obj.docstring.value = new
                obj.docstring.__dict__.pop("parsed", None)  # parsed again, from the new text
        for member in obj.members.values():
            if not member.is_alias:
                self._walk(member, index)
