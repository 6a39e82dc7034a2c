"""A small Gaussian process for the compass sampler's model: Matérn-5/2 kernel with one
length scale per axis, constant mean, hyperparameters fitted by maximum marginal
likelihood (Adam on their logarithms, within bounds), and the log expected improvement.

Sized for a sweep's few hundred points in four dimensions; Optuna's ``GPSampler`` keeps
its Gaussian process private (and on torch), so the compass has its own. The correlation
of thousands of candidates with the points is compiled (:func:`matern52`) with the bits
of the numpy formula the trials were first drawn with (tested), so a seed gives the same
trials.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from scipy.special import ndtr

from vfgym.plant._jit import jit

SQRT5 = math.sqrt(5.0)
COLD_STEPS, WARM_STEPS = 60, 20
"""Adam steps of a fit from the default hyperparameters, and from a previous fit's."""
LEARNING_RATE = 0.1

LENGTH_BOUNDS = (0.02, 5.0)
"""Length scales allowed, in unit coordinates (the search box is [0, 1] per axis)."""
NOISE_BOUNDS = (1e-6, 0.2)
"""Noise variance allowed, on standardised targets: the objective is exact, but its cliffs
(a constraint crossed) are better taken as noise than as wild wiggles."""


@jit(simd=True)
def _distances(a: np.ndarray, b: np.ndarray, lengths: np.ndarray, out: np.ndarray) -> None:
    """``out[i, j] = sqrt(sum over k of ((a[i, k] - b[j, k]) / lengths[k])²)``."""
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
    """The Matérn-5/2 correlation between the rows of ``a`` and of ``b``: the numpy
    formula's operations in its order in two compiled loops, numpy's own ``exp`` between
    them (libm's differs in the last bit)."""
    a = np.ascontiguousarray(a, dtype=np.float64)
    b = np.ascontiguousarray(b, dtype=np.float64)
    lengths = np.ascontiguousarray(lengths, dtype=np.float64)
    r = np.empty((len(a), len(b)))
    _distances(a, b, lengths, r)
    e = np.multiply(r, -SQRT5)
    np.exp(e, out=e)
    _polynomial(r, e)
    return r


class GaussianProcess:
    """A GP regression of ``y`` (standardised inside) on the points ``x`` (n, d), its log
    hyperparameters (length scales, signal and noise variance) fitted from ``start`` (a
    previous fit's ``theta``: fewer steps), or kept as ``start`` if not ``fit``."""

    def __init__(self, x: np.ndarray, y: np.ndarray, start: Any = None, fit: bool = True) -> None:
        self.x = np.asarray(x, dtype=np.float64)
        self._d2: np.ndarray | None = None  # squared differences per axis, for the fit
        y = np.asarray(y, dtype=np.float64)
        self.mean = float(y.mean())
        self.scale = float(y.std()) or 1.0
        self.y = (y - self.mean) / self.scale
        d = self.x.shape[1]
        default = np.r_[np.full(d, math.log(0.3)), 0.0, math.log(1e-3)]
        if not fit:
            self.theta = np.asarray(start, dtype=np.float64)
        elif start is not None and len(start) == len(default):
            self.theta = self._fit(np.asarray(start, dtype=np.float64), WARM_STEPS)
        else:
            self.theta = self._fit(default, COLD_STEPS)
        self._factor()

    def _unpack(self, theta: np.ndarray) -> tuple[np.ndarray, float, float]:
        d = self.x.shape[1]
        return np.exp(theta[:d]), float(np.exp(theta[d])), float(np.exp(theta[d + 1]))

    def _nll(self, theta: np.ndarray) -> tuple[float, np.ndarray]:
        """Negative log marginal likelihood and its gradient in the log hyperparameters."""
        lengths, var, noise = self._unpack(theta)
        n, dim = self.x.shape
        if self._d2 is None or self._d2.shape[1] != n:
            # The points' squared differences per axis, (d, n, n): fixed during a fit.
            self._d2 = np.square(self.x.T[:, :, None] - self.x.T[:, None, :])
        diff2 = self._d2 / np.square(lengths)[:, None, None]
        r = np.sqrt(np.maximum(diff2.sum(0), 0.0))
        e = np.exp(-SQRT5 * r)
        corr = (1.0 + SQRT5 * r + (5.0 / 3.0) * r * r) * e
        k = var * corr + (noise + 1e-10) * np.eye(n)
        try:
            chol = np.linalg.cholesky(k)
        except np.linalg.LinAlgError:
            return 1e25, np.zeros_like(theta)
        # K⁻¹ = L⁻ᵀL⁻¹ from one inverse of the factor (four general solves before: each
        # factors L again; this step dominates a long sweep's model batches).
        linv = np.linalg.inv(chol)
        alpha = linv.T @ (linv @ self.y)
        nll = 0.5 * float(self.y @ alpha) + float(np.log(np.diag(chol)).sum())
        w = np.outer(alpha, alpha) - linv.T @ linv  # d nll / d K = -w / 2
        grad = np.empty_like(theta)
        wc = w * (var * (5.0 / 3.0) * (1.0 + SQRT5 * r) * e)
        grad[:dim] = -0.5 * (diff2.reshape(dim, -1) @ wc.ravel())
        grad[dim] = -0.5 * float((w * corr).sum()) * var
        grad[dim + 1] = -0.5 * float(np.trace(w)) * noise
        return nll, grad

    def _fit(self, start: np.ndarray, steps: int) -> np.ndarray:
        """Adam on the log hyperparameters, projected onto their bounds; the best seen."""
        dim = self.x.shape[1]
        lo = np.r_[
            np.full(dim, math.log(LENGTH_BOUNDS[0])), math.log(0.05), math.log(NOISE_BOUNDS[0])
        ]
        hi = np.r_[
            np.full(dim, math.log(LENGTH_BOUNDS[1])), math.log(20.0), math.log(NOISE_BOUNDS[1])
        ]
        theta = np.clip(start, lo, hi)
        m = np.zeros_like(theta)
        v = np.zeros_like(theta)
        best, best_f = theta.copy(), math.inf
        for i in range(1, steps + 1):
            f, g = self._nll(theta)
            if f < best_f:
                best, best_f = theta.copy(), f
            m = 0.9 * m + 0.1 * g
            v = 0.999 * v + 0.001 * g * g
            step = LEARNING_RATE * (m / (1 - 0.9**i)) / (np.sqrt(v / (1 - 0.999**i)) + 1e-8)
            theta = np.clip(theta - step, lo, hi)
        return best

    def _factor(self) -> None:
        lengths, var, noise = self._unpack(self.theta)
        self.lengths, self.var, self.noise = lengths, var, noise
        k = var * matern52(self.x, self.x, lengths)
        k += (noise + 1e-10) * np.eye(len(self.x))
        self.chol = np.linalg.cholesky(k)
        self.linv = np.linalg.inv(self.chol)  # L⁻¹: predictions multiply, not solve
        self.alpha = self.linv.T @ (self.linv @ self.y)

    def predict(self, xs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Posterior mean and standard deviation at the rows of ``xs``, in ``y``'s units."""
        at = Believer(self, xs)
        return at.mean, at.sd()


class Believer:
    """The posterior of ``gp`` (left as it is) at the candidates ``xs`` while candidates
    are added to its observations at their predicted means (the kriging believer): the
    mean stays, the variance takes a rank-one update per point. As
    conditioning the process on it then predicting, up to rounding, at O(candidates ×
    points) per point instead of O(candidates × points²)."""

    def __init__(self, gp: GaussianProcess, xs: np.ndarray) -> None:
        self.gp = gp
        self.xs = np.asarray(xs, dtype=np.float64)
        ks = gp.var * matern52(self.xs, gp.x, gp.lengths)
        self.mean = (ks @ gp.alpha) * gp.scale + gp.mean
        self._v = gp.linv @ ks.T  # (n, m): L⁻¹ k(x, candidate)
        self._var = gp.var - (self._v * self._v).sum(0)  # standardised, unclipped
        self._u: list[np.ndarray] = []  # the rank-one updates, one per believed point

    def sd(self) -> np.ndarray:
        """Posterior standard deviation at the candidates, in ``y``'s units."""
        return np.sqrt(np.maximum(self._var, 1e-18)) * self.gp.scale

    def believe(self, j: int) -> None:
        """Add candidate ``j`` to the observations at its predicted mean."""
        gp = self.gp
        k = gp.var * matern52(self.xs, self.xs[j : j + 1], gp.lengths)[:, 0]
        cov = k - self._v.T @ self._v[:, j]
        for u in self._u:
            cov -= u * u[j]
        u = cov / math.sqrt(max(self._var[j], 0.0) + gp.noise + 1e-10)
        self._u.append(u)
        self._var = self._var - u * u


TAIL_Z = -20.0
"""Below this z the log expected improvement takes the normal tail's asymptotic series
(four terms: relative error about 945/z¹⁰, 1e-10 here); above it the direct formula loses
at most z² ≈ 400 ulps to cancellation."""
_LOG_SQRT_2PI = 0.5 * math.log(2.0 * math.pi)


def log_expected_improvement(best: float, mu: np.ndarray, sd: np.ndarray) -> np.ndarray:
    """log E[max(best − f, 0)] for f ~ N(mu, sd²) (minimisation), finite where the
    improvement itself underflows to zero (a candidate many deviations above ``best``).

    EI = sd·h(z) with z = (best − mu)/sd and h(z) = z·Φ(z) + φ(z); in the tail
    h(z) = φ(z)·(1/z² − 3/z⁴ + 15/z⁶ − 105/z⁸ + …).
    """
    z = (best - np.asarray(mu, dtype=np.float64)) / sd
    logh = np.empty_like(z)
    tail = z < TAIL_Z
    zt = z[~tail]
    with np.errstate(divide="ignore"):  # h = 0 only where the tail series takes over
        logh[~tail] = np.log(zt * ndtr(zt) + np.exp(-0.5 * zt * zt) / math.sqrt(2.0 * math.pi))
    t = z[tail]
    w = 1.0 / (t * t)
    logh[tail] = (
        -0.5 * t * t - _LOG_SQRT_2PI + np.log(w * (1.0 - w * (3.0 - w * (15.0 - w * 105.0))))
    )
    return np.log(sd) + logh
