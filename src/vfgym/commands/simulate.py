"""``vfgym simulate``: one move, its measures printed. ``vfgym export --format csv`` writes
the same move's per-tick trace, ``vfgym plot response`` draws it."""

from __future__ import annotations

import argparse


def add_parser(sub: argparse._SubParsersAction) -> None:
    from vfgym.commands._common import add_axis_option

    p = sub.add_parser(
        "simulate", help="simulate one scenario and print its measures", description=__doc__
    )
    p.add_argument(
        "--scenario",
        default="paper-step",
        help="scenario name (see `vfgym simulate --list`), or train-<seed>/test-<seed>",
    )
    g = p.add_mutually_exclusive_group()
    g.add_argument("--settings", help="YAML file of V-F settings")
    g.add_argument("--baseline", help="paper, rule-of-thumb, fixed-frequency or scurve")
    p.add_argument("--list", action="store_true", help="list the named scenarios and exit")
    add_axis_option(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from vfgym.commands._common import (
        axis_from_args,
        controller_from_args,
        scenario_from_args,
    )
    from vfgym.moves.scenarios import SCENARIOS
    from vfgym.scoring import evaluate

    axis = axis_from_args(args)
    if args.list:
        listed = [m for split in ("train", "test") for m in axis.moves.of(split).moves]
        for s in [*listed, *SCENARIOS.values()]:
            print(f"{s.name:12s} {s.description}")
        return 0
    scenario = scenario_from_args(args, axis)
    ev = evaluate(controller_from_args(args, axis), [scenario], axis=axis)
    m = ev.metrics[0][0]
    print(f"{ev.labels()[0]} on {scenario.name}: cost {ev.cost[0, 0]:.4g}")
    for key in sorted(m):
        v = m[key]
        print(f"  {key:30s} {v:.6g}" if isinstance(v, float) else f"  {key:30s} {v}")
    return 0
