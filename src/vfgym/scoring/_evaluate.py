"""Every (controller, scenario) pair in one compiled, multi-threaded call, scored by
:func:`vfgym.scoring.score`: what the envs, the sweeps and the reports all call."""

from __future__ import annotations

import math
import threading
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

import numba
import numpy as np

from vfgym.axis import (
    NOMINAL,
    PAPER_AXIS,
    VERDICT_PLANT_SEED,
    Axis,
    PlantVariant,
    draw_plants,
    plant_on,
)
from vfgym.moves.baselines import (
    Baseline,
    Controller,
    FixedFrequency,
    SCurveSource,
    controller_label,
    resolve,
)
from vfgym.moves.scenarios import Scenario
from vfgym.params import (
    DEFAULT_MEASURES,
    PAPER_PLANT,
    Measures,
    Plant,
    Settings,
)
from vfgym.plant import Trace, command_end_s, pack, simulate
from vfgym.plant import _kernel as K
from vfgym.plant._notice import announce_compile
from vfgym.plant._threads import keeps_torch_threads
from vfgym.plant.measures import NAMES as METRIC_NAMES
from vfgym.plant.measures import from_acc

if TYPE_CHECKING:
    from vfgym.scoring._plants import AcrossPlants

from vfgym.scoring._cost import (
    CONSTRAINTS,
    DEFAULT_BOUNDS,
    DEFAULT_WEIGHTS,
    OBJECTIVES,
    Bounds,
    CostWeights,
    Score,
    score,
)
from vfgym.scoring._scheduled import Scheduler, score_scheduled


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
        """All constraints ≤ 0, per pair."""
        return np.all(self.constraints <= 0.0, axis=-1)

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


@dataclass(frozen=True)
class Move:
    """A scenario made ready to simulate: its plant, its command and when that ends.

    Parameters
    ----------
    scenario : Scenario
        The scenario.
    plant : Plant
        The plant with the scenario's load.
    command : numpy.ndarray
        The position command per tick (rad).
    command_end_s : float
        Time at which the command reached its final value (s).
    model : Plant or None
        The modelled plant the controllers are set for (baselines resolved, pulse sources
        planned, commands shaped on it), where ``plant`` is a true plant that differs
        from it (:class:`~vfgym.axis.PlantVariant`); ``None``: ``plant``.
    """

    scenario: Scenario
    plant: Plant
    command: np.ndarray
    command_end_s: float
    model: Plant | None = None

    @classmethod
    def of(
        cls, scenario: Scenario, base: Plant = PAPER_PLANT, variant: PlantVariant = NOMINAL
    ) -> Move:
        """The move of a scenario on a base plant, optionally on a true plant.

        Parameters
        ----------
        scenario : Scenario
            The scenario.
        base : Plant
            The plant before the scenario's load.
        variant : PlantVariant
            The true plant relative to the modelled one (default: the modelled plant).

        Returns
        -------
        Move
            Its (true) plant, command and command end, with the modelled plant.
        """
        plant = scenario.plant(base)
        cmd = scenario.command(plant)
        end = command_end_s(cmd, plant.tick_hz)
        if variant.nominal:
            return cls(scenario, plant, cmd, end)
        return cls(scenario, variant.apply(plant), cmd, end, model=plant)


def on_plant(move: Move, variant: PlantVariant) -> Move:
    """The same move on a true plant (its command and controllers' plant unchanged).

    Parameters
    ----------
    move : Move
        A move on its modelled plant.
    variant : PlantVariant
        The true plant relative to the modelled one.

    Returns
    -------
    Move
        The move on ``variant.apply(move.plant)``, its ``model`` the modelled plant.
    """
    if variant.nominal:
        return move
    return replace(move, plant=variant.apply(move.plant), model=move.plant)


def _as_run(c: Controller, move: Any) -> tuple[Settings, np.ndarray | None] | None:
    """The settings and external pulse train a controller runs with on a move (``None``
    pulses: the V-F controller makes them), or ``None`` if it cannot run it. Baselines and
    pulse sources are set for the modelled plant (a move's ``model``, if it has one)."""
    model = getattr(move, "model", None) or move.plant
    c = resolve(c, model)
    if isinstance(c, Settings):
        return c, None
    train = c.pulses(move.scenario, model)
    return None if train is None else (Settings(ts_over_tf=c.ts_over_tf), train)


def score_pairs(
    controllers: Sequence[Controller],
    moves: Sequence[Any],
    *,
    measures: Measures = DEFAULT_MEASURES,
    weights: CostWeights = DEFAULT_WEIGHTS,
    bounds: Bounds = DEFAULT_BOUNDS,
    while_running: Callable[[], None] | None = None,
) -> list[Score | None]:
    """Score ``controllers[i]`` on ``moves[i]`` for every i in one compiled, multi-threaded call.

    Parameters
    ----------
    controllers : sequence
        One controller per move (V-F settings, a pulse source or a baseline).
    moves : sequence
        :class:`Move` objects, or anything with their attributes (the envs' episodes);
        moves sharing a command array share it in the batch.
    measures : Measures
        Windows and bands of the measures.
    weights : CostWeights
        Weights of the cost.
    bounds : Bounds
        Bounds of the constraints.
    while_running : callable or None
        Work of the caller's to do while the compiled call runs (the vector env's next
        draws): on this thread, beside the call on a worker thread when this thread may
        use two or more numba threads (the call then takes one fewer), else after it. It
        must not touch the moves being scored.

    Returns
    -------
    list of Score or None
        One :class:`~vfgym.scoring.Score` per pair (its ``metrics`` hold the measures),
        or ``None`` where a pulse source cannot run the move (a moving reference).

    Raises
    ------
    ValueError
        If the two sequences differ in length.
    """
    if len(controllers) != len(moves):
        raise ValueError(f"{len(controllers)} controllers for {len(moves)} moves")
    slots: dict[int, int] = {}
    cmds: list[np.ndarray] = []
    ext_parts: list[np.ndarray] = [np.zeros(0, np.int8)]
    prm, cmd_idx, ext_idx, rows = [], [], [], []
    for r, (c, mv) in enumerate(zip(controllers, moves, strict=True)):
        run = _as_run(c, mv)
        if run is None:
            continue
        settings, train = run
        j = slots.setdefault(id(mv.command), len(cmds))
        if j == len(cmds):
            cmds.append(mv.command)
        e = 0
        if train is not None:
            ext_parts.append(train)
            e = len(ext_parts) - 1
        cmd = mv.command
        prm.append(pack(settings, mv.plant, measures, float(cmd[-1]), cmd.size, e > 0))
        cmd_idx.append(j)
        ext_idx.append(e)
        rows.append(r)
    out: list[Score | None] = [None] * len(moves)
    if not rows:
        if while_running is not None:
            while_running()
        return out
    acc = K.new_acc(len(rows))
    announce_compile("evaluate", "the batched simulation kernel", K.run_batch)
    keeps_torch_threads(_run_beside)(
        K.run_batch,
        while_running,
        np.concatenate(cmds),
        np.concatenate([[0], np.cumsum([c.size for c in cmds])]).astype(np.int64),
        np.array(cmd_idx, np.int64),
        np.concatenate(ext_parts),
        np.concatenate([[0], np.cumsum([x.size for x in ext_parts])]).astype(np.int64),
        np.array(ext_idx, np.int64),
        np.stack(prm),
        acc,
    )
    for k, r in enumerate(rows):
        mv = moves[r]
        m = from_acc(acc[k], mv.plant, measures, float(mv.command[-1]), mv.command_end_s)
        out[r] = score(m, mv.scenario, mv.plant, measures, weights, bounds)
    return out


def _run_beside(run: Callable[..., None], beside: Callable[[], None] | None, *args: Any) -> None:
    """``run(*args)`` (a compiled call, which releases the GIL) with ``beside()`` on this
    thread: at once on a worker thread when this thread may use two or more numba
    threads, else one after the other. Python stays on this thread; the caller guards
    torch's thread count around the whole (the first query of numba's threads starts
    them), and the worker calls nothing of torch's."""
    if beside is None:
        run(*args)
        return
    n = numba.get_num_threads()
    if n < 2:
        run(*args)
        beside()
        return
    failed: list[BaseException] = []

    def work() -> None:
        numba.set_num_threads(n - 1)  # numba's thread count is per thread
        try:
            run(*args)
        except BaseException as e:  # re-raised on this thread below
            failed.append(e)

    worker = threading.Thread(target=work, name="vfgym-batch")
    worker.start()
    try:
        beside()
    finally:
        _join(worker)
    if failed:
        raise failed[0]


def _join(worker: threading.Thread) -> None:
    """Wait for the thread even through Ctrl-C, then raise the interrupt: a compiled call
    cannot be stopped, and the caller may run the next one (or read its arrays) at once."""
    interrupted: KeyboardInterrupt | None = None
    while worker.is_alive():
        try:
            worker.join()
        except KeyboardInterrupt as e:
            interrupted = e
    if interrupted is not None:
        raise interrupted


def evaluate(
    settings: Any,
    scenarios: str | Scenario | Sequence[str | Scenario] = "paper-step",
    *,
    axis: Axis = PAPER_AXIS,
    plant: Plant | None = None,
    measures: Measures | None = None,
    weights: CostWeights = DEFAULT_WEIGHTS,
    bounds: Bounds = DEFAULT_BOUNDS,
    keep_traces: bool = False,
    decimation: int = 1,
    while_running: Callable[[], None] | None = None,
    plants: Sequence[PlantVariant] | int = (),
    plant_seed: int | None = None,
) -> Evaluation:
    """Score every controller on every scenario through one batched kernel call.

    The one scoring path, ``params → simulate → trace → metrics → cost``: the Gymnasium
    envs' rewards, the Optuna objective and the reports all call it.

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
    axis : Axis
        The problem: its plant, measures, moves and uncertainty; ``plants`` as a count
        draws within its uncertainty. Default: the paper's axis
        (:data:`vfgym.PAPER_AXIS`: 16 train and 32 test moves).
    plant : Plant or None
        On the paper's axis, another base plant (each scenario applies its load to it);
        ``None``: the axis's.
    measures : Measures or None
        On the paper's axis, other windows and bands; ``None``: the axis's.
    weights : CostWeights
        Weights of the cost.
    bounds : Bounds
        Bounds of the constraints.
    keep_traces : bool
        Also return per-tick traces (simulated one by one; the measures are the batch's,
        and equal the traces' own).
    decimation : int
        Keep every ``decimation``-th tick in the traces.
    while_running : callable or None
        Work of the caller's to do while the compiled call runs (a sweep writes the
        trials being simulated): as :func:`score_pairs` runs it.
    plants : sequence of PlantVariant, or int
        True plants within an axis's uncertainty
        (:func:`vfgym.axis.draw_plants`): every pair is also scored on each,
        in the same batched call, into :attr:`Evaluation.across`. A count draws that many
        within the axis's uncertainty from ``plant_seed`` (an exactly known axis: the ±5 %
        inertia plants). Empty: the modelled plant only.
    plant_seed : int or None
        The seed ``plants`` were (or are) drawn from, recorded with them (default for a
        count: :data:`vfgym.axis.VERDICT_PLANT_SEED`).

    Returns
    -------
    Evaluation
        Measures, constraints, objectives and cost of every (controller, scenario) pair.

    Raises
    ------
    ValueError
        If a controller or a scenario is not known or not allowed.
    """
    ctrls = _check_controllers(settings)
    plant, measures = plant_on(axis, plant, measures)
    spec: Any = scenarios if isinstance(scenarios, (str, Scenario)) else list(scenarios)
    scens = axis.scenario_set(spec)
    variants: tuple[PlantVariant, ...]
    if isinstance(plants, int):
        if plant_seed is None:
            plant_seed = VERDICT_PLANT_SEED
        unc = axis.uncertainty
        variants = draw_plants(unc, plant.motor, plants, plant_seed)
        plant_seed = None if unc.exact else plant_seed
    else:
        variants = tuple(plants)
    moves = [Move.of(sc, plant) for sc in scens]
    nc, ns = len(ctrls), len(scens)
    true_moves = [Move.of(sc, plant, v) for v in variants for sc in scens]
    all_moves = moves + true_moves
    on = [NOMINAL] * ns + [v for v in variants for _ in scens]
    # a tuner is asked once a move; a scheduler runs each move itself (None: no settings)
    chosen = [[None if isinstance(c, Scheduler) else _choose(c, sc) for sc in scens] for c in ctrls]
    batched = [ci for ci, c in enumerate(ctrls) if not isinstance(c, Scheduler)]
    flat = score_pairs(
        [chosen[ci][k % ns] for ci in batched for k in range(len(all_moves))],
        [mv for _ in batched for mv in all_moves],
        measures=measures,
        weights=weights,
        bounds=bounds,
        while_running=while_running,
    )
    per = len(all_moves)
    rows: list[list[Any]] = [[] for _ in ctrls]
    for j, ci in enumerate(batched):
        rows[ci] = flat[j * per : (j + 1) * per]
    for ci, c in enumerate(ctrls):
        if isinstance(c, Scheduler):
            rows[ci] = score_scheduled(c, all_moves, on, measures, weights, bounds)
    results = [r for row in rows for r in row[:ns]]
    across = None
    if variants:
        from vfgym.scoring._plants import across_arrays

        across = across_arrays([row[ns:] for row in rows], variants, plant_seed, ns)
    nan_m = dict.fromkeys(METRIC_NAMES, math.nan)
    metrics = [[dict(nan_m) for _ in range(ns)] for _ in range(nc)]
    cost = np.full((nc, ns), np.nan)
    cons = np.full((nc, ns, len(CONSTRAINTS)), np.nan)
    objs = np.full((nc, ns, len(OBJECTIVES)), np.nan)
    traces: list[list[Trace | None]] | None = (
        [[None] * ns for _ in range(nc)] if keep_traces else None
    )
    for r, res in enumerate(results):
        ci, si = divmod(r, ns)
        if res is None:
            continue
        cost[ci, si], cons[ci, si], objs[ci, si] = res.cost, res.constraints, res.objectives
        metrics[ci][si] = res.metrics
        if traces is not None and chosen[ci][si] is not None:  # (a scheduler's: none)
            run = _as_run(chosen[ci][si], moves[si])
            assert run is not None  # (it was scored)
            s, ext = run
            traces[ci][si] = simulate(
                moves[si].command,
                s,
                moves[si].plant,
                pulses=ext,
                measures=measures,
                decimation=decimation,
            )
    return Evaluation(ctrls, scens, metrics, cost, cons, objs, traces, across, chosen)
