"""The main job's figures in README.md and docs/index.md are the main job's output now.

Runs ``vfgym sweep --config experiments/quick.yaml`` (about 20 s once compiled) and
compares each page's ``quick-figures`` block with the one
``experiments/quick_figures.py`` makes from the run; on a difference, run
``PYTHONPATH=src python experiments/quick_figures.py`` to rewrite the blocks.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _script():
    spec = importlib.util.spec_from_file_location(
        "quick_figures", ROOT / "experiments/quick_figures.py"
    )
    assert spec and spec.loader
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def main_job(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return _script().run_main_job(tmp_path_factory.mktemp("runs"))


def test_pages_show_what_the_main_job_prints(main_job: Path):
    diffs = _script().check(main_job)
    assert not diffs, "run `PYTHONPATH=src python experiments/quick_figures.py`:\n" + "\n".join(
        diffs
    )


def test_the_block_holds_the_runs_numbers(main_job: Path, tmp_path: Path):
    """A page whose block disagrees by one digit is caught."""
    qf = _script()
    block = qf.render(main_job)
    report = (main_job / "report.txt").read_text(encoding="utf-8")
    verdict = report[report.index("held-out verdict") :].splitlines()
    tuned_mean = verdict[2].split()[-1]  # the report's own line: tuned  32/32  median [IQR]  mean
    rows = [line for line in block.splitlines() if line.startswith("| tuned |")]
    assert len(rows) == 1 and f" | {tuned_mean} | " in rows[0]
    for page in qf.PAGES:
        (tmp_path / page).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / page).write_text(
            qf.replace_block((ROOT / page).read_text(encoding="utf-8"), block.replace(
                tuned_mean, tuned_mean + "1"), page), encoding="utf-8")  # fmt: skip
    assert len(qf.check(main_job, tmp_path)) == len(qf.PAGES)


def test_the_main_jobs_axis_is_the_paper_machine_within_a_datasheet_tolerance():
    """The main job tunes the paper's machine (plant, measures, moves as the default axis)
    with the tolerance a datasheet motor has: inertia ±10 %, the drive's gain ±5 %."""
    import yaml

    from vfgym.axis import PAPER_AXIS, load_axis
    from vfgym.tuning import SweepConfig

    cfg = yaml.safe_load((ROOT / "experiments/quick.yaml").read_text(encoding="utf-8"))
    axis = load_axis(ROOT / cfg["axis"])
    assert (axis.plant, axis.measures, axis.moves) == (
        PAPER_AXIS.plant, PAPER_AXIS.measures, PAPER_AXIS.moves)  # fmt: skip
    assert axis.uncertainty.ranges() == {"inertia": (0.9, 1.1), "torque_per_count": (0.95, 1.05)}
    assert SweepConfig(axis=str(ROOT / cfg["axis"])).axis == axis
