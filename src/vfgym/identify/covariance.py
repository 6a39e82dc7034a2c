"""The covariance of least-squares estimates from correlated residuals (Newey–West).

The residuals of a capture are not independent from sample to sample (the count's
quantisation and the loop's limit cycles last many samples), so the estimates'
covariance is the sandwich (JᵀJ)⁻¹ S (JᵀJ)⁻¹ with S the Bartlett-weighted sum of the
score's autocovariances, computed here with FFTs.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np


def newey_west(jac: np.ndarray, res: np.ndarray, lengths: Sequence[int], floor: int) -> np.ndarray:
    """Newey–West estimate of the score's covariance, Σ_l w_l Σ_t g_t g_{t+l}ᵀ.

    Parameters
    ----------
    jac : numpy.ndarray
        The Jacobian of the residuals (rows: samples).
    res : numpy.ndarray
        The residuals.
    lengths : sequence of int
        Samples of each capture (the rows are split there: no lag crosses captures).
    floor : int
        The least bandwidth (samples).

    Returns
    -------
    numpy.ndarray
        S, with g_t = J_t·r_t and Bartlett weights up to :func:`correlation_length`.
    """
    p = jac.shape[1]
    S = np.zeros((p, p))
    start = 0
    for n in lengths:
        r = res[start : start + n]
        g = jac[start : start + n] * r[:, None]
        start += n
        lag = correlation_length(r, floor)
        size = 1 << int(np.ceil(np.log2(2 * n)))
        G = np.fft.rfft(g, size, axis=0)
        for a in range(p):
            for b in range(a, p):
                cc = np.fft.irfft(np.conj(G[:, a]) * G[:, b], size)  # Σ_t g_a(t) g_b(t+l)
                w = 1.0 - np.arange(lag + 1) / (lag + 1)
                s = cc[0] + np.sum(w[1:] * (cc[1 : lag + 1] + cc[size - lag :][::-1]))
                S[a, b] = S[b, a] = s
    return S


def correlation_length(r: np.ndarray, floor: int) -> int:
    """The Newey–West bandwidth.

    Parameters
    ----------
    r : numpy.ndarray
        One capture's residuals.
    floor : int
        The least bandwidth (samples).

    Returns
    -------
    int
        Twice the lag at which the residuals' autocorrelation first falls below 0.05, at
        least ``floor``, at most a quarter of the record (samples).
    """
    x = r - r.mean()
    n = x.size
    size = 1 << int(np.ceil(np.log2(2 * n)))
    f = np.fft.rfft(x, size)
    ac = np.fft.irfft(f * np.conj(f), size)[:n]
    first = n // 4
    if ac[0] > 0:
        below = np.flatnonzero(ac / ac[0] < 0.05)
        first = int(below[0]) if below.size else n // 4
    return int(min(max(floor, 2 * first, 1), max(1, n // 4)))


__all__ = ["correlation_length", "newey_west"]
