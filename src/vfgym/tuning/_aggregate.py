"""How a sweep scores one setting over a move set: one number from its cost on each move.

A sweep over several moves minimises an *aggregate* of the per-move costs
(``SweepConfig.aggregate``, ``vfgym sweep --aggregate``):

mean
    the mean cost over the moves (the default): good on the typical move.
cvar
    the conditional value at risk: the mean of the worst ``cvar_alpha`` share of the
    moves (``cvar_alpha`` = 0.25: the worst quarter). With ``n`` moves sorted from the
    most costly, each move weighs ``1/n`` and the worst ones are taken until their weights
    sum to ``α``, the last one in part: ``CVaR = Σ wᵢ·cᵢ / α`` with
    ``wᵢ = min(1/n, max(0, α − (i−1)/n))``. So α = 1 is the mean, α ≤ 1/n the worst
    move, and in between it lies between the two and never decreases as α shrinks.
worst
    the highest cost over the moves: good on every move, at the typical move's expense.

Costs that are not defined (NaN: a pulse source on a moving reference) are left out. The
feasibility of a setting does not depend on the aggregate: it is feasible only if every
constraint holds on every move (:func:`vfgym.tuning.aggregate`, the worst constraint over
the moves).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from vfgym._validate import check_choice, check_real
from vfgym.moves.axis import axis_kwargs
from vfgym.moves.scenarios import Scenario
from vfgym.params import Settings
from vfgym.scoring import evaluate

if TYPE_CHECKING:
    from vfgym.tuning._config import SweepConfig

AGGREGATES = ("mean", "cvar", "worst")
"""Aggregates of a setting's per-move costs a sweep may minimise (see the module docstring)."""
DEFAULT_AGGREGATE = "mean"
"""The aggregate a sweep minimises unless told otherwise."""
DEFAULT_CVAR_ALPHA = 0.25
"""The share of the costliest moves whose mean ``cvar`` takes: the worst quarter."""


def check_aggregate(how: Any, cvar_alpha: Any) -> tuple[str, float]:
    """Check an aggregate and its CVaR share.

    Parameters
    ----------
    how : str
        One of :data:`AGGREGATES`.
    cvar_alpha : float
        The share of the costliest moves ``cvar`` averages, in (0, 1].

    Returns
    -------
    tuple of (str, float)
        ``(how, cvar_alpha)``, validated.

    Raises
    ------
    ValueError
        One line naming the parameter, the value and what is allowed.
    """
    how = check_choice("aggregate", how, AGGREGATES)
    return how, check_real("cvar_alpha", cvar_alpha, 0.0, 1.0, lo_open=True)


def cvar(costs: Any, alpha: float = DEFAULT_CVAR_ALPHA) -> float:
    """The mean of the costliest ``alpha`` share of the costs (see the module docstring).

    Parameters
    ----------
    costs : array_like of float
        One cost per move; NaN entries are left out.
    alpha : float
        The share, in (0, 1]: 1 gives the mean, ``1/n`` or less the highest cost.

    Returns
    -------
    float
        The conditional value at risk; NaN without a finite cost.
    """
    x = np.asarray(costs, dtype=float).ravel()
    x = np.sort(x[np.isfinite(x)])[::-1]
    n = x.size
    if n == 0:
        return math.nan
    above = np.arange(n) / n  # the weight of the moves costlier than each one
    w = np.minimum(1.0 / n, np.maximum(0.0, alpha - above))
    return float(np.dot(w, x) / w.sum())


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
        One aggregate per controller, shaped (controllers,) (a 0-d array for a 1-D
        input); NaN entries are left out, NaN where a row has no finite cost.
    """
    how, cvar_alpha = check_aggregate(how, cvar_alpha)
    c = np.asarray(costs, dtype=float)
    rows = np.atleast_2d(c)
    out = np.full(rows.shape[0], np.nan)
    for i, row in enumerate(rows):
        x = row[np.isfinite(row)]
        if x.size == 0:
            continue
        if how == "mean":
            out[i] = x.mean()
        elif how == "worst":
            out[i] = x.max()
        else:
            out[i] = cvar(x, cvar_alpha)
    return out.reshape(()) if c.ndim == 1 else out


def describe(cfg: SweepConfig) -> str:
    """The sweep's aggregate as reports name it: ``mean``, ``worst`` or ``cvar 0.25``.

    Parameters
    ----------
    cfg : SweepConfig
        The sweep's configuration (its ``aggregate`` and ``cvar_alpha``).

    Returns
    -------
    str
        A short name.
    """
    return f"cvar {cfg.cvar_alpha:g}" if cfg.aggregate == "cvar" else cfg.aggregate


def set_cost(settings: Settings, scenarios: Sequence[Scenario], cfg: SweepConfig) -> float:
    """A setting's cost over the sweep's scenarios, as the sweep scores it.

    Parameters
    ----------
    settings : Settings
        The setting (e.g. the paper's, to report the tuned one against).
    scenarios : sequence of Scenario
        The sweep's scenarios.
    cfg : SweepConfig
        The sweep's configuration: its aggregate, CVaR share and axis.

    Returns
    -------
    float
        :func:`aggregate_costs` of :func:`vfgym.evaluate`'s costs on the axis's plant.
    """
    ev = evaluate(settings, list(scenarios), **axis_kwargs(cfg.load_axis()))
    return float(aggregate_costs(ev.cost[0], cfg.aggregate, cfg.cvar_alpha))
