"""Parallel kernel calls that leave the caller's OpenMP thread count as it was.

numba's OpenMP threading layer calls ``omp_set_num_threads(numba.get_num_threads())`` on
the calling thread before each parallel region. torch reads its intra-op thread count from
the same OpenMP setting when both end up on one libgomp, so after a user's
``torch.set_num_threads(1)`` one parallel vfgym call (``vfgym.evaluate``, a vector env
stepping many envs) silently left torch on every core: training then competes with
itself and with anything else on the machine. :func:`keeps_torch_threads` wraps every
parallel compiled call, so vfgym never changes the thread count a user set.
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from functools import wraps
from typing import ParamSpec, TypeVar

P = ParamSpec("P")
R = TypeVar("R")


def keeps_torch_threads(fn: Callable[P, R]) -> Callable[P, R]:
    """Wrap a parallel compiled function: torch's thread count after the call is the one
    it had before (checked only when torch is imported; a no-op otherwise)."""

    @wraps(fn)
    def call(*args: P.args, **kwargs: P.kwargs) -> R:
        torch = sys.modules.get("torch")
        if torch is None:
            return fn(*args, **kwargs)
        n = torch.get_num_threads()
        try:
            return fn(*args, **kwargs)
        finally:
            if torch.get_num_threads() != n:
                torch.set_num_threads(n)

    return call
