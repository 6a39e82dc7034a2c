"""The quantisation covariance of the estimates against its definition, summed in full."""

from __future__ import annotations

import numpy as np

from vfgym.identify.covariance import quantisation_meat


def _bernoulli_cov(theta: np.ndarray) -> np.ndarray:
    """½·B₂(frac(θₛ − θₜ)): the covariance over a uniform phase of 0.5 − frac(θ + φ)."""
    x = np.mod(theta[:, None] - theta[None, :], 1.0)
    return 0.5 * (x * x - x + 1.0 / 6.0)


def test_the_meat_is_j_sigma_j_with_the_sawtooth_covariance_per_piece():
    rng = np.random.default_rng(2)
    n, p = 120, 3
    jac = rng.normal(size=(n, p))
    theta = np.cumsum(rng.uniform(0.0, 2.5, size=n))  # a motion, in counts
    theta[40:70] = theta[40] + 0.3  # a rest: the same place within a count throughout
    groups = [np.arange(0, 40), np.arange(40, 70), np.arange(70, n)]
    sigma = np.zeros((n, n))
    for g in groups:
        sigma[np.ix_(g, g)] = _bernoulli_cov(theta[g])
    want = jac.T @ sigma @ jac
    got = quantisation_meat(jac, theta, groups)
    assert np.allclose(got, want, rtol=0.02, atol=1e-3 * np.abs(want).max())
    # a rest carries its error whole: as if every sample erred alike
    rest = jac[40:70]
    one = quantisation_meat(rest, theta[40:70], [np.arange(30)])
    whole = rest.T @ np.ones((30, 30)) @ rest / 12.0
    assert np.allclose(one, whole, rtol=0.02, atol=0.02 * np.abs(whole).max())


def test_the_sampled_monte_carlo_error_has_that_covariance():
    """0.5 − frac(θ + φ) over many uniform φ: its sample covariance through J."""
    rng = np.random.default_rng(3)
    n = 60
    jac = rng.normal(size=(n, 2))
    theta = np.cumsum(rng.uniform(0.0, 1.3, size=n))
    phi = rng.uniform(size=20000)
    err = 0.5 - np.mod(theta[None, :] + phi[:, None], 1.0)
    score = err @ jac
    mc = score.T @ score / phi.size
    got = quantisation_meat(jac, theta, [np.arange(n)])
    assert np.allclose(got, mc, rtol=0.05, atol=0.02 * np.abs(mc).max())
