"""Gaussian processes for the compass sampler's model: a Matérn-5/2 kernel (one length scale
per axis), a signal variance and white noise, their hyperparameters of greatest marginal
likelihood (scikit-learn's, with its gradient; L-BFGS-B from a previous fit's when given);
the kriging believer's rank-one updates; and the log expected improvement.

Optuna's ``GPSampler`` keeps its Gaussian process private (and on torch), so the compass
takes scikit-learn's likelihood; the posterior is a few lines of linear algebra here, as
thousands of candidates are scored against it each batch.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from scipy.optimize import minimize
from scipy.spatial.distance import cdist
from scipy.special import ndtr
from sklearn.gaussian_process import GaussianProcessRegressor  # type: ignore[import-untyped]
from sklearn.gaussian_process.kernels import (  # type: ignore[import-untyped]
    ConstantKernel,
    Matern,
    WhiteKernel,
)

LENGTH_BOUNDS = (0.02, 5.0)
"""Length scales allowed, in unit coordinates (the search box is [0, 1] per axis)."""
VARIANCE_BOUNDS = (0.05, 20.0)
"""Signal variance allowed, on standardised targets."""
NOISE_BOUNDS = (1e-6, 0.2)
"""Noise variance allowed, on standardised targets: the objective is exact, but its cliffs
(a constraint crossed) are better taken as noise than as wild wiggles."""
SQRT5 = math.sqrt(5.0)
JITTER = 1e-10
"""Added to the diagonal (scikit-learn's ``alpha``), beside the noise."""


def matern52(a: np.ndarray, b: np.ndarray, lengths: np.ndarray) -> np.ndarray:
    """The Matérn-5/2 correlation between the rows of ``a`` and of ``b``, (1 + s + s²/3)·e⁻ˢ
    with s = √5 × the distance scaled per axis (in place: thousands of candidates)."""
    s = cdist(a * (SQRT5 / lengths), b * (SQRT5 / lengths))
    e = np.exp(-s)
    s2 = s * s
    s2 *= 1.0 / 3.0
    s += 1.0
    s += s2
    s *= e
    return s


class GaussianProcess:
    """A GP regression of ``y`` (standardised inside) on the points ``x`` (n, d), its log
    hyperparameters ``theta`` (length scales, signal variance, noise variance) fitted from
    ``start`` (a previous fit's ``theta``) or the defaults by scikit-learn's marginal
    likelihood, or kept as ``start`` if not ``fit``. Its posterior at new points is a
    :class:`Believer`'s."""

    def __init__(self, x: np.ndarray, y: np.ndarray, start: Any = None, fit: bool = True) -> None:
        self.x = np.asarray(x, dtype=np.float64)
        y = np.asarray(y, dtype=np.float64)
        self.mean = float(y.mean())
        self.scale = float(y.std()) or 1.0
        self.y = (y - self.mean) / self.scale
        d = self.x.shape[1]
        theta = np.r_[np.full(d, math.log(0.3)), 0.0, math.log(1e-3)]
        if start is not None and len(start) == len(theta):
            theta = np.asarray(start, dtype=np.float64)
        if fit:
            theta = self._fit(theta)
        self.theta = theta
        self.lengths, self.var, self.noise = (
            np.exp(theta[:d]),
            math.exp(theta[d]),
            math.exp(theta[d + 1]),
        )
        k = self.var * matern52(self.x, self.x, self.lengths)
        k[np.diag_indices_from(k)] += self.noise + JITTER
        self.linv = np.linalg.inv(np.linalg.cholesky(k))  # L⁻¹: predictions multiply, not solve
        self.alpha = self.linv.T @ (self.linv @ self.y)

    def _fit(self, theta: np.ndarray) -> np.ndarray:
        """The log hyperparameters of greatest marginal likelihood (scikit-learn's, with its
        gradient; L-BFGS-B within the bounds, from ``theta``)."""
        d = self.x.shape[1]
        kernel = ConstantKernel(1.0, VARIANCE_BOUNDS) * Matern(
            np.ones(d), LENGTH_BOUNDS, nu=2.5
        ) + WhiteKernel(1.0, NOISE_BOUNDS)
        reg = GaussianProcessRegressor(kernel, alpha=JITTER, optimizer=None, copy_X_train=False)
        reg.fit(self.x, self.y)
        order = np.r_[d, :d, d + 1]  # scikit-learn's: variance, length scales, noise
        best = minimize(
            lambda t: tuple(-v for v in reg.log_marginal_likelihood(t, eval_gradient=True)),
            theta[order], jac=True, method="L-BFGS-B", bounds=reg.kernel_.bounds,
        )  # fmt: skip
        return best.x[np.argsort(order)]


class Believer:
    """The posterior of ``gp`` (left as it is) at the candidates ``xs`` while candidates
    are added to its observations at their predicted means (the kriging believer): the
    mean stays, the variance takes a rank-one update per point. Equal, up to rounding, to
    conditioning the process on each point and predicting again, at O(candidates × points)
    per point instead of O(candidates × points²)."""

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
        u = cov / math.sqrt(max(self._var[j], 0.0) + gp.noise + JITTER)
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
