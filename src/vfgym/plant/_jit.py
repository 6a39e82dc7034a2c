"""The one numba policy of vfgym: every compiled function is built by :func:`jit`.

Each option numba takes is decided here, once, with its reason:

``cache``
    On where numba can write machine code (next to the source, in ``NUMBA_CACHE_DIR`` or
    the user's cache directory): a new process then loads the kernel instead of compiling
    it for several seconds. Off on a read-only install with nowhere to write, so that the
    package imports and compiles in every process instead of failing (:data:`CACHE`).
    numba keys a cached function on its own file only, so a module whose machine code
    takes in code or constants of other modules guards its cache with
    :func:`guard_cache`.
``fastmath``
    Never. The kernels must do IEEE double operations in the written order, so that they
    agree bit for bit with the plain-Python reference (:mod:`vfgym.plant.reference`);
    fastmath would let LLVM reassociate sums and assume no NaN or infinity.
``error_model``
    ``"python"`` by default: a zero divisor raises ZeroDivisionError, as the plain-Python
    reference does, instead of running on with an infinity. ``"numpy"`` (IEEE results, no
    check) for code that must vectorise (``simd=True``, the SIMD lanes): the check is a
    branch per division that keeps LLVM from turning a loop over lanes into vector code.
    Every divisor there is validated > 0 when the parameter row is packed.
``inline``
    ``"always"`` for the blocks of a tick (``inline=True``): numba puts their code into
    the caller before typing, so a tick's loop is one function that LLVM optimises whole,
    with the loop state in registers and no call per tick, and a loop over lanes holds no
    call that would stop it vectorising. ``"never"`` (numba's default) otherwise: LLVM
    still inlines small callees where it pays. Inlining costs compile time: numba
    deep-copies the callee's IR at every call site, at a cost that grows with the
    callee's blocks times its variables, so it suits a few blocks called once each (the
    kernel's tick), not a helper called at hundreds of sites (the SIMD lanes, which took
    minutes so, use an intrinsic and loops specialised by literal arguments instead).
``nogil``
    Always: compiled code touches no Python object, so it releases the GIL and threads
    of the caller (agents, sweep workers) run beside it.
``parallel``
    Only for the entry points that spread runs over numba's threads (``parallel=True``,
    loops with ``prange``). Those threads follow the OpenMP wait policy set below.
``boundscheck``
    Not set, so ``NUMBA_BOUNDSCHECK=1`` can still switch index checks on to debug.
"""

from __future__ import annotations

import hashlib
import os
from collections.abc import Callable, Mapping
from pathlib import Path
from types import ModuleType
from typing import Any

# numba's OpenMP workers spin a while after each parallel call by default. With several
# processes on the cores (sweep workers, a busy machine) spinning workers take the cores
# from working ones (measured ~3x slower: two processes stepping vector envs), so vfgym
# makes them sleep (PASSIVE). Waking them costs ~55 us a call on this VM, though, so a
# user who has the machine to themselves may opt in to spinning: setting OMP_WAIT_POLICY
# or GOMP_SPINCOUNT (libgomp's default is 300000) keeps the user's choice. libgomp reads
# them when numba first starts its threads; set here, before numba is imported.
if "GOMP_SPINCOUNT" not in os.environ:
    os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

import numba


def workers_spin(environ: Mapping[str, str]) -> bool:
    """Whether numba's OpenMP workers spin between parallel calls under these variables.

    Parameters
    ----------
    environ
        Environment variables, as ``os.environ``.

    Returns
    -------
    bool
        False when ``OMP_WAIT_POLICY`` is PASSIVE or ``GOMP_SPINCOUNT`` is 0 (libgomp's
        reading), else True.
    """
    if environ.get("OMP_WAIT_POLICY", "").strip().upper() == "PASSIVE":
        return False
    return environ.get("GOMP_SPINCOUNT", "").strip() not in ("0",)


SPINNING_WORKERS = workers_spin(os.environ)
"""Whether this process's numba workers spin between parallel calls (see above)."""


def _probe() -> None:  # a function of this package's files, for the cache check below
    return None


def _can_cache() -> bool:
    """Whether numba can cache machine code of this package's files somewhere writable."""
    from numba.core.caching import FunctionCache

    try:
        FunctionCache(_probe)
    except RuntimeError:
        return False
    return True


CACHE = _can_cache()
"""Whether compiled functions are cached on disk (False on a read-only install)."""

COMPILED: list[Any] = []
"""Every dispatcher :func:`jit` has built, in order (the test that no compiled function
bypasses the policy reads it)."""


def jit_options(*, inline: bool = False, parallel: bool = False, simd: bool = False) -> dict:
    """The keyword arguments of ``numba.njit`` under this policy (see the module docstring).

    Parameters
    ----------
    inline
        A block of a tick, compiled into its caller.
    parallel
        An entry point that spreads work over numba's threads (``prange``).
    simd
        Code whose loops must vectorise (no zero-division check).

    Returns
    -------
    dict
        ``cache``, ``fastmath``, ``error_model``, ``inline``, ``nogil``, ``parallel``.
    """
    return {
        "cache": CACHE,
        "fastmath": False,
        "error_model": "numpy" if simd else "python",
        "inline": "always" if inline else "never",
        "nogil": True,
        "parallel": parallel,
    }


def jit(
    func: Callable | None = None,
    /,
    *,
    inline: bool = False,
    parallel: bool = False,
    simd: bool = False,
) -> Any:
    """Compile ``func`` with numba under the package's policy.

    Use as ``@jit`` or ``@jit(inline=True)``.

    Parameters
    ----------
    func
        The function; None to get a decorator.
    inline, parallel, simd
        As in :func:`jit_options`.

    Returns
    -------
    numba dispatcher, or a decorator making one
    """

    def build(f: Callable) -> Any:
        dispatcher = numba.njit(**jit_options(inline=inline, parallel=parallel, simd=simd))(f)
        COMPILED.append(dispatcher)
        return dispatcher

    return build if func is None else build(func)


def guard_cache(dispatcher: Any, sources: tuple[ModuleType, ...]) -> None:
    """Drop the numba cache of ``dispatcher``'s module when any of ``sources`` changed.

    numba keys a cached function on its own file only, so a module whose functions take
    in code or constants of other modules (inlined blocks, called kernels, slot numbers)
    would keep stale machine code after an edit of those. Call this at the end of such a
    module, before any of its functions run; the hash of the sources, and of this policy,
    is kept next to the cache files.

    Parameters
    ----------
    dispatcher
        Any cached function of the module to guard.
    sources
        The modules its machine code depends on, besides its own.
    """
    try:
        cache_dir = Path(dispatcher._cache._cache_path)
    except AttributeError:  # no cache, or a numba without this layout: nothing to guard
        return
    stem = Path(dispatcher.py_func.__code__.co_filename).stem
    digest = hashlib.sha256()
    for path in [Path(__file__), *(Path(str(mod.__file__)) for mod in sources)]:
        digest.update(path.read_bytes())
    stamp = cache_dir / f"{stem}.kernel-sha256"
    try:
        if stamp.read_text() == digest.hexdigest():
            return
    except OSError:
        pass
    for f in cache_dir.glob(f"{stem}.*.nb[ic]"):
        f.unlink(missing_ok=True)
    try:
        cache_dir.mkdir(parents=True, exist_ok=True)
        stamp.write_text(digest.hexdigest())
    except OSError:
        pass
