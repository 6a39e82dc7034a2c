"""The plants :class:`vfgym.permove.adaptive.EstimatingScheduler` checks a move's table on
outside the ranges, beside its design plants and the grid within them
(:func:`vfgym.envs.calibration_plants`): *shadow* plants just outside them,
with the points between shadows where the base's feasibility changes, located by
bisection (feasibility is not monotone in the plant, and a continuation tends to break a
limit first where the base only just keeps it)."""

from __future__ import annotations

import itertools
from collections.abc import Callable
from dataclasses import replace

from vfgym.axis import PlantVariant

SHADOWED = ("inertia", "torque_per_count", "load_offset_nm")
"""The quantities a shadow plant moves outside their ranges."""
SHADOW_LEVELS = (0.125, 0.25, 0.5, 1.0)
"""Shadow plants lie these shares of ``AdaptiveOptions.shadow`` outside each range's edge."""
BISECTIONS = 4
"""Halvings between two neighbouring points of a shadow line where the base holds on one and
breaks a limit on the other (:func:`boundary_plants`)."""


def shadow_lines(
    design: tuple[PlantVariant, ...], rated_torque_nm: float, shadow: float
) -> list[tuple[PlantVariant, ...]]:
    """Each design plant with one quantity of :data:`SHADOWED` moved outward from its range's
    edge, one line a (plant, quantity, side): the plant at the edge first (within the
    ranges), then its shadows at :data:`SHADOW_LEVELS` shares of ``shadow`` beyond it (a
    share of the edge for a factor, of ``rated_torque_nm`` for the load torque).

    Parameters
    ----------
    design : tuple of PlantVariant
        The axis's design plants (their corners span the ranges; a quantity known exactly
        has its one value as both edges).
    rated_torque_nm : float
        The motor's rated torque (the load torque's scale).
    shadow : float
        How far outside, (0, 0.5].

    Returns
    -------
    list of tuple of PlantVariant
        The lines, each once, each from the edge outward.
    """
    out: dict[tuple[PlantVariant, ...], None] = {}
    for k in SHADOWED:
        lo, hi = (f(getattr(p, k) for p in design) for f in (min, max))
        for side, edge in ((-1.0, lo), (1.0, hi)):
            if k == "load_offset_nm":
                vals = [edge + side * f * shadow * rated_torque_nm for f in (0.0, *SHADOW_LEVELS)]
            else:
                vals = [edge * (1.0 + side * f * shadow) for f in (0.0, *SHADOW_LEVELS)]
            for p in design:
                out[tuple(replace(p, **{k: v}) for v in vals)] = None
    return list(out)


def shadow_plants(
    design: tuple[PlantVariant, ...], rated_torque_nm: float, shadow: float
) -> list[PlantVariant]:
    """The design plants each with one quantity of :data:`SHADOWED` just outside its
    range: the shadows of :func:`shadow_lines`, without the edges.

    Parameters
    ----------
    design : tuple of PlantVariant
        The axis's design plants.
    rated_torque_nm : float
        The motor's rated torque (the load torque's scale).
    shadow : float
        How far outside, (0, 0.5].

    Returns
    -------
    list of PlantVariant
        The shadow plants, each once.
    """
    out = {q: None for line in shadow_lines(design, rated_torque_nm, shadow) for q in line[1:]}
    return list(out)


def boundary_plants(
    line: tuple[PlantVariant, ...], holds: Callable[[PlantVariant], bool], steps: int = BISECTIONS
) -> list[PlantVariant]:
    """The plants between neighbouring points of ``line`` where ``holds`` changes, found by
    bisection: ``steps`` halvings of each such interval, keeping the side that changes; the
    midpoints where ``holds`` is true (nearer the boundary at each step).

    Parameters
    ----------
    line : tuple of PlantVariant
        Plants differing in one quantity, in order (:func:`shadow_lines`).
    holds : callable
        Whether the base keeps every limit on a plant.
    steps : int
        Halvings of each interval (≥ 0).

    Returns
    -------
    list of PlantVariant
        The midpoints where ``holds``, each once.
    """
    out: dict[PlantVariant, None] = {}
    for a, b in itertools.pairwise(line):
        if holds(a) == holds(b):
            continue
        k = next(f for f in SHADOWED if getattr(a, f) != getattr(b, f))
        side = holds(a)
        for _ in range(steps):
            m = replace(a, **{k: 0.5 * (getattr(a, k) + getattr(b, k))})
            if holds(m):
                out[m] = None
            if holds(m) == side:
                a = m
            else:
                b = m
    return list(out)


__all__ = [
    "BISECTIONS",
    "SHADOWED",
    "SHADOW_LEVELS",
    "boundary_plants",
    "shadow_lines",
    "shadow_plants",
]
