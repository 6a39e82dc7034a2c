"""The compass's Gaussian process (``tuning/_gp.py``, scikit-learn's regression) against the
textbook formulas of a Matérn-5/2 process with the same hyperparameters, its fit against
the marginal likelihood it maximises, and its acquisition in logs."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.stats import norm

from vfgym.tuning import _gp
from vfgym.tuning._gp import (
    JITTER,
    LENGTH_BOUNDS,
    NOISE_BOUNDS,
    VARIANCE_BOUNDS,
    Believer,
    GaussianProcess,
    log_expected_improvement,
)
from vfgym.tuning._model import _Fit


def matern52(a: np.ndarray, b: np.ndarray, lengths: np.ndarray) -> np.ndarray:
    """The Matérn-5/2 correlation, from its formula: (1 + √5 r + 5r²/3)·exp(−√5 r), r the
    distance scaled per axis."""
    r = np.sqrt((((a[:, None, :] - b[None, :, :]) / lengths) ** 2).sum(-1))
    return (1.0 + math.sqrt(5.0) * r + 5.0 / 3.0 * r * r) * np.exp(-math.sqrt(5.0) * r)


def _k(gp: GaussianProcess, x: np.ndarray) -> np.ndarray:
    return gp.var * matern52(x, x, gp.lengths) + (gp.noise + JITTER) * np.eye(len(x))


def _posterior(gp: GaussianProcess, x: np.ndarray, y_std: np.ndarray, xs: np.ndarray):
    """The posterior mean and deviation at ``xs`` given standardised ``y_std`` at ``x``, with
    ``gp``'s hyperparameters and standardisation: the textbook formulas, solved directly."""
    k = _k(gp, x)
    ks = gp.var * matern52(xs, x, gp.lengths)
    mean = ks @ np.linalg.solve(k, y_std) * gp.scale + gp.mean
    var = gp.var - np.einsum("ij,ji->i", ks, np.linalg.solve(k, ks.T))
    return mean, np.sqrt(np.maximum(var, 1e-18)) * gp.scale


def _nll(x: np.ndarray, y_std: np.ndarray, theta: np.ndarray) -> float:
    """The negative log marginal likelihood (without n/2·log 2π) at log hyperparameters
    ``theta`` (length scales, signal variance, noise variance), from its formula."""
    d = x.shape[1]
    lengths, var, noise = np.exp(theta[:d]), math.exp(theta[d]), math.exp(theta[d + 1])
    k = var * matern52(x, x, lengths) + (noise + JITTER) * np.eye(len(x))
    chol = np.linalg.cholesky(k)
    return 0.5 * float(y_std @ np.linalg.solve(k, y_std)) + float(np.log(np.diag(chol)).sum())


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


def _ours(x: np.ndarray, y: np.ndarray) -> GaussianProcess:
    theta = np.r_[np.log(LENGTHS), math.log(VAR), math.log(NOISE)]
    return GaussianProcess(x, y, start=theta, fit=False)


def test_the_kernel_is_the_matern_five_halves():
    x, _ = _data()
    b = np.random.default_rng(1).random((7, 4))
    np.testing.assert_allclose(
        _gp.matern52(x, b, LENGTHS), matern52(x, b, LENGTHS), rtol=1e-12, atol=1e-14
    )


def test_a_process_kept_unfitted_keeps_its_hyperparameters():
    gp = _ours(*_data())
    np.testing.assert_allclose(gp.lengths, LENGTHS, rtol=1e-12)
    assert gp.var == pytest.approx(VAR, rel=1e-12) and gp.noise == pytest.approx(NOISE, rel=1e-12)
    np.testing.assert_allclose(np.exp(gp.theta), np.r_[LENGTHS, VAR, NOISE], rtol=1e-12)


def test_the_posterior_is_the_textbook_one():
    x, y = _data()
    xs = np.random.default_rng(2).random((300, 4))
    gp = _ours(x, y)
    at = Believer(gp, xs)
    mu, sd = at.mean, at.sd()
    ref_mu, ref_sd = _posterior(gp, x, gp.y, xs)
    np.testing.assert_allclose(mu, ref_mu, rtol=1e-8, atol=1e-8)
    np.testing.assert_allclose(sd, ref_sd, rtol=1e-5, atol=1e-6)


@pytest.mark.parametrize("seed", [3, 4])
def test_the_fit_maximises_the_marginal_likelihood(seed):
    """From the defaults and from a previous fit's hyperparameters: better than the start,
    and no small step within the bounds does better (a local optimum, or on a bound)."""
    x, y = _data(50, seed=seed)
    start = np.r_[np.full(4, math.log(0.3)), 0.0, math.log(1e-3)]
    fitted = GaussianProcess(x, y)
    nll = _nll(x, fitted.y, fitted.theta)
    assert nll < _nll(x, fitted.y, start) - 1.0
    lo = np.log(np.r_[np.full(4, LENGTH_BOUNDS[0]), VARIANCE_BOUNDS[0], NOISE_BOUNDS[0]])
    hi = np.log(np.r_[np.full(4, LENGTH_BOUNDS[1]), VARIANCE_BOUNDS[1], NOISE_BOUNDS[1]])
    for i in range(len(start)):
        for h in (-0.05, 0.05):
            t = fitted.theta.copy()
            t[i] = min(max(t[i] + h, lo[i]), hi[i])
            assert _nll(x, fitted.y, t) >= nll - 1e-6
    again = GaussianProcess(x, y, start=fitted.theta)
    assert _nll(x, fitted.y, again.theta) <= nll + 1e-6


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
    at = Believer(gp, cand)
    mu, sd = at.mean, at.sd()
    best = float(mu.min() - 60.0 * sd.max())  # far below every candidate
    assert not expected_improvement(best, mu, sd).any()
    want = int(np.argmax(log_expected_improvement(best, mu, sd)))
    assert want != 0
    (chosen,) = _Fit(gp, [], best).choose(1, lambda: cand)
    np.testing.assert_array_equal(chosen, cand[want])


def test_believed_points_give_the_posterior_of_conditioning_on_their_predictions():
    x, y = _data(40, seed=5)
    cand = np.random.default_rng(6).random((200, 4))
    gp = _ours(x, y)
    b = Believer(gp, cand)
    mu0 = Believer(gp, cand).mean
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
