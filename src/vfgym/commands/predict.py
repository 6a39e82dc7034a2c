"""``vfgym predict``: the settings an amortised tuner picks for a move, as YAML. The tuner is
the settings model vfgym ships (a neighbour look-up: the optima of training moves ranked by
their mean cost on the training moves nearest the move in feature space, the 8 best
simulated on the move and the best of them kept; no training needed), a settings model of
``vfgym fit`` (JSON) for an axis, or a trained VFTune-v0 agent (``.zip``); one used on
another axis than its own, or on a move unlike its training moves, says so on stderr.
``--refine N`` then runs a short sweep on the move from those settings. A VFServo-v0 agent
(``.zip``) prints the schedule it runs on the move instead: each change of settings with the
time it takes effect, and the move's cost."""

from __future__ import annotations

import argparse


def add_parser(sub: argparse._SubParsersAction) -> None:
    from vfgym.commands._common import add_axis_option

    p = sub.add_parser(
        "predict",
        help="print the settings an amortised tuner picks for a scenario",
        description=__doc__ + " The output is a settings file that "
        "`vfgym evaluate --settings` reads.",
    )
    p.add_argument(
        "--model",
        help="a settings model (.json, e.g. runs/fit/NAME/settings_model.json), a VFTune-v0 "
        "agent (.zip, e.g. runs/train/NAME/best_model.zip) or a VFServo-v0 agent (.zip: its "
        "schedule on the move); default: the pretrained settings model shipped with vfgym",
    )
    p.add_argument("--scenario", default="paper-step", help="scenario name (or test-<seed>)")
    p.add_argument(
        "--refine",
        metavar="N",
        help="then run N trials of the default sampler on the move, the prediction first",
    )
    p.add_argument("--seed", default="0", help="the refinement sampler's seed (default 0)")
    p.add_argument("--out", help="also write the YAML to this file")
    add_axis_option(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from vfgym._validate import check_int, check_output_path
    from vfgym.commands._common import axis_from_args, scenario_from_args, warn_line
    from vfgym.space import settings_to_dict

    refine_n = (
        None if args.refine is None else check_int("--refine", args.refine, 1, 100_000, text=True)
    )
    seed = check_int("--seed", args.seed, 0, 2**31 - 1, text=True)
    axis = axis_from_args(args)
    scenario = scenario_from_args(args, axis)
    if args.out is not None:
        check_output_path("--out", args.out)
    if args.model is None:
        from vfgym.permove import load_tuner

        tuner = load_tuner(None, axis, warn=warn_line("predict"))
    else:
        from vfgym.commands.evaluate import load_policy
        from vfgym.permove import Tuner

        tuner = load_policy(args.model, axis, "predict")
        if not isinstance(tuner, Tuner):  # a VFServo-v0 agent's scheduler
            from vfgym.agents import load_agent, schedule_of

            agent = load_agent(args.model)

            if refine_n is not None:
                raise ValueError(
                    f"--refine {refine_n} is not allowed with a VFServo-v0 agent: its "
                    "settings change during the move"
                )
            doc = {"source": f"agent {args.model}", "scenario": scenario.name}
            return _emit(doc | schedule_of(agent, scenario, axis), args.out)
    settings = tuner(scenario)
    source = tuner.source
    doc = {"settings": settings_to_dict(settings), "source": source, "scenario": scenario.name}
    if refine_n is not None:
        from vfgym.permove import refine

        r = refine(scenario, settings, refine_n, seed=seed, axis=axis)
        doc = {
            "settings": settings_to_dict(r.settings),
            "source": f"{source}, refined by {refine_n} trials (seed {seed})",
            "scenario": scenario.name,
            "cost": r.cost,
            "feasible": r.feasible,
            "predicted": {"settings": settings_to_dict(settings), "cost": r.start_cost},
        }
    return _emit(doc, args.out)


def _emit(doc: dict, out: str | None) -> int:
    """Print ``doc`` as YAML (and write it to ``out``)."""
    import yaml

    text = yaml.safe_dump(doc, sort_keys=False)
    print(text, end="")
    if out:
        from vfgym.io.runs import write_text

        write_text(out, text)
    return 0
