"""A scheduler that watches the response: on an axis whose plant is known only within
ranges, it holds the move's robust setting for the first milliseconds, tells the true
plant from what the controller measures meanwhile, and ramps to settings computed for that
plant.

A fixed per-move setting must be feasible on the worst plant of the ranges; once the
response has told the plant, a scheduler need not be. Changing ``value`` mid-move is a jump
in pulse frequency, so the change is a ramp, with L/value held (the cost's ridge at
L = value, docs/model.md §1). For each move, offline:

1. the base: the settings model's robust setting (feasible on the axis's design plants);
2. for each design plant, its *signature*: VFServo-v0's dynamic observations over the
   hold, the base in force (the same command, so they differ by the plant alone): what
   the drive measures (encoder counts, its speed counter, the torque it commands), never
   the simulator's continuous state;
3. for each design plant, a *continuation*: a residual action (in
   :class:`vfgym.space.Relative`'s coordinates) reached by a linear ramp from the end of
   the hold, searched by CMA-ES (``cmaes``) for the least cost on that plant, feasible on
   it, on its ``neighbours`` nearest design plants (each quantity over its range; the
   signatures are not monotone in the plant: encoder counts) and on ``probes`` plants
   on the way to each, up to halfway (where a true plant told as this one lies;
   feasibility is not monotone in the plant, so points between are checked, not the ends
   only). The zero
   action (the base held) is the start: a continuation is never worse than the base on
   its plant.

Online (:meth:`EstimatingScheduler.run_move`): hold the base, take the design plant whose
signature is nearest to the observed one, and run its continuation. Everything runs
through VFServo-v0 on the true plant, so :func:`vfgym.evaluate` scores it as every other
controller.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from vfgym._validate import check_int, check_real
from vfgym.axis import Axis, PlantVariant
from vfgym.envs import N_SIGNATURE, check_plants
from vfgym.envs.servo import VFServoEnv
from vfgym.moves.scenarios import Scenario
from vfgym.params import Settings
from vfgym.plant.measures import NAMES as METRIC_NAMES
from vfgym.scoring import Scheduler

SCALE = (1.0, 0.0, 1.0, 1.0)
"""Residual scales (value, L/value, k, Ts/Tf): ±1 moves a coordinate half its range; L/value
held at the base's."""
INFEASIBLE = 10.0
"""Added to the search's cost of a continuation that breaks a limit on one of its plants."""


@dataclass(frozen=True)
class AdaptiveOptions:
    """How :class:`EstimatingScheduler` holds, tells the plant and searches.

    Parameters
    ----------
    hold_ms : float
        The base is held this long before the plant is told (> 0, at most 50 ms).
    interval_ms : float
        VFServo-v0's control interval (0.1 to 20 ms).
    evals : int
        CMA-ES episodes per design plant's continuation (≥ 1).
    sigma : float
        CMA-ES's initial step, in action units (0, 1].
    neighbours : int
        A continuation must also be feasible on this many nearest design plants (≥ 0).
    probes : int
        ... and on this many plants on the way to each, evenly up to halfway (≥ 0).
    seed : int
        CMA-ES's seed.
    """

    hold_ms: float = 2.0
    interval_ms: float = 1.0
    evals: int = 150
    sigma: float = 0.3
    neighbours: int = 2
    probes: int = 2
    seed: int = 0

    def __post_init__(self) -> None:
        check_real("hold_ms", self.hold_ms, 0.0, 50.0, lo_open=True)
        check_real("interval_ms", self.interval_ms, 0.1, 20.0)
        check_int("evals", self.evals, 1)
        check_real("sigma", self.sigma, 0.0, 1.0, lo_open=True)
        check_int("neighbours", self.neighbours, 0)
        check_int("probes", self.probes, 0)
        check_int("seed", self.seed, 0)


@dataclass(frozen=True)
class Continuation:
    """What the scheduler does once it has told a design plant."""

    plant: PlantVariant
    signature: np.ndarray
    """The dynamic observations over the hold on this plant, flattened."""
    action: np.ndarray
    """The residual action ramped to (zero: the base held)."""
    ramp: int
    """Intervals of the ramp."""
    cost: float
    """Its cost on this plant (the search's)."""


@dataclass(frozen=True)
class MoveTable:
    """One move's base and its continuations, one per design plant."""

    base: Settings
    hold: int
    """Intervals the base is held."""
    continuations: tuple[Continuation, ...]

    def told(self, signature: np.ndarray) -> Continuation:
        """The continuation whose plant's signature is nearest to ``signature``."""
        d = [float(np.sum((c.signature - signature) ** 2)) for c in self.continuations]
        return self.continuations[int(np.argmin(d))]


class EstimatingScheduler(Scheduler):
    """Hold the robust base, tell the plant from the response, ramp to its continuation
    (module doc); a :class:`vfgym.scoring.Scheduler` for :func:`vfgym.evaluate`.

    Parameters
    ----------
    axis : Axis
        An axis stating its uncertainty (its design plants are the ones told apart).
    model : PickModel or SettingsModel
        The axis's settings model (``vfgym fit``'s): each move's robust base.
    options : AdaptiveOptions
        Hold, interval and search.

    Raises
    ------
    ValueError
        If the axis states no uncertainty.
    """

    def __init__(self, axis: Axis, model: Any, options: AdaptiveOptions | None = None) -> None:
        if axis.uncertainty.exact:
            raise ValueError(f"axis={axis.name!r} states no uncertainty: nothing to tell apart")
        self.axis, self.model = axis, model
        self.options = options or AdaptiveOptions()
        self.design = tuple(axis.design_plants())
        self._tables: dict[str, tuple[VFServoEnv, MoveTable]] = {}

    def table(self, scenario: Scenario) -> MoveTable:
        """The move's base and continuations (computed once per move).

        Parameters
        ----------
        scenario : Scenario
            The move.

        Returns
        -------
        MoveTable
            The move's table.
        """
        return self._table(scenario)[1]

    def run_move(self, scenario: Scenario, plant: PlantVariant) -> dict[str, Any]:
        """The measures of the move scheduled on the true plant ``plant``
        (:class:`vfgym.scoring.Scheduler`)."""
        env, table = self._table(scenario)
        seen: list[np.ndarray] = []
        env.reset(options={"plant": plant})
        cont: Continuation | None = None
        t = 0
        while True:
            act = np.zeros(4) if cont is None else _ramp(cont.action, cont.ramp, table.hold, t)
            obs, _, term, trunc, info = env.step(act)
            t += 1
            if term or trunc:
                return {k: info[k] for k in METRIC_NAMES}
            if cont is None:
                seen.append(obs[:N_SIGNATURE])
                if t == table.hold:
                    cont = table.told(np.concatenate(seen))

    def _table(self, scenario: Scenario) -> tuple[VFServoEnv, MoveTable]:
        if scenario.name not in self._tables:
            ax, o = self.axis, self.options
            base = self.model.settings(scenario, ax.plant, ax.measures, self.design)
            env = VFServoEnv(scenario, axis=ax, residual=True, residual_base=base,
                             residual_scale=SCALE, interval_s=o.interval_ms * 1e-3)  # fmt: skip
            hold = max(1, math.ceil(o.hold_ms / o.interval_ms - 1e-9))
            sigs = [_signature(env, p, hold) for p in self.design]
            conts = []
            for i, p in enumerate(self.design):  # checked where a plant told as p lies
                near = check_plants(self.design, i, o.neighbours, o.probes)
                action, ramp, cost = _search(env, hold, p, near, o)
                conts.append(Continuation(p, sigs[i], action, ramp, cost))
            self._tables[scenario.name] = (env, MoveTable(base, hold, tuple(conts)))
        return self._tables[scenario.name]


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


def _search(
    env: VFServoEnv, hold: int, plant: PlantVariant, near: list[PlantVariant], o: AdaptiveOptions
) -> tuple[np.ndarray, int, float]:
    """The continuation for ``plant``: (action, ramp intervals, cost on ``plant``); the best
    of CMA-ES's, feasible on ``plant`` and ``near``, else the base held."""
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
    done = 0
    while done < o.evals:
        told = []
        for _ in range(opt.population_size):
            x = opt.ask()
            r = run(x)
            told.append((x, -r[1] + (0.0 if r[0] else INFEASIBLE)))
            done += 1
            if r[0] and (not best[0] or r[1] > best[1]):
                best = r
        opt.tell(told)
    return best[2], best[3], -best[1]


__all__ = ["AdaptiveOptions", "Continuation", "EstimatingScheduler", "MoveTable"]
