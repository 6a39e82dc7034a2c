"""The episodes :class:`vfgym.permove.adaptive.EstimatingScheduler` runs on VFServo-v0 to
build a move's table: the base held over the hold and a residual action ramped to after it
(:func:`_ramp`), a plant's signature over the hold, whether an action keeps every limit on
a plant (and, with a count, ends the move inside the window wherever the base does), and
the CMA-ES search of a continuation."""

from __future__ import annotations

import math
from typing import Any, Protocol

import numpy as np

from vfgym.axis import PlantVariant
from vfgym.envs import N_SIGNATURE
from vfgym.envs.servo import VFServoEnv


class SearchOptions(Protocol):
    """What :func:`_search` reads of :class:`vfgym.permove.adaptive.AdaptiveOptions`."""

    @property
    def evals(self) -> int: ...

    @property
    def sigma(self) -> float: ...

    @property
    def seed(self) -> int: ...


END_CONSTRAINTS = ("overshoot", "arrival")
"""The constraints settled where the move ends (:data:`vfgym.scoring.CONSTRAINTS`)."""
INFEASIBLE = 10.0
"""Added to the search's cost of a continuation that breaks a limit on one of its plants."""


def _end(info: dict[str, Any]) -> np.ndarray:
    """An episode's end-of-move constraints (:data:`END_CONSTRAINTS`), ``inf`` where it
    breaks any limit."""
    if not info["feasible"]:
        return np.full(len(END_CONSTRAINTS), math.inf)
    return np.array([info[f"constraint_{n}"] for n in END_CONSTRAINTS])


def _keeps(
    env: VFServoEnv,
    plant: PlantVariant,
    action: np.ndarray,
    ramp: int,
    hold: int,
    base: np.ndarray,
    count: float,
) -> bool:
    """Whether ``action`` keeps every limit on ``plant`` and ends the move at least
    ``count`` (one encoder count in the constraints' units; 0: the limits alone) inside the
    overshoot and in-position limits wherever the base's end (``base``: :func:`_end` of the
    base's episode) is (``AdaptiveOptions.count_margin``)."""
    end = _end(_episode(env, plant, lambda t: _ramp(action, ramp, hold, t))[0])
    return bool(np.all(end <= np.maximum(base, -count)))


def _ramp(action: np.ndarray, ramp: int, hold: int, t: int) -> np.ndarray:
    """The action at interval ``t``: the base until ``hold``, then a linear ramp of
    ``ramp`` intervals to ``action``."""
    if t < hold:
        return np.zeros(4)
    return action * min(1.0, (t - hold + 1) / ramp)


def _episode(env: VFServoEnv, plant: PlantVariant, act: Any) -> tuple[dict[str, Any], int]:
    """One episode on ``plant`` under ``act(t)``: its last ``info`` and its length."""
    env.reset(options={"plant": plant})
    t = 0
    while True:
        *_, term, trunc, info = env.step(act(t))
        t += 1
        if term or trunc:
            return info, t


def _signature(env: VFServoEnv, plant: PlantVariant, hold: int) -> np.ndarray:
    """The dynamic observations over the first ``hold`` intervals on ``plant``, base held."""
    env.reset(options={"plant": plant})
    seen = []
    for _ in range(hold):
        obs, _, term, trunc, _ = env.step(np.zeros(4))
        seen.append(obs[:N_SIGNATURE])
        if term or trunc:
            break
    seen += [seen[-1]] * (hold - len(seen))  # a move over before the hold: its last seen
    return np.concatenate(seen)


_Found = tuple[np.ndarray, int, float]
"""A searched candidate: (action, ramp intervals, cost on its plant)."""


def _search(
    env: VFServoEnv, hold: int, plant: PlantVariant, near: list[PlantVariant], o: SearchOptions
) -> list[_Found]:
    """The continuation for ``plant`` first: (action, ramp intervals, cost on ``plant``), the
    best of CMA-ES's, feasible on ``plant`` and ``near``, else the base held; then the
    other feasible candidates, cheapest first."""
    from cmaes import CMA

    info, steps = _episode(env, plant, lambda t: np.zeros(4))
    best = (bool(info["feasible"]), -float(info["cost"]), np.zeros(4), 1)

    def run(x: np.ndarray) -> tuple[bool, float, np.ndarray, int]:
        a = np.clip(x[:4], -1.0, 1.0)
        ramp = max(1, round(float(np.clip(x[4], 0.0, 1.0)) * steps))
        ok, cost = True, math.nan
        for i, p in enumerate([plant, *near]):
            info, _ = _episode(env, p, lambda t: _ramp(a, ramp, hold, t))
            ok = ok and bool(info["feasible"])
            cost = float(info["cost"]) if i == 0 else cost
            if not ok:
                break
        return ok, -cost, a, ramp

    lo, hi = np.r_[-np.ones(4), 0.0], np.ones(5)
    opt = CMA(mean=np.r_[np.zeros(4), 0.2], sigma=o.sigma, bounds=np.c_[lo, hi], seed=o.seed)
    done, feasible = 0, []
    while done < o.evals:
        told = []
        for _ in range(opt.population_size):
            x = opt.ask()
            r = run(x)
            told.append((x, -r[1] + (0.0 if r[0] else INFEASIBLE)))
            done += 1
            if r[0]:
                feasible.append((r[2], r[3], -r[1]))
            if r[0] and (not best[0] or r[1] > best[1]):
                best = r
        opt.tell(told)
    rest = sorted(feasible, key=lambda f: f[2])
    return [(best[2], best[3], -best[1]), *(f for f in rest if f[0] is not best[2])]
