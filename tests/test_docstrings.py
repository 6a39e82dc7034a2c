"""Every public function and class documents its parameters, numpydoc style (as python-control).

The public API is every name in the ``__all__`` of :mod:`vfgym` and of its subpackages
``plant``, ``moves``, ``scoring``, ``report`` and ``tuning``; a module named there (such as
``vfgym.moves.baselines`` or ``vfgym.envs``) contributes the names of its own ``__all__``.
For each function, each public method of each class, and each class's constructor:

- every parameter has an entry ``name : type`` in the ``Parameters`` section (a class's
  constructor arguments may instead be listed under ``Attributes``, for result types that
  callers read rather than build), ``*args`` and ``**kwargs`` with their stars;
- no entry names a parameter the signature does not have (a stale entry after a rename);
- a function that returns something has a ``Returns`` (or ``Yields``) section;
- an exception the function raises itself (a ``raise X(...)`` in its own body) is named
  in a ``Raises`` section.
"""

from __future__ import annotations

import ast
import importlib
import inspect
import re
import textwrap
import types
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest

PACKAGES = ("vfgym", "vfgym.plant", "vfgym.moves", "vfgym.scoring", "vfgym.report", "vfgym.tuning")
_ENTRY = re.compile(r"^(\*{0,2}\w+(?:\s*,\s*\*{0,2}\w+)*)(?:\s+:.*)?$")


def public_api() -> Iterator[tuple[str, Any]]:
    """(qualified name, object) of each public function and class, each object once."""
    seen: set[int] = set()
    for package_name in PACKAGES:
        package = importlib.import_module(package_name)
        for name in package.__all__:
            obj = getattr(package, name)
            if isinstance(obj, types.ModuleType):
                # its __all__, or else the public names it defines itself
                names = getattr(obj, "__all__", None) or [
                    n
                    for n, v in vars(obj).items()
                    if not n.startswith("_") and getattr(v, "__module__", None) == obj.__name__
                ]
                pairs = [(f"{obj.__name__}.{n}", getattr(obj, n)) for n in names]
            else:
                pairs = [(f"{package_name}.{name}", obj)]
            for qualname, member in pairs:
                if (inspect.isfunction(member) or inspect.isclass(member)) and id(
                    member
                ) not in seen:
                    seen.add(id(member))
                    yield qualname, member


def sections(doc: str) -> dict[str, list[str]]:
    """numpydoc sections of a cleaned docstring: title -> the lines under its underline."""
    lines = doc.splitlines()
    found: dict[str, list[str]] = {}
    current: list[str] | None = None
    for i, line in enumerate(lines):
        below = lines[i + 1] if i + 1 < len(lines) else ""
        if line.strip() and re.fullmatch(r"-{3,}", below.strip()) and not line.startswith(" "):
            current = found.setdefault(line.strip(), [])
            continue
        if current is not None and not re.fullmatch(r"-{3,}", line.strip()):
            current.append(line)
    return found


def entries(lines: list[str]) -> list[str]:
    """The names a Parameters-like section documents (``a, b : float`` documents two)."""
    names: list[str] = []
    for line in lines:
        if line and not line[0].isspace():
            match = _ENTRY.match(line.rstrip())
            if match:
                names += [n.strip() for n in match[1].split(",")]
    return names


def raised_names(func: Callable[..., Any]) -> set[str]:
    """Exceptions the function raises itself: ``raise Name(...)`` in its own body.

    Raises inside nested functions are not its own, nor are those a surrounding ``try``
    catches (by name, or as ``Exception``).
    """
    try:
        source = textwrap.dedent(inspect.getsource(func))
    except (OSError, TypeError):
        return set()
    tree = ast.parse(source).body[0]
    found: set[str] = set()

    def caught_by(handlers: list[ast.ExceptHandler]) -> set[str]:
        names: set[str] = set()
        for h in handlers:
            types = h.type.elts if isinstance(h.type, ast.Tuple) else [h.type]
            for t in types:
                if t is None:
                    names.add("*")
                elif isinstance(t, ast.Name | ast.Attribute):
                    name = t.id if isinstance(t, ast.Name) else t.attr
                    names.add("*" if name in ("Exception", "BaseException") else name)
        return names

    def walk(node: ast.AST, caught: frozenset[str]) -> None:
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.FunctionDef | ast.AsyncFunctionDef | ast.Lambda):
                continue
            if isinstance(child, ast.Try):
                inner = caught | caught_by(child.handlers)
                for stmt in child.body:
                    walk_one(stmt, inner)
                for part in (*child.handlers, *child.orelse, *child.finalbody):
                    walk_one(part, caught)
                continue
            walk_one(child, caught)

    def walk_one(node: ast.AST, caught: frozenset[str]) -> None:
        if isinstance(node, ast.Raise) and node.exc is not None:
            exc = node.exc.func if isinstance(node.exc, ast.Call) else node.exc
            name = None
            if isinstance(exc, ast.Name) and exc.id[:1].isupper():
                name = exc.id
            elif isinstance(exc, ast.Attribute):
                name = exc.attr
            if name is not None and name not in caught and "*" not in caught:
                found.add(name)
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.Lambda):
            return
        walk(node, caught)

    walk(tree, frozenset())
    return found


def _returns_something(func: Callable[..., Any]) -> bool:
    annotation = inspect.signature(func).return_annotation
    return annotation not in (None, "None", inspect.Signature.empty, "NoReturn")


def problems(
    qualname: str,
    signature: inspect.Signature,
    doc: str | None,
    *,
    returns: bool,
    raised: set[str],
    attributes_count: bool = False,
) -> list[str]:
    """What the docstring ``doc`` misses for a callable of this ``signature``.

    ``returns``: the callable returns a value; ``raised``: the exceptions it raises itself;
    ``attributes_count``: entries under ``Attributes`` document parameters (constructors).
    """
    if not doc:
        return [f"{qualname}: no docstring"]
    found = sections(doc)
    documented = entries(found.get("Parameters", []))
    known = documented + (entries(found.get("Attributes", [])) if attributes_count else [])
    names = []
    for p in signature.parameters.values():
        if p.name not in ("self", "cls"):
            names.append({p.VAR_POSITIONAL: "*", p.VAR_KEYWORD: "**"}.get(p.kind, "") + p.name)
    out = [f"{qualname}: parameter {n!r} not documented" for n in names if n not in known]
    out += [
        f"{qualname}: documents {n!r}, which is not a parameter"
        for n in documented
        if n not in names
    ]
    if returns and not ({"Returns", "Yields"} & found.keys()):
        out.append(f"{qualname}: returns a value but has no Returns section")
    raises = " ".join(found.get("Raises", []))
    out += [
        f"{qualname}: raises {exc} but its Raises section does not say so"
        for exc in sorted(raised)
        if not re.search(rf"\b{exc}\b", raises)
    ]
    return out


def check_function(qualname: str, func: Callable[..., Any]) -> list[str]:
    """Problems of a public function's (or method's) docstring."""
    return problems(
        qualname,
        inspect.signature(func),
        inspect.getdoc(func),
        returns=_returns_something(func),
        raised=raised_names(func),
    )


def check(qualname: str, obj: Any) -> list[str]:
    """Problems of a public function, or of a class (constructor and public methods)."""
    if inspect.isfunction(obj):
        return check_function(qualname, obj)
    out = []
    raised = set()
    for hook in ("__init__", "__post_init__"):  # what building one raises itself
        if inspect.isfunction(vars(obj).get(hook)):
            raised |= raised_names(vars(obj)[hook])
    doc = inspect.cleandoc(obj.__doc__) if obj.__doc__ else None
    out += problems(
        qualname, inspect.signature(obj), doc, returns=False, raised=raised, attributes_count=True
    )
    for name, member in vars(obj).items():
        if name.startswith("_"):
            continue
        if isinstance(member, staticmethod | classmethod):
            member = member.__func__
        if inspect.isfunction(member):
            out += check_function(f"{qualname}.{name}", member)
        elif isinstance(member, property) and not member.__doc__:
            out.append(f"{qualname}.{name}: property without a docstring")
    return out


API = sorted(public_api(), key=lambda pair: pair[0])


def test_the_api_is_found() -> None:
    """The walk reaches the functions, classes and modules' members it should."""
    names = {q for q, _ in API}
    for expected in (
        "vfgym.simulate",
        "vfgym.Settings",
        "vfgym.evaluate",
        "vfgym.scoring.score",
        "vfgym.moves.baselines.rule_of_thumb",
        "vfgym.tuning.run_grid",
        "vfgym.report.compare",
        "vfgym.envs.VFTuneEnv",
    ):
        assert expected in names
    assert len(API) > 90


@pytest.mark.parametrize(("qualname", "obj"), API, ids=[q for q, _ in API])
def test_public_docstring(qualname: str, obj: Any) -> None:
    found = check(qualname, obj)
    assert not found, "\n".join(found)


REPO = Path(__file__).resolve().parents[1]


def model_citations(text: str) -> list[str]:
    """The section numbers cited as ``docs/model.md §n`` or ``§n–§m`` in a text."""
    out: list[str] = []
    for match in re.finditer(r"docs/model\.md(?:``)? (§\d+(?:\s*[–-]\s*§\d+)?)", text):
        bounds = [int(n) for n in re.findall(r"\d+", match[1])]
        out += [f"§{n}" for n in range(bounds[0], bounds[-1] + 1)]
    return out


def test_docstrings_cite_sections_of_docs_model_md() -> None:
    """Every ``docs/model.md §n`` in the source and README names a section of that page,
    and nothing cites the spec outside the repository (``MODEL.md``) any more."""
    sections_ = set(
        re.findall(r"^## (§\d+)", (REPO / "docs" / "model.md").read_text("utf-8"), re.M)
    )
    assert {"§1", "§2", "§3", "§4", "§5"} <= sections_
    files = [*sorted((REPO / "src" / "vfgym").rglob("*.py")), REPO / "README.md"]
    cited: set[str] = set()
    for path in files:
        text = path.read_text(encoding="utf-8")
        assert "MODEL.md" not in text, f"{path} cites MODEL.md, outside the repository"
        for section in model_citations(text):
            assert section in sections_, f"{path} cites docs/model.md {section}, which is absent"
            cited.add(section)
    assert {"§1", "§3", "§5"} <= cited  # the check reads the citations it should
    assert model_citations("see ``docs/model.md`` §1–§3") == ["§1", "§2", "§3"]


def test_a_missing_entry_is_caught() -> None:
    def f(a: int, b: float = 1.0, *rest: int, **options: Any) -> int:
        """Sum.

        Parameters
        ----------
        a : int
            First.
        *rest : int
            More.
        c : float
            Not a parameter.

        Raises
        ------
        KeyError
            Never.
        """
        if a < 0:
            raise ValueError(f"a={a}")
        return a

    assert check_function("f", f) == [
        "f: parameter 'b' not documented",
        "f: parameter '**options' not documented",
        "f: documents 'c', which is not a parameter",
        "f: returns a value but has no Returns section",
        "f: raises ValueError but its Raises section does not say so",
    ]


def test_raises_caught_in_the_function_are_not_its_own() -> None:
    def h(x: int) -> None:
        """Nothing escapes."""
        try:
            if x:
                raise ValueError("x")
        except ValueError:
            pass
        try:
            raise KeyError("k")
        except Exception:
            pass

        def inner() -> None:
            raise TypeError("not h's")

        if x < 0:
            raise OverflowError("escapes")

    assert raised_names(h) == {"OverflowError"}


def test_a_complete_docstring_passes() -> None:
    def g(a: int, b: float, **options: Any) -> float:
        """Scaled.

        Parameters
        ----------
        a, b : float
            The factors.
        **options
            Ignored.

        Returns
        -------
        float
            a·b.

        Raises
        ------
        ValueError
            If ``a`` is negative.
        """
        if a < 0:
            raise ValueError(f"a={a}")
        return a * b

    assert check_function("g", g) == []
