"""How a sweep scores one setting over a move set: one number from its cost on each move.

A sweep minimises an aggregate of the per-move costs (``vfgym sweep --aggregate``): the
``mean`` (the default: good on the typical move), the ``worst`` (good on every move, at
the typical move's expense), or the ``cvar``, the mean of the costliest ``cvar_alpha``
share of the moves. For CVaR, with ``n`` moves sorted from the most costly, each weighs
``1/n`` and the worst are taken until their weights sum to ``α``, the last in part:
``CVaR = Σ wᵢ·cᵢ / α``, ``wᵢ = min(1/n, max(0, α − (i−1)/n))``; α = 1 is the mean, α ≤ 1/n
the worst move. Undefined costs (NaN: a pulse source on a moving reference) are left out.
Feasibility does not depend on the aggregate: a setting is feasible only if every
constraint holds on every move (:func:`aggregate`).
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np

from vfgym._validate import check_choice, check_real
from vfgym.scoring import Evaluation

AGGREGATES = ("mean", "cvar", "worst")
"""Aggregates of a setting's per-move costs a sweep may minimise (see the module docstring)."""
DEFAULT_AGGREGATE = "mean"
DEFAULT_CVAR_ALPHA = 0.25
"""The share of the costliest moves whose mean ``cvar`` takes: the worst quarter."""


def check_aggregate(how: Any, cvar_alpha: Any) -> tuple[str, float]:
    """``(how, cvar_alpha)`` validated: one of :data:`AGGREGATES`, a share in (0, 1]."""
    how = check_choice("aggregate", how, AGGREGATES)
    return how, check_real("cvar_alpha", cvar_alpha, 0.0, 1.0, lo_open=True)


def aggregate_costs(
    costs: Any, how: str = DEFAULT_AGGREGATE, cvar_alpha: float = DEFAULT_CVAR_ALPHA
) -> np.ndarray:
    """Each controller's aggregate cost over the moves.

    Parameters
    ----------
    costs : array_like of float
        Costs shaped (controllers, moves), or (moves,) for one controller.
    how : str
        ``mean``, ``cvar`` or ``worst`` (:data:`AGGREGATES`).
    cvar_alpha : float
        The share of the costliest moves ``cvar`` averages, in (0, 1].

    Returns
    -------
    numpy.ndarray
        One aggregate per controller (0-d for a 1-D input), NaN entries left out; NaN
        where a row has no finite cost.
    """
    how, cvar_alpha = check_aggregate(how, cvar_alpha)
    c = np.asarray(costs, dtype=float)

    def one(row: np.ndarray) -> float:
        x = row[np.isfinite(row)]
        if x.size == 0:
            return math.nan
        if how != "cvar":
            return float(x.mean() if how == "mean" else x.max())
        x, n = np.sort(x)[::-1], x.size
        above = np.arange(n) / n  # the weight of the moves costlier than each one
        w = np.minimum(1.0 / n, np.maximum(0.0, cvar_alpha - above))
        return float(np.dot(w, x) / w.sum())

    out = np.array([one(r) for r in np.atleast_2d(c)], dtype=np.float64)
    return out.reshape(()) if c.ndim == 1 else out


class Aggregate(NamedTuple):
    """Each controller's scores over a scenario set (arrays indexed by controller).

    Attributes
    ----------
    cost : numpy.ndarray
        The cost's aggregate over the scenarios (the mean by default), (C,).
    constraints : numpy.ndarray
        Worst (max) of each constraint over the scenarios, (C, 4).
    feasible : numpy.ndarray
        Every constraint ≤ 0 on every scenario, (C,) bool.
    objectives : numpy.ndarray
        The objectives' means over the scenarios, (C, 3).
    """

    cost: np.ndarray
    constraints: np.ndarray
    feasible: np.ndarray
    objectives: np.ndarray


def aggregate(
    ev: Evaluation, how: str = DEFAULT_AGGREGATE, cvar_alpha: float = DEFAULT_CVAR_ALPHA
) -> Aggregate:
    """Each controller's results over the scenarios, as a sweep scores a setting.

    Parameters
    ----------
    ev : Evaluation
        What :func:`vfgym.evaluate` returned.
    how : str
        The cost's aggregate over the scenarios: ``mean``, ``cvar`` or ``worst``.
    cvar_alpha : float
        The share of the costliest scenarios ``cvar`` averages.

    Returns
    -------
    Aggregate
        Per controller: the cost's aggregate (on the modelled plant), the worst of each
        constraint over the scenarios and any true plants the evaluation holds
        (:attr:`vfgym.Evaluation.across`), feasibility, the objectives' means.
    """
    cons = np.nanmax(ev.constraints, axis=1)
    if ev.across is not None:  # robust: the worst over the true plants of the design too
        cons = np.fmax(cons, np.nanmax(ev.across.constraints, axis=(1, 2)))
    return Aggregate(
        cost=aggregate_costs(ev.cost, how, cvar_alpha),
        constraints=cons,
        feasible=np.all(cons <= 0.0, axis=1),
        objectives=np.nanmean(ev.objectives, axis=1),
    )
