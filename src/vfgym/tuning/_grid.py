"""The exhaustive grid, refined around its best points: the near-true optimum a sweep's
best is reported against."""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from vfgym import space
from vfgym.axis import axis_digest
from vfgym.io.runs import write_text
from vfgym.moves.scenarios import Scenario
from vfgym.params import PAPER_SETTINGS, Settings
from vfgym.scoring import CONSTRAINTS, evaluate
from vfgym.tuning._aggregate import aggregate
from vfgym.tuning._config import GridConfig


@dataclass(frozen=True, eq=False)
class GridRow:
    """One evaluated setting of the grid.

    Attributes
    ----------
    level : int
        0: the whole space; n: the n-th refinement round.
    settings : Settings
        The setting.
    u : numpy.ndarray
        The settings as unit coordinates in [-1, 1] (:meth:`vfgym.space.Dim.to_unit`).
    cost : float
        Mean cost over the scenarios.
    constraints : numpy.ndarray
        Worst of each constraint over the scenarios, (4,).
    feasible : bool
        Every constraint ≤ 0 on every scenario.
    """

    level: int
    settings: Settings
    u: np.ndarray
    cost: float
    constraints: np.ndarray
    feasible: bool


@dataclass(frozen=True, eq=False)
class GridResult:
    """What :func:`run_grid` evaluated, and its best row.

    Attributes
    ----------
    rows : list of GridRow
        Every evaluated setting, in the order evaluated.
    best : GridRow
        The feasible row of least cost (of least cost, if none is feasible).
    scenarios : list of Scenario
        The scenarios each setting was scored on.
    """

    rows: list[GridRow]
    best: GridRow
    scenarios: list[Scenario]


def run_grid(
    cfg: GridConfig, progress: Callable[[int, int, float], None] | None = None
) -> GridResult:
    """Evaluate the dense grid and its refinements on the config's axis, one compiled call
    of :func:`vfgym.evaluate` per batch.

    Parameters
    ----------
    cfg : GridConfig
        The grid.
    progress : callable or None
        Called after each batch with (settings done, settings in all, best feasible cost).

    Returns
    -------
    GridResult
        Every setting evaluated, and the best.
    """
    scenarios = cfg.scenario_list()
    axis = cfg.axis_or_paper()
    evaluate(PAPER_SETTINGS, scenarios, axis=axis)  # compile/load once before timing batches
    pts = space.grid(cfg.points, cfg.laws)
    total = len(pts) * (1 + cfg.refine * cfg.keep)
    rows: dict[Settings, GridRow] = {}
    done = 0
    best_cost = math.inf
    step = 2.0 / (cfg.points - 1)
    for level in range(cfg.refine + 1):
        if level > 0:
            pool = sorted((r for r in rows.values() if r.feasible), key=lambda r: r.cost) or sorted(
                rows.values(), key=lambda r: r.cost
            )
            centers: list[GridRow] = []
            for r in pool:
                if all(
                    r.settings.accel_law != c.settings.accel_law or np.max(np.abs(r.u - c.u)) > step
                    for c in centers
                ):
                    centers.append(r)
                if len(centers) == cfg.keep:
                    break
            step = step * 2.0 / (cfg.points - 1)
            half, pts = step * (cfg.points - 1) / 2.0, []
            for c in centers:
                axes = [
                    np.linspace(max(-1.0, x - half), min(1.0, x + half), cfg.points) for x in c.u
                ]
                pts += [
                    space.from_action(np.array(u), c.settings.accel_law)
                    for u in np.array(np.meshgrid(*axes, indexing="ij")).reshape(4, -1).T
                ]
        todo = [s for s in pts if s not in rows]
        for i in range(0, len(todo), cfg.batch):
            chunk = todo[i : i + cfg.batch]
            agg = aggregate(evaluate(chunk, scenarios, axis=axis))
            for j, s in enumerate(chunk):
                rows[s] = GridRow(
                    level=level,
                    settings=s,
                    u=np.array([d.to_unit(getattr(s, d.name)) for d in space.SPACE]),
                    cost=float(agg.cost[j]),
                    constraints=agg.constraints[j].astype(float),
                    feasible=bool(agg.feasible[j]),
                )
                if agg.feasible[j]:
                    best_cost = min(best_cost, float(agg.cost[j]))
            done += len(chunk)
            if progress is not None:
                progress(done, max(total, done), best_cost)
    best = min(rows.values(), key=lambda r: (not r.feasible, r.cost))
    return GridResult(list(rows.values()), best, scenarios)


def write_grid_csv(rows: Sequence[GridRow], path: Path) -> Path:
    """Write ``grid.csv`` atomically, a line per row, floats as ``repr`` (read back
    exactly)."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(
        ["level", *space.NAMES, "accel_law", "cost", *[f"c_{c}" for c in CONSTRAINTS], "feasible"]
    )
    for r in rows:
        s = r.settings
        w.writerow(
            [
                r.level,
                *[repr(float(getattr(s, n))) for n in space.NAMES],
                s.accel_law,
                repr(r.cost),
                *[repr(float(x)) for x in r.constraints],
                int(r.feasible),
            ]
        )
    return write_text(path, buf.getvalue())


def grid_reference(cfg: GridConfig, result: GridResult) -> dict[str, Any]:
    """``reference.yaml``'s mapping (what a sweep's ``find_reference`` reads back): the
    grid's best in the Settings-YAML format, what it was scored on, how the grid ran."""
    b = result.best
    return {
        "settings": space.settings_to_dict(b.settings),
        "cost": b.cost,
        "feasible": b.feasible,
        "constraints": dict(zip(CONSTRAINTS, [float(x) for x in b.constraints], strict=True)),
        "scenarios": [s.name for s in result.scenarios],
        "laws": list(cfg.laws),
        "axis": axis_digest(cfg.load_axis()),
        "points": cfg.points,
        "refine": cfg.refine,
        "keep": cfg.keep,
        "evaluated": len(result.rows),
        "source": "vfgym grid",
    }
