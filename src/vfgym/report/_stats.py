"""The statistics of a comparison: spreads (median, IQR, bootstrap interval of the mean) and
per-scenario win / loss / tie.

win / loss / tie
    per scenario, a tuned candidate *wins* against a baseline when its cost is lower, *loses*
    when higher, and *ties* when the two are equal within a relative 1e-9 (identical
    settings give identical costs). A pulse-source baseline on a moving reference has no
    cost (NaN): that scenario is *n/a* and counted apart. Win rate = wins / (wins + losses
    + ties).
spread
    over the scenarios where a measure is defined: n, the median with its interquartile
    range (25th and 75th percentiles, linear interpolation), and the mean with a percentile
    bootstrap 95 % interval (``resamples`` draws with replacement, seeded, so a report is
    reproducible). Paired cost differences (tuned − baseline) get the same spread.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

TIE_RTOL = 1e-9
DEFAULT_RESAMPLES = 2000


@dataclass(frozen=True)
class Spread:
    """n, median with interquartile range, mean with a bootstrap interval (see :func:`spread`).

    Attributes
    ----------
    n : int
        Finite values the spread is over.
    median, q1, q3 : float
        Median and the 25th and 75th percentiles (NaN when n = 0).
    mean : float
        Mean of the values.
    ci_low, ci_high : float
        Percentile bootstrap interval of the mean.
    """

    n: int
    median: float
    q1: float
    q3: float
    mean: float
    ci_low: float
    ci_high: float


@dataclass(frozen=True)
class WinLoss:
    """A tuned candidate against a baseline over the scenarios.

    Attributes
    ----------
    tuned : str
        The tuned candidate's label.
    baseline : str
        The baseline's label.
    outcomes : tuple of str
        Per scenario: ``win``, ``loss``, ``tie`` or ``n/a`` (see :func:`outcome`).
    cost_diff : Spread
        Tuned cost − baseline cost (negative: tuned better), over the comparable scenarios.
    """

    tuned: str
    baseline: str
    outcomes: tuple[str, ...]
    cost_diff: Spread

    @property
    def wins(self) -> int:
        """Scenarios where the tuned candidate costs less."""
        return self.outcomes.count("win")

    @property
    def losses(self) -> int:
        """Scenarios where it costs more."""
        return self.outcomes.count("loss")

    @property
    def ties(self) -> int:
        """Scenarios where the costs are equal within :data:`TIE_RTOL`."""
        return self.outcomes.count("tie")

    @property
    def not_applicable(self) -> int:
        """Scenarios where either has no cost (a pulse source on a moving reference)."""
        return self.outcomes.count("n/a")

    @property
    def win_rate(self) -> float:
        """wins / (wins + losses + ties); NaN with no comparable scenario."""
        n = self.wins + self.losses + self.ties
        return self.wins / n if n else math.nan


def spread(
    values: Sequence[float] | np.ndarray,
    *,
    resamples: int = DEFAULT_RESAMPLES,
    seed: int = 0,
    level: float = 0.95,
) -> Spread:
    """Spread of the finite values (NaN dropped; see the module docstring).

    Parameters
    ----------
    values : sequence of float or numpy.ndarray
        The values, one per scenario.
    resamples : int
        Bootstrap draws with replacement.
    seed : int
        Seed of the draws, so that a report is reproducible.
    level : float
        Coverage of the bootstrap interval.

    Returns
    -------
    Spread
        n, median, quartiles, mean and its interval; all NaN (n = 0) without a finite
        value.
    """
    x = np.asarray(values, dtype=float)
    x = x[np.isfinite(x)]
    n = int(x.size)
    if n == 0:
        nan = math.nan
        return Spread(0, nan, nan, nan, nan, nan, nan)
    q1, med, q3 = np.percentile(x, [25.0, 50.0, 75.0])
    rng = np.random.default_rng(seed)
    means = np.empty(resamples)
    chunk = max(1, 2_000_000 // n)
    for start in range(0, resamples, chunk):
        stop = min(resamples, start + chunk)
        means[start:stop] = x[rng.integers(0, n, size=(stop - start, n))].mean(axis=1)
    alpha = (1.0 - level) / 2.0
    lo, hi = np.quantile(means, [alpha, 1.0 - alpha])
    return Spread(n, float(med), float(q1), float(q3), float(x.mean()), float(lo), float(hi))


def outcome(tuned_cost: float, baseline_cost: float) -> str:
    """The outcome of one scenario for a tuned candidate against a baseline.

    Parameters
    ----------
    tuned_cost : float
        The tuned candidate's cost.
    baseline_cost : float
        The baseline's cost.

    Returns
    -------
    str
        ``win`` (lower cost), ``loss`` or ``tie`` (equal within :data:`TIE_RTOL`); ``n/a``
        when either cost is not finite.
    """
    if not (math.isfinite(tuned_cost) and math.isfinite(baseline_cost)):
        return "n/a"
    if math.isclose(tuned_cost, baseline_cost, rel_tol=TIE_RTOL, abs_tol=1e-12):
        return "tie"
    return "win" if tuned_cost < baseline_cost else "loss"
