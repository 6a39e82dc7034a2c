"""VFServo-v0's one-decision mode (``decision="once"``): the base held for a hold period,
then one residual correction, ramped to and held for the rest of the move.

The gain an adaptive controller can take on an axis known within ranges needs one
correction chosen after a few milliseconds and held to the end (an option in the sense of
Sutton, Precup and Singh 1999: the temporally extended action is the choice that pays).
So the episode is one step:

* at reset the move's base (the residual base) runs for ``hold_s`` on the episode's true
  plant, interval by interval, as the per-interval mode would run the zero action; the
  observation is what the drive measured over the hold (each interval's dynamic features,
  :data:`N_SIGNATURE` of them), the base as an action and the move's features; with
  ``tell=True`` also what that response tells of the plant, as the scheduler tells it:
  its difference from the modelled plant's response over the same hold (simulated by the
  controller, which knows its command and its model), and the quantities of the design
  plant whose response is nearest and of a blend of the three nearest;
* the action is a residual correction in :class:`vfgym.space.Relative`'s coordinates
  (4 entries) reached by a linear ramp and held to the move's end; its fifth entry is the
  ramp's length, from one control interval (-1) to the rest of the move (+1)
  (:func:`ramp_of`; the scheduler's searched ramps on loads-uncertain ran from 6 to 122
  intervals of 1 ms, 6 % to 100 % of the move);
* the reward is the share of the base's cost on the same (move, true plant) saved,
  times :data:`REWARD_SCALE`, so the spread of the cost between moves is not the agent's
  to explain; the episode ends ``terminated`` (a decision, not a time-out: nothing is
  bootstrapped after it).

**The shield** (``shield=True``, Alshiekh et al. 2018's idea as the scheduler's search uses
it): the design plant whose hold response is nearest to the one seen is *told* (on an
exactly known axis, its one plant); the
candidate runs on it, on its nearest design plants (each quantity over its range) and on
plants on the way to them, up to halfway (:func:`check_plants`), and where it breaks a limit
the base holds on one of them the base is run instead; and on the in-range plants of a grid
over the ranges (:func:`calibration_plants`) whose hold responses are told as the same
design plant (with three uncertain quantities the neighbours' checks leave much of a
design plant's cell unchecked); and on the told plant with its quantities at their ranges'
ends (:func:`alike_plants`) where their hold responses are told as it (a 2 ms hold shows
the inertia, hardly the drive's gain or a load torque). With ``shield_gentler`` a
correction that breaks is tried halved, quartered ... on the same plants before the base.
The true plant is never read.

Every continuation of a step (the candidate and the base on the true plant and on each
checked plant) starts from its plant's state at the end of the hold and runs in the
single-move kernel (:func:`continue_move`); the SIMD lanes of the vector env, tried here,
were no faster on a whole move (16 continuations of a 21 000-tick move: 20 ms in lanes,
16 ms one by one).
"""

from __future__ import annotations

import itertools
import math
from collections import OrderedDict
from dataclasses import fields, replace
from typing import Any

import numpy as np

from vfgym.axis import NOMINAL, PlantVariant
from vfgym.plant import _jit as J
from vfgym.plant import _kernel as K
from vfgym.plant import _layout as L
from vfgym.plant.measures import from_acc
from vfgym.scoring import score

from . import _batch as B
from ._common import Episode, scored_info

N_SIGNATURE = 14
"""The dynamic features of an interval a decision sees (error … progress: what the drive
measures, :data:`vfgym.envs._batch.OBS_DYNAMIC` before the settings in force)."""
REWARD_SCALE = 10.0
"""The reward is this times the share of the base's cost saved: a 10 % saving is 1."""
SHIELD_NEIGHBOURS = 2
"""The shield also checks this many design plants nearest the told one (as the
scheduler's search, :class:`vfgym.permove.adaptive.AdaptiveOptions`)."""
SHIELD_PROBES = 2
"""... and this many plants on the way to each, evenly up to halfway."""
CALIBRATION_PLANTS = 81
"""In-range plants on a grid over the design's ranges (:func:`calibration_plants`: at most
this many, 9 levels a quantity for two uncertain quantities, 81 for one, 4 for three ...),
where the scheduler's thresholds are calibrated and, told as a design plant, a correction
for it is checked (the shield, and the scheduler's table)."""
CACHE_MOVES = 1024
"""Moves whose checked plants' hold states are remembered (a training pool's)."""

_jit = J.jit


# --- the plants a decision is checked on ------------------------------------------------


def plant_spans(plants: tuple[PlantVariant, ...]) -> dict[str, float]:
    """Each quantity's range over ``plants`` (only the ones that vary).

    Parameters
    ----------
    plants : tuple of PlantVariant
        An axis's design plants.

    Returns
    -------
    dict
        Field name → its range (> 0).
    """
    out = {}
    for f in fields(PlantVariant):
        x = [getattr(p, f.name) for p in plants]
        if max(x) > min(x):
            out[f.name] = max(x) - min(x)
    return out


def plant_distance(a: PlantVariant, b: PlantVariant, span: dict[str, float]) -> float:
    """Euclidean distance between two plants, each quantity over its range.

    Parameters
    ----------
    a, b : PlantVariant
        The plants.
    span : dict
        :func:`plant_spans` of the design.

    Returns
    -------
    float
        The distance.
    """
    return math.sqrt(sum(((getattr(a, k) - getattr(b, k)) / w) ** 2 for k, w in span.items()))


def plant_between(a: PlantVariant, b: PlantVariant, share: float) -> PlantVariant:
    """The plant a ``share`` of the way from ``a`` to ``b`` (each quantity).

    Parameters
    ----------
    a, b : PlantVariant
        The ends.
    share : float
        0 gives ``a``, 1 gives ``b``.

    Returns
    -------
    PlantVariant
        The plant between.
    """
    x = {f.name: (getattr(a, f.name), getattr(b, f.name)) for f in fields(PlantVariant)}
    return PlantVariant(**{k: u + share * (v - u) for k, (u, v) in x.items()})


def check_plants(
    design: tuple[PlantVariant, ...], i: int, neighbours: int, probes: int
) -> list[PlantVariant]:
    """The plants a decision for design plant ``i`` is checked on: its ``neighbours``
    nearest design plants (each quantity over its range; the hold responses are not
    monotone in the plant, encoder counts) and ``probes`` plants on the way to each,
    evenly up to halfway, where a true plant told as plant ``i`` lies (feasibility is not
    monotone in the plant, so points between are checked, not the ends only).

    Parameters
    ----------
    design : tuple of PlantVariant
        The axis's design plants.
    i : int
        The told plant's index.
    neighbours, probes : int
        How many of each, ≥ 0.

    Returns
    -------
    list of PlantVariant
        The neighbours then the probes (plant ``i`` itself not among them).
    """
    span = plant_spans(design)
    d = [plant_distance(design[i], q, span) for q in design]
    near = [design[j] for j in np.argsort(d, kind="stable")[1 : 1 + neighbours]]
    return near + [
        plant_between(design[i], q, j / (2 * probes)) for q in near for j in range(1, probes + 1)
    ]


def calibration_plants(design: tuple[PlantVariant, ...], count: int) -> list[PlantVariant]:
    """In-range plants on a grid over the design's ranges (at most ``count``, at least 2
    levels a quantity): where the scheduler's fit thresholds are measured, and, each told
    as its nearest design plant, where a correction for that plant is checked.

    Parameters
    ----------
    design : tuple of PlantVariant
        The axis's design plants (their corners span the ranges).
    count : int
        The most plants.

    Returns
    -------
    list of PlantVariant
        The grid's plants.
    """
    span = plant_spans(design)
    lo = {k: min(getattr(p, k) for p in design) for k in span}
    levels = max(2, math.floor(count ** (1.0 / max(1, len(span))) + 1e-9))
    out = []
    for idx in np.ndindex(*(levels,) * len(span)):
        x = {k: lo[k] + w * j / (levels - 1) for (k, w), j in zip(span.items(), idx, strict=True)}
        out.append(replace(design[0], **x))
    return out


def alike_plants(design: tuple[PlantVariant, ...], i: int) -> list[PlantVariant]:
    """Design plant ``i`` with each uncertain quantity at its range's low end, its own
    value or the high end, every combination but itself (3^d - 1 plants for d
    quantities): where a true plant that responds as plant ``i`` over the hold may lie.

    Parameters
    ----------
    design : tuple of PlantVariant
        The axis's design plants (their corners span the ranges).
    i : int
        The plant's index.

    Returns
    -------
    list of PlantVariant
        The plants, without duplicates.
    """
    span = plant_spans(design)
    p = design[i]
    levels = {k: (min(getattr(q, k) for q in design), getattr(p, k),
                  max(getattr(q, k) for q in design)) for k in span}  # fmt: skip
    out = []
    for idx in itertools.product(range(3), repeat=len(span)):
        q = replace(p, **{k: levels[k][j] for k, j in zip(span, idx, strict=True)})
        if q != p:
            out.append(q)
    return list(dict.fromkeys(out))


def ramp_of(x: float, longest: int) -> int:
    """The ramp's length in control intervals for an action's fifth entry ``x`` in
    [-1, 1]: 1 (a jump) at -1 to ``longest`` at +1, rounded.

    Parameters
    ----------
    x : float
        The entry.
    longest : int
        The longest ramp: the control intervals of the move after the hold.

    Returns
    -------
    int
        Intervals, ≥ 1.
    """
    share = (min(max(float(x), -1.0), 1.0) + 1.0) / 2.0
    return 1 + round(share * (longest - 1))


# --- a continuation ----------------------------------------------------------------------


@_jit
def continue_move(act, w, ring, cmd, ramp: int) -> None:
    """Run a move from its workspace row's state to its end: the residual action ``act``
    reached by a linear ramp over ``ramp`` control intervals (interval j from now at
    (j+1)/ramp of it, as :class:`vfgym.permove.adaptive.EstimatingScheduler` ramps) and
    held; then the move's accumulators into ``w[W_ACC:]``. As the per-interval episode of
    that schedule: one that ends during the ramp (the motor settled) holds the settings
    then in force to the move's end. The action must be good
    (:func:`vfgym.envs._batch.action_ok`)."""
    a = np.zeros(4)
    for j in range(ramp):
        for k in range(4):
            a[k] = act[k] * ((j + 1) / ramp)
        if B.env_step(a, w, ring, cmd) != 0:  # ended: the rest run, its accumulators kept
            return
    B.run_out(w, ring, cmd)


J.guard_cache(continue_move, (B, K, L))


# --- one env's decisions ---------------------------------------------------------------


class _Plants(dict):
    """One move's checked plants' hold states (plant → :class:`_Held`), and, once worked
    out, the calibration plants told as each design plant and the plants alike each."""

    told_as: list[list[PlantVariant]] | None = None
    alike: dict[int, list[PlantVariant]] | None = None


class _Held:
    """One plant's state at the end of the hold on one move: workspace row, ring, the
    episode (for scoring) and the hold's response, with the base's outcome from there once
    known."""

    __slots__ = ("base", "ep", "ring", "signature", "w")

    def __init__(self, ep: Episode, w: np.ndarray, ring: np.ndarray, sig: np.ndarray) -> None:
        self.ep, self.w, self.ring, self.signature = ep, w, ring, sig
        self.base: tuple[float, bool] | None = None


class DecisionCore:
    """The one-decision mode of one env (module doc): the hold at reset, the decision at
    the step, the shield's checks. Shares its per-move caches with the other sub-envs of a
    vector env through ``cache``.

    Parameters
    ----------
    core : ServoCore
        The env's configuration and its per-interval machinery.
    cache : dict or None
        Per-move hold states of the checked plants (shared by a vector env's sub-envs).
    """

    def __init__(self, core: Any, cache: OrderedDict | None = None) -> None:
        c = core.config
        self.core, self.config = core, c
        self.hold = c.hold_intervals
        self.ramp = 1
        self.design: tuple[PlantVariant, ...] = ()
        self.checks: list[list[PlantVariant]] = []
        self.shield, self.tell = c.shield, c.tell
        if c.shield or c.tell:  # an exact axis: its plant, which the controller knows
            exact = c.axis.uncertainty.exact
            self.design = (NOMINAL,) if exact else tuple(c.axis.design_plants())
            self.checks = [
                check_plants(self.design, i, SHIELD_NEIGHBOURS, SHIELD_PROBES)
                for i in range(len(self.design))
            ]
        # the in-range plants a correction is also checked on, each where told as its own
        self.calib: list[PlantVariant] = []
        if c.shield and len(self.design) > 1:
            self.calib = calibration_plants(self.design, CALIBRATION_PLANTS)
        self.spans = plant_spans(self.design) if len(self.design) > 1 else {}
        self.cache: OrderedDict = OrderedDict() if cache is None else cache
        self._obs32 = np.zeros(core.n_obs, dtype=np.float32)
        self.ep: Episode | None = None
        self._w = np.zeros(core.width)
        self._ring = np.zeros(core.ring_len)
        self.ended_in_hold: tuple[float, dict[str, Any]] | None = None
        self.signature = np.zeros(0)

    def episode(self) -> Episode:
        """The episode of the last reset."""
        if self.ep is None:
            raise RuntimeError("DecisionCore: reset() before the decision")
        return self.ep

    # -- the hold ----------------------------------------------------------------------
    def _hold(self, ep: Episode) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
        """The base held for the hold on ``ep``: (workspace, ring, each interval's
        dynamic features, the flags of the last interval)."""
        core = self.core
        w = np.zeros(core.width)
        ring = np.zeros(core.ring_len)
        cmd = ep.command
        core.start(w, ring, cmd, ep)
        rows = np.zeros((self.hold, N_SIGNATURE))
        zero = np.zeros(4)
        flags = 0
        for h in range(self.hold):
            _, flags = B.step_one(zero, w, ring, cmd, self._obs32)
            rows[h] = self._obs32[:N_SIGNATURE]
            if flags & B.ENDED:
                rows[h + 1 :] = rows[h]  # a move over before the hold: its last seen
                break
        return w, ring, rows, flags

    def reset(self, ep: Episode) -> np.ndarray:
        """Hold the base on the episode's true plant; the observation."""
        self.ep = ep
        self._w, self._ring, rows, flags = self._hold(ep)
        self.ended_in_hold = None
        if flags & B.ENDED:
            self.ended_in_hold = self.core.finish(self._w, ep, flags)
        self.signature = rows.reshape(-1)
        base = self._w[B.X_SET : B.X_SET + 4]  # the base in force, as an action
        parts = [self.signature, base, ep.features]
        if self.tell:
            parts += self._told()
        return np.concatenate(parts).astype(np.float32)

    def _told(self) -> list[np.ndarray]:
        """What the hold's response tells of the plant (``tell=True``): its difference from
        the modelled plant's response over the same hold, then the quantities of the
        nearest design plant and of a blend of the 3 nearest (weights 1/distance), each
        over its range in [-1, 1]."""
        held = self._move_cache(self.episode())
        nominal = self._held(self.episode(), held, NOMINAL).signature
        d = np.array([np.sqrt(np.sum((held[p].signature - self.signature) ** 2))
                      for p in self.design])  # fmt: skip
        near = np.argsort(d, kind="stable")[:3]
        w = 1.0 / (d[near] + 1e-9 * (1.0 + d.max()))
        lo = {k: min(getattr(p, k) for p in self.design) for k in self.spans}
        q = np.array([[2 * (getattr(self.design[i], k) - lo[k]) / span - 1 for k, span in
                       self.spans.items()] for i in near])  # fmt: skip
        q = q.reshape(len(near), len(self.spans))
        return [self.signature - nominal, q[0], w @ q / w.sum()]

    def longest(self) -> int:
        """The longest ramp: the move's control intervals after the hold (≥ 1)."""
        n, m = int(self._w[B.C_N]), int(self._w[B.C_I])
        return max(1, -(-n // m) - self.hold)

    # -- the shield's plants -----------------------------------------------------------
    def _move_cache(self, ep: Episode) -> _Plants:
        """The move's checked plants' hold states (the design plants' first, whose
        responses tell the plant)."""
        key = ep.scenario
        held = self.cache.get(key)
        if held is None:
            held = _Plants()
            for p in self.design:
                self._held(ep, held, p)
            self.cache[key] = held
            while len(self.cache) > CACHE_MOVES:
                self.cache.popitem(last=False)
        else:
            self.cache.move_to_end(key)
        return held

    def _held(self, ep: Episode, held: _Plants, p: PlantVariant) -> _Held:
        """Plant ``p``'s state at the hold's end on ``ep``'s move, remembered in ``held``."""
        if p not in held:
            src = self.core.source
            other = Episode.make(ep.scenario, src.base, src.measures, p)
            other = replace(other, command=ep.command)  # one command per move, shared
            w, ring, rows, _ = self._hold(other)
            held[p] = _Held(other, w, ring, rows.reshape(-1))
        return held[p]

    def told(self) -> int:
        """The design plant whose hold response is nearest to the one seen."""
        return self._nearest(self._move_cache(self.episode()), self.signature)

    def _nearest(self, held: _Plants, signature: np.ndarray) -> int:
        """The design plant whose hold response is nearest to ``signature``."""
        d = [float(np.sum((held[p].signature - signature) ** 2)) for p in self.design]
        return int(np.argmin(d))

    def _told_as(self, ep: Episode, held: _Plants, i: int) -> list[PlantVariant]:
        """The calibration plants told as design plant ``i`` on ``ep``'s move, beyond the
        plants :func:`check_plants` gives it (worked out once a move)."""
        if held.told_as is None:
            out: list[list[PlantVariant]] = [[] for _ in self.design]
            for q in self.calib:
                j = self._nearest(held, self._held(ep, held, q).signature)
                if q != self.design[j] and q not in self.checks[j]:
                    out[j].append(q)
            held.told_as = out
        return held.told_as[i]

    def _alike(self, ep: Episode, held: _Plants, i: int) -> list[PlantVariant]:
        """Design plant ``i`` with its quantities at their ranges' ends and its own values
        (every combination, :func:`alike_plants`) that are told as it on ``ep``'s move: the
        plants its hold response cannot tell from it (a 2 ms hold shows the inertia, hardly
        the drive's gain or a load torque)."""
        if held.alike is None:
            held.alike = {}
        if i not in held.alike:
            own = [q for q in alike_plants(self.design, i)
                   if self._nearest(held, self._held(ep, held, q).signature) == i]  # fmt: skip
            held.alike[i] = own
        return held.alike[i]

    # -- the decision ------------------------------------------------------------------
    def _outcome(self, w: np.ndarray, ep: Episode) -> tuple[float, bool, Any]:
        """The scored move of a lane's accumulators on its plant: (cost, feasible, score)."""
        c = self.config
        acc = w[B.W_ACC : B.W_ACC + L.N_ACC]
        m = from_acc(acc, ep.plant, c.measures, ep.target_rad, ep.command_end_s)
        s = score(m, ep.scenario, ep.plant, c.measures, c.weights, c.bounds)
        return float(s.cost), bool(np.all(np.asarray(s.constraints) <= 0.0)), s

    def decide(self, action: np.ndarray) -> tuple[float, dict[str, Any]]:
        """Run the decision (the correction, 4 entries, and its ramp, the fifth) on the
        true plant, the shield's checks first: the reward and the scored move's info."""
        ep = self.episode()
        self.ramp = ramp_of(action[4], self.longest())
        action = np.asarray(action[:4], dtype=np.float64)
        if self.ended_in_hold is not None:  # nothing left to decide
            reward, info = self.ended_in_hold
            info.update(base_cost=info["cost"], base_feasible=info["feasible"], shielded=False,
                        ramp=self.ramp, correction=np.zeros(4))  # fmt: skip
            return 0.0, info
        checked: list[_Held] = []
        told = -1
        if self.shield:
            told = self.told()
            held = self._move_cache(ep)
            told_as = self._told_as(ep, held, told)
            alike = self._alike(ep, held, told)
            for p in dict.fromkeys([self.design[told], *self.checks[told], *told_as, *alike]):
                checked.append(self._held(ep, held, p))
        c0, ok0, s0 = self._outcome(self._run([(self._w, self._ring, np.zeros(4))])[0], ep)
        ran = np.zeros(4)
        for i in range(self.config.shield_gentler + 1):  # unshielded: nothing checked breaks
            tried = action * 0.5**i  # the correction, then halved ... toward the base
            if not self._breaks(checked, tried):
                shielded, ran = i > 0, tried
                c, ok, s = self._outcome(self._run([(self._w, self._ring, tried)])[0], ep)
                break
        else:
            shielded = True
            c, ok, s = c0, ok0, s0
        reward = REWARD_SCALE * (c0 - c) / c0
        if ok0 and not ok:
            reward -= self.config.violation_penalty
        info = scored_info(ep, s.metrics, s.cost, s.constraints)
        info.update(base_cost=c0, base_feasible=ok0, shielded=shielded, ramp=self.ramp,
                    correction=ran)  # fmt: skip
        if told >= 0:
            info["told_plant"] = self.design[told]  # for evaluation: the estimate
        return reward, info

    def _breaks(self, checked: list[_Held], action: np.ndarray) -> bool:
        """Whether ``action`` breaks a limit on a checked plant where the base holds it
        (each plant's base run once a move, then remembered; no plant run after the first
        that breaks)."""
        for h in checked:
            if h.base is None:
                cb, okb, _ = self._outcome(self._run([(h.w, h.ring, np.zeros(4))])[0], h.ep)
                h.base = (cb, okb)
            if h.base[1] and not self._outcome(self._run([(h.w, h.ring, action)])[0], h.ep)[1]:
                return True
        return False

    def _run(self, runs: list[tuple[np.ndarray, np.ndarray, np.ndarray]]) -> list[np.ndarray]:
        """Each (workspace, ring, action) run from the hold to the move's end; each one's
        final workspace row (its accumulators)."""
        out = []
        for w, ring, act in runs:
            w, ring = w.copy(), ring.copy()
            continue_move(act, w, ring, self.episode().command, self.ramp)
            out.append(w)
        return out


__all__ = [
    "N_SIGNATURE",
    "REWARD_SCALE",
    "DecisionCore",
    "alike_plants",
    "calibration_plants",
    "check_plants",
    "continue_move",
    "plant_between",
    "plant_distance",
    "plant_spans",
    "ramp_of",
]
