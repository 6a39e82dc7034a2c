"""``bench_identify.py --part resonance``: a compliant transmission's resonance identified
from simulated captures of the planned moves.

    python benchmarks/bench_identify.py --part resonance [--resonance-plants 10]
        [--seed 20261205]

The nominal axis is ``experiments/axes/belt-compliant.yaml`` (106 Hz, ζ 0.03). Each true
plant is drawn from ``--seed`` (plant k: ``default_rng([seed, 1000 + k])``): its
resonance log-uniform in 20–200 Hz, its damping ratio uniform in 0.02–0.1, the drive's
gain ×0.95–1.05 of the one set. The plan's moves run on it, captured at 1 MHz from 10-100
ms before the drive's enable (as ``--part blocks`` does), then
:func:`vfgym.identify.pipeline.identify_axis` identifies it. Printed per plant: the true
resonance, the guess and the identified one, the error, the 95 % interval, whether it
holds the truth, whether the capture showed the resonance, whether the fit
explains the capture (its residual against the floor it is judged against), the wall and
CPU seconds; then the goal lines (every resonance within 5 %; every identification within
30 s), the intervals that hold the truth and the axes written. It asserts nothing (the
machine is shared).
"""

from __future__ import annotations

import argparse
import math
import tempfile
import time
from pathlib import Path

import numpy as np

from vfgym.axis import PlantVariant, load_axis
from vfgym.identify.capture import read_capture
from vfgym.identify.pipeline import identify_axis
from vfgym.identify.plan import make_plan
from vfgym.identify.resonance_problem import with_resonance
from vfgym.identify.simulated import record_capture
from vfgym.params import PAPER_SETTINGS

AXIS = Path(__file__).resolve().parents[1] / "experiments" / "axes" / "belt-compliant.yaml"
GOAL_SHARE = 0.05
GOAL_S = 30.0


def part_resonance(args: argparse.Namespace) -> None:
    """The resonance of ``--resonance-plants`` drawn compliant plants (module doc)."""
    axis = load_axis(AXIS)
    plan = make_plan(axis, PAPER_SETTINGS)
    n = args.resonance_plants
    print(
        f"\n== resonance: {n} plants of seed {args.seed} on {axis.name}; "
        f"plan {plan.duration_s:.3g} s"
    )
    print(
        "plant  true Hz  zeta   gain   guess Hz  ident Hz  err %   95 % interval Hz     holds  "
        "shown  explained  fit rms  floor  wall s  cpu s"
    )
    errs, walls = [], []
    holds: list[bool] = []
    written: list[bool] = []
    with tempfile.TemporaryDirectory() as tmp:
        for k in range(n):
            rng = np.random.default_rng([args.seed, 1000 + k])
            f = float(math.exp(rng.uniform(math.log(20.0), math.log(200.0))))
            zeta = float(rng.uniform(0.02, 0.1))
            gain = float(rng.uniform(0.95, 1.05))
            u = float(rng.uniform(0.0, 1.0))
            true = PlantVariant(torque_per_count=gain).apply(with_resonance(axis.plant, f, zeta))
            rest = 0.2
            start = -0.1 * u - 0.01
            path = record_capture(
                true,
                plan.pulses,
                Path(tmp) / f"r{k}.vcd",
                start_s=start,
                rest_s=rest,
                length_s=rest - start + plan.duration_s + 0.1,
            )
            t0, c0 = time.perf_counter(), time.process_time()
            ident, _, _ = identify_axis(
                axis, [read_capture(path)], PAPER_SETTINGS, from_enable=True
            )
            wall, cpu = time.perf_counter() - t0, time.process_time() - c0
            res = ident.resonance
            assert res is not None
            err = 100.0 * (res.resonance_hz / f - 1.0)
            errs.append(abs(err))
            walls.append(wall)
            lo, hi = res.resonance_range_hz
            holds.append(lo <= f <= hi)
            written.append(res.shown and ident.explained)
            print(
                f"{k:5d}  {f:7.2f}  {zeta:.3f}  {gain:.3f}  {res.guess_hz:8.2f}  "
                f"{res.resonance_hz:8.2f}  {err:+6.2f}  [{lo:7.2f}, {hi:7.2f}]  "
                f"{'yes' if holds[-1] else 'no':>5}  {'yes' if res.shown else 'no':>5}  "
                f"{'yes' if ident.explained else 'no':>9}  {ident.fit.residual_rms_counts:7.2f}  "
                f"{ident.floor_counts:5.2f}  "
                f"{wall:6.1f}  {cpu:5.1f}",
                flush=True,
            )
    within = sum(e <= 100.0 * GOAL_SHARE for e in errs)
    fast = sum(w <= GOAL_S for w in walls)
    print(
        f"goal: resonance within {GOAL_SHARE:.0%}: {within}/{n} (largest error {max(errs):.2f} %)"
    )
    print(f"goal: identification within {GOAL_S:g} s wall: {fast}/{n} (longest {max(walls):.1f} s)")
    print(f"95 % interval holds the true resonance: {sum(holds)}/{n}")
    print(f"compliant axis written (resonance shown, fit explained): {sum(written)}/{n}")


def main() -> None:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n\n")[0])
    ap.add_argument("--resonance-plants", type=int, default=10)
    ap.add_argument("--seed", type=int, default=20261205)
    part_resonance(ap.parse_args())


if __name__ == "__main__":
    main()
