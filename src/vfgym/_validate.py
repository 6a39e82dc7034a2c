"""Input checks shared by every public entry point.

Each check raises ``ValueError`` naming the parameter, the value given and the allowed
range, so a bad setting is caught where it is made, not deep inside a simulation.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from typing import Any

import numpy as np


def _interval(lo: float | None, hi: float | None, lo_open: bool, hi_open: bool) -> str:
    left = "(" if (lo_open or lo is None) else "["
    right = ")" if (hi_open or hi is None) else "]"
    lo_s = "-inf" if lo is None else f"{lo:g}"
    hi_s = "inf" if hi is None else f"{hi:g}"
    return f"{left}{lo_s}, {hi_s}{right}"


def check_real(
    name: str,
    value: Any,
    lo: float | None = None,
    hi: float | None = None,
    *,
    lo_open: bool = False,
    hi_open: bool = False,
) -> float:
    """Return ``value`` as a finite float inside the interval, else raise ``ValueError``."""
    allowed = _interval(lo, hi, lo_open, hi_open)
    if isinstance(value, bool):
        raise ValueError(f"{name}={value!r} must be a real number in {allowed}")
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name}={value!r} must be a real number in {allowed}") from None
    bad = (
        not math.isfinite(x)
        or (lo is not None and (x <= lo if lo_open else x < lo))
        or (hi is not None and (x >= hi if hi_open else x > hi))
    )
    if bad:
        raise ValueError(f"{name}={value!r} is out of range: allowed {allowed}")
    return x


def check_int(name: str, value: Any, lo: int | None = None, hi: int | None = None) -> int:
    """Return ``value`` as an int inside ``[lo, hi]``; a float must be whole."""
    allowed = f"whole numbers in {_interval(lo, hi, False, False)}"
    if isinstance(value, bool):
        raise ValueError(f"{name}={value!r} must be one of the {allowed}")
    if isinstance(value, (int, np.integer)):
        n = int(value)
    else:
        try:
            x = float(value)
        except (TypeError, ValueError):
            raise ValueError(f"{name}={value!r} must be one of the {allowed}") from None
        if not math.isfinite(x) or x != round(x):
            raise ValueError(f"{name}={value!r} is not allowed: {allowed}")
        n = round(x)
    if (lo is not None and n < lo) or (hi is not None and n > hi):
        raise ValueError(f"{name}={value!r} is out of range: allowed {allowed}")
    return n


def check_bool(name: str, value: Any) -> bool:
    """Return ``value`` if it is a bool (``True`` / ``False``; no 0, 1 or strings)."""
    if not isinstance(value, (bool, np.bool_)):
        raise ValueError(f"{name}={value!r} must be true or false")
    return bool(value)


def check_choice(name: str, value: Any, choices: Iterable[str]) -> str:
    """Return ``value`` if it is one of ``choices``."""
    options = tuple(choices)
    if value not in options:
        raise ValueError(f"{name}={value!r} is not allowed: choose one of {', '.join(options)}")
    return value


def check_finite_array(name: str, values: Any, dtype: Any = np.float64) -> np.ndarray:
    """Return a 1-D contiguous array of finite values (no NaN, no inf)."""
    arr = np.ascontiguousarray(np.asarray(values, dtype=dtype))
    if arr.ndim != 1:
        raise ValueError(f"{name} must be a 1-D array of per-tick values, got shape {arr.shape}")
    if arr.size == 0:
        raise ValueError(f"{name} must hold at least one tick, got an empty array")
    if np.issubdtype(arr.dtype, np.floating) and not np.all(np.isfinite(arr)):
        i = int(np.flatnonzero(~np.isfinite(arr))[0])
        raise ValueError(
            f"{name}[{i}]={arr[i]!r} is out of range: allowed finite values (no NaN or inf)"
        )
    return arr
