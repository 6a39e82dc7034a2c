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

**Outside the design** (``AdaptiveOptions.fallback``): a plant outside the stated ranges
would still be told as its nearest design plant, and its continuation run where nothing
checked it. Two checks, both in the move's table:

* *the response fits no design plant*: its distance to the nearest design plant's
  signature exceeds that plant's *threshold*, ``margin`` times the farthest an in-range
  plant told as it lies (the ranges sampled on a grid, and the check plants on the way to
  its neighbours: the design's spacing as the encoder's quantisation renders it); the
  scheduler then holds the base for the rest of the move;
* *shadow plants*: the response does not tell every quantity (over a 2 ms hold a drive
  gain ×0.95 looks as the nominal plant: the torque the drive commands is its gain as
  set, times its error), so each continuation is also run on the *shadow* plants told as
  its plant (whose responses fit it): the design plants with one quantity (inertia, drive
  gain, load torque) ``shadow``, a half, a quarter and an eighth of it outside its range
  (a share of the edge for a factor, of the motor's rated torque for the load torque),
  and, between two neighbours of that line (the edge first) where the base holds on one
  and breaks a limit on the other, the plants where it holds found by bisecting towards
  its boundary (a continuation tends to break a limit first where the base only just
  keeps it; feasibility is not monotone in the plant, so the shadows alone leave gaps;
  :mod:`vfgym.permove._shadows`); and on the in-range plants the thresholds are
  calibrated on that are told as its plant (with several uncertain quantities a
  neighbour's check leaves much of the range between design plants unchecked). Where it
  breaks a limit on one that the base holds (with ``count_margin``, or ends the move there
  less than one encoder count inside the overshoot or in-position limit where the base
  ends farther inside: where the motor comes to rest is quantised to a count, and under a
  load torque the base and a continuation rest a count apart, so a plant the checks
  cannot tell from a checked one may put the continuation's a count beyond the window's
  edge, the base's not),
  the cheapest that breaks none there of the search's other candidates, of gentler
  versions of its own (scaled towards the base, checked on its plants as the search
  checks) and of a second search on its plants and those checked plants (none dearer
  than the base on its plant) replaces it; if none does, told that
  plant, the scheduler holds the base for the rest of the move. Where every checked
  plant that breaks the cheapest lies farther from its plant's signature than every
  in-range plant told as it, a response nearer than halfway between the two still runs
  the cheapest (:attr:`Continuation.trusted`): the replacement or the held base is for
  the responses the breaking plants give, not for the plants in range.

Each move's outcome is recorded in :attr:`EstimatingScheduler.runs`
(:meth:`EstimatingScheduler.fallbacks` counts them). In range the first check fires only
beyond the calibration plants' spread, and the second changes a continuation only where
a shadow plant or an in-range calibration plant told as its plant breaks it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from vfgym._validate import check_int, check_real
from vfgym.axis import Axis, PlantVariant
from vfgym.envs import CALIBRATION_PLANTS, N_SIGNATURE, calibration_plants, check_plants
from vfgym.envs.servo import VFServoEnv
from vfgym.moves.scenarios import Scenario
from vfgym.params import Settings
from vfgym.permove._episodes import _end, _episode, _Found, _keeps, _ramp, _search, _signature
from vfgym.permove._shadows import (
    BISECTIONS,
    SHADOW_LEVELS,
    SHADOWED,
    boundary_plants,
    shadow_lines,
    shadow_plants,
)
from vfgym.plant.measures import NAMES as METRIC_NAMES
from vfgym.scoring import Scheduler

SCALE = (1.0, 0.0, 1.0, 1.0)
"""Residual scales (value, L/value, k, Ts/Tf): ±1 moves a coordinate half its range; L/value
held at the base's."""
RUNNERS_UP = 24
"""Searched candidates (the cheapest feasible first) tried in turn where a shadow plant
breaks a continuation."""
GENTLER = (0.75, 0.5, 0.25)
"""... then the search's cheapest scaled by these (checked on its plants as the search
checks), the cheapest of all that no shadow plant breaks taken."""


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
    fallback : bool
        Hold the base for the rest of the move when the response fits no design plant or
        the told plant's continuation breaks a limit on a shadow plant, and run the
        cheapest searched continuation no shadow plant breaks (module doc); ``False``:
        the search's cheapest, always (the scheduler as it was without them).
    margin : float
        A response fits a design plant within this many times the farthest an in-range
        plant told as it lies (≥ 1).
    shadow : float
        Shadow plants lie up to this far outside each range's edge (and a half, a quarter
        and an eighth of it): a share of the edge for a factor (inertia, drive gain), of the
        motor's rated torque for the load torque (0, 0.5].
    count_margin : bool
        Also replace a continuation that ends the move less than one encoder count inside
        the overshoot or in-position limit on a checked plant where the base ends farther
        inside (module doc). Off by default: it closes breaks at the base's own boundary
        that the checks miss, at a cost in range (docs/results/agents.md, "A count inside
        the window").
    """

    hold_ms: float = 2.0
    interval_ms: float = 1.0
    evals: int = 150
    sigma: float = 0.3
    neighbours: int = 2
    probes: int = 2
    seed: int = 0
    fallback: bool = True
    margin: float = 1.25
    shadow: float = 0.1
    count_margin: bool = False

    def __post_init__(self) -> None:
        check_real("hold_ms", self.hold_ms, 0.0, 50.0, lo_open=True)
        check_real("interval_ms", self.interval_ms, 0.1, 20.0)
        check_int("evals", self.evals, 1)
        check_real("sigma", self.sigma, 0.0, 1.0, lo_open=True)
        check_int("neighbours", self.neighbours, 0)
        check_int("probes", self.probes, 0)
        check_int("seed", self.seed, 0)
        for name in ("fallback", "count_margin"):
            if not isinstance(getattr(self, name), bool):
                raise ValueError(f"{name}={getattr(self, name)!r} must be true or false")
        check_real("margin", self.margin, 1.0, math.inf)
        check_real("shadow", self.shadow, 0.0, 0.5, lo_open=True)


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
    threshold: float = math.inf
    """A response farther than this from :attr:`signature` fits no design plant."""
    shadows: tuple[PlantVariant, ...] = ()
    """Shadow plants told as this one where :attr:`action` breaks a limit the base holds,
    as every searched candidate did (any: the base is held instead)."""
    searched_action: np.ndarray | None = None
    """Where the search's cheapest broke a limit on a shadow plant told as this one that the
    base holds, and :attr:`action` is the cheapest searched candidate that breaks none
    there (and is no dearer than the base on this plant): the search's cheapest (run with
    the fallback off); else ``None``."""
    searched_ramp: int = 1
    """... and its ramp."""
    trusted: float = 0.0
    """Where :attr:`action` replaces the search's cheapest or the base is held: a response
    within this of :attr:`signature` still runs the cheapest, since every checked plant
    told as this one that breaks it lies farther (halfway from the farthest in-range plant
    told as this one to the nearest that breaks it, within :attr:`threshold`; 0: none
    lies so near)."""

    @property
    def safer(self) -> bool:
        """Whether :attr:`action` replaces the search's cheapest (:attr:`searched_action`)."""
        return self.searched_action is not None

    @property
    def cheapest(self) -> tuple[np.ndarray, int]:
        """The search's cheapest: its action and ramp."""
        if self.searched_action is not None:
            return self.searched_action, self.searched_ramp
        return self.action, self.ramp


@dataclass(frozen=True)
class Told:
    """What a hold's response tells: the nearest design plant's continuation, how far the
    response is from its signature, and whether that is within its threshold."""

    continuation: Continuation
    residual: float
    fits: bool


@dataclass(frozen=True)
class ScheduledRun:
    """One move the scheduler ran (:attr:`EstimatingScheduler.runs`).

    Attributes
    ----------
    scenario : str
        The move's name.
    plant : PlantVariant
        The true plant it ran on (recorded for evaluation; the scheduler never reads it).
    told : PlantVariant
        The design plant the response was nearest to.
    residual : float
        The response's distance from that plant's signature.
    held : str
        ``""`` if it ran the told plant's continuation; else why it held the base to the
        end: ``"response"`` (the response fits no design plant) or ``"shadow"`` (the
        continuation breaks a limit on a shadow plant told as this one).
    """

    scenario: str
    plant: PlantVariant
    told: PlantVariant
    residual: float
    held: str


@dataclass(frozen=True)
class Fallbacks:
    """How often the scheduler held its base to the end (:meth:`EstimatingScheduler.fallbacks`).

    Attributes
    ----------
    runs : int
        Moves run.
    response : int
        ... held because the response fit no design plant.
    shadow : int
        ... held because the told plant's continuation breaks a limit on a shadow plant.
    """

    runs: int
    response: int
    shadow: int

    @property
    def held(self) -> int:
        """Moves on which the base was held to the end."""
        return self.response + self.shadow


@dataclass(frozen=True)
class MoveTable:
    """One move's base and its continuations, one per design plant."""

    base: Settings
    hold: int
    """Intervals the base is held."""
    continuations: tuple[Continuation, ...]

    def told(self, signature: np.ndarray) -> Continuation:
        """The continuation whose plant's signature is nearest to ``signature``."""
        return self.tell(signature).continuation

    def tell(self, signature: np.ndarray) -> Told:
        """The continuation whose plant's signature is nearest to ``signature``, the
        distance and whether it is within that plant's threshold.

        Parameters
        ----------
        signature : numpy.ndarray
            A hold's response, flattened.

        Returns
        -------
        Told
            The nearest, its residual and fit.
        """
        d = [float(np.sum((c.signature - signature) ** 2)) for c in self.continuations]
        i = int(np.argmin(d))
        r = math.sqrt(d[i])
        return Told(self.continuations[i], r, r <= self.continuations[i].threshold)


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
        self.runs: list[ScheduledRun] = []
        """Every move run, in order (:class:`ScheduledRun`)."""

    def fallbacks(self) -> Fallbacks:
        """How often it held its base to the end, over :attr:`runs`.

        Returns
        -------
        Fallbacks
            The counts.
        """
        held = [r.held for r in self.runs]
        return Fallbacks(len(held), held.count("response"), held.count("shadow"))

    def without_fallback(self) -> EstimatingScheduler:
        """The same scheduler (its tables shared, computed once) with the fallback off:
        what it would run without it, for comparison.

        Returns
        -------
        EstimatingScheduler
            A scheduler of the same options but ``fallback=False``, with its own
            :attr:`runs`.
        """
        other = EstimatingScheduler.__new__(EstimatingScheduler)
        other.axis, other.model, other.design = self.axis, self.model, self.design
        other.options = replace(self.options, fallback=False)
        other._tables, other.runs = self._tables, []
        return other

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
        action, ramp, told = np.zeros(4), 1, None
        t = 0
        while True:
            obs, _, term, trunc, info = env.step(_ramp(action, ramp, table.hold, t))
            t += 1
            if told is None and not (term or trunc):
                seen.append(obs[:N_SIGNATURE])
            if told is None and (t == table.hold or term or trunc):
                told = table.tell(np.concatenate(seen) if seen else np.zeros(0))
                held = _held(told, self.options.fallback) if t == table.hold else ""
                c = told.continuation
                if not self.options.fallback or told.residual < c.trusted:
                    held, (action, ramp) = "", c.cheapest
                elif not held:
                    action, ramp = c.action, c.ramp
                self.runs.append(ScheduledRun(scenario.name, plant, c.plant, told.residual,
                                              held))  # fmt: skip
            if term or trunc:
                return {k: info[k] for k in METRIC_NAMES}

    def _table(self, scenario: Scenario) -> tuple[VFServoEnv, MoveTable]:
        if scenario.name not in self._tables:
            ax, o = self.axis, self.options
            base = self.model.settings(scenario, ax.plant, ax.measures, self.design)
            env = VFServoEnv(scenario, axis=ax, residual=True, residual_base=base,
                             residual_scale=SCALE, interval_s=o.interval_ms * 1e-3)  # fmt: skip
            hold = max(1, math.ceil(o.hold_ms / o.interval_ms - 1e-9))
            sigs = [_signature(env, p, hold) for p in self.design]
            conts, cands = [], []
            for i, p in enumerate(self.design):  # checked where a plant told as p lies
                near = check_plants(self.design, i, o.neighbours, o.probes)
                found = _search(env, hold, p, near, o)
                conts.append(Continuation(p, sigs[i], *found[0]))
                cands.append(found)
            table = _outside(env, MoveTable(base, hold, tuple(conts)), cands, ax, o)
            self._tables[scenario.name] = (env, table)
        return self._tables[scenario.name]


def _held(told: Told, fallback: bool) -> str:
    """Why the base is held to the end after ``told`` (``""``: it is not)."""
    if not fallback:
        return ""
    if not told.fits:
        return "response"
    return "shadow" if told.continuation.shadows else ""


def _outside(
    env: VFServoEnv, table: MoveTable, cands: list[list[_Found]], axis: Axis, o: AdaptiveOptions
) -> MoveTable:
    """``table`` with each continuation's threshold, and where a shadow plant told as its
    plant breaks it, the cheapest of the search's ``cands``, of the gentler versions of
    its cheapest (:data:`GENTLER`) and of a second search on those plants too that breaks
    none and is no dearer than the base on its plant, else the shadows that break it
    (module doc)."""
    conts, hold = table.continuations, table.hold
    design = tuple(c.plant for c in conts)
    far = np.zeros(len(conts))  # the farthest an in-range plant told as each lies
    calib = calibration_plants(design, CALIBRATION_PLANTS)
    calib += [q for i in range(len(design)) for q in check_plants(design, i, o.neighbours,
                                                                   o.probes)]  # fmt: skip
    sigs = {q: _signature(env, q, hold) for q in calib}
    for q in calib:
        told = table.tell(sigs[q])
        i = conts.index(told.continuation)
        far[i] = max(far[i], told.residual)
    conts = tuple(replace(c, threshold=o.margin * far[i]) for i, c in enumerate(conts))
    table = replace(table, continuations=conts)
    base: dict[PlantVariant, np.ndarray] = {}  # the base's end on each plant, run once
    count = 0.0  # with count_margin, one encoder count in the end constraints' units
    if o.count_margin:
        count = 1.0 / axis.measures.in_position_counts if axis.measures.in_position_counts else 1.0

    def end(q: PlantVariant) -> np.ndarray:
        if q not in base:
            base[q] = _end(_episode(env, q, lambda t: np.zeros(4))[0])
        return base[q]

    def holds(q: PlantVariant) -> bool:
        return bool(np.all(np.isfinite(end(q))))

    def keeps(q: PlantVariant, a: np.ndarray, r: int) -> bool:
        return _keeps(env, q, a, r, hold, end(q), count)

    lines = shadow_lines(design, axis.plant.motor.rated_torque_nm, o.shadow)
    bounds = {line: boundary_plants(line, holds, BISECTIONS) for line in lines}
    # the in-range plants the thresholds were calibrated on, then the shadows: a
    # continuation is checked on every plant told as its own
    checked = dict.fromkeys([*calib, *(q for line in lines for q in (*line[1:], *bounds[line]))])
    mine: list[list[PlantVariant]] = [[] for _ in conts]  # told as each, the base holding
    residual: dict[PlantVariant, float] = {}
    for q in checked:
        told = table.tell(sigs[q] if q in sigs else _signature(env, q, hold))
        i = conts.index(told.continuation)
        if told.fits and np.any(conts[i].action != 0.0) and holds(q):
            mine[i].append(q)
            residual[q] = told.residual
    out = []
    for i, (c, qs, found, r_in) in enumerate(zip(conts, mine, cands, far, strict=True)):
        breaks = {q: not keeps(q, c.action, c.ramp) for q in qs}
        broken = [q for q in qs if breaks[q]]
        if not broken:
            out.append(c)
            continue
        lines_c = [(line, bounds[line]) for line in lines if set(qs) & {*line, *bounds[line]}]
        r_out = _nearest_break(env, table, c, breaks, lines_c, holds, keeps, residual)
        if r_out > r_in:  # every plant that breaks it lies beyond the in-range ones
            c = replace(c, trusted=min(c.threshold, 0.5 * (r_in + r_out)))
        near = check_plants(design, i, o.neighbours, o.probes)
        # never dearer than the base on its plant (held, it costs the base's)
        base_cost = float(_episode(env, c.plant, lambda t: np.zeros(4))[0]["cost"])
        pool = [(f, qs) for f in found[1 : 1 + RUNNERS_UP] if f[2] <= base_cost]
        for k in GENTLER:  # the cheapest, scaled down: its cost on its plant, if it holds there
            a, r = c.action * k, c.ramp
            info, _ = _episode(env, c.plant, lambda t, a=a, r=r: _ramp(a, r, hold, t))
            if info["feasible"] and float(info["cost"]) <= base_cost:
                pool.append(((a, r, float(info["cost"])), [*qs, *near]))
        # searched again, feasible also where it broke and on the other plants checked
        rest = [q for q in qs if q not in broken]
        again = _search(env, hold, c.plant, [*broken, *near, *rest], o)[0]
        if again[2] <= base_cost:  # feasible on qs by its search; their ends checked apart
            pool.append((again, qs if count else []))
        for (a, r, cost), check in sorted(pool, key=lambda x: x[0][2]):
            if np.any(a != 0.0) and all(keeps(q, a, r) for q in check):
                out.append(replace(c, action=a, ramp=r, cost=cost, searched_action=c.action,
                                   searched_ramp=c.ramp))  # fmt: skip
                break
        else:
            out.append(replace(c, shadows=tuple(broken)))
    return replace(table, continuations=tuple(out))


def _nearest_break(
    env: VFServoEnv,
    table: MoveTable,
    c: Continuation,
    known: dict[PlantVariant, bool],
    lines: list[tuple[tuple[PlantVariant, ...], list[PlantVariant]]],
    holds: Any,
    keeps: Any,
    residual: dict[PlantVariant, float],
) -> float:
    """The least residual, from ``c``'s signature, of a plant told as ``c`` where the base
    holds and ``c``'s action breaks a limit: of the plants of ``known`` it breaks (plant →
    whether it breaks, run already) and of the plants found by bisecting, on each of
    ``lines`` (a shadow line with the base's boundary plants on it), where the action's own
    feasibility changes (a break lies nearer than the first checked plant that shows it)."""
    cache = dict(known)

    def breaks(q: PlantVariant) -> bool:
        if q not in cache:
            cache[q] = not keeps(q, c.action, c.ramp)
        return cache[q]

    r = min(residual[q] for q, b in known.items() if b)
    for line, bound in lines:
        k = next(f for f in SHADOWED if getattr(line[0], f) != getattr(line[-1], f))
        pts = tuple(sorted({*line, *bound}, key=lambda q: abs(getattr(q, k) - getattr(line[0], k))))
        for m in boundary_plants(pts, breaks, BISECTIONS):
            told = table.tell(_signature(env, m, table.hold))
            if told.continuation is c and told.fits and holds(m):
                r = min(r, told.residual)
    return r


__all__ = [
    "BISECTIONS",
    "SHADOWED",
    "SHADOW_LEVELS",
    "AdaptiveOptions",
    "Continuation",
    "EstimatingScheduler",
    "Fallbacks",
    "MoveTable",
    "ScheduledRun",
    "Told",
    "calibration_plants",
    "shadow_plants",
]
