"""`vfgym grid`: the exhaustive reference through the batched kernel, and the gap a sweep
reports to it."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest
import yaml

from vfgym import cli, space, tuning
from vfgym.axis import PAPER_AXIS
from vfgym.commands._common import load_settings
from vfgym.scoring import evaluate


def grid_rows(run: Path) -> list[dict[str, str]]:
    with open(run / "grid.csv", newline="") as fh:
        return list(csv.DictReader(fh))


@pytest.fixture(scope="module")
def grid_run(tmp_path_factory) -> Path:
    root = tmp_path_factory.mktemp("runs")
    argv = ["grid", "--scenarios", "short-move", "--points", "3", "--refine", "1", "--keep", "2",
            "--runs-dir", str(root), "--no-progress"]  # fmt: skip
    assert cli.main(argv) == 0
    (run,) = (root / "grid").iterdir()
    return run


def test_grid_covers_the_space_and_its_best_is_the_reference(grid_run):
    rows = grid_rows(grid_run)
    level0 = [r for r in rows if r["level"] == "0"]
    want = {(*(getattr(s, n) for n in space.NAMES), s.accel_law) for s in space.grid(3)}
    got = {(*(float(r[n]) for n in space.NAMES), r["accel_law"]) for r in level0}
    assert got == want and len(level0) == 81
    assert len(rows) > 81  # the refinement added points

    ref = yaml.safe_load((grid_run / "reference.yaml").read_text())
    feasible = [r for r in rows if r["feasible"] == "1"]
    assert ref["cost"] == min(float(r["cost"]) for r in feasible)
    assert ref["evaluated"] == len(rows) and ref["scenarios"] == ["short-move"]
    # The reference is a Settings-YAML file scored on the one path.
    ev = evaluate(load_settings(str(grid_run / "reference.yaml"), PAPER_AXIS), "short-move")
    assert float(ev.mean_cost[0]) == pytest.approx(ref["cost"], rel=1e-12)
    assert bool(ev.feasible.all()) == ref["feasible"]


def test_refinement_stays_next_to_the_best_level0_points(grid_run):
    rows = grid_rows(grid_run)
    unit = {
        key: np.array([d.to_unit(float(r[d.name])) for d in space.SPACE])
        for key, r in enumerate(rows)
    }
    level0 = [i for i, r in enumerate(rows) if r["level"] == "0"]
    level1 = [i for i, r in enumerate(rows) if r["level"] == "1"]
    step = 1.0  # 3 points over [-1, 1]
    for i in level1:
        assert min(np.max(np.abs(unit[i] - unit[j])) for j in level0) <= step + 1e-9


def test_batches_do_not_change_the_numbers():
    cfg = tuning.GridConfig(scenarios="short-move", points=2, refine=0, batch=5)
    a = tuning.run_grid(cfg)
    b = tuning.run_grid(tuning.GridConfig(scenarios="short-move", points=2, refine=0))
    assert [r.cost for r in a.rows] == [r.cost for r in b.rows]
    one = evaluate(a.rows[7].settings, "short-move")
    assert a.rows[7].cost == float(one.mean_cost[0])


def test_sweep_reports_its_gap_to_the_reference(grid_run, capsys):
    root = grid_run.parent.parent
    argv = ["sweep", "--scenarios", "short-move", "--trials", "4", "--runs-dir", str(root),
            "--study", "g", "--no-progress", "--no-plots"]  # fmt: skip
    assert cli.main(argv) == 0
    out = capsys.readouterr().out
    best = yaml.safe_load((root / "sweep" / "g" / "best.yaml").read_text())
    ref = yaml.safe_load((grid_run / "reference.yaml").read_text())
    gap = 100.0 * (best["cost"] - ref["cost"]) / ref["cost"]
    assert best["reference"]["gap_pct"] == pytest.approx(gap)
    assert best["reference"]["path"] == str(grid_run / "reference.yaml")
    assert f"{gap:+.2f} %" in out
    # A reference for other scenarios is refused by name.
    bad = [*argv[:-4], "--study", "h", "--scenarios", "paper-step", "--reference", str(grid_run)]
    assert cli.main(bad) == 2
    assert "reference" in capsys.readouterr().err


def test_a_reference_for_another_problem_is_passed_over_or_refused_by_its_key(grid_run):
    from vfgym.tuning._results import find_reference

    scenarios = tuning.GridConfig(scenarios="short-move").scenario_list()
    runs = str(grid_run.parent.parent)
    assert find_reference(None, runs, scenarios, ("rise",)).path == grid_run / "reference.yaml"
    for laws, axis, key in ((("rise", "slew"), None, "laws"), (("rise",), "abc", "axis")):
        assert find_reference(None, runs, scenarios, laws, axis) is None
        with pytest.raises(ValueError, match=f"^reference=.* is for {key} "):
            find_reference(str(grid_run), runs, scenarios, laws, axis)


def test_bad_grid_options(tmp_path, capsys):
    assert cli.main(["grid", "--points", "1", "--runs-dir", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "points" in err and len(err.strip().splitlines()) == 1
    assert cli.main(["grid", "--scenarios", "nowhere", "--runs-dir", str(tmp_path)]) == 2
    assert "scenario" in capsys.readouterr().err
