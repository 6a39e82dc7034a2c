"""``vfgym predict``: the settings a trained VFTune-v0 agent picks for a move, as YAML."""

from __future__ import annotations

import argparse


def add_parser(sub: argparse._SubParsersAction) -> None:
    from vfgym.commands._common import add_axis_option

    p = sub.add_parser(
        "predict",
        help="print the settings an agent picks for a scenario",
        description=__doc__ + " The output is a settings file that "
        "`vfgym evaluate --settings` reads.",
    )
    p.add_argument("--model", required=True, help="a saved model, e.g. RUN/best_model.zip")
    p.add_argument("--scenario", default="paper-step", help="scenario name (or test-<seed>)")
    p.add_argument("--out", help="also write the YAML to this file")
    add_axis_option(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    import yaml

    from vfgym._validate import check_output_path
    from vfgym.commands._common import axis_from_args, scenario_from_args
    from vfgym.space import settings_to_dict

    scenario = scenario_from_args(args, axis_from_args(args))
    if args.out is not None:
        check_output_path("--out", args.out)
    try:
        from vfgym.agents import policy_settings
    except ImportError as exc:  # pragma: no cover - depends on the install
        raise ValueError(
            f"agent support needs the agents extra ({exc.name} missing): "
            'pip install -c constraints.txt -e ".[agents]"'
        ) from None
    settings = policy_settings(args.model, args.axis)(scenario)
    doc = {
        "settings": settings_to_dict(settings),
        "source": f"agent {args.model}",
        "scenario": scenario.name,
    }
    text = yaml.safe_dump(doc, sort_keys=False)
    print(text, end="")
    if args.out:
        from vfgym.io.runs import write_text

        write_text(args.out, text)
    return 0
