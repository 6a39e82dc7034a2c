"""A first-use compile says so: one line on stderr, with its expected duration.

numba compiles a kernel at its first call, for seconds to a minute, unless its machine
code is in numba's cache (:mod:`vfgym.plant._jit`). Each compiled entry point of vfgym
(simulate, evaluate, VFServo-v0's step, the vector env's SIMD-lane step) calls
:func:`announce_compile` before it runs, so a user whose first call will compile reads
why it waits and for how long, and one whose cache is warm reads nothing. A compile of
more than ~30 s (the vector env's) runs under :func:`compiling`, which also shows its
progress. Kept apart from the compile policy, whose text guards the caches: the figures
here may change without recompiling anything.
"""

from __future__ import annotations

import sys
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any, TextIO

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
    "simulate": 5.1,
    "evaluate": 12.6,
    "servo env": 22.5,
    "vector env": 47.7,
    "vector env, threads": 65.8,
}
"""CPU seconds a first call compiles for, with numba's cache empty, per entry point
(measured on a 2-core machine, docs/speed.md, at load ≈ 5–6, so on the high side:
``python benchmarks/bench_plant.py --cold``; the vector env's two entries the median of
three runs); what :func:`announce_compile` tells the user. The envs' compiled steps
compile the kernel's two-mass loop too since the compliant transmission: their figures are
docs/speed.md's times the ratio measured then, in one sitting, against the code before it
(docs/results/compliant.md); :func:`vfgym.simulate` and a batch of rigid plants in
:func:`vfgym.evaluate` (``run_batch_rigid``: 9.2 s CPU at load 7–8 against 14.6 s for the
mixed batch) compile their plant's loop alone, their figures unchanged."""

_ANNOUNCED: set[str] = set()


def announced(entry: str) -> bool:
    """Whether ``entry``'s compile has been checked (and announced if due) in this process:
    a cheap test for callers of :func:`compiling` on every call.

    Parameters
    ----------
    entry
        A key of :data:`COLD_COMPILE_S`.

    Returns
    -------
    bool
    """
    return entry in _ANNOUNCED


def announce_compile(entry: str, what: str, *dispatchers: Any) -> bool:
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

    Returns
    -------
    bool
        Whether it said so (the first call will compile).
    """
    if entry in _ANNOUNCED:
        return False
    _ANNOUNCED.add(entry)
    if all(is_compiled(d) for d in dispatchers):
        return False
    where = "cached for later runs" if CACHE else "not cached here: compiled again next run"
    print(
        f"vfgym: compiling {what} once (about {COLD_COMPILE_S[entry]:.0f} s; {where}) ...",
        file=sys.stderr,
        flush=True,
    )
    return True


_WIDTH = 40  # of the rewritten progress line, so that a shorter text covers a longer one

PROGRESS_EVERY_S = 10.0
"""Seconds between two progress lines when stderr is not a terminal (a log file); on a
terminal the one progress line is rewritten every second."""


def _progress(stream: TextIO, stop: threading.Event, start: float) -> None:
    """Write the seconds compiled so far to ``stream`` until ``stop`` is set."""
    tty = stream.isatty()
    every = 1.0 if tty else PROGRESS_EVERY_S
    while not stop.wait(every):
        spent = time.perf_counter() - start
        if tty:
            stream.write(f"\rvfgym: ... compiling, {spent:.0f} s".ljust(_WIDTH))
        else:
            stream.write(f"vfgym: ... compiling, {spent:.0f} s\n")
        stream.flush()


@contextmanager
def compiling(entry: str, what: str, *dispatchers: Any) -> Iterator[None]:
    """:func:`announce_compile`, then, while the body (the first call) compiles, a
    progress line on stderr from a thread: the seconds so far, rewritten every second on
    a terminal, a line every :data:`PROGRESS_EVERY_S` otherwise; and the time it took
    at the end. Nothing when the machine code is at hand.

    Parameters
    ----------
    entry, what, dispatchers
        As :func:`announce_compile`.

    Yields
    ------
    None
    """
    if not announce_compile(entry, what, *dispatchers):
        yield
        return
    stream = sys.stderr
    start = time.perf_counter()
    stop = threading.Event()
    ticker = threading.Thread(target=_progress, args=(stream, stop, start), daemon=True)
    ticker.start()
    try:
        yield
    finally:
        stop.set()
        ticker.join()
        done = f"vfgym: compiled in {time.perf_counter() - start:.0f} s"
        stream.write(f"\r{done.ljust(_WIDTH)}\n" if stream.isatty() else f"{done}\n")
        stream.flush()
