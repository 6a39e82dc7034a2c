"""Trials and seconds each sampler needs to get within 1 % and 2 % of the grid optimum, and
its gap after 50, 100 and 200 trials, on several scenario sets over several seeds.

Each (problem, sampler, seed) runs the worker ``vfgym sweep`` runs with one worker: the
same objective, sampler, batch and warm starts (enqueued first), on a SQLite file in a
temporary folder, for ``--max-trials`` completed trials. A trial's gap is its best
feasible cost so far against the problem's grid reference (``vfgym grid``; looked up in
``--refs``, a runs folder of grid runs, by scenario set). Seconds run from the worker's
start (the compiled kernel loaded from numba's cache) to the tell of the trial that
first got within the target; they are wall-clock on whatever else the machine runs
(the load average is printed with each problem).

    vfgym grid --config experiments/grid-paper-step.yaml --runs-dir refs   # one per problem
    python experiments/trials_to_reference.py --refs refs

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

import optuna

from vfgym import tuning
from vfgym.moves.axis import axis_digest

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


def problem_config(problem: str, **kw: object) -> tuning.SweepConfig:
    """The sweep configuration of a problem: a scenario set, or ``AXIS_FILE:SET``."""
    if problem.endswith(".yaml") or ".yaml:" in problem:
        axis, _, scen = problem.partition(".yaml")
        scen = scen.lstrip(":") or "train"
        return tuning.SweepConfig(axis=axis + ".yaml", scenarios=scen, **kw)  # type: ignore[arg-type]
    return tuning.SweepConfig(scenarios=problem, **kw)  # type: ignore[arg-type]


def problem_reference(refs: str, problem: str) -> tuning.FoundReference:
    """The grid reference of a problem in the runs folder ``refs`` (exits if none)."""
    cfg = problem_config(problem)
    found = tuning.find_reference(
        None, refs, cfg.scenario_list(), ("rise",), axis_digest(cfg.load_axis())
    )
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
            if t.user_attrs["feasible"]:
                best = min(best, t.user_attrs["cost"])
            gaps.append(tuning.gap_pct(best, ref_cost) if best < math.inf else math.inf)
            secs.append((t.datetime_complete - start).total_seconds())
        top = tuning.best_trial(study)
        return Run(gaps, secs, bool(top is not None and top.user_attrs["feasible"]))


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
    args = ap.parse_args()
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    warnings.filterwarnings("ignore")
    caps = {k: int(v) for k, v in (c.split("=") for c in args.cap.split(",") if c)}
    seeds = [int(s) for s in args.seeds.split(",")]
    head = (f"{'sampler':8s} {'trials to 1 %':>14s} {'to 2 %':>12s} {'s to 1 %':>14s} "
            f"{'s to 2 %':>14s} " + " ".join(f"{'gap@' + str(n):>8s}" for n in CHECKPOINTS)
            + "  best feasible")  # fmt: skip
    for problem in args.problems.split(";"):
        found = problem_reference(args.refs, problem)
        ref_cost = float(found[0]["cost"])
        load = os.getloadavg()[0]
        print(f"\n{problem}: reference {found[1]} cost {ref_cost:.6f} "
              f"({found[0].get('evaluated', '?')} settings); load average {load:.1f}")  # fmt: skip
        print(head)
        for sampler in args.samplers.split(","):
            n = min(args.max_trials, caps.get(sampler, args.max_trials))
            t0 = time.monotonic()
            runs = [run_one(problem, sampler, s, n, ref_cost, args.storage) for s in seeds]
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
