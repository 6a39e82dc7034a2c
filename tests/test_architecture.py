"""Imports run one way, downward: the layers of docs/architecture.md, read from the source.

Every module under ``src/vfgym`` is parsed (``ast``, so imports inside functions and under
``TYPE_CHECKING`` count too: a lazy import does not hide a dependency), and so are the
strings that name a module (``importlib.import_module`` targets, entry points such as
``"vfgym.envs.tune:VFTuneEnv"``). Each module belongs to one *part*: the subpackage it sits
in (``plant``, ``moves`` …) or, for a top-level module, its own name (``params``, ``cli``);
the package's ``__init__`` (the public API, re-exports only) is the part ``vfgym``.

A part may import its own modules, the parts of its own layer (siblings) and those of lower
layers, never a higher layer; and the parts import one another without a circle. Within the
tuners' two packages (``permove``, ``agents``) the modules, too, import one another without
a circle.
"""

from __future__ import annotations

import ast
import re
from collections.abc import Iterable, Mapping
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
SRC = REPO / "src"
PACKAGE = SRC / "vfgym"
ARCHITECTURE_DOC = REPO / "docs" / "architecture.md"

# Lowest first. The reasons are in docs/architecture.md ("Dependency direction").
LAYERS: tuple[tuple[str, ...], ...] = (
    ("_validate", "_limits", "mechanics", "params", "space", "io"),  # shared vocabulary; io: files
    ("plant",),  # params -> Trace
    ("moves",),  # what the plant is asked to do
    ("axis",),  # the problem: plant, measures, moves, uncertainty
    ("scoring",),  # measures -> constraints -> cost
    ("tuning", "report", "envs", "identify"),  # built on the scoring path (identify: plant, moves)
    ("permove",),  # per-move settings models, torch-free
    ("vfgym",),  # the public API (vfgym/__init__.py): re-exports of the layers below
    ("agents",),  # stable-baselines3 on the envs
    ("commands", "cli"),  # the command line
)
LAYER_OF = {part: rank for rank, parts in enumerate(LAYERS) for part in parts}

# A string naming a vfgym module, optionally with ":attribute" (an entry point).
_MODULE_STRING = re.compile(r"vfgym(?:\.\w+)+(?::\w+)?")


def module_name(path: Path) -> str:
    """``src/vfgym/plant/_kernel.py`` -> ``vfgym.plant._kernel`` (packages by their folder)."""
    parts = list(path.relative_to(SRC).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def part_of(module: str) -> str:
    """The part of a module: ``vfgym.plant._kernel`` -> ``plant``, ``vfgym`` -> ``vfgym``."""
    pieces = module.split(".")
    return pieces[1] if len(pieces) > 1 else pieces[0]


MODULES = {module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


def _resolve(name: str) -> str | None:
    """The longest prefix of a dotted name that is a module of the package (None: not ours)."""
    pieces = name.split(".")
    for end in range(len(pieces), 0, -1):
        candidate = ".".join(pieces[:end])
        if candidate in MODULES:
            return candidate
    return None


def imports_of(module: str, source: str) -> set[str]:
    """The package's modules that ``module`` imports anywhere in ``source``."""
    is_package = MODULES[module].name == "__init__.py"
    package = module if is_package else module.rpartition(".")[0]
    found: set[str] = set()
    for node in ast.walk(ast.parse(source)):
        names: Iterable[str] = ()
        if isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - (node.level - 1)]
                target = ".".join([*base, node.module] if node.module else base)
            else:
                target = node.module or ""
            # ``from vfgym.moves import baselines`` imports the module vfgym.moves.baselines;
            # ``from vfgym.moves import SCENARIOS`` a name of the package vfgym.moves.
            subs = [f"{target}.{alias.name}" for alias in node.names]
            names = [n if n in MODULES else target for n in subs]
        elif isinstance(node, ast.Constant) and isinstance(node.value, str):
            if _MODULE_STRING.fullmatch(node.value):
                names = [node.value.partition(":")[0]]
        elif isinstance(node, ast.JoinedStr) and node.values:
            head = node.values[0]  # f"vfgym.commands.{name}": the fixed prefix is imported
            if isinstance(head, ast.Constant) and isinstance(head.value, str):
                prefix = head.value.rstrip(".")
                if head.value.endswith(".") and _MODULE_STRING.fullmatch(prefix):
                    names = [prefix]
        for name in names:
            resolved = _resolve(name)
            if resolved is not None and resolved != module:
                found.add(resolved)
    return found


def import_graph() -> dict[str, set[str]]:
    """Module -> the package's modules it imports."""
    return {m: imports_of(m, p.read_text(encoding="utf-8")) for m, p in MODULES.items()}


def upward_imports(
    graph: Mapping[str, Iterable[str]], layer_of: Mapping[str, int] = LAYER_OF
) -> list[str]:
    """Each import of a higher layer's part, as ``"importer -> imported"``."""
    bad = []
    for module, targets in graph.items():
        for target in sorted(targets):
            src, dst = part_of(module), part_of(target)
            if layer_of[dst] > layer_of[src]:
                bad.append(
                    f"{module} -> {target} ({src}: layer {layer_of[src]}, {dst}: {layer_of[dst]})"
                )
    return bad


def part_cycles(graph: Mapping[str, Iterable[str]]) -> list[list[str]]:
    """Circles between parts (a part importing itself is not one), each as a path."""
    edges: dict[str, set[str]] = {}
    for module, targets in graph.items():
        for target in targets:
            src, dst = part_of(module), part_of(target)
            if src != dst:
                edges.setdefault(src, set()).add(dst)
    cycles: list[list[str]] = []
    state: dict[str, int] = {}  # 1: on the current path, 2: done
    path: list[str] = []

    def visit(node: str) -> None:
        state[node] = 1
        path.append(node)
        for nxt in sorted(edges.get(node, ())):
            if state.get(nxt) == 1:
                cycles.append([*path[path.index(nxt) :], nxt])
            elif nxt not in state:
                visit(nxt)
        path.pop()
        state[node] = 2

    for node in sorted(edges):
        if node not in state:
            visit(node)
    return cycles


def module_cycles(graph: Mapping[str, Iterable[str]]) -> list[list[str]]:
    """Circles between modules (strongly connected groups of two or more), each sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    groups: list[list[str]] = []

    def visit(node: str) -> None:
        index[node] = low[node] = len(index)
        stack.append(node)
        on_stack.add(node)
        for nxt in sorted(graph.get(node, ())):
            if nxt not in index:
                visit(nxt)
                low[node] = min(low[node], low[nxt])
            elif nxt in on_stack:
                low[node] = min(low[node], index[nxt])
        if low[node] == index[node]:
            group = []
            while True:
                top = stack.pop()
                on_stack.discard(top)
                group.append(top)
                if top == node:
                    break
            if len(group) > 1:
                groups.append(sorted(group))

    for node in sorted(graph):
        if node not in index:
            visit(node)
    return groups


GRAPH = import_graph()
TUNER_PACKAGES = ("permove", "agents")


def test_every_module_has_a_layer() -> None:
    """A new top-level module or subpackage must be placed in LAYERS (and in the docs)."""
    unplaced = sorted({part_of(m) for m in MODULES} - set(LAYER_OF))
    assert not unplaced, f"parts without a layer in tests/test_architecture.py: {unplaced}"


def test_imports_run_downward() -> None:
    bad = upward_imports(GRAPH)
    assert not bad, "imports of a higher layer:\n" + "\n".join(bad)


def test_no_circle_between_parts() -> None:
    cycles = part_cycles(GRAPH)
    assert not cycles, "import circles: " + "; ".join(" -> ".join(c) for c in cycles)


def test_no_circle_between_modules() -> None:
    """No module imports, even lazily, a module that imports it back (as
    ``scoring/_evaluate.py`` and ``_plants.py``, ``tuning/_aggregate.py`` and ``_config.py``,
    ``agents/loaded.py`` and ``agents/training.py`` once did)."""
    cycles = module_cycles(GRAPH)
    assert not cycles, "module circles: " + "; ".join(" <-> ".join(c) for c in cycles)


def private_reaches(module: str, source: str) -> list[str]:
    """What ``module`` imports that is private to another subpackage: one of its
    ``_modules``, or a ``_name`` of one of its modules (the root's own shared modules,
    ``vfgym._validate`` and ``vfgym._limits``, are the whole package's vocabulary)."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if not isinstance(node, ast.ImportFrom) or node.level or not node.module:
            continue
        if not node.module.startswith("vfgym.") or part_of(node.module) == part_of(module):
            continue
        pieces = node.module.split(".")[2:]
        names = [a.name for a in node.names if a.name.startswith("_")]
        if any(p.startswith("_") for p in pieces) or names:
            found.append(
                f"{module}: from {node.module} import {', '.join(a.name for a in node.names)}"
            )
    return found


PUBLIC_ONLY = (*TUNER_PACKAGES, "commands")
"""The parts that reach other subpackages through their public modules and names only."""


def test_the_tuners_and_the_commands_use_only_public_modules_of_others() -> None:
    """``permove``, ``agents`` and ``commands`` reach other subpackages through their
    public modules and names only: a command parses and prints, the library does the work."""
    bad = [
        line
        for m, p in MODULES.items()
        if part_of(m) in PUBLIC_ONLY
        for line in private_reaches(m, p.read_text(encoding="utf-8"))
    ]
    assert not bad, "private imports:\n" + "\n".join(bad)


COMMAND_FUNCTION_LINES = 80
"""The longest function ``commands/`` may hold: more is orchestration that belongs in the
library, where a notebook can call it."""


def long_functions(source: str, most: int) -> list[tuple[str, int]]:
    """The functions (and methods) of ``source`` longer than ``most`` lines."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            n = (node.end_lineno or node.lineno) - node.lineno + 1
            if n > most:
                found.append((node.name, n))
    return found


def test_no_long_function_in_the_commands() -> None:
    bad = [
        f"{m}.{name}: {n} lines"
        for m, p in MODULES.items()
        if part_of(m) == "commands"
        for name, n in long_functions(p.read_text(encoding="utf-8"), COMMAND_FUNCTION_LINES)
    ]
    assert not bad, f"functions over {COMMAND_FUNCTION_LINES} lines:\n" + "\n".join(bad)


def test_a_long_function_is_caught() -> None:
    body = "\n".join(f"    x{i} = {i}" for i in range(81))
    assert long_functions(f"def f():\n{body}\n", 80) == [("f", 82)]
    assert long_functions("def g():\n    return 1\n", 80) == []


def test_a_private_reach_is_caught() -> None:
    src = (
        "from vfgym.permove._x import a\n"
        "from vfgym.permove import _b, c\n"
        "from vfgym._validate import d"
    )
    assert private_reaches("vfgym.agents.loaded", src) == [
        "vfgym.agents.loaded: from vfgym.permove._x import a",
        "vfgym.agents.loaded: from vfgym.permove import _b, c",
    ]


def test_a_module_circle_is_caught() -> None:
    graph = {"vfgym.agents.a": {"vfgym.agents.b"}, "vfgym.agents.b": {"vfgym.agents.a"}}
    assert module_cycles(graph) == [["vfgym.agents.a", "vfgym.agents.b"]]


def documented_files(text: str) -> set[str]:
    """The files of the tree in docs/architecture.md (the block that opens ``src/vfgym/``),
    as paths relative to ``src/vfgym``; a line ending in ``/`` is a folder."""
    lines = text.split("\nsrc/vfgym/\n", 1)[1].split("```", 1)[0].splitlines()
    folders: list[str] = []
    files: set[str] = set()
    for line in lines:
        if not line.strip():
            continue
        depth = (len(line) - len(line.lstrip(" "))) // 2 - 1
        name = line.split()[0]
        del folders[depth:]
        if name.endswith("/"):
            folders.append(name.rstrip("/"))
        else:
            files.add("/".join([*folders, name]))
    return files


def test_the_architecture_doc_lists_every_module() -> None:
    """docs/architecture.md's file tree names each module once it exists, and no other."""
    listed = documented_files(ARCHITECTURE_DOC.read_text(encoding="utf-8"))
    actual = {p.relative_to(PACKAGE).as_posix() for p in PACKAGE.rglob("*.py")}
    actual.add("py.typed")
    assert not actual - listed, f"not in docs/architecture.md's tree: {sorted(actual - listed)}"
    assert not listed - actual, f"in docs/architecture.md but absent: {sorted(listed - actual)}"


def test_the_graph_is_read_from_the_source() -> None:
    """Known edges, so that a parser that finds nothing cannot pass the tests above."""
    assert "vfgym.plant._layout" in GRAPH["vfgym.plant._kernel"]
    assert "vfgym.moves.scenarios" in GRAPH["vfgym.scoring._cost"]
    # a lazy import inside a function, and an entry-point string
    assert "vfgym.agents.heldout" in GRAPH["vfgym.agents.training"]
    assert "vfgym.envs.tune" in GRAPH["vfgym.envs"]
    # f"vfgym.commands.{name}" imports the commands package
    assert "vfgym.commands" in GRAPH["vfgym.cli"]


@pytest.mark.parametrize(
    ("source", "expected"),
    [
        ("from vfgym.scoring import score", ["vfgym.scoring"]),
        ("def f():\n    from vfgym.scoring._cost import score", ["vfgym.scoring._cost"]),
        (
            "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    import vfgym.tuning",
            ["vfgym.tuning"],
        ),
        ("from .. import scoring", ["vfgym.scoring"]),
        ("X = 'vfgym.envs.tune:VFTuneEnv'", ["vfgym.envs.tune"]),
        ("import numpy\nfrom . import _layout", []),
    ],
)
def test_an_upward_import_is_caught(source: str, expected: list[str]) -> None:
    """The checker flags an import of a higher layer in each form the source may use."""
    found = imports_of("vfgym.plant.measures", source)
    assert upward_imports({"vfgym.plant.measures": found}) == [
        f"vfgym.plant.measures -> {t} (plant: layer 1, {part_of(t)}: {LAYER_OF[part_of(t)]})"
        for t in expected
    ]


def test_a_circle_is_caught() -> None:
    graph = {"vfgym.tuning._x": {"vfgym.report._y"}, "vfgym.report._y": {"vfgym.tuning"}}
    assert part_cycles(graph) == [["report", "tuning", "report"]]
