"""A sweep's overhead: its trials' time against the kernel's for the same settings; prints
figures, asserts nothing (machines are noisy).

Runs the main job (``experiments/quick.yaml``: the compass on the default axis's 16 train
moves, the default SQLite storage, one worker) for ``--trials`` trials in a fresh folder,
timing the trials (:func:`vfgym.tuning.run_worker`, the study already created, the
kernel already compiled: what a sweep adds to the simulation), then simulates the
settings those trials drew again, one setting a call (:func:`vfgym.evaluate` on the same
moves), and prints both and their ratio. ``--long N`` also runs an ``N``-trial sweep and
prints the ratio of its trials' time to the first's, and to its own first ``--trials``
(the same trials, timed in the same run: the ratio least disturbed by a load that
changes between runs), and the wall time a trial of its first, second and last hundred
took (cost per trial growing with the study's size shows in the last against the second:
the first hundred are mostly the compass's polls, the rest mostly model batches).

``--repeat N`` times the short sweep and the kernel N times each, alternately, and takes
the fastest of each (on a shared machine one run may be twice another); ``--sql`` counts
the SQL statements of one more short sweep, not timed (what a trial costs the storage,
whatever the load).

    python benchmarks/bench_sweep.py [--trials 100] [--long 1000] [--repeat 1] [--sql]
        [--config FILE] [--dump FILE]
"""

from __future__ import annotations

import argparse
import datetime
import json
import tempfile
import time
from pathlib import Path
from typing import NamedTuple

from vfgym import evaluate, space, tuning
from vfgym.io.runs import read_yaml

ROOT = Path(__file__).resolve().parents[1]


class Seconds(NamedTuple):
    """Wall-clock and CPU seconds (the process's, all threads)."""

    wall: float
    cpu: float

    def __str__(self) -> str:
        return f"{self.wall:.2f} s wall, {self.cpu:.2f} s CPU"

    def over(self, other: Seconds) -> str:
        """Their ratios, wall and CPU."""
        return f"{self.wall / other.wall:.1f}x wall, {self.cpu / other.cpu:.1f}x CPU"


class Sweep(NamedTuple):
    """A timed sweep: its seconds, the settings of its completed trials, the wall
    seconds each trial took, by completion (from the previous completion, or the sweep's
    start), and the SQL statements it ran."""

    seconds: Seconds
    settings: list
    per_trial: list[float]
    statements: int


def sweep_seconds(
    config: Path, trials: int, folder: Path, dump: str = "", sql: bool = False
) -> Sweep:
    """``trials`` trials of the config's sweep in ``folder``, timed (and with ``sql``,
    the SQL statements of every engine counted: a little slower)."""
    import optuna
    import sqlalchemy

    cfg = tuning.SweepConfig.resolve(
        read_yaml(config), {"trials": trials, "runs_dir": str(folder)}, source=str(config)
    )
    spec = tuning.resolve_storage(cfg.storage, folder / "sweep")
    (folder / "sweep").mkdir(parents=True, exist_ok=True)
    storage = tuning.open_storage(spec, cfg.heartbeat, cfg.grace)
    study, _ = tuning.create_or_load(storage, "bench", cfg, cfg.scenario_list())
    scenarios = cfg.scenario_list()
    evaluate(space.Settings(), scenarios[:1], axis=cfg.axis)  # compiled
    statements = [0]

    def count(*_: object) -> None:
        statements[0] += 1

    start = datetime.datetime.now()
    if sql:
        sqlalchemy.event.listen(sqlalchemy.engine.Engine, "before_cursor_execute", count)
    t, c = time.perf_counter(), time.process_time()
    tuning.run_worker(cfg, spec, "bench")
    seconds = Seconds(time.perf_counter() - t, time.process_time() - c)
    if sql:
        sqlalchemy.event.remove(sqlalchemy.engine.Engine, "before_cursor_execute", count)
    if dump:
        params = [tr.params for tr in study.get_trials(deepcopy=False)]
        Path(dump).write_text(json.dumps(params, indent=0))
    done = study.get_trials(deepcopy=False, states=(optuna.trial.TrialState.COMPLETE,))
    ends = sorted(tr.datetime_complete for tr in done if tr.datetime_complete is not None)
    per_trial = [(b - a).total_seconds() for a, b in zip([start, *ends[:-1]], ends, strict=True)]
    settings = [tuning.trial_settings(tr) for tr in done]
    return Sweep(seconds, settings, per_trial, statements[0])


def block_ms(per_trial: list[float], first: int, last: int) -> float:
    """Mean wall milliseconds a trial of ``first`` … ``last - 1`` (by completion) took."""
    part = per_trial[first:last]
    return 1000.0 * sum(part) / max(len(part), 1)


def kernel_seconds(config: Path, settings: list) -> Seconds:
    """Seconds to simulate each setting on the config's moves, one setting a call."""
    cfg = tuning.SweepConfig.resolve(read_yaml(config), {}, source=str(config))
    scenarios = cfg.scenario_list()
    axis = cfg.axis
    evaluate(settings[0], scenarios, axis=axis)  # compiled
    t, c = time.perf_counter(), time.process_time()
    for s in settings:
        evaluate(s, scenarios, axis=axis)
    return Seconds(time.perf_counter() - t, time.process_time() - c)


def fastest(times: list[Seconds]) -> Seconds:
    """The least wall and the least CPU time among repeats (the run least disturbed by
    other jobs: on a shared machine the spread is large)."""
    return Seconds(min(t.wall for t in times), min(t.cpu for t in times))


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--config", type=Path, default=ROOT / "experiments" / "quick.yaml")
    p.add_argument("--trials", type=int, default=100)
    p.add_argument("--long", type=int, default=0, help="also an N-trial sweep (0: not)")
    p.add_argument("--dump", default="", help="write the trials' parameters to this JSON file")
    p.add_argument(
        "--repeat", type=int, default=1, help="time the short sweep and the kernel N times "
        "each, alternately, and take the fastest of each (the long sweep runs once)",
    )  # fmt: skip
    p.add_argument("--sql", action="store_true", help="count one more short sweep's SQL statements")
    a = p.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        sweeps, kernels = [], []
        for i in range(max(a.repeat, 1)):
            dump = a.dump if i == 0 else ""
            sweeps.append(sweep_seconds(a.config, a.trials, Path(tmp) / f"short{i}", dump))
            kernels.append(kernel_seconds(a.config, sweeps[-1].settings))
        settings = sweeps[0].settings
        sweep_s, kernel_s = fastest([s.seconds for s in sweeps]), fastest(kernels)
        of = f" (fastest of {len(sweeps)})" if len(sweeps) > 1 else ""
        print(f"sweep, {len(settings)} trials ({a.config.name}, sqlite): {sweep_s}{of}")
        print(f"kernel, the same {len(settings)} settings one a call: {kernel_s}{of}")
        print(f"sweep / kernel: {sweep_s.over(kernel_s)} (target <= 4x)")
        if a.sql:  # one more run: counting slows each statement down
            counted = sweep_seconds(a.config, a.trials, Path(tmp) / "counted", "", True)
            print(f"SQL statements a trial: {counted.statements / len(counted.settings):.1f}")
        if a.long:
            long_s, done, per_trial, _ = sweep_seconds(a.config, a.long, Path(tmp) / "long")
            print(f"sweep, {len(done)} trials: {long_s}")
            print(
                f"{len(done)} / {len(settings)} trials, time: {long_s.over(sweep_s)} "
                f"(target <= {1.2 * len(done) / len(settings):.1f}x: 12x for 1,000 / 100)"
            )
            first = sum(per_trial[: len(settings)])
            print(
                f"{len(done)} trials / their first {len(settings)} (the short sweep's trials, "
                f"timed in the same run): {sum(per_trial) / first:.1f}x wall"
            )
            n, k = len(per_trial), min(100, len(per_trial) // 3)
            if k:
                blocks = [(0, k), (k, 2 * k), (n - k, n)]
                ms = [block_ms(per_trial, lo, hi) for lo, hi in blocks]
                print(
                    "wall ms a trial of the long sweep, by completion: "
                    + ", ".join(
                        f"{lo}-{hi - 1}: {m:.1f}" for (lo, hi), m in zip(blocks, ms, strict=True)
                    )
                    + f"; last / second block: {ms[2] / ms[1]:.2f}x (growth with the study)"
                )


if __name__ == "__main__":
    main()
