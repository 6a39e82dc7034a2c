"""Every (controller, move, plant) triple in one compiled, multi-threaded call, scored by
:func:`vfgym.scoring.score`: what the envs, the sweeps and the reports all call.

An evaluation is a list of triples: each controller on each scenario of the axis, on the
modelled plant and on each true plant asked for. A fixed controller or a tuner's choice
for the move runs in the batched kernel (:func:`vfgym.scoring.score_pairs`); a
:class:`~vfgym.scoring.Scheduler` runs its own move on the same triples. Every controller
so meets the same moves on the same plants, the axis's.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from os import PathLike
from typing import Any

import numpy as np
from tqdm import tqdm

from vfgym.axis import (
    NOMINAL,
    PAPER_AXIS,
    VERDICT_PLANT_SEED,
    Axis,
    PlantVariant,
    as_axis,
    draw_plants,
)
from vfgym.moves.baselines import (
    Baseline,
    Controller,
    FixedFrequency,
    SCurveSource,
    controller_label,
)
from vfgym.moves.scenarios import Scenario
from vfgym.params import Settings
from vfgym.plant import Trace, simulate
from vfgym.plant.measures import NAMES as METRIC_NAMES
from vfgym.scoring._batch import Move, as_run, score_pairs
from vfgym.scoring._cost import (
    CONSTRAINTS,
    DEFAULT_BOUNDS,
    DEFAULT_WEIGHTS,
    OBJECTIVES,
    Bounds,
    CostWeights,
    Score,
)
from vfgym.scoring._plants import AcrossPlants, robust_constraints
from vfgym.scoring._scheduled import Scheduler, score_scheduled

PROGRESS_CHUNK = 512
"""Pairs per batched kernel call while a progress bar shows (two cores run 512 moves in
a few seconds; fewer calls would leave the bar still, more would cost the batch's
parallelism)."""


@dataclass
class Evaluation:
    """Measures, constraints, objectives and cost of each (controller, scenario) pair.

    What :func:`evaluate` returns. Arrays are shaped (controllers, scenarios), constraints
    and objectives with a last axis in the order of :data:`~vfgym.scoring.CONSTRAINTS`
    (4) and :data:`~vfgym.scoring.OBJECTIVES` (3). A pulse source on a moving reference
    is not applicable: its entries are NaN.

    Attributes
    ----------
    controllers : list
        The controllers, as given (V-F :class:`~vfgym.Settings`, pulse sources, baselines).
    scenarios : list of Scenario
        The scenarios.
    metrics : list of list of dict
        ``metrics[c][s]``: the named measures (:mod:`vfgym.plant.measures`) plus
        ``ideal_time_s``, ``time_ratio``, ``window_rad`` and ``arrived``.
    cost : numpy.ndarray
        The scalar cost, (controllers, scenarios).
    constraints : numpy.ndarray
        (controllers, scenarios, 4), in the order of :data:`CONSTRAINTS`; feasible ≤ 0.
    objectives : numpy.ndarray
        (controllers, scenarios, 3), in the order of :data:`OBJECTIVES`.
    traces : list of list of Trace or None
        Per-tick traces when asked for (``keep_traces``), else ``None``.
    across : AcrossPlants or None
        The same pairs on true plants within an axis's uncertainty, when asked for
        (``plants``); the arrays above are the modelled plant's.
    chosen : list of list
        ``chosen[c][s]``: the controller as it ran on scenario ``s`` (a tuner's choice
        for it; ``None`` for a :class:`~vfgym.scoring.Scheduler`, whose settings change
        during the move).
    """

    controllers: list[Controller]
    scenarios: list[Scenario]
    metrics: list[list[dict[str, Any]]]
    cost: np.ndarray
    constraints: np.ndarray
    objectives: np.ndarray
    traces: list[list[Trace | None]] | None = field(default=None, repr=False)
    across: AcrossPlants | None = field(default=None, repr=False)
    chosen: list[list[Any]] = field(default_factory=list, repr=False)

    @property
    def mean_cost(self) -> np.ndarray:
        """Mean cost over the scenarios, per controller (NaN entries skipped)."""
        return np.nanmean(self.cost, axis=1)

    @property
    def feasible(self) -> np.ndarray:
        """All constraints ≤ 0, per pair (on the modelled plant)."""
        return np.all(self.constraints <= 0.0, axis=-1)

    @property
    def robust_constraints(self) -> np.ndarray:
        """Each pair's constraints as a robust tuner ranks it: the worst over the modelled
        plant and every true plant of :attr:`across` (:func:`vfgym.scoring.robust_constraints`).

        Returns
        -------
        numpy.ndarray
            (controllers, scenarios, 4); :attr:`constraints` where there are no true plants.
        """
        if self.across is None:
            return self.constraints
        return robust_constraints(self.constraints, self.across.constraints, axis=1)

    def metric(self, name: str) -> np.ndarray:
        """One measure of every pair.

        Parameters
        ----------
        name : str
            A key of :attr:`metrics` (e.g. ``move_time_s``).

        Returns
        -------
        numpy.ndarray
            float, (controllers, scenarios).
        """
        return np.array([[float(m[name]) for m in row] for row in self.metrics])

    def labels(self) -> list[str]:
        """Short names of the controllers, for tables.

        Returns
        -------
        list of str
            One per controller (:func:`vfgym.moves.baselines.controller_label`).
        """
        return [
            controller_label(c)
            if isinstance(c, (Settings, FixedFrequency, SCurveSource, Baseline))
            else str(getattr(c, "source", None) or getattr(c, "__name__", "tuner"))
            for c in self.controllers
        ]


def _choose(c: Any, sc: Scenario) -> Controller | Baseline:
    """A controller as it runs on a move: a tuner's choice for it, else itself."""
    if isinstance(c, (Settings, FixedFrequency, SCurveSource, Baseline)):
        return c
    out = c(sc)
    if not isinstance(out, Settings):
        raise ValueError(
            f"the tuner {c!r} gave {out!r} for move {sc.name!r}: a tuner gives vfgym.Settings "
            "(a controller that schedules its own move is a vfgym.scoring.Scheduler)"
        )
    return out


def _check_controllers(controllers: Any) -> list[Any]:
    kinds = (Settings, FixedFrequency, SCurveSource, Baseline, Scheduler)
    if isinstance(controllers, (*kinds, str)) or callable(controllers):
        controllers = [controllers]
    out = [Baseline(c) if isinstance(c, str) else c for c in controllers]
    for i, c in enumerate(out):
        if not isinstance(c, kinds) and not callable(c):
            raise ValueError(
                f"settings[{i}]={c!r} is not allowed: give vfgym.Settings, a baseline "
                "pulse source (FixedFrequency, SCurveSource), a tuner (move -> Settings, "
                "e.g. vfgym.agents.load_tuner's) or a vfgym.scoring.Scheduler"
            )
    if not out:
        raise ValueError("settings=[] is not allowed: give at least one")
    return out


def evaluate(
    settings: Any,
    scenarios: str | Scenario | Sequence[str | Scenario] = "paper-step",
    *,
    axis: Axis | str | PathLike[str] = PAPER_AXIS,
    weights: CostWeights = DEFAULT_WEIGHTS,
    bounds: Bounds = DEFAULT_BOUNDS,
    keep_traces: bool = False,
    decimation: int = 1,
    while_running: Callable[[], None] | None = None,
    plants: Sequence[PlantVariant] | int = (),
    plant_seed: int | None = None,
    progress: bool = False,
) -> Evaluation:
    """Score every controller on every scenario, on the axis's modelled plant and on each
    true plant asked for, through one batched kernel call.

    The one scoring path, ``params → simulate → trace → metrics → cost``: the Gymnasium
    envs' rewards, the Optuna objective and the reports all call it. Every controller,
    fixed settings, a tuner or a scheduler alike, runs on the same (move, plant) triples:
    the axis's plant, as modelled, and the true plants of ``plants``.

    Parameters
    ----------
    settings : Settings, pulse source, str, Baseline, tuner, or a sequence of these
        V-F :class:`~vfgym.Settings`, a baseline pulse source, a baseline name or
        :class:`~vfgym.moves.baselines.Baseline` (derived per scenario plant), or a tuner:
        a callable from a move to its settings (:func:`vfgym.agents.load_tuner`'s
        settings models and VFTune-v0 agents), asked once per move, or a
        :class:`~vfgym.scoring.Scheduler` that changes its settings during the move
        (``load_tuner``'s VFServo-v0 agents), run on every (move, plant) pair.
    scenarios : str, Scenario, or a sequence of these
        Names, :class:`~vfgym.Scenario` objects, or a set spec resolved on the axis
        (:meth:`vfgym.Axis.scenario_set`: ``train`` / ``test``, its move sets; ``named``;
        a move's name; a list).
    axis : Axis, str or os.PathLike
        The problem: its plant, measures, moves and uncertainty (an axis file's path is
        loaded). Default: the paper's axis (:data:`vfgym.PAPER_AXIS`: 16 train and 32 test
        moves). Another machine is another axis: ``dataclasses.replace(vfgym.PAPER_AXIS,
        plant=...)`` runs the paper's moves on it.
    weights : CostWeights
        Weights of the cost.
    bounds : Bounds
        Bounds of the constraints.
    keep_traces : bool
        Also return per-tick traces on the modelled plant (simulated one by one; the
        measures are the batch's, and equal the traces' own).
    decimation : int
        Keep every ``decimation``-th tick in the traces.
    while_running : callable or None
        Work of the caller's to do while the compiled call runs (a sweep writes the
        trials being simulated): as :func:`score_pairs` runs it.
    plants : sequence of PlantVariant, or int
        True plants within the axis's uncertainty (:func:`vfgym.axis.draw_plants`): every
        triple is also scored on each, into :attr:`Evaluation.across`. A count draws that
        many within the axis's uncertainty from ``plant_seed`` (an exactly known axis: the
        ±5 % inertia plants). Empty: the modelled plant only.
    plant_seed : int or None
        The seed ``plants`` were (or are) drawn from, recorded with them (default for a
        count: :data:`vfgym.axis.VERDICT_PLANT_SEED`).
    progress : bool
        Show a progress bar over the triples on stderr (a terminal's; tqdm hides it
        elsewhere): the fixed controllers' batch then runs in calls of
        :data:`PROGRESS_CHUNK` pairs, a scheduler's triples one by one.

    Returns
    -------
    Evaluation
        Measures, constraints, objectives and cost of every (controller, scenario) pair,
        and of every triple on the true plants.

    Raises
    ------
    ValueError
        If a controller, a scenario or the axis is not known or not allowed.
    """
    ctrls = _check_controllers(settings)
    axis = as_axis(axis)
    spec: Any = scenarios if isinstance(scenarios, (str, Scenario)) else list(scenarios)
    scens = axis.scenario_set(spec)
    variants, plant_seed = _true_plants(axis, plants, plant_seed)
    on = (NOMINAL, *variants)
    nc, npl, ns = len(ctrls), len(on), len(scens)
    moves = [[Move.of(sc, axis.plant, v) for sc in scens] for v in on]
    # a tuner is asked once a move; a scheduler runs each (move, plant) itself
    chosen = [[None if isinstance(c, Scheduler) else _choose(c, sc) for sc in scens] for c in ctrls]
    triples = [(c, p, s) for c in range(nc) for p in range(npl) for s in range(ns)]
    batched = [t for t in triples if not isinstance(ctrls[t[0]], Scheduler)]
    bar = tqdm(total=len(triples), unit="run", desc="evaluate", disable=None if progress else True,
               dynamic_ncols=True, leave=False)  # fmt: skip
    step = PROGRESS_CHUNK if progress else max(1, len(batched))
    scores: dict[tuple[int, int, int], Score | None] = {}
    for at in range(0, len(batched), step):
        part = batched[at : at + step]
        scores.update(zip(part, score_pairs(
            [chosen[c][s] for c, _, s in part], [moves[p][s] for _, p, s in part],
            measures=axis.measures, weights=weights, bounds=bounds,
            while_running=while_running if at == 0 else None,
        ), strict=True))  # fmt: skip
        bar.update(len(part))
    if not batched and while_running is not None:  # (only schedulers: the caller's work)
        while_running()
    for c, p, s in triples:
        if isinstance(ctrls[c], Scheduler):
            (scores[c, p, s],) = score_scheduled(ctrls[c], [moves[p][s]], [on[p]], axis.measures,
                                                 weights, bounds)  # fmt: skip
            bar.update(1)
    bar.close()
    nan_m = dict.fromkeys(METRIC_NAMES, math.nan)
    metrics = [[dict(nan_m) for _ in range(ns)] for _ in range(nc)]
    cost = np.full((nc, npl, ns), np.nan)
    cons = np.full((nc, npl, ns, len(CONSTRAINTS)), np.nan)
    objs = np.full((nc, ns, len(OBJECTIVES)), np.nan)
    for (c, p, s), res in scores.items():
        if res is None:  # a pulse source on a moving reference
            continue
        cost[c, p, s], cons[c, p, s] = res.cost, res.constraints
        if p == 0:
            objs[c, s], metrics[c][s] = res.objectives, res.metrics
    across = AcrossPlants(variants, plant_seed, cost[:, 1:], cons[:, 1:]) if variants else None
    traces = _traces(chosen, moves[0], axis, decimation) if keep_traces else None
    return Evaluation(ctrls, scens, metrics, cost[:, 0], cons[:, 0], objs, traces, across, chosen)


def _true_plants(
    axis: Axis, plants: Sequence[PlantVariant] | int, seed: int | None
) -> tuple[tuple[PlantVariant, ...], int | None]:
    """The true plants of ``plants`` (a count drawn within the axis's uncertainty) and the
    seed to record with them (``None`` for a fixed set such as the ±5 % line)."""
    if not isinstance(plants, int):
        return tuple(plants), seed
    seed = VERDICT_PLANT_SEED if seed is None else seed
    drawn = draw_plants(axis.uncertainty, axis.plant, plants, seed)
    return drawn, None if axis.uncertainty.exact else seed


def _traces(
    chosen: list[list[Any]], moves: list[Move], axis: Axis, decimation: int
) -> list[list[Trace | None]]:
    """Per-tick traces of each controller's run on each move, as modelled (none for a
    scheduler, or a pulse source that cannot run the move)."""
    out: list[list[Trace | None]] = []
    for row in chosen:
        out.append([])
        for c, mv in zip(row, moves, strict=True):
            run = None if c is None else as_run(c, mv)
            out[-1].append(None if run is None else simulate(
                mv.command, run[0], mv.plant, pulses=run[1], measures=axis.measures,
                decimation=decimation,
            ))  # fmt: skip
    return out
