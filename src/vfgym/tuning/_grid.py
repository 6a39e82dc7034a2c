"""The exhaustive grid, refined around its best points: the near-true optimum a sweep's
best is reported against. :func:`run_grid` evaluates it; :func:`grid` is ``vfgym grid``
as one call (its run folder, the reference, the grid's best against the paper's)."""

from __future__ import annotations

import csv
import io
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from vfgym import space
from vfgym._validate import check_output_path
from vfgym.axis import AXIS_FILE, write_axis
from vfgym.io.runs import record_command, write_text, write_yaml
from vfgym.moves.scenarios import Scenario
from vfgym.params import PAPER_SETTINGS, Settings
from vfgym.report import Report, format_compact
from vfgym.scoring import CONSTRAINTS, evaluate
from vfgym.tuning._aggregate import aggregate
from vfgym.tuning._config import GridConfig
from vfgym.tuning._results import against_paper


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
    cfg: GridConfig, progress: Callable[[int, int, float], object] | None = None
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
    axis = cfg.axis
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
        "axis": cfg.axis_key(),
        "points": cfg.points,
        "refine": cfg.refine,
        "keep": cfg.keep,
        "evaluated": len(result.rows),
        "source": "vfgym grid",
    }


class GridStart(NamedTuple):
    """What :func:`grid` is about to evaluate, told before it starts.

    Attributes
    ----------
    name : str
        The run's name.
    run_dir : pathlib.Path
        The run folder.
    settings : int
        Settings of the whole-space grid (the refinements add more).
    scenarios : tuple of str
        The scenarios' names.
    """

    name: str
    run_dir: Path
    settings: int
    scenarios: tuple[str, ...]


@dataclass(frozen=True, eq=False)
class GridRun:
    """What :func:`grid` evaluated and wrote.

    Attributes
    ----------
    config : GridConfig
        The grid.
    result : GridResult
        Every setting evaluated, and the best.
    reference : dict
        ``reference.yaml``'s mapping (:func:`grid_reference`, with ``elapsed_s``).
    comparison : Report
        The grid's best against the paper's settings on the scenarios.
    run_dir : pathlib.Path
        The run folder: config.yaml, axis.yaml, command.txt, grid.csv, reference.yaml,
        report.txt.
    elapsed_s : float
        Wall seconds of the evaluation.
    """

    config: GridConfig
    result: GridResult
    reference: dict[str, Any]
    comparison: Report
    run_dir: Path
    elapsed_s: float

    def text(self) -> str:
        """The report as ``vfgym grid`` prints it (``report.txt``).

        Returns
        -------
        str
            Settings evaluated and their rate, the reference against the paper's cost,
            its settings, and the table by scenario.
        """
        ref, n, elapsed = self.reference, len(self.result.rows), self.elapsed_s
        s = ref["settings"]
        runs = n * len(self.result.scenarios)
        return "\n".join(
            [
                f"{n} settings evaluated in {elapsed:.1f} s ({runs / elapsed:.0f} runs/s)",
                f"reference: cost {ref['cost']:.4f} "
                f"({'feasible' if ref['feasible'] else 'INFEASIBLE'}) against the paper's "
                f"{self.comparison.column('paper').mean_cost:.4f}",
                f"settings: value {s['value_rad']:.6g} rad, error limit "
                f"{s['error_limit_rad']:.6g} rad, k {s['k']:.6g}, Ts/Tf {s['ts_over_tf']:.4g}, "
                f"law {s['accel_law']}",
                "",
                format_compact(self.comparison),
            ]
        )


def grid(
    config: GridConfig,
    *,
    argv: Sequence[str] | None = None,
    on_start: Callable[[GridStart], object] | None = None,
    on_progress: Callable[[int, int, float], object] | None = None,
) -> GridRun:
    """Run ``vfgym grid``: evaluate the grid (:func:`run_grid`) in a run folder,
    ``RUNS_DIR/grid/NAME/``, and write every setting (``grid.csv``), the best as the
    reference a sweep on the same problem reports its gap to (``reference.yaml``), and
    the report.

    Parameters
    ----------
    config : GridConfig
        The grid.
    argv : sequence of str or None
        The command line to record in ``command.txt`` (after ``vfgym``); default: the
        configuration's options.
    on_start : callable or None
        Called with a :class:`GridStart` once the run folder is made.
    on_progress : callable or None
        As :func:`run_grid`'s ``progress``.

    Returns
    -------
    GridRun
        What was evaluated and written.
    """
    cfg = config
    scenarios = cfg.scenario_list()
    name = cfg.name or _default_grid_name(cfg)
    run_dir = Path(cfg.runs_dir) / "grid" / name
    check_output_path("runs_dir", run_dir, folder=True, shown=cfg.runs_dir, root=cfg.runs_dir)
    run_dir.mkdir(parents=True, exist_ok=True)
    write_yaml(run_dir / "config.yaml", {"command": "grid", **cfg.to_dict(), "name": name})
    write_axis(cfg.axis, run_dir / AXIS_FILE)
    record_command(run_dir, ["vfgym", *(argv if argv is not None else cfg.command_words("grid"))])
    if on_start is not None:
        first = cfg.points ** len(space.SPACE) * len(cfg.laws)
        on_start(GridStart(name, run_dir, first, tuple(s.name for s in scenarios)))
    t0 = time.monotonic()
    result = run_grid(cfg, on_progress)
    elapsed = time.monotonic() - t0
    write_grid_csv(result.rows, run_dir / "grid.csv")
    ref = grid_reference(cfg, result) | {"elapsed_s": round(elapsed, 3)}
    write_yaml(run_dir / "reference.yaml", ref)
    comparison = against_paper(result.best.settings, scenarios, "grid", cfg.axis)
    out = GridRun(cfg, result, ref, comparison, run_dir, elapsed)
    write_text(run_dir / "report.txt", out.text() + "\n")
    return out


def _default_grid_name(cfg: GridConfig) -> str:
    """A grid run's default name: the axis (if given) and scenarios, the laws if not the
    default, the points and rounds (``train16s0-p12-r2k4``).

    Parameters
    ----------
    cfg : GridConfig
        The grid.

    Returns
    -------
    str
        The name.
    """
    slug = "".join(c if c.isalnum() or c in "._-" else "_" for c in str(cfg.scenarios))[:60]
    if not cfg.default_axis:
        slug = f"{cfg.axis.name}-{slug}"[:60]
    elif cfg.scenarios in ("train", "test"):
        slug += f"{cfg.scenario_count}s{cfg.first_seed}"
    laws = "" if cfg.laws == ("rise",) else "-" + "_".join(cfg.laws)
    return f"{slug}{laws}-p{cfg.points}-r{cfg.refine}k{cfg.keep}"
