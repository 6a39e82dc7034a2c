"""``vfgym identify`` on captures of the planned moves from drawn plants: accuracy,
coverage of the 95 % intervals, and wall time.

    python benchmarks/bench_identify.py [--plants 20] [--seed 20261205] [--axis FILE]

Each plant is drawn from ``--seed`` (a stream no test uses): inertia ratio 0–8 on the
nominal axis's motor, Coulomb friction up to 5 % of the rated torque, viscous friction up
to 3e-4 N·m·s/rad, a load torque up to ±5 % of rated; the drive's gain is as set. The
planned moves (``vfgym identify --plan``) run on it after a rest, and a 2 s capture at
1 MHz records them as a logic analyser does (a start at an arbitrary instant of a 0.5 s rest,
edges rounded to 1 µs, the encoder as A/B edges only). The identification (reading the
VCD, placing it on the tick grid, the fit) is timed on the wall clock.

Printed: per plant the errors, then the summary against the goals: inertia within ±2 %,
Coulomb friction and load torque within ±1 % of the rated torque, ≥ 90 % of the 95 %
intervals holding the truth, ≤ 30 s an identification on 2 cores. Coverage counts the
estimated (excited) quantities among inertia, Coulomb, viscous and load torque, and the
gain where it is estimated. It asserts nothing (the machine is shared).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from vfgym.identify.capture import read_capture
from vfgym.identify.fit import fit
from vfgym.identify.model import record_of
from vfgym.identify.plan import make_plan
from vfgym.identify.report import identify_report
from vfgym.identify.signals import record_capture
from vfgym.moves.axis import PAPER_AXIS, load_axis
from vfgym.params import PAPER_SETTINGS
from vfgym.plant.uncertainty import PlantVariant

REST_S = 0.5
CAPTURE_S = 2.0


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--plants", type=int, default=20)
    ap.add_argument("--seed", type=int, default=20261205)
    ap.add_argument("--axis", help="the nominal axis file (default: the paper's axis)")
    args = ap.parse_args(argv)
    axis = load_axis(args.axis) if args.axis else PAPER_AXIS
    nominal = axis.plant
    m = nominal.motor
    rated = m.rated_torque_nm
    plan = make_plan(axis, PAPER_SETTINGS)
    print(
        f"axis {axis.name}: {len(plan.moves)} planned moves, {plan.duration_s:.3g} s; "
        f"captures of {CAPTURE_S:g} s at 1 MHz; {args.plants} plants from seed {args.seed}"
    )
    # compile the kernel outside the timings
    with tempfile.TemporaryDirectory() as tmp:
        warm = record_capture(nominal, plan.pulses[:20000], Path(tmp) / "w.vcd", start_s=0.05)
        fit([record_of(read_capture(warm), nominal)], nominal, PAPER_SETTINGS)
    rows = []
    hits = total = 0
    print(
        "plant  ratio  |dJ| %   dCoulomb %rated  dviscous %rated@top  dload %rated  gain   "
        "rms counts  sat ms  wall s  outside 95 %"
    )
    with tempfile.TemporaryDirectory() as tmp:
        for k in range(args.plants):
            rng = np.random.default_rng([args.seed, k])
            ratio = rng.uniform(0.0, 8.0)
            truth = {
                "inertia": (1.0 + ratio) / (1.0 + m.inertia_ratio),
                "coulomb_nm": rng.uniform(0.0, 0.05) * rated,
                "viscous_nm_s_rad": rng.uniform(0.0, 3e-4),
                "load_torque_nm": rng.uniform(-0.05, 0.05) * rated,
                "torque_per_count": 1.0,
            }
            plant = PlantVariant(
                inertia=truth["inertia"],
                coulomb_offset_nm=truth["coulomb_nm"] - m.coulomb_nm,
                viscous_offset_nm_s_rad=truth["viscous_nm_s_rad"] - m.viscous_nm_s_rad,
                load_offset_nm=truth["load_torque_nm"] - m.load_torque_nm,
            ).apply(nominal)
            path = record_capture(
                plant,
                plan.pulses,
                Path(tmp) / "c.vcd",
                start_s=REST_S * rng.uniform(0.4, 0.9),
                rest_s=REST_S,
                length_s=CAPTURE_S,
            )
            t0 = time.perf_counter()
            cap = read_capture(path)
            rec = record_of(cap, nominal)
            result = fit([rec], nominal, PAPER_SETTINGS)
            ident = identify_report(axis, result, [rec])
            wall = time.perf_counter() - t0
            err = {e.name: e.value - truth[e.name] for e in result.estimates}
            top = nominal.pulse_top_speed_rad_s
            outside = []
            for e in result.estimates:
                if not e.excited:
                    continue
                total += 1
                if e.low <= truth[e.name] <= e.high:
                    hits += 1
                else:
                    outside.append(e.name)
            row = {
                "inertia_pct": 100 * err["inertia"] / truth["inertia"],
                "coulomb_pct": 100 * err["coulomb_nm"] / rated,
                "viscous_pct": 100 * err["viscous_nm_s_rad"] * top / rated,
                "load_pct": 100 * err["load_torque_nm"] / rated,
                "wall": wall,
                "explained": ident.explained,
            }
            rows.append(row)
            gain = result.estimate("torque_per_count")
            print(
                f"{k:5d}  {ratio:5.2f}  {abs(row['inertia_pct']):6.3f}   "
                f"{row['coulomb_pct']:+14.4f}  {row['viscous_pct']:+19.4f}  "
                f"{row['load_pct']:+12.4f}  {gain.value if gain.excited else float('nan'):5.3f}  "
                f"{result.residual_rms_counts:10.3f}  {result.saturated_s * 1e3:6.1f}  "
                f"{wall:6.2f}  {' '.join(outside) or '-'}",
                flush=True,
            )
    a = {key: np.array([r[key] for r in rows]) for key in rows[0]}
    print()
    print(
        f"inertia error: max {np.abs(a['inertia_pct']).max():.3f} %, mean "
        f"{np.abs(a['inertia_pct']).mean():.3f} % (goal within 2 %): "
        f"{np.count_nonzero(np.abs(a['inertia_pct']) <= 2)}/{len(rows)} within"
    )
    for key, label in (("coulomb_pct", "Coulomb"), ("load_pct", "load torque")):
        x = np.abs(a[key])
        print(
            f"{label} error: max {x.max():.4f} % of rated, mean {x.mean():.4f} % (goal within "
            f"1 %): {np.count_nonzero(x <= 1)}/{len(rows)} within"
        )
    x = np.abs(a["viscous_pct"])
    print(f"viscous error (its torque at the top speed): max {x.max():.4f} % of rated")
    print(
        f"coverage of the 95 % intervals: {hits}/{total} = {hits / max(total, 1):.1%} (goal 90 %)"
    )
    print(
        f"wall time an identification (2 s capture): mean {a['wall'].mean():.2f} s, max "
        f"{a['wall'].max():.2f} s (goal 30 s on 2 cores)"
    )
    print(f"explained (residual near the floor): {int(a['explained'].sum())}/{len(rows)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
