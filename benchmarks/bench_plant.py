"""Plant throughput and cold start: prints figures, asserts nothing (machines are noisy).

Ticks per second on the paper step (10 rad, baseline settings) for the compiled kernel
with measures only, with the full per-tick trace, and for the plain-Python reference;
and on the same step with a compliant transmission (the issue's example: the load beyond
a 1 N·m/rad spring, ~49 Hz; and with Coulomb friction, the load ringing on a held motor),
as a ratio to the rigid kernel's: ratios are taken within this one run, each pair timed
in turns. Cold start: `import vfgym` plus the first
simulation in a fresh process, with numba's cache cold (a new cache directory) and warm.

``--cold`` prints only the first-use compile of each entry point (simulate, evaluate,
VFServo-v0's step, the vector env's SIMD-lane step on the calling thread (16 envs) and on
numba's threads (512 envs), VFTune-v0's vector step): its CPU
seconds in a fresh process with an empty cache and with the cache it left (CPU time, not
wall time: on a shared machine the wall time mostly measures the others' load), the
figures vfgym's one-line compile notice quotes (``vfgym.plant._notice.COLD_COMPILE_S``).

    python benchmarks/bench_plant.py [--ticks N] [--repeats R] [--cold]
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

from vfgym import DEFAULT_MEASURES, PAPER_PLANT, PAPER_SETTINGS, Transmission, step_command
from vfgym.plant import _kernel as K
from vfgym.plant import _layout as L
from vfgym.plant import pack
from vfgym.plant.reference import reference_run

COLD = (
    "import time; t=time.perf_counter(); import vfgym; "
    "vfgym.simulate(vfgym.step_command(10.0, 14000)); print(time.perf_counter()-t)"
)


def best_rate(fn, ticks: int, repeats: int) -> float:
    """Best of ``repeats`` runs, in ticks per second."""
    best = float("inf")
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t)
    return ticks / best


def rates_in_turns(fns, ticks: int, repeats: int) -> list[float]:
    """Best rate of each function (ticks per CPU second), timed in turns, so that a change
    of the machine's load hits them alike (CPU time: on a shared machine wall time mostly
    measures the others' load)."""
    best = [float("inf")] * len(fns)
    for _ in range(repeats):
        for j, fn in enumerate(fns):
            t = time.process_time()
            fn()
            best[j] = min(best[j], time.process_time() - t)
    return [ticks / b for b in best]


COMPLIANT = {
    "compliant": PAPER_PLANT.with_motor(inertia_ratio=0.5).replace(
        transmission=Transmission(3.0e-5, 1.0, 0.002)
    ),
    "compliant + Coulomb": PAPER_PLANT.with_motor(inertia_ratio=0.5, coulomb_nm=0.02).replace(
        transmission=Transmission(3.0e-5, 1.0, 0.002)
    ),
}
"""The two-mass plants timed against the rigid paper plant (the issue's example)."""


def cold_start(cache_dir: str) -> float:
    env = dict(os.environ, NUMBA_CACHE_DIR=cache_dir)
    out = subprocess.run(
        [sys.executable, "-c", COLD], env=env, check=True, capture_output=True, text=True
    )
    return float(out.stdout.strip())


FIRST_USE = {
    "simulate": "vfgym.simulate(vfgym.step_command(10.0, 14000))",
    "evaluate": "vfgym.evaluate(['paper'], ['short-move'])",
    "servo env": (
        "e = gym.make('vfgym/VFServo-v0'); e.reset(seed=0); e.step(np.zeros(4, np.float32))"
    ),
    "vector env": (
        "e = gym.make_vec('vfgym/VFServo-v0', num_envs=16, vectorization_mode="
        "'vector_entry_point'); e.reset(seed=0); e.step(np.zeros((16, 4), np.float32))"
    ),
    "vector env, threads": (
        "e = gym.make_vec('vfgym/VFServo-v0', num_envs=512, vectorization_mode="
        "'vector_entry_point'); e.reset(seed=0); e.step(np.zeros((512, 4), np.float32))"
    ),
    "VFTune vector env": (
        "e = gym.make_vec('vfgym/VFTune-v0', num_envs=4, vectorization_mode="
        "'vector_entry_point'); e.reset(seed=0); e.step(np.zeros((4, 4), np.float32))"
    ),
}
"""The first call of each entry point, as the compile notice names them."""


def first_use(code: str, cache_dir: str) -> tuple[float, float, str]:
    """(CPU s, wall s, stderr) of ``code`` after ``import vfgym`` in a fresh process."""
    prog = (
        "import time, gymnasium as gym, numpy as np, vfgym\n"
        "c, w = time.process_time(), time.perf_counter()\n"
        f"{code}\n"
        "print(time.process_time() - c, time.perf_counter() - w)"
    )
    env = dict(os.environ, NUMBA_CACHE_DIR=cache_dir)
    out = subprocess.run(
        [sys.executable, "-c", prog], env=env, check=True, capture_output=True, text=True
    )
    cpu, wall = out.stdout.split()[-2:]
    return float(cpu), float(wall), out.stderr.strip()


def cold_compiles() -> None:
    """Print each entry point's first-use compile, cold and warm cache."""
    load = ", ".join(f"{x:.2f}" for x in os.getloadavg())
    print(f"first-use compile, fresh process and cache (load average {load})")
    for name, code in FIRST_USE.items():
        with tempfile.TemporaryDirectory() as cache:
            cpu, wall, notice = first_use(code, cache)
            warm_cpu, _, warm_notice = first_use(code, cache)
        lines = notice.splitlines()
        progress = f" (+ {len(lines) - 1} progress lines)" if len(lines) > 1 else ""
        print(
            f"  {name:19s}: cold {cpu:6.1f} s CPU ({wall:6.1f} s wall), warm {warm_cpu:5.2f} s "
            f"CPU; notice cold: {lines[0] if lines else '-'}{progress}; warm: {warm_notice or '-'}"
        )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ticks", type=int, default=2_800_000, help="ticks per kernel run")
    ap.add_argument("--ref-ticks", type=int, default=70_000, help="ticks per reference run")
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--cold", action="store_true", help="only the first-use compiles")
    args = ap.parse_args()
    if args.cold:
        cold_compiles()
        return
    n = args.ticks
    cmd = step_command(10.0, n)
    prm = pack(PAPER_SETTINGS, PAPER_PLANT, DEFAULT_MEASURES, 10.0, n)
    ext = np.zeros(0, np.int8)
    acc = K.new_acc()
    no_rec = np.zeros((L.N_ROWS, 0))
    rec = np.empty((L.N_ROWS, n))
    K.run_one(cmd[:100], ext, prm, acc, no_rec, 1)  # compile outside the timing
    metrics = best_rate(lambda: K.run_one(cmd, ext, prm, acc, no_rec, 1), n, args.repeats)
    full = best_rate(lambda: K.run_one(cmd, ext, prm, acc, rec, 1), n, args.repeats)
    m = args.ref_ticks
    ref = best_rate(lambda: reference_run(cmd[:m], ext, prm), m, 1)
    print(f"paper step, {n} ticks, one core")
    print(f"  kernel, measures only : {metrics / 1e6:8.1f} M ticks/s   (target >= 50)")
    print(f"  kernel, full trace    : {full / 1e6:8.1f} M ticks/s   (target >= 25)")
    print(f"  plain-Python reference: {ref / 1e6:8.3f} M ticks/s")
    print(f"  kernel / reference    : {metrics / ref:8.0f} x         (target >= 20)")
    rigid_run = (lambda: K.run_one(cmd, ext, prm, acc, no_rec, 1),)
    for name, plant in COMPLIANT.items():
        prm2 = pack(PAPER_SETTINGS, plant, DEFAULT_MEASURES, 10.0, n)
        K.run_one(cmd[:100], ext, prm2, acc, no_rec, 1)
        rigid, two = rates_in_turns(
            (*rigid_run, lambda p=prm2: K.run_one(cmd, ext, p, acc, no_rec, 1)), n, args.repeats
        )
        print(
            f"  kernel, {name:20s}: {two / 1e6:6.1f} M ticks/CPU s, rigid in turns "
            f"{rigid / 1e6:6.1f}: {two / rigid:5.2f} x the rigid   (target >= 0.5)"
        )
    with tempfile.TemporaryDirectory() as cache:
        cold = cold_start(cache)
        warm = cold_start(cache)
    print(
        f"cold start, import + first simulation: {cold:.2f} s cold cache (target <= 3), "
        f"{warm:.2f} s warm cache (target <= 1)"
    )


if __name__ == "__main__":
    main()
