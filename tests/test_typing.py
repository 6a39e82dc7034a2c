"""mypy over ``src/vfgym`` (config in pyproject.toml), starting from what passes, never regressing.

``tests/typing_baseline.txt`` lists the modules that do not pass yet, each with its count
of mypy errors. The test fails when a module has more errors than listed (a module not
listed may have none), and also when it has fewer: then the baseline must be lowered, so
the list only shrinks. Rewrite it after fixing errors with::

    python tests/test_typing.py --update

which refuses to raise any count. The mypy cache (``.mypy_cache``) keeps a warm run to
about a second; a cold one takes ~30 s.
"""

from __future__ import annotations

import re
import subprocess
import sys
from collections import Counter
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
BASELINE = Path(__file__).with_name("typing_baseline.txt")
_ERROR = re.compile(r"^(?P<path>[^:\s]+\.py):\d+(?::\d+)?: error: ")


def run_mypy() -> tuple[Counter[str], str]:
    """mypy's error count per file (paths relative to the repository) and its output."""
    proc = subprocess.run(
        [sys.executable, "-m", "mypy", "--no-error-summary", "--hide-error-context"],
        cwd=REPO,
        capture_output=True,
        text=True,
        check=False,
    )
    if proc.returncode not in (0, 1):  # 2: mypy itself failed (config, crash)
        raise RuntimeError(f"mypy exited {proc.returncode}:\n{proc.stdout}{proc.stderr}")
    counts: Counter[str] = Counter()
    for line in proc.stdout.splitlines():
        match = _ERROR.match(line)
        if match:
            counts[Path(match["path"]).as_posix()] += 1
    return counts, proc.stdout


def read_baseline(path: Path = BASELINE) -> dict[str, int]:
    """``path count`` per line; ``#`` starts a comment."""
    baseline: dict[str, int] = {}
    for raw in path.read_text(encoding="utf-8").splitlines():
        line = raw.split("#", 1)[0].strip()
        if line:
            name, count = line.split()
            baseline[name] = int(count)
    return baseline


def compare(counts: Counter[str], baseline: dict[str, int]) -> tuple[list[str], list[str]]:
    """(modules with more errors than listed, modules with fewer), each as a sentence."""
    grown = [
        f"{name}: {counts[name]} mypy errors, baseline {baseline.get(name, 0)}"
        for name in sorted(counts)
        if counts[name] > baseline.get(name, 0)
    ]
    shrunk = [
        f"{name}: {counts.get(name, 0)} mypy errors, baseline {listed}: lower it"
        for name, listed in sorted(baseline.items())
        if counts.get(name, 0) < listed
    ]
    return grown, shrunk


def write_baseline(counts: Counter[str], path: Path = BASELINE) -> None:
    header = (
        "# mypy errors per module not yet passing (tests/test_typing.py). Counts may only go\n"
        "# down; a module that passes is removed. Rewrite: python tests/test_typing.py --update\n"
    )
    body = "".join(f"{name} {counts[name]}\n" for name in sorted(counts) if counts[name])
    path.write_text(header + body, encoding="utf-8")


@pytest.fixture(scope="module")
def mypy_result() -> tuple[Counter[str], str]:
    return run_mypy()


def test_no_module_gains_type_errors(mypy_result: tuple[Counter[str], str]) -> None:
    counts, output = mypy_result
    grown, _ = compare(counts, read_baseline())
    if grown:
        new = [
            ln for ln in output.splitlines() if any(ln.startswith(g.split(":")[0]) for g in grown)
        ]
        pytest.fail("type errors above the baseline:\n" + "\n".join([*grown, "", *new]))


def test_baseline_shrinks_with_the_errors(mypy_result: tuple[Counter[str], str]) -> None:
    counts, _ = mypy_result
    _, shrunk = compare(counts, read_baseline())
    assert not shrunk, (
        "fewer type errors than the baseline lists (run python tests/test_typing.py --update):\n"
        + "\n".join(shrunk)
    )


def test_mypy_sees_the_package(mypy_result: tuple[Counter[str], str]) -> None:
    """The check is not vacuous: the baseline is non-empty only while mypy reports errors,
    and a module with a known error is counted (see also test_compare_flags_growth)."""
    counts, output = mypy_result
    assert "error:" in output or not read_baseline()
    assert all(name.startswith("src/vfgym/") for name in counts)


def test_compare_flags_growth_and_shrinkage() -> None:
    baseline = {"src/vfgym/a.py": 2, "src/vfgym/b.py": 1}
    grown, shrunk = compare(Counter({"src/vfgym/a.py": 3, "src/vfgym/c.py": 1}), baseline)
    assert grown == [
        "src/vfgym/a.py: 3 mypy errors, baseline 2",
        "src/vfgym/c.py: 1 mypy errors, baseline 0",
    ]
    assert shrunk == ["src/vfgym/b.py: 0 mypy errors, baseline 1: lower it"]


def test_a_type_error_is_counted(tmp_path: Path) -> None:
    """mypy with the project's config reports an error planted in a module of its own."""
    bad = tmp_path / "bad.py"
    bad.write_text("def f(x: int) -> str:\n    return x\n", encoding="utf-8")
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "mypy",
            "--config-file",
            str(REPO / "pyproject.toml"),
            "--cache-dir",  # the repository's cache: typeshed's stubs are read already
            str(REPO / ".mypy_cache"),
            str(bad),
        ],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        check=False,
    )
    assert proc.returncode == 1 and "Incompatible return value type" in proc.stdout


if __name__ == "__main__":
    if sys.argv[1:] != ["--update"]:
        sys.exit("usage: python tests/test_typing.py --update")
    current, _ = run_mypy()
    grown, _ = compare(current, read_baseline())
    if grown:
        sys.exit("not written: these modules gained errors; fix them first:\n" + "\n".join(grown))
    write_baseline(current)
    print(f"{BASELINE}: {sum(current.values())} errors in {len(+current)} modules")
