"""A first-use compile says so: one line on stderr, with its expected duration.

numba compiles a kernel at its first call, for seconds to a minute, unless its machine
code is in numba's cache (:mod:`vfgym.plant._jit`). Each compiled entry point of vfgym
(simulate, evaluate, VFServo-v0's step, the vector env's SIMD-lane step) calls
:func:`announce_compile` before it runs, so a user whose first call will compile reads
why it waits and for how long, and one whose cache is warm reads nothing. Kept apart
from the compile policy, whose text guards the caches: the figures here may change
without recompiling anything.
"""

from __future__ import annotations

import sys
from typing import Any

from vfgym.plant._jit import CACHE


def is_compiled(dispatcher: Any) -> bool:
    """Whether ``dispatcher`` has machine code at hand: compiled in this process, or in
    numba's cache on disk and up to date with its source (numba's own index check).

    Parameters
    ----------
    dispatcher
        A function :func:`jit` built.

    Returns
    -------
    bool
        False when a first call would compile it (no cache, a stale or a missing one).
    """
    if getattr(dispatcher, "signatures", True):  # compiled, or not a numba function
        return True
    try:
        return bool(dispatcher._cache._cache_file._load_index())
    except (AttributeError, OSError, EOFError, ValueError):  # no cache (read-only install)
        return False


COLD_COMPILE_S = {
    "simulate": 6.5,
    "evaluate": 15.2,
    "servo env": 18.7,
    "vector env": 256.2,
}
"""CPU seconds a first call compiles for, with numba's cache empty, per entry point
(measured on the README's 2-core machine at load ≈ 10–17, so on the high side:
``python benchmarks/bench_plant.py --cold``); what :func:`announce_compile` tells the
user."""

_ANNOUNCED: set[str] = set()


def announce_compile(entry: str, what: str, *dispatchers: Any) -> None:
    """Say in one line on stderr that a first call is about to compile ``what``, and how
    long that takes (:data:`COLD_COMPILE_S` of ``entry``), unless every dispatcher is
    compiled already (:func:`is_compiled`).

    Checked once per process and entry: the callers call this before each call of
    their compiled entry point, at the cost of a set lookup.

    Parameters
    ----------
    entry
        A key of :data:`COLD_COMPILE_S`.
    what
        What compiles, for the user (e.g. ``"the simulation kernel"``).
    dispatchers
        The entry points whose first call would compile it.
    """
    if entry in _ANNOUNCED:
        return
    _ANNOUNCED.add(entry)
    if all(is_compiled(d) for d in dispatchers):
        return
    where = "cached for later runs" if CACHE else "no cache here: again next session"
    print(
        f"vfgym: compiling {what} once (about {COLD_COMPILE_S[entry]:.0f} s; {where}) ...",
        file=sys.stderr,
        flush=True,
    )
