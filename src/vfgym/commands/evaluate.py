"""``vfgym evaluate``: tuned settings (and agents) against baselines on a scenario set.

Prints the table (per scenario, in aggregate with n and spread, win/loss against each
baseline) and writes it to ``runs/evaluate/<name>/`` as ``results.csv`` (per scenario and
controller), ``summary.csv`` (spreads), ``results.json`` (everything) and ``table.txt``,
with ``config.yaml`` and ``command.txt``. Every number comes from :func:`vfgym.evaluate`.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from vfgym.axis import Axis

AGENTS_HINT = 'pip install -c constraints.txt -e ".[agents]"'
MAX_PLANTS = 1000
"""The most true plants ``--plants`` draws: every controller runs every move on each, so
1000 plants on the 32 test moves are already 32 000 runs a controller (minutes each on two
cores for the baselines, hours for a scheduler)."""


def add_parser(sub: argparse._SubParsersAction) -> None:
    from vfgym.commands._common import add_axis_option

    p = sub.add_parser(
        "evaluate",
        help="compare tuned settings or an agent with baselines on scenarios",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument(
        "--settings",
        action="append",
        default=[],
        metavar="FILE.yaml",
        help="settings file (key `settings:` as best.yaml); repeat to compare several",
    )
    p.add_argument(
        "--model",
        action="append",
        default=[],
        metavar="MODEL",
        help="a tuner that picks settings per scenario: a settings model (.json, e.g. "
        "runs/fit/NAME/settings_model.json of vfgym fit) or a trained VFTune-v0 agent "
        "(.zip), or a VFServo-v0 agent (.zip) that schedules settings during each move "
        "(agents need the agents extra); repeat to compare several",
    )
    p.add_argument(
        "--adaptive",
        action="append",
        default=[],
        metavar="MODEL.json",
        help="a settings model of the axis (vfgym fit's) run as a scheduler that holds its "
        "robust setting for 2 ms, tells the true plant from the response and ramps to "
        "settings for that plant, or holds its robust setting to the end where the response "
        "fits no plant within the axis's ranges (vfgym.permove.EstimatingScheduler; an "
        "--axis with an uncertainty: block); repeat to compare several",
    )
    _add_moves_options(p)
    _add_judging_options(p)
    add_axis_option(p)
    p.set_defaults(func=run)


def _add_moves_options(p: argparse.ArgumentParser) -> None:
    """The baselines and the moves an evaluation runs on."""
    from vfgym.commands._common import positive_int, whole

    p.add_argument(
        "--against",
        default="paper,rule-of-thumb,fixed-frequency,scurve",
        metavar="NAMES",
        help="comma-separated baselines: paper, rule-of-thumb, fixed-frequency, scurve, "
        "or 'none' (default: all four)",
    )
    p.add_argument(
        "--scenarios",
        default="test",
        metavar="SPEC",
        help="a scenario name, 'named', 'train', 'test' or a comma list (default: test; "
        "with --axis, the axis's test moves)",
    )
    p.add_argument(
        "--count",
        type=positive_int,
        help="train/test as this many random draws instead of the axis's move sets "
        "(default: the paper axis's 16 train and 32 test moves, or 32 draws with "
        "--first-seed; an axis file sets its own)",
    )
    p.add_argument(
        "--first-seed",
        type=whole(0),
        help="seed of the first random scenario (default: 0; an axis sets its own)",
    )


def _add_judging_options(p: argparse.ArgumentParser) -> None:
    """The bootstrap, the true plants, and where the run folder goes."""
    from vfgym.axis import VERDICT_PLANT_SEED, VERDICT_PLANTS
    from vfgym.commands._common import SEED, positive_int, whole

    p.add_argument(
        "--bootstrap",
        type=positive_int,
        default=2000,
        metavar="N",
        help="bootstrap resamples for the 95%% interval of means (default: 2000)",
    )
    p.add_argument("--seed", type=SEED, default=0, help="bootstrap seed (default: 0)")
    p.add_argument(
        "--plants",
        type=whole(1, MAX_PLANTS),
        metavar="N",
        help="true plants drawn within the axis's uncertainty on which every controller is "
        f"also judged (default: {VERDICT_PLANTS}; an axis without uncertainty: the ±5 %% "
        "inertia sensitivity line instead)",
    )
    p.add_argument(
        "--plant-seed",
        type=SEED,
        default=VERDICT_PLANT_SEED,
        metavar="S",
        help=f"seed of the drawn plants (default: {VERDICT_PLANT_SEED})",
    )
    p.add_argument(
        "--name",
        help="run folder name (default: a timestamp); an earlier evaluation of another job "
        "under the same name is refused unless --force",
    )
    p.add_argument("--runs-dir", default="runs", help="root of run folders (default: runs)")
    p.add_argument(
        "--force",
        action="store_true",
        help="replace an earlier evaluation of another job under the same --name",
    )


def _labels(paths: list[str], taken: set[str]) -> list[str]:
    """Short labels: the file's stem, or its path when stems clash."""
    stems = [Path(p).stem for p in paths]
    out = []
    for p, s in zip(paths, stems, strict=True):
        out.append(p if (stems.count(s) > 1 or s in taken) else s)
    return out


def load_policy(model_path: str, axis: Axis, command: str = "evaluate") -> Any:
    """``--model FILE`` read by :func:`vfgym.agents.load_tuner` (a settings model needs no
    torch; an agent, a tuner or a scheduler) on ``axis``, its warnings one line each on
    stderr. Without the agents extra an agent is a one-line ``ValueError``."""
    from vfgym.commands._common import warn_line

    if not Path(model_path).is_file():
        raise ValueError(f"{model_path}: no such file")
    try:
        from vfgym.agents import load_tuner

        return load_tuner(model_path, axis, warn=warn_line(command))
    except ImportError as exc:
        raise ValueError(
            f"--model {model_path}: agent support is not installed ({exc}); install the "
            f"agents extra: {AGENTS_HINT}"
        ) from None


def adaptive_scheduler(model_path: str, axis: Axis) -> Any:
    """``--adaptive``: the axis's settings model run as a
    :class:`vfgym.permove.EstimatingScheduler`; a one-line ``ValueError`` for a missing
    file or an axis without uncertainty."""
    from vfgym.permove import EstimatingScheduler, load_settings_model

    if not Path(model_path).is_file():
        raise ValueError(f"--adaptive {model_path}: no such file")
    try:
        model = load_settings_model(model_path)
    except ValueError as exc:  # its message names --model
        raise ValueError(
            f"--adaptive {model_path}: {str(exc).split(': ', 1)[-1]}; --adaptive takes the "
            "axis's settings model (vfgym fit's runs/fit/NAME/settings_model.json)"
        ) from None
    if axis.uncertainty.exact:
        raise ValueError(
            f"--adaptive {model_path} is not allowed on axis {axis.name}: it states no "
            "uncertainty, so there is no plant to tell (give --axis FILE with an "
            "uncertainty: block)"
        )
    return EstimatingScheduler(axis, model)


def fallback_lines(cands: list[Any]) -> list[str]:
    """One line per ``--adaptive`` scheduler: on how many of its (move, plant) runs it held
    its robust base to the end, and why (:meth:`vfgym.permove.EstimatingScheduler.fallbacks`)."""
    from vfgym.permove import EstimatingScheduler

    out = []
    for c in cands:
        if isinstance(c.policy, EstimatingScheduler):
            f = c.policy.fallbacks()
            out.append(
                f"{c.label}: held its robust base to the end on {f.held} of {f.runs} (move, "
                f"plant) runs: {f.response} whose response fit no design plant, {f.shadow} "
                "whose told plant's continuation breaks a limit just outside the ranges"
            )
    return out


def run(args: argparse.Namespace) -> int:
    from vfgym.axis import AXIS_FILE, VERDICT_PLANTS, write_axis
    from vfgym.commands._common import axis_from_args
    from vfgym.io.runs import new_run_dir, record_command, write_yaml
    from vfgym.report import compare, format_across, format_table, write_report

    _check_args(args)
    on = axis_from_args(args)  # the problem: the paper's axis without --axis
    if on.uncertainty.exact and args.plants is not None:
        raise ValueError(
            f"--plants={args.plants} is ignored: axis {on.name} states no uncertainty (give "
            "an axis file with an uncertainty: block, or leave --plants out for the ±5 % "
            "inertia sensitivity line)"
        )
    base = _baselines(args.against)
    cands = _candidates(args, on, {b.label for b in base})
    plants = VERDICT_PLANTS if args.plants is None else args.plants
    config = _config(args, on, cands, base, plants)
    _check_name_free(args, config)  # before any work: a name in use is refused at once
    report = compare(
        cands,
        base,
        args.scenarios,
        axis=on,
        count=32 if args.count is None and args.first_seed is not None else args.count,
        first_seed=args.first_seed,
        resamples=args.bootstrap,
        seed=args.seed,
        plants=plants,
        plant_seed=args.plant_seed,
        progress=True,  # (on a terminal)
    )
    report.scenario_spec = args.scenarios
    run_dir = new_run_dir(args.runs_dir, "evaluate", args.name)
    write_yaml(
        run_dir / "config.yaml", config | {"scenario_names": [s.name for s in report.scenarios]}
    )
    record_command(run_dir)
    write_axis(on, run_dir / AXIS_FILE)
    paths = write_report(report, run_dir)
    print(format_table(report), end="")
    assert report.across is not None  # (compare was given the plants)
    print("\n" + "\n".join(format_across([c.label for c in report.columns], report.across)))
    for line in fallback_lines(cands):
        print(line)
    print(f"\nwrote {run_dir}/ ({', '.join(paths)}, config.yaml, {AXIS_FILE}, command.txt)")
    return 0


def _check_args(args: argparse.Namespace) -> None:
    """What the options must hold before anything is loaded or run."""
    from vfgym._validate import check_name, check_output_path

    if not args.settings and not args.model and not args.adaptive:
        raise ValueError(
            "nothing to evaluate: give --settings FILE.yaml, --model MODEL or --adaptive MODEL"
        )
    for opt, v in (("--count", args.count), ("--first-seed", args.first_seed)):
        if args.axis and v is not None:
            raise ValueError(
                f"{opt}={v} is not allowed with --axis {args.axis}: the axis file sets its "
                "move sets (moves.train, moves.test)"
            )
    if args.name is not None:
        check_name("--name", args.name)
    check_output_path(
        "--runs-dir",
        Path(args.runs_dir) / "evaluate" / (args.name or ""),
        folder=True,
        shown=args.runs_dir,
        root=args.runs_dir,
    )


def _baselines(against: str) -> list[Any]:
    """The baselines of ``--against`` (``all``, ``none`` or a comma list)."""
    from vfgym.moves.baselines import BASELINE_NAMES
    from vfgym.report import baseline_candidates

    against = against.strip()
    if against in ("all", ""):
        against = ",".join(BASELINE_NAMES)
    return [] if against == "none" else baseline_candidates(against)


def _candidates(args: argparse.Namespace, axis: Axis, taken: set[str]) -> list[Any]:
    """The controllers evaluated: settings files, models and adaptive schedulers, each
    loaded for ``axis`` and labelled apart from the baselines' ``taken`` labels."""
    from vfgym.commands._common import load_settings
    from vfgym.report import Candidate

    cands = [
        Candidate(lab, load_settings(f, axis), source=f)
        for lab, f in zip(_labels(args.settings, taken), args.settings, strict=True)
    ]
    cands += [
        Candidate(f"{'agent' if m.endswith('.zip') else 'model'}:{lab}",
                  policy=load_policy(m, axis), source=m)
        for lab, m in zip(_labels(args.model, taken), args.model, strict=True)
    ]  # fmt: skip
    cands += [
        Candidate(f"adaptive:{lab}", policy=adaptive_scheduler(m, axis), source=m)
        for lab, m in zip(_labels(args.adaptive, taken), args.adaptive, strict=True)
    ]
    return cands


def _config(
    args: argparse.Namespace, axis: Axis, cands: list[Any], base: list[Any], plants: int
) -> dict[str, Any]:
    """What the evaluation is (``config.yaml``, less the scenario names it resolved to):
    an earlier run folder of the same name holds the same job or another."""
    from dataclasses import asdict

    from vfgym.axis import AXIS_FILE
    from vfgym.scoring import DEFAULT_BOUNDS, DEFAULT_WEIGHTS
    from vfgym.space import settings_to_dict

    fixed = [c for c in cands if c.controller is not None]
    return {
        "kind": "evaluate",
        "settings": [
            {"file": c.source, "label": c.label, "settings": settings_to_dict(c.controller)}
            for c in fixed
        ],
        "models": [{"file": c.source, "label": c.label} for c in cands if c.controller is None],
        "against": [b.label for b in base],
        "scenarios": args.scenarios,
        "count": args.count,
        "first_seed": args.first_seed,
        "bootstrap": {"resamples": args.bootstrap, "seed": args.seed, "level": 0.95},
        "plants": {"count": plants, "seed": args.plant_seed},
        "plant": f"the axis's ({AXIS_FILE}; each scenario adds its load)",
        "axis": {"file": args.axis, "name": axis.name},
        "weights": asdict(DEFAULT_WEIGHTS),
        "bounds": asdict(DEFAULT_BOUNDS),
    }


def _check_name_free(args: argparse.Namespace, config: dict[str, Any]) -> None:
    """``--name``'s run folder may be made or reused: one that holds an evaluation of
    another job (its ``config.yaml`` differs) is refused unless ``--force``."""
    from vfgym.io.runs import read_yaml

    if args.name is not None and not args.force:
        old = Path(args.runs_dir) / "evaluate" / args.name / "config.yaml"
        data = read_yaml(old) if old.is_file() else None
        if isinstance(data, dict):
            data.pop("scenario_names", None)
        if old.is_file() and data != config:
            raise ValueError(
                f"--name={args.name!r} is in use: {old.parent} holds an evaluation of "
                "another job (other controllers, moves, plants or axis); give another "
                "--name, or --force to replace it"
            )
