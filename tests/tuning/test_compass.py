"""The compass sampler's local model step (no simulation: synthetic observations)."""

from __future__ import annotations

import numpy as np

from vfgym.tuning._compass import Observation, propose_local


def _observe(points: np.ndarray) -> list[Observation]:
    """A cost falling along the diagonal (u0 + u1) behind a diagonal constraint edge
    u1 - u0 <= 0.05: an axis poll from the centre (0.5, 0.5) either breaks the constraint
    or raises the cost; only a move along the edge both ways at once pays."""
    out = []
    for i, u in enumerate(points):
        cost = float(np.exp(2.0 - (u[0] + u[1]) + 0.1 * (u[2] - 0.5) ** 2))
        g = float(u[1] - u[0] - 0.05)
        out.append(Observation(i, u.copy(), "rise", cost, max(g, 0.0), g <= 0.0, np.array([g])))
    return out


def test_local_points_stay_in_the_box_and_follow_the_diagonal_edge():
    rng = np.random.default_rng(0)
    centre = np.array([0.5, 0.5, 0.5, 0.5])
    steps = 0.04
    polls = [centre + s * steps * np.eye(4)[d] for d in range(4) for s in (1, -1)]
    x = np.vstack([centre, *polls, centre + rng.uniform(-0.15, 0.15, (20, 4))])
    obs = _observe(x)
    radius = np.full(4, 2 * steps)
    pts = propose_local(x, obs, centre, radius, [], 3, np.random.default_rng(1))
    assert len(pts) == 3
    for p in pts:
        assert np.all(np.abs(p - centre) <= radius + 1e-12)  # within the box
    best_centre = obs[0].cost
    wins = [o for o in _observe(np.array(pts)) if o.feasible and o.cost < best_centre]
    assert wins  # at least one beats the centre, feasibly: a diagonal move
    moved = np.array(pts[0]) - centre
    assert moved[0] > 0 and moved[1] > 0  # both coordinates at once, up the edge


def test_local_points_are_a_function_of_the_seed():
    x = np.random.default_rng(2).uniform(0.3, 0.7, (25, 4))
    obs = _observe(x)
    centre = x[np.argmin([o.cost if o.feasible else np.inf for o in obs])]
    a = propose_local(x, obs, centre, np.full(4, 0.1), [], 2, np.random.default_rng(5))
    b = propose_local(x, obs, centre, np.full(4, 0.1), [], 2, np.random.default_rng(5))
    assert np.array_equal(np.array(a), np.array(b))
