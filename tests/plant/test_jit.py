"""The one JIT policy (vfgym.plant._jit): every compiled function of the package is built
by it, with its options, and the cache guard drops machine code of changed sources."""

from __future__ import annotations

import importlib
import importlib.util
import re
from pathlib import Path
from types import SimpleNamespace

import numba
import pytest
from numba.core.caching import FunctionCache
from numba.core.registry import CPUDispatcher

import vfgym
from vfgym.plant import _jit as J

SRC = Path(vfgym.__file__).parent


def compiled_modules() -> list[str]:
    """Every module of the package whose source mentions numba or the policy."""
    names = []
    for path in sorted(SRC.rglob("*.py")):
        text = path.read_text(encoding="utf-8")
        if re.search(r"\bnumba\b|\b_jit\b", text) and path.name != "_jit.py":
            rel = path.relative_to(SRC.parent).with_suffix("")
            names.append(".".join(rel.parts).removesuffix(".__init__"))
    return names


def test_the_compiled_modules_are_found():
    assert {"vfgym.plant._kernel", "vfgym.plant._tick", "vfgym.plant._lanes"} <= set(
        compiled_modules()
    )
    assert "vfgym.envs._batch" in compiled_modules()


@pytest.mark.parametrize("name", compiled_modules())
def test_every_compiled_function_is_built_by_the_policy(name):
    module = importlib.import_module(name)
    mine = [
        v
        for v in vars(module).values()
        if isinstance(v, CPUDispatcher) and v.py_func.__module__ == name
    ]
    built = {id(d) for d in J.COMPILED}
    assert [d.py_func.__name__ for d in mine if id(d) not in built] == []


def test_every_compiled_function_has_the_policys_options():
    importlib.import_module("vfgym.envs._batch")  # the last module to compile functions
    assert len(J.COMPILED) > 20
    for d in J.COMPILED:
        opts = d.targetoptions
        assert opts["fastmath"] is False, d
        assert opts["nogil"] is True, d
        assert opts["error_model"] in ("python", "numpy"), d
        assert opts["inline"] in ("always", "never"), d
        assert isinstance(d._cache, FunctionCache) is J.CACHE, d


@pytest.mark.parametrize(
    ("kw", "expect"),
    [
        ({}, {"error_model": "python", "inline": "never", "parallel": False}),
        ({"inline": True}, {"error_model": "python", "inline": "always", "parallel": False}),
        ({"simd": True}, {"error_model": "numpy", "inline": "never", "parallel": False}),
        ({"parallel": True}, {"error_model": "python", "inline": "never", "parallel": True}),
    ],
)
def test_options_by_use(kw, expect):
    assert J.jit_options(**kw) == {"cache": J.CACHE, "fastmath": False, "nogil": True, **expect}


@J.jit(inline=True)
def _twice(x):
    return 2.0 * x


@J.jit(simd=True)
def _ratio_simd(a, b):
    return a / _twice(b)


@J.jit
def _ratio(a, b):
    return a / _twice(b)


def test_an_inlined_block_and_the_two_error_models():
    assert {id(_twice), id(_ratio_simd), id(_ratio)} <= {id(d) for d in J.COMPILED}
    assert _ratio_simd(3.0, 0.75) == _ratio(3.0, 0.75) == 2.0
    assert _ratio_simd(1.0, 0.0) == float("inf")  # numpy error model: the IEEE result
    with pytest.raises(ZeroDivisionError):  # python error model: raises, as the reference
        _ratio(1.0, 0.0)


def test_nowhere_to_cache_means_no_cache(monkeypatch):
    def read_only(_func):
        raise RuntimeError("cannot cache function: no locator available")

    monkeypatch.setattr(numba.core.caching, "FunctionCache", read_only)
    assert J._can_cache() is False


def _module(path: Path, text: str):
    path.write_text(text)
    spec = importlib.util.spec_from_file_location(path.stem, path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_the_cache_guard_drops_machine_code_when_a_source_changes(tmp_path, monkeypatch):
    src = _module(tmp_path / "dep.py", "X = 1\n")
    user = _module(tmp_path / "user.py", "def f():\n    return 1\n")
    cache = tmp_path / "cache"
    fake = SimpleNamespace(_cache=SimpleNamespace(_cache_path=str(cache)), py_func=user.f)
    stale = cache / "user.f-1.py311.nbi"
    other = cache / "dep.g-1.py311.nbi"

    def guard_and_plant():
        J.guard_cache(fake, (src,))
        cache.mkdir(exist_ok=True)
        stale.write_text("machine code")
        other.write_text("another module's machine code")

    guard_and_plant()  # first time: no stamp yet
    J.guard_cache(fake, (src,))
    assert stale.exists()  # same sources: the cache stays
    (tmp_path / "dep.py").write_text("X = 2\n")
    J.guard_cache(fake, (src,))
    assert not stale.exists()  # a source changed: this module's cache goes
    assert other.exists()  # and only this module's
    stale.write_text("machine code")
    J.guard_cache(fake, (src,))
    assert stale.exists()
    policy = tmp_path / "policy.py"
    policy.write_text("# another policy\n")
    monkeypatch.setattr(J, "__file__", str(policy))  # the policy's own file is hashed too
    J.guard_cache(fake, (src,))
    assert not stale.exists()
