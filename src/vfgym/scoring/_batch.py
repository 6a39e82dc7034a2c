"""Pairs of (controller, move) scored in one compiled, multi-threaded call: the batched
simulation under :func:`vfgym.evaluate`, the robust rules and the tuners' searches.

A :class:`Move` is a scenario made ready to simulate on a (true) plant; :func:`score_pairs`
runs any list of (controller, move) pairs through the batched kernel and scores each by
:func:`vfgym.scoring.score`.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numba
import numpy as np

from vfgym.axis import NOMINAL, PlantVariant
from vfgym.moves.baselines import Controller, resolve
from vfgym.moves.scenarios import Scenario
from vfgym.params import DEFAULT_MEASURES, Measures, Plant, Settings
from vfgym.plant import _kernel as K
from vfgym.plant import _layout as L
from vfgym.plant import command_end_s, pack
from vfgym.plant._notice import announce_compile
from vfgym.plant._threads import keeps_torch_threads
from vfgym.plant.measures import from_acc
from vfgym.scoring._cost import (
    DEFAULT_BOUNDS,
    DEFAULT_WEIGHTS,
    Bounds,
    CostWeights,
    Score,
    score,
)


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
    def of(cls, scenario: Scenario, base: Plant, variant: PlantVariant = NOMINAL) -> Move:
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


def as_run(c: Controller, move: Any) -> tuple[Settings, np.ndarray | None] | None:
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
        run = as_run(c, mv)
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
    prm_rows = np.stack(prm)
    # a batch of rigid plants runs (and on first use compiles) the rigid loop alone
    run = K.run_batch if bool(np.any(prm_rows[:, L.P_TWO] != 0.0)) else K.run_batch_rigid
    announce_compile("evaluate", "the batched simulation kernel", run)
    keeps_torch_threads(_run_beside)(
        run,
        while_running,
        np.concatenate(cmds),
        np.concatenate([[0], np.cumsum([c.size for c in cmds])]).astype(np.int64),
        np.array(cmd_idx, np.int64),
        np.concatenate(ext_parts),
        np.concatenate([[0], np.cumsum([x.size for x in ext_parts])]).astype(np.int64),
        np.array(ext_idx, np.int64),
        prm_rows,
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
