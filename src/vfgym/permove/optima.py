"""Per-move optima: the best settings for each of many moves, found together through the
batched kernel (:func:`vfgym.scoring.score_pairs`), the reference the amortised tuners
(the supervised model, the agents) are judged against and the supervised model learns.

For every move: a coarse grid over the search space (:func:`vfgym.space.grid`, ``points``
values per dimension, in unit coordinates), then ``rounds`` of local refinement, each a
3⁴ pattern (every unit coordinate at −h, 0, +h) around the ``keep`` best distinct points
so far, the step h halving each round. All moves' settings of a stage go through one
compiled call. The best of a move is its feasible setting of least cost (of least cost,
if none is feasible), as the grid's (:func:`vfgym.tuning.run_grid`). On an axis with
uncertainty, feasible means feasible on its design plants too: the ``keep`` best of each
move are checked on them after every stage (best first, until the ``keep`` best are all
checked), and one that fails ranks as infeasible.

The optima are cached in a CSV (:func:`write_optima`, :func:`read_optima`), one row per
move: the scenario's name, the four settings, cost, feasible.
"""

from __future__ import annotations

import csv
import itertools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from vfgym import space
from vfgym._validate import check_int
from vfgym.axis import NOMINAL, PlantVariant
from vfgym.io.runs import write_text
from vfgym.moves.scenarios import Scenario
from vfgym.params import DEFAULT_MEASURES, PAPER_PLANT, Measures, Plant, Settings
from vfgym.scoring import (
    DEFAULT_BOUNDS,
    DEFAULT_WEIGHTS,
    Bounds,
    CostWeights,
    Move,
    score_pairs,
    worst_on,
)


@dataclass(frozen=True)
class OptimumSearch:
    """How :func:`move_optima` searches each move; every default here.

    Parameters
    ----------
    points : int
        Values per dimension of the coarse grid, 2 to 16 (``points⁴`` settings a move).
    rounds : int
        Refinement rounds, 0 to 20.
    keep : int
        Best distinct points refined around each round, 1 to 16.
    batch : int
        (setting, move) pairs per compiled call, ≥ 1.
    accel_law : str
        The acceleration law of every setting.
    """

    points: int = 6
    rounds: int = 8
    keep: int = 3
    batch: int = 20_000
    accel_law: str = "rise"

    def __post_init__(self) -> None:
        s = object.__setattr__
        s(self, "points", check_int("points", self.points, 2, 16))
        s(self, "rounds", check_int("rounds", self.rounds, 0, 20))
        s(self, "keep", check_int("keep", self.keep, 1, 16))
        s(self, "batch", check_int("batch", self.batch, 1))
        Settings(accel_law=self.accel_law)  # checks the law

    @property
    def evaluations(self) -> int:
        """Settings scored per move at most."""
        return self.points**4 + self.rounds * self.keep * 3**4


@dataclass(frozen=True)
class MoveOptimum:
    """The best settings found for one move.

    Attributes
    ----------
    scenario : str
        The move's scenario name.
    settings : Settings
        The best settings.
    cost : float
        Their cost on the move (the scoring path's).
    feasible : bool
        Every constraint ≤ 0.
    """

    scenario: str
    settings: Settings
    cost: float
    feasible: bool


def _rank(cost: float, feasible: bool) -> tuple[int, float]:
    return (0 if feasible else 1, cost if math.isfinite(cost) else math.inf)


def _pattern(h: float) -> np.ndarray:
    return np.array(list(itertools.product((-h, 0.0, h), repeat=len(space.SPACE))))


def move_optima(
    scenarios: Sequence[Scenario],
    search: OptimumSearch = OptimumSearch(),
    *,
    plant: Plant = PAPER_PLANT,
    measures: Measures = DEFAULT_MEASURES,
    weights: CostWeights = DEFAULT_WEIGHTS,
    bounds: Bounds = DEFAULT_BOUNDS,
    progress: Callable[[str], None] | None = None,
    plants: Sequence[PlantVariant] = (),
    true_plants: Sequence[PlantVariant] | None = None,
) -> list[MoveOptimum]:
    """The best settings of each move (coarse grid, then local refinement; module doc).

    Parameters
    ----------
    scenarios : sequence of Scenario
        The moves.
    search : OptimumSearch
        Grid size, refinement rounds, points kept, batch size.
    plant, measures, weights, bounds
        The scoring path's inputs (:func:`vfgym.evaluate`).
    progress : callable or None
        Called with one line after each stage.
    plants : sequence of PlantVariant
        True plants a setting must also be feasible on to count as feasible (an axis's
        :meth:`~vfgym.axis.Axis.design_plants`): robust optima. Only the
        contenders are checked on them, best first (the module doc).
    true_plants : sequence of PlantVariant or None
        Each move's true plant, relative to the modelled one: the optimum of the move as
        it runs there (an oracle that knows the plant); ``None``: the modelled plant.

    Returns
    -------
    list of MoveOptimum
        One per scenario, in order.
    """
    on = [NOMINAL] * len(scenarios) if true_plants is None else list(true_plants)
    if len(on) != len(scenarios):
        raise ValueError(f"true_plants: {len(on)} given for {len(scenarios)} moves")
    moves = [Move.of(sc, plant, v) for sc, v in zip(scenarios, on, strict=True)]
    design = tuple(plants)
    # per move: unit point (rounded) -> [rank, u, feasible, cost, checked on the design]
    seen: list[dict[tuple, list]] = [{} for _ in moves]

    def run(points: list[list[np.ndarray]]) -> None:
        pairs = [
            (i, u)
            for i, pts in enumerate(points)
            for u in pts
            if tuple(np.round(u, 12)) not in seen[i]
        ]
        for a in range(0, len(pairs), search.batch):
            chunk = pairs[a : a + search.batch]
            ctrls = [space.from_action(u, search.accel_law) for _, u in chunk]
            res = score_pairs(
                ctrls,
                [moves[i] for i, _ in chunk],
                measures=measures,
                weights=weights,
                bounds=bounds,
            )
            for (i, u), r in zip(chunk, res, strict=True):
                assert r is not None  # V-F settings run every move
                feas = r.feasible
                entry = [_rank(r.cost, feas), u, feas, float(r.cost), not design or not feas]
                seen[i][tuple(np.round(u, 12))] = entry
        settle(search.keep)

    def settle(keep: int) -> None:
        """Check on the design plants, best first, until each move's ``keep`` best are
        all checked: a setting feasible as modelled but not on a design plant ranks as
        infeasible. Only the contenders are checked, so the design costs a few
        simulations a move and round, not one per plant for every setting."""
        while True:
            todo = [
                (i, e)
                for i in range(len(moves))
                for e in sorted(seen[i].values(), key=lambda e: e[0])[:keep]
                if not e[4]
            ]
            if not todo:
                return
            worst = worst_on(
                [space.from_action(e[1], search.accel_law) for _, e in todo],
                [moves[i] for i, _ in todo],
                design,
                measures=measures,
                weights=weights,
                bounds=bounds,
            )
            for (_, e), w in zip(todo, worst, strict=True):
                e[4] = True
                if not bool(np.all(w <= 0.0)):
                    e[2] = False
                    e[0] = _rank(e[3], False)

    coarse = np.linspace(-1.0, 1.0, search.points)
    grid = np.array(list(itertools.product(coarse, repeat=len(space.SPACE))))
    run([list(grid) for _ in moves])
    if progress:
        progress(f"coarse grid: {len(grid)} settings x {len(moves)} moves")
    h = 2.0 / (search.points - 1) / 2.0
    for rnd in range(search.rounds):
        pat = _pattern(h)
        todo = []
        for i in range(len(moves)):
            centers: list[np.ndarray] = []
            for e in sorted(seen[i].values(), key=lambda v: v[0]):
                u = e[1]
                if all(np.max(np.abs(u - c)) > h for c in centers):
                    centers.append(u)
                if len(centers) == search.keep:
                    break
            todo.append([np.clip(c + p, -1.0, 1.0) for c in centers for p in pat])
        run(todo)
        if progress:
            progress(f"refinement round {rnd + 1}/{search.rounds}: step {h:.4g}")
        h /= 2.0
    out = []
    for sc, s in zip(scenarios, seen, strict=True):
        _, u, feas, cost, _ = min(s.values(), key=lambda v: v[0])
        out.append(MoveOptimum(sc.name, space.from_action(u, search.accel_law), cost, feas))
    return out


OPTIMA_FIELDS = ("scenario", *space.NAMES, "accel_law", "cost", "feasible")
"""Columns of an optima CSV."""


def write_optima(path: str | Path, optima: Sequence[MoveOptimum], header: str = "") -> None:
    """Write optima as CSV (``header``: comment lines starting with ``#`` first).

    Parameters
    ----------
    path : str or Path
        The file.
    optima : sequence of MoveOptimum
        The rows.
    header : str
        Lines written first, each prefixed with ``# ``.
    """
    lines = [f"# {h}" for h in header.splitlines()]
    lines.append(",".join(OPTIMA_FIELDS))
    for o in optima:
        vals = [repr(float(getattr(o.settings, n))) for n in space.NAMES]
        lines.append(
            ",".join([o.scenario, *vals, o.settings.accel_law, repr(o.cost), str(int(o.feasible))])
        )
    write_text(path, "\n".join(lines) + "\n")


def read_optima(path: str | Path) -> list[MoveOptimum]:
    """Optima from a CSV written by :func:`write_optima`.

    Parameters
    ----------
    path : str or Path
        The file.

    Returns
    -------
    list of MoveOptimum
        In the file's order.

    Raises
    ------
    ValueError
        If the file is missing or a row is malformed.
    """
    p = Path(path)
    if not p.is_file():
        raise ValueError(f"optima file {p}: no such file")
    rows = [ln for ln in p.read_text().splitlines() if ln and not ln.startswith("#")]
    out = []
    for rec in csv.DictReader(rows):
        try:
            s = Settings(
                **{n: float(rec[n]) for n in space.NAMES}, accel_law=rec["accel_law"].strip()
            )
            out.append(MoveOptimum(rec["scenario"], s, float(rec["cost"]), rec["feasible"] == "1"))
        except (KeyError, TypeError, ValueError) as exc:
            raise ValueError(f"optima file {p}: bad row {rec}: {exc}") from None
    return out


__all__ = [
    "OPTIMA_FIELDS",
    "MoveOptimum",
    "OptimumSearch",
    "move_optima",
    "read_optima",
    "write_optima",
]
