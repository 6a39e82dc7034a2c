"""Trials and seconds each sampler needs to get within 1 % and 2 % of the grid optimum, and
its gap after 50, 100 and 200 trials, on several scenario sets over several seeds.

Every sampler searches the same coordinates from the same warm starts (a fair match):
:class:`vfgym.space.Relative` (log value, log L/value, log k relative to the loaded limit's
k, log Ts/Tf), which the compass searches, as unit coordinates ``u0``–``u3``; the warm
starts the sweep enqueues (the paper's settings, the rule of thumb) tried first; every
sampler told the log of the cost, with the constraints on the trial (TPE, GP and NSGA-II
learn them; CMA-ES and random ignore them). CMA-ES starts at the better warm start
(feasible first, then by cost) with ``sigma0`` :data:`CMA_SIGMA0`; the GP sampler is asked
for :data:`BATCHES` ``["gp"]`` trials at once and conditions on the running ones, as
Optuna's GPSampler does. :data:`BATCHES` gives every sampler's batch (trials asked before
the first is told). The compass runs as ``vfgym sweep`` runs it with one worker
(:func:`vfgym.tuning.run_worker`: Optuna's `study.optimize`); the others through
:func:`run_relative`, the same objective on the same storage kind.

Each (problem, sampler, seed) runs on a fresh study on a file in a temporary folder
(SQLite, or ``--storage journal``), for ``--max-trials`` completed trials. A trial's gap
is its best feasible cost so far against the problem's grid reference (``vfgym grid``;
looked up in ``--refs``, a runs folder of grid runs, by scenario set). Seconds run from
the start (the compiled kernel loaded from numba's cache) to the trial that first got
within the target; wall-clock on whatever else the machine runs (the load average is
printed with each problem).

    vfgym grid --config experiments/grid-paper-step.yaml --runs-dir refs   # one per problem
    python experiments/trials_to_reference.py --refs refs

Held-out problems (``--held-out N``): N move sets of :data:`HELD_OUT_MOVES` moves drawn
from the test distribution of each axis in :data:`HELD_OUT_AXES` (seeds no default was
chosen on), by ``--held-out-seed`` (printed); ``--print-held-out`` prints them with the
``vfgym grid`` command of each one's reference and exits.

Columns: trials (and seconds) to within 1 % and 2 %, median and 90th percentile (nearest
rank: of 5 seeds, the worst) over the seeds (``>N``: not within N trials); median gap in %
after 50, 100 and 200 trials; the best's feasibility (every run's best must be feasible).
The grid sampler is not run: the reference is the grid's own optimum.
"""

from __future__ import annotations

import argparse
import datetime as dt
import math
import os
import statistics
import tempfile
import time
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import optuna

from vfgym import space, tuning
from vfgym.scoring import CONSTRAINTS
from vfgym.tuning._results import FoundReference, find_reference, gap_pct
from vfgym.tuning._study import relative_space

PROBLEMS = (
    "paper-step",
    "heavy-load",
    "short-move",
    "multi-move",
    "experiments/axes/paper.yaml:train",
    "reversal",
)
"""The paper's step; one loaded, one short, one multi-move scenario; the main job's train
set (the 16 train moves of the default axis, one machine, its load fixed); and
``reversal``, a check the sampler was never adjusted on. ``AXIS_FILE:SET`` is a scenario
set on an axis."""


HELD_OUT_AXES = ("experiments/axes/paper.yaml", "experiments/axes/loads.yaml")
"""The axes held-out problems are drawn on: the default one, and the paper's plant under
a random load per move."""
HELD_OUT_MOVES = 4
"""Moves of a held-out problem (each drawn from its axis's test distribution)."""
HELD_OUT_SEED = 20261202
"""The default seed of the held-out draws."""


def held_out(n: int, seed: int) -> list[str]:
    """``n`` problems per axis of :data:`HELD_OUT_AXES`, each :data:`HELD_OUT_MOVES` moves
    ``test-<s>`` of seeds drawn by ``seed`` (from 10 000 up: the axes' test sets use
    0–31, their train sets 0–15), as ``AXIS_FILE:test-s1,test-s2,...``."""
    rng = np.random.default_rng(seed)
    out = []
    for axis in HELD_OUT_AXES:
        for _ in range(n):
            seeds = rng.choice(np.arange(10_000, 1_000_000), HELD_OUT_MOVES, replace=False)
            out.append(f"{axis}:" + ",".join(f"test-{int(x)}" for x in sorted(seeds)))
    return out


def grid_command(problem: str, refs: str) -> str:
    """The ``vfgym grid`` command of a problem's reference (the main job's coarse grid:
    experiments/grid-quick.yaml's 7 points, 3 rounds around the best 3)."""
    cfg = problem_config(problem)
    where = f"--axis {cfg.axis_file} " if cfg.axis_file else ""
    return (f"vfgym grid {where}--scenarios {cfg.scenarios} --points 7 --refine 3 --keep 3 "
            f"--runs-dir {refs} --no-progress")  # fmt: skip


def problem_config(problem: str, **kw: object) -> tuning.SweepConfig:
    """The sweep configuration of a problem: a scenario set, or ``AXIS_FILE:SET``."""
    if problem.endswith(".yaml") or ".yaml:" in problem:
        axis, _, scen = problem.partition(".yaml")
        scen = scen.lstrip(":") or "train"
        return tuning.SweepConfig(axis=axis + ".yaml", scenarios=scen, **kw)  # type: ignore[arg-type]
    return tuning.SweepConfig(scenarios=problem, **kw)  # type: ignore[arg-type]


def problem_reference(refs: str, problem: str) -> FoundReference:
    """The grid reference of a problem in the runs folder ``refs`` (exits if none)."""
    cfg = problem_config(problem)
    found = find_reference(None, refs, cfg.scenario_list(), ("rise",), cfg.axis_key())
    if found is None:
        raise SystemExit(f"no grid reference for {problem} in {refs}/grid/*/")
    return found


CHECKPOINTS = (50, 100, 200)


@dataclass(frozen=True)
class Run:
    """One seeded sweep: best feasible gap (%) after each trial and when each trial ended."""

    gaps: list[float]
    seconds: list[float]
    best_feasible: bool

    def trials_to(self, pct: float) -> int | None:
        return next((i + 1 for i, g in enumerate(self.gaps) if g <= pct), None)

    def seconds_to(self, pct: float) -> float | None:
        n = self.trials_to(pct)
        return None if n is None else self.seconds[n - 1]

    def gap_after(self, n: int) -> float:
        return self.gaps[min(n, len(self.gaps)) - 1] if self.gaps else math.inf


def run_one(
    problem: str, sampler: str, seed: int, trials: int, ref_cost: float, storage: str = "sqlite"
) -> Run:
    """The sweep's worker on a fresh SQLite study; the trials read back in completion order."""
    with tempfile.TemporaryDirectory(prefix="vfgym-ttr-") as tmp:
        cfg = problem_config(
            problem, sampler=sampler, objective="cost", trials=trials, seed=seed,
            storage=f"sqlite:///{tmp}/study.db" if storage == "sqlite" else f"journal:{tmp}/j.log",
            progress=False, plots=False,
        )  # fmt: skip
        spec = tuning.resolve_storage(cfg.storage, Path(tmp))
        tuning.create_or_load(tuning.open_storage(spec), "s", cfg, cfg.scenario_list())
        start = dt.datetime.now()
        tuning.run_worker(cfg, spec, "s")
        study = optuna.load_study(study_name="s", storage=tuning.open_storage(spec))
        done = study.get_trials(deepcopy=False, states=(optuna.trial.TrialState.COMPLETE,))
        done.sort(key=lambda t: (t.datetime_complete, t.number))
        best, gaps, secs = math.inf, [], []
        for t in done:
            res = tuning.stored_result(t)
            if res is not None and res.feasible:
                best = min(best, res.cost)
            gaps.append(gap_pct(best, ref_cost) if best < math.inf else math.inf)
            secs.append((t.datetime_complete - start).total_seconds())
        top = tuning.best_trial(study)
        top_res = None if top is None else tuning.stored_result(top)
        return Run(gaps, secs, bool(top_res is not None and top_res.feasible))


BATCHES = {"tpe": 1, "gp": 8, "cmaes": 8, "nsga2": 8, "random": 16}
"""Trials asked before the first is told, by sampler: TPE one at a time; the GP sampler 8,
conditioned on the running ones (the compass's model batch); CMA-ES's population (4 + 3
ln 4 = 8 in four dimensions), a share of NSGA-II's generation; random sampling 16."""
CMA_SIGMA0 = 0.1
"""CMA-ES's first step in unit coordinates (about half a natural-log unit on each axis:
the compass's first step, 0.4, is 0.07–0.1 of them)."""


def relative_sampler(name: str, seed: int, x0: dict[str, float]) -> optuna.samplers.BaseSampler:
    """An Optuna sampler over the unit coordinates ``u0``–``u3``, seeded; CMA-ES from ``x0``
    with ``sigma0`` :data:`CMA_SIGMA0`."""
    s = optuna.samplers
    if name == "tpe":
        return s.TPESampler(seed=seed, multivariate=True)
    if name == "cmaes":
        return s.CmaEsSampler(x0=x0, sigma0=CMA_SIGMA0, seed=seed, warn_independent_sampling=False)
    if name == "gp":
        return s.GPSampler(seed=seed, deterministic_objective=True)
    if name == "nsga2":
        return s.NSGAIISampler(seed=seed)
    if name == "random":
        return s.RandomSampler(seed=seed)
    raise ValueError(f"sampler={name!r}: not one of {', '.join(BATCHES)}")


def run_relative(
    problem: str, sampler: str, seed: int, trials: int, ref_cost: float, storage: str = "sqlite"
) -> Run:
    """An Optuna sampler on :class:`vfgym.space.Relative`'s unit coordinates (``u0``–``u3``),
    the warm starts enqueued first, told the log cost with the constraints set on each
    trial, asked :data:`BATCHES` trials at a time; on a fresh study on a file."""
    cfg = problem_config(problem, objective="cost")
    scenarios = cfg.scenario_list()
    base = cfg.axis.plant
    rel = relative_space(scenarios, base)
    law = cfg.laws[0]
    objective = tuning.Objective(scenarios, cfg.laws, "cost", axis=cfg.axis,
                                 aggregate=cfg.aggregate, cvar_alpha=cfg.cvar_alpha)  # fmt: skip
    starts = [s for _, s in tuning.warm_starts(scenarios, base)]
    scored = objective.score_many(starts)  # (not counted: the study scores them again)
    best_start = min(
        range(len(starts)), key=lambda i: (not scored[i].attrs["feasible"], scored[i].values)
    )
    names = [f"u{i}" for i in range(len(space.SPACE))]
    units = [dict(zip(names, map(float, rel.to_unit(s)), strict=True)) for s in starts]
    dists = {n: optuna.distributions.FloatDistribution(0.0, 1.0) for n in names}
    with tempfile.TemporaryDirectory(prefix="vfgym-ttr-") as tmp:
        url = f"sqlite:///{tmp}/study.db" if storage == "sqlite" else f"journal:{tmp}/j.log"
        spec = tuning.resolve_storage(url, Path(tmp))
        study = optuna.create_study(
            storage=tuning.open_storage(spec),
            sampler=relative_sampler(sampler, seed, units[best_start]),
        )
        for u in units:
            study.enqueue_trial(u)
        start = time.monotonic()
        best, gaps, secs, top = math.inf, [], [], None
        while len(gaps) < trials:
            asked = [study.ask(dists) for _ in range(min(BATCHES[sampler], trials - len(gaps)))]
            settings = [rel.settings([t.params[n] for n in names], law) for t in asked]
            for t, res in zip(asked, objective.score_many(settings), strict=True):
                for name, v in zip(CONSTRAINTS, res.attrs["constraints"], strict=True):
                    t.set_constraint(name, v)
                study.tell(t, math.log(max(float(res.values), 1e-12)))
                if res.attrs["feasible"] and res.values < best:
                    best = float(res.values)
                key = (not res.attrs["feasible"], res.values)
                top = key if top is None or key < top else top
                gaps.append(gap_pct(best, ref_cost) if best < math.inf else math.inf)
                secs.append(time.monotonic() - start)
    return Run(gaps, secs, bool(top is not None and not top[0]))


SEARCHES = {
    "compass": "Relative; the warm starts enqueued; a trial at a time (the worker)",
    **{
        k: f"Relative (u0-u3); the warm starts enqueued; told the log cost; batch {v}"
        + (f"; x0 the better warm start, sigma0 {CMA_SIGMA0}" if k == "cmaes" else "")
        + ("; conditioned on the running trials" if k == "gp" else "")
        for k, v in BATCHES.items()
    },
}
"""What each sampler searches, from where, in batches of how many (printed with the table)."""


def p90(values: list[float]) -> float:
    """The 90th percentile by nearest rank (the ⌈0.9·n⌉-th smallest; of 5 seeds, the worst)."""
    x = sorted(values)
    return x[max(math.ceil(0.9 * len(x)), 1) - 1]


def _spread(values: list[float | None], fmt: str, cap: str) -> str:
    """``median / 90th percentile`` of values where None is "not reached" (``cap``)."""
    x = sorted(math.inf if v is None else v for v in values)
    med = statistics.median(x)

    def show(v: float) -> str:
        return cap if v == math.inf else format(v, fmt)

    return f"{show(med)} / {show(p90(x))}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--refs", default="runs", help="runs folder holding the grid references")
    ap.add_argument("--problems", default=";".join(PROBLEMS), help="';'-separated scenario sets")
    ap.add_argument("--samplers", default=",".join(s for s in tuning.SAMPLERS if s != "grid"))
    ap.add_argument("--seeds", default="0,1,2,3,4")
    ap.add_argument("--max-trials", type=int, default=200)
    ap.add_argument("--cap", default="gp=100", help="fewer trials for slow samplers, e.g. gp=100")
    ap.add_argument("--storage", default="sqlite", choices=("sqlite", "journal"))
    ap.add_argument("--held-out", type=int, default=0, help="held-out problems per axis")
    ap.add_argument("--held-out-seed", type=int, default=HELD_OUT_SEED)
    ap.add_argument(
        "--print-held-out",
        action="store_true",
        help="print the held-out problems and their grid commands, and exit",
    )
    args = ap.parse_args()
    problems = [p for p in args.problems.split(";") if p]
    if args.held_out:
        extra = held_out(args.held_out, args.held_out_seed)
        print(f"held-out problems: {args.held_out} per axis of {', '.join(HELD_OUT_AXES)}, "
              f"{HELD_OUT_MOVES} test moves each, drawn by seed {args.held_out_seed}")  # fmt: skip
        for p in extra:
            print(f"  {p}\n    reference: {grid_command(p, args.refs)}")
        if args.print_held_out:
            return
        problems += extra
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    warnings.filterwarnings("ignore")
    caps = {k: int(v) for k, v in (c.split("=") for c in args.cap.split(",") if c)}
    seeds = [int(s) for s in args.seeds.split(",")]
    head = (f"{'sampler':8s} {'trials to 1 %':>14s} {'to 2 %':>12s} {'s to 1 %':>14s} "
            f"{'s to 2 %':>14s} " + " ".join(f"{'gap@' + str(n):>8s}" for n in CHECKPOINTS)
            + "  best feasible")  # fmt: skip
    for name in args.samplers.split(","):
        print(f"{name}: {SEARCHES.get(name, '?')}")
    for problem in problems:
        found = problem_reference(args.refs, problem)
        ref_cost = float(found[0]["cost"])
        load = os.getloadavg()[0]
        print(f"\n{problem}: reference {found[1]} cost {ref_cost:.6f} "
              f"({found[0].get('evaluated', '?')} settings); load average {load:.1f}")  # fmt: skip
        print(head)
        for sampler in args.samplers.split(","):
            n = min(args.max_trials, caps.get(sampler, args.max_trials))
            t0 = time.monotonic()
            run = run_one if sampler == "compass" else run_relative
            runs = [run(problem, sampler, s, n, ref_cost, args.storage) for s in seeds]
            cap = f">{n}"
            gaps = " ".join(
                f"{statistics.median(r.gap_after(c) for r in runs):+8.2f}" if c <= n else "       -"
                for c in CHECKPOINTS
            )
            print(
                f"{sampler:8s} {_spread([r.trials_to(1.0) for r in runs], 'g', cap):>14s} "
                f"{_spread([r.trials_to(2.0) for r in runs], 'g', cap):>12s} "
                f"{_spread([r.seconds_to(1.0) for r in runs], '.1f', '-'):>14s} "
                f"{_spread([r.seconds_to(2.0) for r in runs], '.1f', '-'):>14s} {gaps}  "
                f"{sum(r.best_feasible for r in runs)}/{len(runs)}"
                f"   [{time.monotonic() - t0:.0f} s, load {os.getloadavg()[0]:.1f}]",
                flush=True,
            )


if __name__ == "__main__":
    main()
