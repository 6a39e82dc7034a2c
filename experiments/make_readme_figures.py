"""Figures and the results table for the README, from real simulations.

Writes ``docs/images/*.png`` and ``docs/results.md``:

- ``paper_step.png``, ``paper_sine.png``: the paper's Fig. 4 and Fig. 5 with its settings
  (command, pulse train, motor; error, speed, acceleration with the motor's limit);
- ``scurve.png``: S-curve speed profiles with and without triangle form prevention;
- ``pulse_frequency.png``: pulse frequency of the V-F controller and of the fixed-frequency
  baseline on the paper step;
- ``tuned_vs_baseline_<scenario>.png``: tuned against the paper's settings and the S-curve
  source on the paper step and on the heavy load, overlaid;
- with ``--sweep``: ``history.png`` and ``pareto.png`` of that sweep.

"Tuned" is the sweep's ``best.yaml`` (or its best trial) when ``--sweep RUN_DIR`` is
given, else the rule-of-thumb baseline; the table says which. Every number comes from
``vfgym.evaluate`` through ``vfgym.report.compare``, as ``vfgym evaluate`` prints them.

    PYTHONPATH=src python experiments/make_readme_figures.py [--sweep runs/sweep/NAME]
"""

from __future__ import annotations

import argparse
import shlex
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def tuned_candidate(sweep: str | None):
    """(Candidate, description) of the tuned settings."""
    from vfgym.axis import PAPER_AXIS
    from vfgym.commands._common import load_settings
    from vfgym.moves.baselines import Baseline
    from vfgym.report import Candidate
    from vfgym.space import settings_from_dict

    if not sweep:
        return (
            Candidate("tuned = rule-of-thumb", Baseline("rule-of-thumb"), source="rule-of-thumb"),
            "no sweep given: the rule-of-thumb baseline stands in for tuned settings",
        )
    d = Path(sweep)
    best = d / "best.yaml"
    if best.is_file():
        return (
            Candidate("tuned", load_settings(str(best), PAPER_AXIS), source=str(best)),
            f"tuned = best settings of the sweep `{d}` (`{best.name}`)",
        )
    from vfgym.commands.plot import load_study
    from vfgym.tuning import stored_result

    study = load_study(str(d))
    if len(study.directions) > 1:
        raise ValueError(
            f"{d}: no best.yaml, and the study has {len(study.directions)} objectives (no "
            "single best trial): give a sweep folder with best.yaml"
        )
    trial = study.best_trial
    res = stored_result(trial)
    data = res.settings if res is not None and res.settings else trial.params
    return (
        Candidate("tuned", settings_from_dict(data, source=f"{d} trial {trial.number}")),
        f"tuned = best trial {trial.number} of the sweep `{d}`",
    )


def git_commit() -> str:
    try:
        out = subprocess.run(
            ["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True, text=True
        )
        return out.stdout.strip() or "unknown"
    except OSError:
        return "unknown"


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--sweep", help="sweep run folder whose best settings are 'tuned'")
    p.add_argument("--out-dir", default=str(ROOT / "docs"), help="default: docs/ of the repo")
    p.add_argument("--count", type=int, default=32, help="random test scenarios (default 32)")
    p.add_argument("--dpi", type=int, default=110)
    args = p.parse_args(argv)

    from vfgym import PAPER_SETTINGS, __version__
    from vfgym.moves.baselines import BASELINE_NAMES, controller_label
    from vfgym.moves.distribution import get_scenario
    from vfgym.report import (
        baseline_candidates,
        compare,
        format_table,
        markdown_costs,
        markdown_table,
    )
    from vfgym.report import figures as plots
    from vfgym.scoring import evaluate

    t0 = time.perf_counter()
    out = Path(args.out_dir)
    img = out / "images"
    img.mkdir(parents=True, exist_ok=True)
    written: list[Path] = []

    def save(fig, name: str) -> None:
        path = img / name
        fig.savefig(path, dpi=args.dpi)
        written.append(path)

    # the paper's Fig. 4 and Fig. 5 with the paper's settings
    for name, fname in (("paper-step", "paper_step.png"), ("paper-sine", "paper_sine.png")):
        sc = get_scenario(name)
        ev = evaluate("paper", [sc], keep_traces=True)
        title = (
            f"{sc.name}: {sc.description}\nthe paper's settings: {controller_label(PAPER_SETTINGS)}"
        )
        save(
            plots.response_figure(
                ev.traces[0][0], title=title, metrics=ev.metrics[0][0], tracking=sc.tracking
            ),
            fname,
        )
    save(plots.scurve_figure(), "scurve.png")
    sc = get_scenario("paper-step")
    ev = evaluate(["paper", "fixed-frequency"], [sc], keep_traces=True)
    save(
        plots.frequency_figure(
            {
                "V-F controller, the paper's settings": ev.traces[0][0],
                "fixed-frequency baseline (f/2)": ev.traces[1][0],
            },
            title=f"{sc.name}: {sc.description}",
        ),
        "pulse_frequency.png",
    )

    tuned, what = tuned_candidate(args.sweep)
    against = [n for n in BASELINE_NAMES if n != tuned.source]
    for name in ("paper-step", "heavy-load"):
        sc = get_scenario(name)
        ctrls = [tuned.controller, "paper", "scurve"]
        ev = evaluate(ctrls, [sc], keep_traces=True)
        labels = [tuned.label, "paper", "scurve"]
        traces = {
            f"{lab} (cost {ev.cost[i, 0]:.3g})": ev.traces[i][0] for i, lab in enumerate(labels)
        }
        save(
            plots.compare_figure(traces, title=f"{sc.name}: {sc.description}\n{what}"),
            f"tuned_vs_baseline_{name}.png",
        )
    if args.sweep:
        from vfgym.commands.plot import load_study

        study = load_study(args.sweep)
        save(plots.history_figure(study), "history.png")
        try:
            save(plots.pareto_figure(study), "pareto.png")
        except ValueError as exc:
            print(f"no pareto.png: {exc}", file=sys.stderr)

    base = baseline_candidates(against)
    named = compare([tuned], base, "named")
    test = compare([tuned], base, "test", count=args.count)
    cmd = "PYTHONPATH=src python experiments/make_readme_figures.py" + "".join(
        f" {shlex.quote(a)}" for a in (argv if argv is not None else sys.argv[1:])
    )
    md = [
        "# Results: tuned settings against the baselines",
        "",
        f"Generated by `{cmd}` (vfgym {__version__}, commit {git_commit()}, "
        f"{time.strftime('%Y-%m-%d')}); every number is `vfgym.evaluate`'s, as "
        "`vfgym evaluate` prints it. Cost: lower is better (move time over the ideal "
        "bang–coast–bang time, or tracking error for the sine, plus penalties; see "
        "`vfgym.scoring`).",
        "",
        f"**Tuned:** {what}.",
        "",
        "Cells: median [interquartile range] over the scenarios; n: scenarios where the "
        "controller applies (a fixed-pulse source cannot follow the sine). Acceleration "
        "against the motor's limit: of the pulse train (2nd difference over 1 ms) and of "
        "the motor. Feasible: scenarios meeting all constraints (overshoot within one "
        "in-position window, pulse-train acceleration within the limit, no time at the "
        "torque limit, arrival: in the in-position window at the end, a sine followed "
        "within the -3 dB bandwidth).",
        "",
        f"## The eight named scenarios ({len(named.scenarios)})",
        "",
        markdown_table(named),
        "Cost per scenario (`*`: a constraint violated; `†`: did not arrive):",
        "",
        markdown_costs(named),
        f"## {len(test.scenarios)} random test scenarios (test-0 … test-{args.count - 1})",
        "",
        markdown_table(test),
        "Win/loss: per scenario, tuned wins when its cost is lower; cost difference "
        f"tuned − baseline with a 95 % bootstrap interval ({test.resamples} resamples, "
        f"seed {test.seed}).",
        "",
        "## Figures",
        "",
        *[f"- `{p.relative_to(out)}`" for p in written],
        "",
    ]
    from vfgym.io.runs import write_text

    write_text(out / "results.md", "\n".join(md))
    write_text(out / "results_named.txt", format_table(named))
    write_text(out / "results_test.txt", format_table(test))
    for path in [*written, out / "results.md"]:
        print(f"wrote {path}")
    print(f"({time.perf_counter() - t0:.1f} s)")
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except ValueError as exc:  # bad input: one line, as the vfgym command line does
        print(f"make_readme_figures: error: {exc}", file=sys.stderr)
        sys.exit(2)
