"""``vfgym identify``: an axis's plant from logic-analyser captures of known moves.

``vfgym identify --axis NOMINAL.yaml --capture FILE [--capture FILE ...] --out OUT.yaml``
reads each capture (VCD as a logic analyser or ``vfgym export`` saves it, with the
pulse, dir, enc_a and enc_b signals — other names with ``--signals`` — sigrok-cli's CSV,
with or without its time column, or vfgym's trace CSV), drives the axis's servo and motor
with the recorded pulse train in the exact simulator, and fits the total inertia, Coulomb
and viscous friction, a constant load torque and the drive's gain (a factor on K3) so
that the simulated encoder count matches the recorded one. It prints the estimates with
95 % intervals and the fit's residual beside the quantisation floor, one line for each
thing the captures cannot show, and writes the axis with the estimates and an
``uncertainty:`` block that holds every plant the captures cannot rule out: where they
fix only the ratio of the inertia and torques to the drive's gain, every gain within its
prior (``--gain-prior``, else the nominal file's ``torque_per_count`` range, else ±10 %),
and the ranges the nominal file states for the inertia and torques (a payload), kept.

A capture that cannot be trusted writes nothing (exit status 2, one line): encoder edges
lost, A and B swapped, a truncated file, a fit whose residual is far above the
quantisation floor (with its likely cause). Glitches, and a pulse train that is not the
axis's plan, are named in notes. ``--out`` is refused if the file exists or is an input,
unless ``--force``.

``vfgym identify --plan --axis NOMINAL.yaml --out DIR`` writes the moves to run for an
identification: ``DIR/identify-moves.yaml`` (the axis with those moves as its ``moves:``
block), ``DIR/identify-moves.vcd`` (their pulse/direction train, to replay) and
``DIR/identify-moves-nominal.vcd`` (a simulated 1 MHz capture of them on the nominal
plant, started before the drive's enable: what a capture looks like, and a dry run with
``--from-enable``). With ``--true-axis TRUE.yaml`` it also writes
``DIR/identify-moves-on-NAME.vcd``: the same moves captured on that file's plant (a
"true" axis), rest before and after, to try the identification on a plant that is not
the nominal one. See docs/guide/identify.md.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import Any

PLAN_FILES = ("identify-moves.yaml", "identify-moves.vcd", "identify-moves-nominal.vcd")
"""The files ``--plan`` writes into its folder."""

DRY_REST_S = 0.2
"""The dry run's time from the drive's enable to the moves (s)."""

DRY_START_S = -0.02
"""When the dry run's capture starts, against the drive's enable (s): before it."""

DRY_AFTER_S = 0.1
"""The dry run's capture runs this long after the moves' pulse train (s)."""

UNITS = {
    "inertia": "x nominal total",
    "coulomb_nm": "N*m",
    "viscous_nm_s_rad": "N*m*s/rad",
    "load_torque_nm": "N*m",
    "torque_per_count": "x K3 as set",
}


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
        help="a capture of the moves: .vcd (logic analyser, vfgym export) or .csv (sigrok-cli, "
        "vfgym export); repeat for several",
    )
    p.add_argument(
        "--signals",
        metavar="MAP",
        help="the capture's signal names, e.g. pulse=D0,dir=D1,enc_a=D2,enc_b=D3 (default: "
        "pulse, dir, enc_a, enc_b)",
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
        "--gain-prior",
        metavar="SHARE",
        type=float,
        help="the drive's gain is within this share of the one set, e.g. 0.1 for +-10 %% "
        "(default: the nominal file's uncertainty.torque_per_count, else 0.1); where the "
        "captures do not separate the gain from the inertia, the estimates and the "
        "written block span it",
    )
    p.add_argument(
        "--plan",
        action="store_true",
        help="write the moves to run (an axis file and a pulse/dir VCD) into the --out folder",
    )
    p.add_argument(
        "--true-axis",
        metavar="FILE.yaml",
        help="with --plan: also write the moves captured on this axis file's plant (a "
        "'true' axis), to try the identification on",
    )
    p.add_argument(
        "--out",
        metavar="PATH",
        required=True,
        help="the identified axis file (with --plan: the folder for the plan)",
    )
    p.add_argument(
        "--force",
        action="store_true",
        help="replace --out (or the plan's files in it) if it exists or is an input",
    )
    add_axis_option(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from vfgym.axis import PAPER_AXIS
    from vfgym.commands._common import axis_from_args, load_settings
    from vfgym.commands.export import refuse_replacing
    from vfgym.params import PAPER_SETTINGS

    out = Path(args.out)
    if args.gain_prior is not None:
        from vfgym.identify.prior import gain_prior

        gain_prior(PAPER_AXIS, args.gain_prior)  # checked before any file is read
    if args.plan:
        if args.capture:
            raise ValueError("--capture is not allowed with --plan: the plan comes first")
        if out.exists() and not out.is_dir():
            raise ValueError(f"--out={args.out!r} is a file: with --plan give a folder")
        for name in PLAN_FILES:
            refuse_replacing("--out", str(out / name), force=args.force)
    else:
        if args.true_axis:
            raise ValueError("--true-axis is allowed only with --plan: it makes a capture")
        if not args.capture:
            raise ValueError(
                "--capture FILE is required: the capture of the moves (or give --plan)"
            )
        from vfgym._validate import check_output_path

        check_output_path("--out", args.out)
        inputs = [("--axis", args.axis), ("--settings", args.settings)]
        inputs += [("--capture", c) for c in args.capture]
        refuse_replacing("--out", args.out, force=args.force, inputs=inputs)
    axis = axis_from_args(args)
    settings = load_settings(args.settings, axis) if args.settings else PAPER_SETTINGS
    if args.plan:
        return _plan(axis, settings, out, args.true_axis)
    return _identify(axis, settings, args)


def _plan(axis: Any, settings: Any, out: Path, true_axis: str | None) -> int:
    from dataclasses import replace

    from vfgym._validate import check_output_path
    from vfgym.axis import MoveSet, MoveSets, load_axis, write_axis
    from vfgym.identify.plan import make_plan
    from vfgym.identify.simulated import record_capture
    from vfgym.io.vcd import train_edges, write_edges

    true = load_axis(true_axis) if true_axis else None
    if true is not None and true.plant.tick_hz != axis.plant.tick_hz:
        raise ValueError(
            f"--true-axis={true_axis!r} is not allowed: its plant.tick_hz={true.plant.tick_hz:g} "
            f"is not the nominal's {axis.plant.tick_hz:g} (the pulses are on the nominal's ticks)"
        )
    out.mkdir(parents=True, exist_ok=True)
    plan = make_plan(axis, settings)
    moves = MoveSet(moves=plan.moves)
    plan_axis = replace(
        axis,
        description=f"identification moves of {axis.name} (vfgym identify --plan)",
        moves=MoveSets(train=moves, test=moves),
    )
    yaml_path, vcd_path, dry_path = (check_output_path("--out", str(out / n)) for n in PLAN_FILES)
    write_axis(plan_axis, yaml_path)
    comment = (
        f"vfgym identify --plan: the identification moves of axis {axis.name}, "
        f"{len(plan.moves)} moves, tick_hz {plan.tick_hz!r}; pulse rises at (i+1/2)T, "
        "dir 1 = positive"
    )
    write_edges(train_edges(plan.pulses, plan.tick_hz), vcd_path, encoder=False, comment=comment)
    # what a 1 MHz capture of the moves on the nominal plant looks like, started before the
    # drive's enable as the procedure asks: a dry run
    length = DRY_REST_S - DRY_START_S + plan.duration_s + DRY_AFTER_S
    record_capture(axis.plant, plan.pulses, dry_path, start_s=DRY_START_S, rest_s=DRY_REST_S,
                   length_s=length, settings=settings)  # fmt: skip
    print(f"identification moves of axis {axis.name}: {plan.duration_s:.3g} s in all")
    for sc in plan.moves:
        print(
            f"  {sc.name:22s} {sc.profile:9s} {sc.distance_rad:+9.4g} rad at "
            f"{sc.speed_rad_s:7.4g} rad/s, {sc.duration_s:.3g} s"
        )
    _say_saturation(plan)
    print(f"wrote {yaml_path} (the moves: block) and {vcd_path} (pulse/dir to replay)")
    print(
        f"wrote {dry_path}: a 1 MHz capture of the moves on the nominal plant (simulated), "
        "for a dry run of vfgym identify --from-enable"
    )
    if true is not None:
        on = check_output_path("--out", str(out / f"identify-moves-on-{true.name}.vcd"))
        record_capture(true.plant, plan.pulses, on, start_s=DRY_START_S, rest_s=DRY_REST_S,
                       length_s=length, settings=settings)  # fmt: skip
        print(
            f"wrote {on}: the same capture of the moves on the plant of {true_axis} "
            "(simulated), to identify with --axis on the nominal file and --from-enable"
        )
    print(
        "to run them: start the capture with the drive disabled, enable it, start the pulse "
        "train 0.2 s later, stop 10 ms after the last move; then vfgym identify --from-enable"
    )
    return 0


def _say_saturation(plan: Any) -> None:
    """Whether the plan's pulse train holds the nominal plant at its torque limit long
    enough for the inertia and the drive's gain to separate, and if not, from what."""
    from vfgym.identify.excite import MIN_SATURATED_S

    ms = MIN_SATURATED_S * 1e3
    if plan.saturated_s >= MIN_SATURATED_S:
        print(
            f"the nominal plant is at its torque limit for {plan.saturated_s * 1e3:.3g} ms: "
            "inertia and the drive's gain separate"
        )
    else:
        held = (
            f"it is at its limit for {plan.saturated_s * 1e3:.3g} ms, under the {ms:.0f} ms "
            "from which the gain separates"
            if plan.saturated_s > 0
            else f"the velocity reversals ask {plan.peak_torque_share:.0%} of its peak"
        )
        heavy = (
            f"from about {plan.saturating_inertia:g}x the nominal inertia"
            if plan.saturating_inertia is not None
            else "on no inertia up to 16x the nominal"
        )
        print(
            f"note: no pulse train holds the nominal plant's torque at its limit: {held}. "
            f"The moves separate the inertia from the drive's gain {heavy}; on a lighter "
            "axis the capture fixes their ratio, and the identified axis spans the gain's "
            "prior (--gain-prior; else the nominal file's torque_per_count range, else "
            "+-10 %)"
        )


def _refuse_unless_shown(ident: Any, fit: Any, paths: list[str]) -> None:
    """One line and no axis written where the model does not explain the captures, or
    they cannot tell a compliant axis's resonance."""
    from vfgym.identify.written import floor_text

    if not ident.explained:
        raise ValueError(
            f"{', '.join(paths)}: the model does not explain the capture (residual "
            f"{fit.residual_rms_counts:.3g} counts RMS against "
            f"{floor_text(ident.floor_counts)}): likely cause: {ident.cause}; no axis written"
        )
    if ident.resonance is not None and not ident.resonance.shown:
        raise ValueError(f"{', '.join(paths)}: {ident.resonance.note}; no axis written")


def _print_resonance(ident: Any) -> None:
    """A compliant axis's transmission as identified (nothing on a rigid axis)."""
    res = ident.resonance
    if res is None:
        return
    lo, hi = res.resonance_range_hz
    zlo, zhi = res.damping_ratio_range
    print(
        f"transmission: resonance {res.resonance_hz:.4g} Hz [{lo:.4g}, {hi:.4g}] (nominal "
        f"{res.nominal_hz:.4g}), damping ratio {res.damping_ratio:.3g} [{zlo:.3g}, "
        f"{zhi:.3g}]; residual on its moves {res.residual_rms_counts:.3g} counts RMS"
    )


def _identify(axis: Any, settings: Any, args: argparse.Namespace) -> int:
    from vfgym._validate import check_output_path
    from vfgym.axis import write_axis
    from vfgym.identify.capture import parse_signal_map, read_capture
    from vfgym.identify.fit import QUANTISATION_FLOOR
    from vfgym.identify.pipeline import identify_axis
    from vfgym.identify.written import MARGIN, floor_text

    out = check_output_path("--out", args.out)
    names = parse_signal_map(args.signals)
    t0 = time.perf_counter()
    captures = [read_capture(path, names) for path in args.capture]
    ident, records, _ = identify_axis(
        axis,
        captures,
        settings,
        from_enable=True if args.from_enable else None,
        gain_share=args.gain_prior,
    )
    for path, cap, rec in zip(args.capture, captures, records, strict=True):
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
    result = ident.fit
    print(f"{'quantity':18s} {'nominal':>11s} {'estimate':>11s}   95 % interval")
    for e in result.estimates:
        if e.name == "torque_per_count" and not e.excited and ident.profile is not None:
            tail = "   (not separated: its prior)"
        elif not e.excited:
            tail = "   (not excited: nominal kept)"
        elif ident.profile is not None:
            tail = "   (over the gain's prior)"
        else:
            tail = ""
        print(
            f"{e.name:18s} {e.nominal:11.5g} {e.value:11.5g}   [{e.low:.5g}, {e.high:.5g}] "
            f"{UNITS[e.name]}{tail}"
        )
    fit = ident.profile.fits[1] if ident.profile is not None else result
    print(
        f"residual: {fit.residual_rms_counts:.3g} counts RMS (max "
        f"{fit.residual_max_counts:.3g}) beside the quantisation floor "
        f"{QUANTISATION_FLOOR:.3g} counts RMS; {fit.samples} samples, "
        f"{time.perf_counter() - t0:.3g} s"
        + (
            f"; judged against {floor_text(ident.floor_counts)}"
            if ident.floor_counts > QUANTISATION_FLOOR
            else ""
        )
    )
    _print_resonance(ident)
    for note in ident.notes:
        print(f"note: {note}")
    _refuse_unless_shown(ident, fit, args.capture)
    for line in ident.kept:
        print(f"kept: {line}")
    write_axis(ident.axis, out)
    print(
        f"wrote {out}: uncertainty = the 95 % intervals x {MARGIN:g}, each at least the "
        "change that moves no sample by more than the quantisation floor"
        + (
            f", over the drive's gain within [{ident.profile.prior[0]:.4g}, "
            f"{ident.profile.prior[1]:.4g}] x K3 as set"
            if ident.profile is not None
            else ""
        )
        + ("; the nominal file's ranges kept" if ident.kept else "")
    )
    return 0
