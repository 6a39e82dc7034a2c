"""The main job's sweep against the floor Optuna itself sets; prints figures, asserts
nothing (machines are noisy: compare the ratios, measured in one run).

The sweep is the command's own path: ``vfgym sweep --config experiments/quick.yaml`` as a
user runs it (a fresh process; only ``--runs-dir``, ``--study`` and, if given,
``--trials`` added), timed by its own report (``N/N completed trials ... in X s``, the
run folder's ``summary.yaml``: from its first trial's start to its last trial's end,
every worker's start-up inside) and as a whole process. The floor is what a user could
reach with Optuna alone on the same problem, in this process: a bare study of as many
trials on the same storage (the config's, opened as the sweep opens it: SQLite in WAL
mode, the heartbeat), each trial suggesting the four settings and returning at once
(Optuna's random sampler: the least a sampler costs), plus the kernel alone on the
sweep's own settings, one setting a call (:func:`vfgym.evaluate` on the same moves, the
axis's design plants with them, compiled first). The target: the sweep's trials at most
1.0x the floor.

``--repeat N`` runs the sweep and the floor N times each, alternately, and takes the
fastest of each (on a shared machine one run may be twice another). ``--sql`` runs the
sweep once more in this process (``vfgym.tuning.sweep``, the command's own call): the SQL
statements of its trials, a trial, and their CPU seconds against the floor's (less
disturbed by other work than wall seconds), of the thread that runs the trials and of
every thread (with those that score ahead and import beside it). ``--long N`` runs an
``N``-trial sweep through the command and prints the wall time a trial of its first,
second and last hundred took (cost per trial growing with the study shows in the last
against the second).

    python benchmarks/bench_sweep.py [--config FILE] [--trials N] [--repeat 1] [--sql]
        [--long 1000]
"""

from __future__ import annotations

import argparse
import datetime
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import NamedTuple

from vfgym import evaluate, space, tuning
from vfgym.io.runs import read_yaml

ROOT = Path(__file__).resolve().parents[1]


class Seconds(NamedTuple):
    """Wall seconds and CPU seconds (the process's, every thread)."""

    wall: float
    cpu: float


class Sweep(NamedTuple):
    """A run of the command: its trials' seconds (as its report prints them), the
    process's wall seconds, the settings of its completed trials, and the wall seconds
    each trial took by completion (from the previous one's, or the trials' start)."""

    trials_s: float
    process_s: float
    settings: list
    per_trial: list[float]


def command(config: Path, folder: Path, trials: int | None) -> list[str]:
    """``vfgym sweep`` on the config as a user runs it, in ``folder``."""
    argv = ["sweep", "--config", str(config), "--runs-dir", str(folder), "--study", "bench"]
    return argv + (["--trials", str(trials)] if trials else [])


def study_of(folder: Path):
    """The sweep's study in ``folder``, opened read-only as ``vfgym plot`` opens it."""
    import optuna

    run = folder / "sweep" / "bench"
    conf = read_yaml(run / "config.yaml")
    storage = tuning.open_storage(tuning.find_storage(conf["storage"], run))
    return optuna.load_study(study_name="bench", storage=storage)


def sweep_seconds(config: Path, folder: Path, trials: int | None) -> Sweep:
    """Run the command in a fresh process and time it."""
    import optuna

    script = Path(sys.executable).with_name("vfgym")  # the console script, as a user runs it
    head = [str(script)] if script.is_file() else [sys.executable, "-m", "vfgym.cli"]
    t = time.perf_counter()
    subprocess.run(
        [*head, *command(config, folder, trials)],
        check=True,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    process_s = time.perf_counter() - t
    summary = read_yaml(folder / "sweep" / "bench" / "summary.yaml")
    study = study_of(folder)
    done = study.get_trials(deepcopy=False, states=(optuna.trial.TrialState.COMPLETE,))
    starts = [tr.datetime_start for tr in done if tr.datetime_start is not None]
    ends = sorted(tr.datetime_complete for tr in done if tr.datetime_complete is not None)
    first = min(starts) if starts else datetime.datetime.now()
    per_trial = [(b - a).total_seconds() for a, b in zip([first, *ends[:-1]], ends, strict=True)]
    settings = [tuning.trial_settings(tr) for tr in done]
    return Sweep(float(summary["elapsed_s"]), process_s, settings, per_trial)


def bare_optuna_seconds(config: Path, folder: Path, trials: int) -> Seconds:
    """A bare Optuna study of ``trials`` trials on the config's storage, opened as the
    sweep opens it; each trial suggests the four settings and returns 0."""
    import optuna

    cfg = tuning.SweepConfig.resolve(read_yaml(config), {}, source=str(config))
    folder.mkdir(parents=True, exist_ok=True)
    storage = tuning.open_storage(
        tuning.resolve_storage(cfg.storage, folder), cfg.heartbeat, cfg.grace
    )
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    study = optuna.create_study(
        storage=storage, study_name="bare", sampler=optuna.samplers.RandomSampler(seed=0)
    )
    dists = space.distributions(cfg.laws)

    def objective(trial: optuna.Trial) -> float:
        for name, d in dists.items():
            if isinstance(d, optuna.distributions.FloatDistribution):
                trial.suggest_float(name, d.low, d.high, log=d.log)
            else:
                trial.suggest_categorical(name, d.choices)
        return 0.0

    t, c = time.perf_counter(), time.process_time()
    study.optimize(objective, n_trials=trials)
    return Seconds(time.perf_counter() - t, time.process_time() - c)


def kernel_seconds(config: Path, settings: list) -> Seconds:
    """Seconds to score each setting on the config's moves as a trial scores it (the
    axis's design plants too), one setting a call, compiled first."""
    cfg = tuning.SweepConfig.resolve(read_yaml(config), {}, source=str(config))
    scenarios, axis = cfg.scenario_list(), cfg.axis
    plants = axis.design_plants()
    evaluate(settings[0], scenarios, axis=axis, plants=plants)  # compiled
    t, c = time.perf_counter(), time.process_time()
    for s in settings:
        evaluate(s, scenarios, axis=axis, plants=plants)
    return Seconds(time.perf_counter() - t, time.process_time() - c)


class InProcess(NamedTuple):
    """The sweep run in this process: SQL statements a trial, and over its trials the
    wall seconds, the CPU seconds of every thread and those of the calling thread (the
    one that runs the trials; the others score ahead and import)."""

    statements: float
    wall: float
    cpu: float
    main_cpu: float


def in_process(config: Path, folder: Path, trials: int | None) -> InProcess:
    """The sweep run in this process (:func:`vfgym.tuning.sweep`, the command's own call),
    its SQL statements counted and its seconds taken from the study's opening to its last
    trial's end (a little slower)."""
    import sqlalchemy

    count, on, marks = [0], [False], []

    def counted(*_: object) -> None:
        count[0] += on[0]

    def mark() -> None:
        marks.append((time.perf_counter(), time.process_time(), time.thread_time()))

    def start(_: tuning.SweepStart) -> None:
        on[0] = True
        mark()

    def stop(p: tuning.SweepProgress) -> None:
        if p.final and on[0]:
            on[0] = False
            mark()

    over = {"runs_dir": str(folder), "study": "bench", "plots": False, "progress": False}
    cfg = tuning.SweepConfig.resolve(
        read_yaml(config), over | ({"trials": trials} if trials else {})
    )
    sqlalchemy.event.listen(sqlalchemy.engine.Engine, "before_cursor_execute", counted)
    try:
        result = tuning.sweep(cfg, on_start=start, on_progress=stop)
    finally:
        sqlalchemy.event.remove(sqlalchemy.engine.Engine, "before_cursor_execute", counted)
    (w0, c0, m0), (w1, c1, m1) = marks
    return InProcess(count[0] / max(result.counts.complete, 1), w1 - w0, c1 - c0, m1 - m0)


def block_ms(per_trial: list[float], first: int, last: int) -> float:
    """Mean wall milliseconds a trial of ``first`` … ``last - 1`` (by completion) took."""
    part = per_trial[first:last]
    return 1000.0 * sum(part) / max(len(part), 1)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--config", type=Path, default=ROOT / "experiments" / "quick.yaml")
    p.add_argument("--trials", type=int, default=None, help="the config's unless given")
    p.add_argument("--repeat", type=int, default=1, help="runs of each, alternately (fastest)")
    p.add_argument("--sql", action="store_true", help="count one more sweep's SQL statements")
    p.add_argument("--long", type=int, default=0, help="also an N-trial sweep (0: not)")
    a = p.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        sweeps, bares, kernels = [], [], []
        for i in range(max(a.repeat, 1)):
            sweeps.append(sweep_seconds(a.config, Path(tmp) / f"sweep{i}", a.trials))
            n = len(sweeps[-1].settings)
            bares.append(bare_optuna_seconds(a.config, Path(tmp) / f"bare{i}", n))
            kernels.append(kernel_seconds(a.config, sweeps[-1].settings))
        n = len(sweeps[0].settings)
        trials_s = min(s.trials_s for s in sweeps)
        bare = Seconds(min(b.wall for b in bares), min(b.cpu for b in bares))
        kernel = Seconds(min(k.wall for k in kernels), min(k.cpu for k in kernels))
        of = f" (fastest of {len(sweeps)})" if len(sweeps) > 1 else ""
        print(f"vfgym sweep --config {a.config.name}, {n} trials: {trials_s:.2f} s (its report)"
              f"; the whole process {min(s.process_s for s in sweeps):.2f} s{of}")  # fmt: skip
        print(f"floor: a bare Optuna study of {n} trials on the same storage {bare.wall:.2f} s "
              f"+ the kernel alone on the same settings {kernel.wall:.2f} s{of}")  # fmt: skip
        print(f"sweep / floor: {trials_s / (bare.wall + kernel.wall):.2f}x (target <= 1.0x)")
        if a.sql:
            run = in_process(a.config, Path(tmp) / "counted", a.trials)
            print(f"SQL statements a trial: {run.statements:.1f}")
            print(
                f"CPU seconds over the trials, the sweep in this process: {run.cpu:.2f} s "
                f"(the thread running the trials {run.main_cpu:.2f} s; wall {run.wall:.2f} s); "
                f"the floor's: {bare.cpu:.2f} + {kernel.cpu:.2f} s{of}; sweep / floor: "
                f"{run.cpu / (bare.cpu + kernel.cpu):.2f}x all threads, "
                f"{run.main_cpu / (bare.cpu + kernel.cpu):.2f}x the trials' thread"
            )
        if a.long:
            long = sweep_seconds(a.config, Path(tmp) / "long", a.long)
            done, per_trial = len(long.settings), long.per_trial
            print(f"vfgym sweep, {done} trials: {long.trials_s:.2f} s (its report), "
                  f"{long.trials_s / trials_s:.1f}x the {n}-trial sweep")  # fmt: skip
            k = min(100, done // 3)
            if k:
                blocks = [(0, k), (k, 2 * k), (done - k, done)]
                ms = [block_ms(per_trial, lo, hi) for lo, hi in blocks]
                each = [f"{lo}-{hi - 1}: {m:.1f}" for (lo, hi), m in zip(blocks, ms, strict=True)]
                print(
                    f"wall ms a trial, by completion: {', '.join(each)}; last / second block: "
                    f"{ms[2] / ms[1]:.2f}x (growth with the study)"
                )


if __name__ == "__main__":
    main()
