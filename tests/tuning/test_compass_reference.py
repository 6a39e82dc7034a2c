"""The default sampler on the main job's problem: ``vfgym sweep --config
experiments/quick.yaml`` (the compass, seed 0, 100 trials on the default axis's 16 train
moves) ends within 1 % of the grid optimum, a reference stored beside this test (its
header names the ``vfgym grid`` command that made it)."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from vfgym import cli, evaluate, space, tuning
from vfgym.io.runs import read_yaml

REFERENCE = Path(__file__).with_name("grid_quick_reference.yaml")


def test_the_stored_reference_is_the_main_jobs_and_scores_its_cost(repo_root):
    cfg = tuning.SweepConfig.resolve(read_yaml(repo_root / "experiments" / "quick.yaml"), {})
    ref = read_yaml(REFERENCE)
    scenarios = cfg.scenario_list()
    assert ref["scenarios"] == [s.name for s in scenarios] and ref["axis"] is None
    ev = evaluate(space.settings_from_dict(ref["settings"]), scenarios)
    # A change to the model or the moves shows here first: make the reference again.
    assert float(ev.cost[0].mean()) == pytest.approx(ref["cost"], rel=1e-9)
    assert bool(ev.feasible.all()) and ref["feasible"]


def test_the_compass_ends_within_one_percent_of_the_grid_optimum(repo_root, tmp_path):
    # the main job's options on the default axis (the paper's machine as modelled, for
    # which the grid reference was made), its tolerance left out
    cfg = yaml.safe_load((repo_root / "experiments" / "quick.yaml").read_text())
    del cfg["axis"]
    cfg |= {"scenarios": "train", "scenario_count": 16, "first_seed": 0}  # its train moves
    quick = tmp_path / "quick.yaml"
    quick.write_text(yaml.safe_dump(cfg))
    argv = ["sweep", "--config", str(quick), "--reference", str(REFERENCE), "--runs-dir",
            str(tmp_path), "--study", "q", "--no-plots", "--no-progress"]  # fmt: skip
    assert cli.main(argv) == 0
    best = yaml.safe_load((tmp_path / "sweep" / "q" / "best.yaml").read_text())
    assert best["sampler"] == "compass" and best["feasible"]
    assert best["reference"]["path"] == str(REFERENCE)
    assert best["reference"]["gap_pct"] <= 1.0, best["reference"]
