"""How a sweep's trial stores its result in the study, and how it is read back.

Each attribute a worker writes is one transaction of Optuna's RDB storage, so the result
goes in as few as Optuna's public API allows:

* the result is ONE user attribute, ``result``: a mapping of ``settings`` (the settings
  scored, as :func:`vfgym.space.settings_to_dict` gives them), ``cost``, ``constraints``
  (the worst of each over the scenarios, in :data:`vfgym.scoring.CONSTRAINTS`' order),
  ``feasible``, ``objectives`` (in :data:`vfgym.scoring.OBJECTIVES`' order) and, for a
  result copied from an earlier trial, ``cached_from``;
* the constraints are ONE system attribute, ``constraints``: the list Optuna reads into
  ``trial.constraints`` (in ``CONSTRAINTS``' order; Optuna's samplers use the values).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, NamedTuple

from vfgym.scoring import CONSTRAINTS

RESULT_ATTR = "result"
"""The user attribute of a trial's result."""

PARTS = ("settings", "cost", "constraints", "feasible", "objectives")
"""A result's parts: the keys of ``result``."""

CONSTRAINTS_KEY = "constraints"
"""Optuna's system attribute of a trial's constraints (the list)."""


class StoredResult(NamedTuple):
    """A completed trial's result as a sweep stored it.

    Attributes
    ----------
    settings : dict or None
        The settings scored, as :func:`vfgym.space.settings_to_dict` gives them.
    cost : float
        The cost's aggregate over the scenarios.
    constraints : tuple of float
        The worst of each constraint over the scenarios, in ``CONSTRAINTS``' order
        (≤ 0: met); empty if the trial has none.
    feasible : bool
        Every constraint met on every scenario.
    objectives : tuple of float
        The objectives' means over the scenarios.
    cached_from : int or None
        The trial whose simulation it copies (None: its own).
    """

    settings: dict[str, Any] | None
    cost: float
    constraints: tuple[float, ...]
    feasible: bool
    objectives: tuple[float, ...]
    cached_from: int | None

    @property
    def arrives(self) -> bool:
        """Whether the move arrived on every scenario (worst ``arrival`` ≤ 0)."""
        if len(self.constraints) != len(CONSTRAINTS):
            return False
        return self.constraints[CONSTRAINTS.index("arrival")] <= 0.0


def stored_result(trial: Any) -> StoredResult | None:
    """A trial's stored result.

    Parameters
    ----------
    trial : optuna.trial.FrozenTrial
        The trial (anything with ``user_attrs``).

    Returns
    -------
    StoredResult or None
        Its result; None if it holds no cost (not scored by a sweep, or not yet).
    """
    parts = trial.user_attrs.get(RESULT_ATTR)
    if not isinstance(parts, Mapping) or "cost" not in parts:
        return None
    cached = parts.get("cached_from")
    settings = parts.get("settings")
    return StoredResult(
        settings=dict(settings) if isinstance(settings, Mapping) else None,
        cost=float(parts["cost"]),
        constraints=tuple(float(c) for c in parts.get("constraints") or ()),
        feasible=bool(parts.get("feasible", False)),
        objectives=tuple(float(o) for o in parts.get("objectives") or ()),
        cached_from=None if cached is None else int(cached),
    )


def result_attr(attrs: Mapping[str, Any]) -> dict[str, Any]:
    """The ``result`` user attribute of a result's attributes (its :data:`PARTS` and
    ``cached_from`` if present).

    Parameters
    ----------
    attrs : mapping
        The result's attributes, as :meth:`vfgym.tuning._objective.Objective.score_many`
        gives them.

    Returns
    -------
    dict
        What is stored as ``result``.
    """
    keys = (*PARTS, "cached_from")
    return {k: attrs[k] for k in keys if k in attrs}


def named_constraints(trial: Any) -> dict[str, float]:
    """A trial's constraints by name (``CONSTRAINTS``).

    Parameters
    ----------
    trial : optuna.trial.FrozenTrial
        The trial.

    Returns
    -------
    dict of str to float
        Each constraint's value by its name (a key that is no index of ``CONSTRAINTS``
        as it is).
    """
    out: dict[str, float] = {}
    for key, value in trial.constraints.items():
        name = CONSTRAINTS[int(key)] if key.isdigit() and int(key) < len(CONSTRAINTS) else key
        out[name] = float(value)
    return out
