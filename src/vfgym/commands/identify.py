"""``vfgym identify``: an axis's plant from logic-analyser captures of known moves.

``vfgym identify --axis NOMINAL.yaml --capture FILE [--capture FILE ...] --out OUT.yaml``
reads each capture (VCD as a logic analyser or ``vfgym export`` saves it, with the
pulse, dir, enc_a and enc_b signals — other names with ``--signals`` — or CSV with the
columns time_s, pulse_count, encoder_count), drives the axis's servo and motor with the
recorded pulse train in the exact simulator, and fits the total inertia, Coulomb and
viscous friction, a constant load torque and the drive's gain (a factor on K3) so that the
simulated encoder count matches the recorded one. It prints the estimates with 95 %
intervals and the fit's residual beside the quantisation floor, one line for each thing
the captures cannot show, and writes the axis with the estimates and an ``uncertainty:``
block (the intervals widened by a stated margin).

``vfgym identify --plan --axis NOMINAL.yaml --out DIR`` writes the moves to run for an
identification: ``DIR/identify-moves.yaml`` (the axis with those moves as its ``moves:``
block), ``DIR/identify-moves.vcd`` (their pulse/direction train, to replay) and
``DIR/identify-moves-nominal.vcd`` (a simulated 1 MHz capture of them on the nominal
plant, started before the drive's enable: what a capture looks like, and a dry run with
``--from-enable``). See docs/guide/identify.md.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import Any


def add_parser(sub: argparse._SubParsersAction) -> None:
    from vfgym.commands._common import add_axis_option

    p = sub.add_parser(
        "identify",
        help="fit an axis's inertia, friction, load torque and drive gain to captures",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument(
        "--capture",
        action="append",
        metavar="FILE",
        help="a capture of the moves: .vcd (logic analyser, vfgym export) or .csv; repeat "
        "for several",
    )
    p.add_argument(
        "--signals",
        metavar="MAP",
        help="VCD signal names, e.g. pulse=D0,dir=D1,enc_a=D2,enc_b=D3 (default: pulse, dir, "
        "enc_a, enc_b)",
    )
    p.add_argument(
        "--settings",
        metavar="FILE.yaml",
        help="settings file: its ts_over_tf is the drive's filter ratio (default 0.25)",
    )
    p.add_argument(
        "--from-enable",
        action="store_true",
        help="the captures started before the drive was enabled (the planned procedure): "
        "the servo held no error then, which shows a load torque (an enable is also "
        "recognised by the axis sagging before the first pulse)",
    )
    p.add_argument(
        "--plan",
        action="store_true",
        help="write the moves to run (an axis file and a pulse/dir VCD) into the --out folder",
    )
    p.add_argument(
        "--out",
        metavar="PATH",
        required=True,
        help="the identified axis file (with --plan: the folder for the plan)",
    )
    add_axis_option(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from vfgym.axis import PAPER_AXIS
    from vfgym.commands._common import axis_from_args, load_settings
    from vfgym.params import PAPER_SETTINGS

    axis = axis_from_args(args) or PAPER_AXIS
    settings = load_settings(args.settings) if args.settings else PAPER_SETTINGS
    if args.plan:
        if args.capture:
            raise ValueError("--capture is not allowed with --plan: the plan comes first")
        return _plan(axis, settings, Path(args.out))
    if not args.capture:
        raise ValueError("--capture FILE is required: the capture of the moves (or give --plan)")
    return _identify(axis, settings, args)


def _plan(axis: Any, settings: Any, out: Path) -> int:
    from dataclasses import replace

    from vfgym._validate import check_output_path
    from vfgym.axis import MoveSet, MoveSets, write_axis
    from vfgym.identify.plan import make_plan
    from vfgym.identify.simulated import record_capture
    from vfgym.io.vcd import train_edges, write_edges

    if out.exists() and not out.is_dir():
        raise ValueError(f"--out={str(out)!r} is a file: with --plan give a folder")
    out.mkdir(parents=True, exist_ok=True)
    plan = make_plan(axis, settings)
    moves = MoveSet(moves=plan.moves)
    plan_axis = replace(
        axis,
        description=f"identification moves of {axis.name} (vfgym identify --plan)",
        moves=MoveSets(train=moves, test=moves),
    )
    yaml_path = check_output_path("--out", str(out / "identify-moves.yaml"))
    vcd_path = check_output_path("--out", str(out / "identify-moves.vcd"))
    dry_path = check_output_path("--out", str(out / "identify-moves-nominal.vcd"))
    write_axis(plan_axis, yaml_path)
    comment = (
        f"vfgym identify --plan: the identification moves of axis {axis.name}, "
        f"{len(plan.moves)} moves, tick_hz {plan.tick_hz!r}; pulse rises at (i+1/2)T, "
        "dir 1 = positive"
    )
    write_edges(train_edges(plan.pulses, plan.tick_hz), vcd_path, encoder=False, comment=comment)
    # what a 1 MHz capture of the moves on the nominal plant looks like, started before the
    # drive's enable as the procedure asks: a dry run
    record_capture(axis.plant, plan.pulses, dry_path, start_s=DRY_START_S, rest_s=DRY_REST_S)
    print(f"identification moves of axis {axis.name}: {plan.duration_s:.3g} s in all")
    for sc in plan.moves:
        print(
            f"  {sc.name:22s} {sc.profile:9s} {sc.distance_rad:+9.4g} rad at "
            f"{sc.speed_rad_s:7.4g} rad/s, {sc.duration_s:.3g} s"
        )
    if plan.saturated_s > 0:
        print(
            f"the nominal plant is at its torque limit for {plan.saturated_s * 1e3:.3g} ms: "
            "inertia and the drive's gain separate"
        )
    else:
        print(
            f"note: the fastest move reaches {plan.peak_torque_share:.0%} of the peak torque on "
            "the nominal plant, never the limit: inertia and the drive's gain will not "
            "separate unless the real axis is heavier (the gain is kept as set)"
        )
    print(f"wrote {yaml_path} (the moves: block) and {vcd_path} (pulse/dir to replay)")
    print(
        f"wrote {dry_path}: a 1 MHz capture of the moves on the nominal plant (simulated), "
        "for a dry run of vfgym identify --from-enable"
    )
    print(
        "to run them: start the capture with the drive disabled, enable it, start the pulse "
        "train 0.2 s later, stop 10 ms after the last move; then vfgym identify --from-enable"
    )
    return 0


DRY_REST_S = 0.2
"""The dry run's time from the drive's enable to the moves (s)."""

DRY_START_S = -0.02
"""When the dry run's capture starts, against the drive's enable (s): before it."""


def _identify(axis: Any, settings: Any, args: argparse.Namespace) -> int:
    from vfgym._validate import check_output_path
    from vfgym.axis import write_axis
    from vfgym.identify.capture import parse_signal_map, read_capture
    from vfgym.identify.fit import QUANTISATION_FLOOR, fit
    from vfgym.identify.model import record_of
    from vfgym.identify.written import MARGIN, identify_report

    out = check_output_path("--out", args.out)
    names = parse_signal_map(args.signals)
    t0 = time.perf_counter()
    records = []
    for path in args.capture:
        cap = read_capture(path, names)
        rec = record_of(cap, axis.plant, True if args.from_enable else None)
        records.append(rec)
        print(
            f"read {path}: {cap.pulse_s.size} pulses, {cap.count.size} encoder steps, "
            f"{cap.end_s:.4g} s"
            + (
                f"; from the drive's enable (the axis moved {rec.sag_counts:+d} counts "
                "before the first pulse)"
                if rec.enabled
                else ""
            )
        )
    result = fit(records, axis.plant, settings)
    ident = identify_report(axis, result, records)
    units = {
        "inertia": "x nominal total",
        "coulomb_nm": "N*m",
        "viscous_nm_s_rad": "N*m*s/rad",
        "load_torque_nm": "N*m",
        "torque_per_count": "x K3 as set",
    }
    print(f"{'quantity':18s} {'nominal':>11s} {'estimate':>11s}   95 % interval")
    for e in result.estimates:
        tail = "" if e.excited else "   (not excited: nominal kept)"
        print(
            f"{e.name:18s} {e.nominal:11.5g} {e.value:11.5g}   [{e.low:.5g}, {e.high:.5g}] "
            f"{units[e.name]}{tail}"
        )
    print(
        f"residual: {result.residual_rms_counts:.3g} counts RMS (max "
        f"{result.residual_max_counts:.3g}) beside the quantisation floor "
        f"{QUANTISATION_FLOOR:.3g} counts RMS; {result.samples} samples, "
        f"{result.evaluations} simulations, {time.perf_counter() - t0:.3g} s"
    )
    for note in ident.notes:
        print(f"note: {note}")
    write_axis(ident.axis, out)
    print(
        f"wrote {out}: uncertainty = the 95 % intervals x {MARGIN:g}, each at least the "
        "change that moves no sample by more than the quantisation floor"
    )
    return 0
