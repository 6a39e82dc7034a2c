"""``vfgym export``: a simulated move's signals as a file.

``--format vcd`` writes the pulse and direction signals and the encoder's A/B channels as a
Value Change Dump (GTKWave, PulseView; see :mod:`vfgym.io.vcd`); ``--format csv`` writes the
per-tick trace (every ``--decimation``-th tick; see :data:`vfgym.io.trace_csv.TRACE_FIELDS`),
with the load's columns where the axis states a transmission: ``load_rad`` and
``load_speed_rad_s`` at the motor shaft, and ``load_mm`` of travel where it states
``travel_mm_per_rad``.
Without ``--out`` the file is ``SCENARIO-CONTROLLER.FORMAT`` in the current folder,
replaced if an earlier export left it (the line printed says so). A file named with
``--out`` that exists, or that is an input (``--settings``, ``--axis``), is refused
unless ``--force``.
"""

from __future__ import annotations

import argparse
import os
from collections.abc import Sequence
from pathlib import Path

FORMATS = ("vcd", "csv")


def add_parser(sub: argparse._SubParsersAction) -> None:
    from vfgym.commands._common import add_axis_option, positive_int

    p = sub.add_parser(
        "export",
        help="write a simulated move as VCD (pulse/dir, encoder A/B) or per-tick CSV",
        description=__doc__,
    )
    p.add_argument("--format", choices=FORMATS, required=True, help="vcd or csv")
    p.add_argument("--scenario", default="paper-step", help="scenario (default: paper-step)")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--settings", metavar="FILE.yaml", help="settings file of the V-F controller")
    g.add_argument("--baseline", help="a baseline instead: paper (default), rule-of-thumb, ...")
    p.add_argument(
        "--out",
        metavar="FILE",
        help="output file (default: SCENARIO-CONTROLLER.vcd or .csv in the current folder)",
    )
    p.add_argument(
        "--force",
        action="store_true",
        help="replace the --out file if it exists",
    )
    p.add_argument(
        "--decimation",
        type=positive_int,
        default=1,
        help="csv: keep every N-th tick (default 1: every tick)",
    )
    p.add_argument(
        "--timescale", default="1 ns", help="vcd: time unit, e.g. '1 ns' (default) or '1 ps'"
    )
    add_axis_option(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from vfgym._validate import check_output_path
    from vfgym.commands._common import axis_from_args, scenario_from_args
    from vfgym.commands.plot import _controller, own_trace
    from vfgym.io.trace_csv import write_trace_csv
    from vfgym.io.vcd import parse_timescale, write_vcd
    from vfgym.scoring import evaluate

    if args.out is not None and args.out.strip():
        check_output_path("--out", args.out)
        refuse_replacing(
            "--out", args.out, force=args.force,
            inputs=[("--settings", args.settings), ("--axis", args.axis)],
        )  # fmt: skip
    axis = axis_from_args(args)
    scenario = scenario_from_args(args, axis)
    if args.format == "vcd":
        parse_timescale(args.timescale)
        if args.decimation != 1:
            raise ValueError(f"--decimation={args.decimation} is not allowed for vcd: every tick")
    ctrl, label = _controller(args, axis)
    out = args.out if args.out is not None else f"{scenario.name}-{Path(label).stem}.{args.format}"
    out = check_output_path("--out", out)
    replaced = args.out is None and out.is_file()
    dec = args.decimation if args.format == "csv" else 1
    ev = evaluate(ctrl, [scenario], keep_traces=True, decimation=dec, axis=axis)
    trace = own_trace(ev, scenario)
    if args.format == "vcd":
        comment = f"scenario {scenario.name}: {scenario.description}\ncontroller {ev.labels()[0]}"
        write_vcd(trace, out, timescale=args.timescale, comment=comment)
    else:
        write_trace_csv(trace, out)
    m = ev.metrics[0][0]
    print(
        f"wrote {out}{' (replacing the earlier export)' if replaced else ''}: {scenario.name}, "
        f"{ev.labels()[0]}, {trace.n_ticks} ticks, {m['pulse_count']} pulses"
    )
    return 0


def refuse_replacing(
    option: str,
    path: str,
    *,
    force: bool,
    inputs: Sequence[tuple[str, str | None]] = (),
) -> None:
    """Refuse to replace a user's file: ``path`` an existing file, or one of ``inputs``.

    Parameters
    ----------
    option : str
        The option ``path`` came from (``--out``).
    path : str
        The file to be written.
    force : bool
        The user said ``--force``: replace it.
    inputs : sequence of (str, str or None)
        The command's input files with their options (``("--axis", FILE)``; ``None``: not
        given).

    Raises
    ------
    ValueError
        One line naming the option, the file and ``--force``.
    OSError
        Naming ``path``, where its folder takes no new file (``/proc``): the write would
        fail the same way, whether it replaced the file or not.
    """
    if force:
        return
    p = Path(path)
    for name, other in inputs:
        if other and p.exists() and Path(other).exists() and os.path.samefile(p, other):
            raise ValueError(
                f"{option}={path!r} is not allowed: it is the {name} file, an input of this "
                "command; give another file, or --force to replace it"
            )
    if p.is_file():
        _takes_a_file(p)
        raise ValueError(
            f"{option}={path!r} is not allowed: the file exists; give another file, or "
            "--force to replace it"
        )


def _takes_a_file(p: Path) -> None:
    """Raise the ``OSError`` a write of ``p`` would meet if its folder takes no new file."""
    import tempfile

    try:
        fd, tmp = tempfile.mkstemp(dir=p.parent, prefix=f".{p.name}.")
    except OSError as exc:
        raise OSError(exc.errno, exc.strerror, str(p)) from None
    os.close(fd)
    os.unlink(tmp)
