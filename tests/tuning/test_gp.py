"""The compass's Gaussian process (``tuning/_gp.py``) against scikit-learn's on the same data
with the same Matérn-5/2 kernel and hyperparameters, and its acquisition in logs."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.stats import norm

from vfgym.tuning._gp import (
    SQRT5,
    Believer,
    GaussianProcess,
    log_expected_improvement,
    matern52,
)
from vfgym.tuning._model import _Fit

sklearn_gp = pytest.importorskip("sklearn.gaussian_process")
kernels = pytest.importorskip("sklearn.gaussian_process.kernels")


def numpy_matern52(a: np.ndarray, b: np.ndarray, lengths: np.ndarray) -> np.ndarray:
    """The Matérn-5/2 correlation in numpy, one axis at a time, in place: the operations
    (and bits) the compiled :func:`matern52` must reproduce, as the trials were first drawn
    with them."""
    r = np.zeros((len(a), len(b)))
    for i in range(a.shape[1]):
        d = np.subtract.outer(a[:, i], b[:, i])
        d /= lengths[i]
        d *= d
        r += d
    np.sqrt(r, out=r)
    e = np.multiply(r, -SQRT5)
    np.exp(e, out=e)
    q = np.multiply(r, 5.0 / 3.0)
    q *= r
    r *= SQRT5
    r += 1.0
    r += q
    r *= e
    return r


def expected_improvement(best: float, mu: np.ndarray, sd: np.ndarray) -> np.ndarray:
    """E[max(best − f, 0)] for f ~ N(mu, sd²), directly (underflows far from ``best``)."""
    z = (best - mu) / sd
    return (best - mu) * norm.cdf(z) + sd * norm.pdf(z)


LENGTHS = np.array([0.2, 0.5, 0.35, 1.3])
VAR, NOISE = 1.7, 1e-3


def _data(n: int = 40, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    x = rng.random((n, 4))
    y = np.log1p(np.exp(3.0 * x[:, 0] - 2.0 * x[:, 1] ** 2 + np.sin(6.0 * x[:, 2]))) + x[:, 3]
    return x, y


def _sklearn(x: np.ndarray, y: np.ndarray):
    kernel = kernels.ConstantKernel(VAR, "fixed") * kernels.Matern(
        LENGTHS, "fixed", nu=2.5
    ) + kernels.WhiteKernel(NOISE + 1e-10, "fixed")
    return sklearn_gp.GaussianProcessRegressor(kernel, optimizer=None, normalize_y=True).fit(x, y)


def _ours(x: np.ndarray, y: np.ndarray) -> GaussianProcess:
    theta = np.r_[np.log(LENGTHS), math.log(VAR), math.log(NOISE)]
    return GaussianProcess(x, y, start=theta, fit=False)


def test_the_kernel_is_scikit_learns_matern_five_halves():
    x, _ = _data()
    b = np.random.default_rng(1).random((7, 4))
    ref = kernels.Matern(LENGTHS, nu=2.5)(x, b)
    np.testing.assert_allclose(numpy_matern52(x, b, LENGTHS), ref, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(matern52(x, b, LENGTHS), ref, rtol=1e-12, atol=1e-14)


def test_posterior_matches_scikit_learn_with_the_same_hyperparameters():
    x, y = _data()
    xs = np.random.default_rng(2).random((300, 4))
    mu, sd = _ours(x, y).predict(xs)
    # White noise belongs to the observations only: scikit-learn's predictive std adds it
    # back at new points, ours is of the latent function.
    ref_mu, ref_sd = _sklearn(x, y).predict(xs, return_std=True)
    np.testing.assert_allclose(mu, ref_mu, rtol=1e-8, atol=1e-8)
    ref_sd = np.sqrt(np.maximum(ref_sd**2 - (NOISE + 1e-10) * y.std() ** 2, 0.0))
    np.testing.assert_allclose(sd, ref_sd, rtol=1e-5, atol=1e-6)


def test_marginal_likelihood_and_its_gradient_match_scikit_learn():
    x, y = _data(30)
    gp = _ours(x, y)
    ref = _sklearn(x, y)
    nll, grad = gp._nll(gp.theta)
    # scikit-learn's theta: log variance, log lengths, log noise; its likelihood keeps
    # the n/2·log 2π ours drops.
    lml = ref.log_marginal_likelihood(ref.kernel_.theta)
    assert nll == pytest.approx(-lml - 0.5 * len(x) * math.log(2 * math.pi), rel=1e-8)
    # The kernel is fixed there, so it gives no gradient: central differences instead.
    h = 1e-6
    for i in range(len(gp.theta)):
        e = np.zeros_like(gp.theta)
        e[i] = h
        fd = (gp._nll(gp.theta + e)[0] - gp._nll(gp.theta - e)[0]) / (2 * h)
        assert grad[i] == pytest.approx(fd, rel=1e-4, abs=1e-6)


def test_the_fit_raises_the_marginal_likelihood_over_its_start():
    x, y = _data(50, seed=3)
    start = np.r_[np.full(4, math.log(0.3)), 0.0, math.log(1e-3)]
    fitted = GaussianProcess(x, y)
    assert fitted._nll(fitted.theta)[0] < fitted._nll(start)[0] - 1.0


def test_log_expected_improvement_is_the_log_of_it_where_that_is_finite():
    mu = np.linspace(-5.0, 30.0, 500)
    sd = np.full_like(mu, 1.3)
    ref = np.log(expected_improvement(0.0, mu, sd))
    np.testing.assert_allclose(log_expected_improvement(0.0, mu, sd), ref, rtol=1e-9)


def test_log_expected_improvement_ranks_where_the_improvement_underflows():
    mu = np.array([60.0, 45.0, 80.0, 45.0])
    sd = np.array([1.0, 1.0, 1.0, 1.1])
    assert not expected_improvement(0.0, mu, sd).any()  # all zero: argmax would take 0
    log_ei = log_expected_improvement(0.0, mu, sd)
    assert np.isfinite(log_ei).all()
    assert int(np.argmax(log_ei)) == 3  # nearest, widest
    assert log_ei[1] > log_ei[0] > log_ei[2]
    # across the switch to the tail series: continuous and decreasing
    t = np.array([19.9999, 20.0, 20.0001]) * 2.0
    v = log_expected_improvement(0.0, t, np.full(3, 2.0))
    assert v[0] > v[1] > v[2] and v[0] - v[2] < 1e-2


def test_a_model_batch_takes_the_best_candidate_when_every_product_underflows():
    x, y = _data(30)
    gp = _ours(x, y)
    cand = np.random.default_rng(4).random((64, 4))
    mu, sd = gp.predict(cand)
    best = float(mu.min() - 60.0 * sd.max())  # far below every candidate
    assert not expected_improvement(best, mu, sd).any()
    want = int(np.argmax(log_expected_improvement(best, mu, sd)))
    assert want != 0
    (chosen,) = _Fit(gp, [], best).choose(1, lambda: cand)
    np.testing.assert_array_equal(chosen, cand[want])


def _posterior(gp: GaussianProcess, x: np.ndarray, y_std: np.ndarray, xs: np.ndarray):
    """The posterior mean and deviation at ``xs`` given standardised ``y_std`` at ``x``, with
    ``gp``'s hyperparameters and standardisation: the textbook formulas, solved directly."""
    k = gp.var * numpy_matern52(x, x, gp.lengths) + (gp.noise + 1e-10) * np.eye(len(x))
    ks = gp.var * numpy_matern52(xs, x, gp.lengths)
    mean = ks @ np.linalg.solve(k, y_std) * gp.scale + gp.mean
    var = gp.var - np.einsum("ij,ji->i", ks, np.linalg.solve(k, ks.T))
    return mean, np.sqrt(np.maximum(var, 1e-18)) * gp.scale


def test_believed_points_give_the_posterior_of_conditioning_on_their_predictions():
    x, y = _data(40, seed=5)
    cand = np.random.default_rng(6).random((200, 4))
    gp = _ours(x, y)
    b = Believer(gp, cand)
    mu0, _ = gp.predict(cand)
    np.testing.assert_allclose(b.mean, mu0, rtol=1e-12, atol=1e-12)
    xs, ys = x, gp.y
    for j in (17, 3, 150, 90):
        b.believe(j)
        xs, ys = np.vstack([xs, cand[j]]), np.append(ys, (mu0[j] - gp.mean) / gp.scale)
        mu, sd = _posterior(gp, xs, ys, cand)
        np.testing.assert_allclose(mu, b.mean, rtol=1e-8, atol=1e-8)
        np.testing.assert_allclose(b.sd(), sd, rtol=1e-6, atol=1e-8)
    assert b.sd()[17] < 0.1 * sd.max()  # a believed point is nearly known


def test_pending_points_are_believed_before_a_batch_is_chosen():
    """A worker's batch while others run: the running points count as believed (their
    neighbourhood less uncertain), and none of them is chosen again."""
    x, y = _data(30)
    gp = _ours(x, y)
    cand = np.random.default_rng(7).random((64, 4))
    fit = _Fit(gp, [], float(y.min()))
    (first,) = fit.choose(1, lambda: cand)
    (again,) = fit.choose(1, lambda: cand, [first])
    assert not np.array_equal(again, first)
    np.testing.assert_array_equal(again, fit.choose(2, lambda: cand)[1])


def test_a_model_batch_chooses_distinct_candidates():
    x, y = _data(30)
    gp = _ours(x, y)
    cand = np.random.default_rng(7).random((64, 4))
    chosen = _Fit(gp, [], float(y.min())).choose(8, lambda: cand)
    assert len({tuple(c) for c in chosen}) == 8


def test_a_batch_on_threads_gives_the_bits_of_a_batch_in_turn(monkeypatch):
    """The models of a batch fitted and predicted side by side (:func:`_model.each`) give
    the same points, bit for bit, as one after the other."""
    from vfgym.tuning import _model
    from vfgym.tuning._model import Observation, propose

    rng = np.random.default_rng(3)
    x = rng.random((40, 4))
    obs = [
        Observation(i, x[i], "ramp", float(1.0 + (x[i] ** 2).sum()), max(0.0, x[i, 0] - 0.6),
                    bool(x[i, 0] <= 0.6), np.array([x[i, 0] - 0.6, x[i, 1] - 0.8]))
        for i in range(40)
    ]  # fmt: skip

    def batch() -> list[np.ndarray]:
        return propose(x, obs, [x[0] * 0.5], 4, 0.0, np.random.default_rng(7)).points

    threaded = batch()
    monkeypatch.setattr(_model, "each", lambda fn, items: [fn(i) for i in items])
    in_turn = batch()
    assert len(threaded) == 4
    assert all(np.array_equal(a, b) for a, b in zip(threaded, in_turn, strict=True))


@pytest.mark.parametrize("seed", range(6))
def test_the_compiled_correlation_is_the_numpy_one_bit_for_bit(seed):
    """The compiled :func:`_gp.matern52` against the numpy formula, on random points and
    length scales across their bounds (one point pair coinciding)."""
    from vfgym.tuning._gp import LENGTH_BOUNDS

    rng = np.random.default_rng(seed)
    a, b = rng.random((rng.integers(1, 300), 4)), rng.random((rng.integers(1, 200), 4))
    b[0] = a[0]
    lengths = np.exp(rng.uniform(*np.log(LENGTH_BOUNDS), 4))
    expected = numpy_matern52(a, b, lengths)
    got = matern52(a, b, lengths)
    assert got.shape == expected.shape and np.array_equal(got, expected)
    assert got[0, 0] == 1.0
