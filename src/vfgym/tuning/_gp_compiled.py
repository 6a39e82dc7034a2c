"""The compiled copies of :func:`vfgym.tuning._gp.matern52`, which a model batch calls for
every candidate against every point (thousands by hundreds, five models a batch), and of
``math.erfc`` element-wise, which it calls for every candidate, model and chosen point
(the normal distribution function of the expected improvement and of feasibility).

Two loops over plain arrays, each doing the numpy version's operations in its order (the
scaled differences squared and summed axis by axis, the square root; then the
polynomial), with numpy's own ``exp`` between them: numpy's vectorised ``exp`` and libm's
differ in the last bit, so the exponential stays numpy's and the result is the same bits
(``tests/tuning/test_gp.py`` checks it on random inputs). One pass over the
(candidates × points) array each, where numpy makes about twenty. ``erfc`` is libm's, as
Python's ``math.erfc`` is (the same bits, tested), without a Python call an element.
"""

from __future__ import annotations

import math

import numpy as np

from vfgym.plant._jit import jit

SQRT5 = math.sqrt(5.0)


@jit(simd=True)
def _distances(a: np.ndarray, b: np.ndarray, lengths: np.ndarray, out: np.ndarray) -> None:
    """``out[i, j] = sqrt(sum over k of ((a[i, k] - b[j, k]) / lengths[k])²)``, summed in
    axis order from 0 (lengths are > 0: bounded in the fit)."""
    n, m = out.shape
    dim = a.shape[1]
    for i in range(n):
        for j in range(m):
            r = 0.0
            for k in range(dim):
                d = (a[i, k] - b[j, k]) / lengths[k]
                r += d * d
            out[i, j] = math.sqrt(r)


@jit(simd=True)
def _polynomial(r: np.ndarray, e: np.ndarray) -> None:
    """``r ← ((√5 r + 1) + (5/3 r) r) · e`` in place, element by element."""
    flat_r = r.reshape(-1)
    flat_e = e.reshape(-1)
    for i in range(flat_r.size):
        x = flat_r[i]
        q = x * (5.0 / 3.0)
        q *= x
        flat_r[i] = ((x * SQRT5 + 1.0) + q) * flat_e[i]


def matern52(a: np.ndarray, b: np.ndarray, lengths: np.ndarray) -> np.ndarray:
    """:func:`vfgym.tuning._gp.matern52`, the same bits, compiled."""
    a = np.ascontiguousarray(a, dtype=np.float64)
    b = np.ascontiguousarray(b, dtype=np.float64)
    lengths = np.ascontiguousarray(lengths, dtype=np.float64)
    r = np.empty((len(a), len(b)))
    _distances(a, b, lengths, r)
    e = np.multiply(r, -SQRT5)
    np.exp(e, out=e)
    _polynomial(r, e)
    return r


@jit(simd=True)
def _erfc_into(x: np.ndarray, out: np.ndarray) -> None:
    for i in range(x.size):
        out[i] = math.erfc(x[i])


def erfc(x: np.ndarray) -> np.ndarray:
    """``math.erfc`` of each element (a float64 array of ``x``'s shape)."""
    x = np.ascontiguousarray(x, dtype=np.float64)
    out = np.empty_like(x)
    _erfc_into(x.reshape(-1), out.reshape(-1))
    return out
