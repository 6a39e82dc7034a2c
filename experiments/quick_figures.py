"""The main job's figures in README.md and docs/index.md, from a run of the main job.

The block between ``<!-- quick-figures:begin -->`` and ``<!-- quick-figures:end -->`` in
each page is made here from a finished ``vfgym sweep --config experiments/quick.yaml``
run folder (its ``best.yaml`` and the held-out verdict in its ``summary.yaml``), never
typed by hand:

    PYTHONPATH=src python experiments/quick_figures.py            # run the main job, rewrite
    PYTHONPATH=src python experiments/quick_figures.py --run runs/sweep/NAME
    PYTHONPATH=src python experiments/quick_figures.py --check    # exit 1 if a page differs

``tests/test_quick_figures.py`` runs the main job and fails when a page disagrees with it.
"""

from __future__ import annotations

import argparse
import difflib
import sys
import tempfile
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parent.parent
PAGES = ("README.md", "docs/index.md")
BEGIN = "<!-- quick-figures:begin -->"
END = "<!-- quick-figures:end -->"
COMMAND = ["sweep", "--config", "experiments/quick.yaml"]
NAMES = {"paper": "paper", "rule-of-thumb": "rule of thumb", "scurve": "S-curve source"}


def _g(x: float) -> str:
    """A cost as the report prints it: three significant digits, a true minus sign."""
    return f"{x:.3g}".replace("-", "−")


def render(run_dir: Path) -> str:
    """The figures block (between the markers, markers excluded) of a main-job run.

    Parameters
    ----------
    run_dir : Path
        A finished ``vfgym sweep --config experiments/quick.yaml`` run folder.

    Returns
    -------
    str
        Markdown: the tuned setting with its train cost, and the held-out verdict table.
    """
    best = yaml.safe_load((run_dir / "best.yaml").read_text(encoding="utf-8"))
    summary = yaml.safe_load((run_dir / "summary.yaml").read_text(encoding="utf-8"))
    verdict = summary["verdict"]
    s = best["settings"]
    change = 100.0 * (best["cost"] / best["paper_cost"] - 1.0)
    lines = [
        f"Made by `python experiments/quick_figures.py` from a run of "
        f"`vfgym sweep --config experiments/quick.yaml` ({summary['trials']['complete']} "
        f"trials); `tests/test_quick_figures.py` re-runs it and fails when this block differs.",
        "",
        f"Tuned setting: value {s['value_rad']:.3f} rad, L {s['error_limit_rad']:.3f} rad, "
        f"k {s['k']:.1f}, Ts/Tf {s['ts_over_tf']:.3f}. Train cost {best['cost']:.3f} against "
        f"the paper's {best['paper_cost']:.3f} ({change:+.0f} %)".replace("-", "−")
        + f", {'feasible' if best['feasible'] else 'infeasible'} on the "
        f"{len(best['scenarios'])} train moves. Held-out verdict on {verdict['title']}:",
        "",
        "| controller | feasible | cost median [IQR] | mean cost | tuned wins/losses "
        "| cost tuned − it: mean (95 % CI) |",
        "| --- | --- | --- | --- | --- | --- |",
    ]
    for row in verdict["controllers"]:
        c = row["cost"]
        name = NAMES.get(row["controller"], row["controller"])
        cells = [
            name,
            f"{row['feasible']}/{row['applicable']}",
            f"{_g(c['median'])} [{_g(c['q1'])}, {_g(c['q3'])}]",
            _g(c["mean"]),
        ]
        if "cost_diff" in row:
            d = row["cost_diff"]
            cells += [
                f"{row['wins']}/{row['losses']}",
                f"{_g(d['mean'])} ({_g(d['ci_low'])}, {_g(d['ci_high'])})",
            ]
        else:
            cells += ["", ""]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join([*lines, "", plants_line(verdict)])


def plants_line(verdict: dict) -> str:
    """The verdict across true plants as one sentence: the ±5 % inertia sensitivity line
    where the axis states no uncertainty, else the feasible (move, plant) pairs."""
    p = verdict["plants"]
    rows = p["controllers"]
    if p["seed"] is None:
        per = " / ".join(x.replace("J", "") for x in p["plants"])
        each = "; ".join(
            f"{NAMES.get(r['controller'], r['controller'])} "
            + " / ".join(f"{n}/{r['moves']}" for n in r["feasible_per_plant"])
            for r in rows
        )
        return (
            f"Sensitivity (the axis states no uncertainty), feasible moves with {per} the "
            f"modelled inertia, the drive's gain as set: {each}."
        )
    each = "; ".join(
        f"{NAMES.get(r['controller'], r['controller'])} {r['feasible']}/{r['pairs']}" for r in rows
    )
    return (
        f"Across {len(p['plants'])} plants drawn within the axis's uncertainty (plant seed "
        f"{p['seed']}), feasible (move, plant) pairs: {each}."
    )


def replace_block(text: str, block: str, page: str) -> str:
    """``text`` with the lines between the markers replaced by ``block``.

    Parameters
    ----------
    text : str
        The page's text.
    block : str
        The new block, markers excluded.
    page : str
        The page's name, for the error message.

    Returns
    -------
    str
        The page's new text.
    """
    head, sep, rest = text.partition(BEGIN)
    _, sep2, tail = rest.partition(END)
    if not sep or not sep2:
        raise SystemExit(f"{page}: no {BEGIN} … {END} block")
    return f"{head}{BEGIN}\n{block}\n{END}{tail}"


def run_main_job(runs_dir: Path) -> Path:
    """Run the main job into ``runs_dir`` (from the repository root) and return its folder.

    Parameters
    ----------
    runs_dir : Path
        The root of the run folders to use.

    Returns
    -------
    Path
        The main job's run folder.
    """
    import os

    from vfgym.cli import main

    here = Path.cwd()
    os.chdir(ROOT)
    try:
        code = main([*COMMAND, "--study", "quick", "--runs-dir", str(runs_dir)])
    finally:
        os.chdir(here)
    if code != 0:
        raise SystemExit(f"the main job exited {code}")
    return runs_dir / "sweep" / "quick"


def check(run_dir: Path, root: Path = ROOT) -> list[str]:
    """The differences between each page's block and the run's, as unified diffs.

    Parameters
    ----------
    run_dir : Path
        A finished main-job run folder.
    root : Path
        The repository whose pages are checked.

    Returns
    -------
    list of str
        One diff per page that disagrees with the run; empty when all agree.
    """
    block = render(run_dir)
    diffs = []
    for page in PAGES:
        text = (root / page).read_text(encoding="utf-8")
        new = replace_block(text, block, page)
        if new != text:
            diff = difflib.unified_diff(
                text.splitlines(), new.splitlines(), page, f"{page} (the run)", lineterm=""
            )
            diffs.append("\n".join(diff))
    return diffs


def main(argv: list[str] | None = None) -> int:
    """Rewrite (or with ``--check`` compare) the pages' blocks; exit 1 when they differ."""
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--run", help="a finished main-job run folder (default: run the main job)")
    p.add_argument("--check", action="store_true", help="compare only; exit 1 on a difference")
    args = p.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        run_dir = Path(args.run) if args.run else run_main_job(Path(tmp))
        if args.check:
            diffs = check(run_dir)
            for d in diffs:
                print(d)
            return 1 if diffs else 0
        block = render(run_dir)
        for page in PAGES:
            path = ROOT / page
            path.write_text(
                replace_block(path.read_text(encoding="utf-8"), block, page), encoding="utf-8"
            )
            print(f"wrote {page}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
