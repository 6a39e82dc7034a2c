"""A sweep's overhead: its trials' time against the kernel's for the same settings; prints
figures, asserts nothing (machines are noisy).

Runs the main job (``experiments/quick.yaml``: the compass on the default axis's 16 train
moves, the default SQLite storage, one worker) for ``--trials`` trials in a fresh folder,
timing the trials (:func:`vfgym.tuning.run_worker`, the study already created, the
kernel already compiled: what a sweep adds to the simulation), then simulates the
settings those trials drew again, one setting a call (:func:`vfgym.evaluate` on the same
moves), and prints both and their ratio. ``--long N`` also runs an ``N``-trial sweep and
prints the ratio of its trials' time to the first's, and the wall time a trial of its
first, second and last hundred took (cost per trial growing with the study's size shows
in the last against the second: the first hundred are mostly the compass's polls, the
rest mostly model batches).

    python benchmarks/bench_sweep.py [--trials 100] [--long 1000] [--config FILE] [--dump FILE]
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
from vfgym.moves.axis import axis_kwargs

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
    """A timed sweep: its seconds, the settings of its completed trials, and the wall
    seconds each trial took, by number (from the previous completion, or the sweep's
    start, to the trial's completion: a batch's time falls on its first trial)."""

    seconds: Seconds
    settings: list
    per_trial: list[float]


def sweep_seconds(config: Path, trials: int, folder: Path, dump: str = "") -> Sweep:
    """``trials`` trials of the config's sweep in ``folder``, timed."""
    import optuna

    cfg = tuning.SweepConfig.resolve(
        read_yaml(config), {"trials": trials, "runs_dir": str(folder)}, source=str(config)
    )
    spec = tuning.resolve_storage(cfg.storage, folder / "sweep")
    (folder / "sweep").mkdir(parents=True, exist_ok=True)
    storage = tuning.open_storage(spec, cfg.heartbeat, cfg.grace)
    study, _ = tuning.create_or_load(storage, "bench", cfg, cfg.scenario_list())
    scenarios = cfg.scenario_list()
    evaluate(space.Settings(), scenarios[:1], **axis_kwargs(cfg.load_axis()))  # compiled
    start = datetime.datetime.now()
    t, c = time.perf_counter(), time.process_time()
    tuning.run_worker(cfg, spec, "bench")
    seconds = Seconds(time.perf_counter() - t, time.process_time() - c)
    if dump:
        params = [tr.params for tr in study.get_trials(deepcopy=False)]
        Path(dump).write_text(json.dumps(params, indent=0))
    done = study.get_trials(deepcopy=False, states=(optuna.trial.TrialState.COMPLETE,))
    ends = sorted(tr.datetime_complete for tr in done if tr.datetime_complete is not None)
    per_trial = [(b - a).total_seconds() for a, b in zip([start, *ends[:-1]], ends, strict=True)]
    settings = [space.settings_from_dict(tr.user_attrs["settings"]) for tr in done]
    return Sweep(seconds, settings, per_trial)


def block_ms(per_trial: list[float], first: int, last: int) -> float:
    """Mean wall milliseconds a trial of ``first`` … ``last - 1`` (by completion) took."""
    part = per_trial[first:last]
    return 1000.0 * sum(part) / max(len(part), 1)


def kernel_seconds(config: Path, settings: list) -> Seconds:
    """Seconds to simulate each setting on the config's moves, one setting a call."""
    cfg = tuning.SweepConfig.resolve(read_yaml(config), {}, source=str(config))
    scenarios = cfg.scenario_list()
    on_axis = axis_kwargs(cfg.load_axis())
    evaluate(settings[0], scenarios, **on_axis)  # compiled
    t, c = time.perf_counter(), time.process_time()
    for s in settings:
        evaluate(s, scenarios, **on_axis)
    return Seconds(time.perf_counter() - t, time.process_time() - c)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--config", type=Path, default=ROOT / "experiments" / "quick.yaml")
    p.add_argument("--trials", type=int, default=100)
    p.add_argument("--long", type=int, default=0, help="also an N-trial sweep (0: not)")
    p.add_argument("--dump", default="", help="write the trials' parameters to this JSON file")
    a = p.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        sweep_s, settings, _ = sweep_seconds(a.config, a.trials, Path(tmp) / "short", a.dump)
        kernel_s = kernel_seconds(a.config, settings)
        print(f"sweep, {len(settings)} trials ({a.config.name}, sqlite): {sweep_s}")
        print(f"kernel, the same {len(settings)} settings one a call: {kernel_s}")
        print(f"sweep / kernel: {sweep_s.over(kernel_s)} (target <= 4x)")
        if a.long:
            long_s, done, per_trial = sweep_seconds(a.config, a.long, Path(tmp) / "long")
            print(f"sweep, {len(done)} trials: {long_s}")
            print(
                f"{len(done)} / {len(settings)} trials, time: {long_s.over(sweep_s)} "
                f"(target <= {1.2 * len(done) / len(settings):.1f}x: 12x for 1,000 / 100)"
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
