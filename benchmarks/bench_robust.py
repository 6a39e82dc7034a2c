"""Tuning that holds on the machine: prints figures, asserts nothing (machines are noisy).

Four measurements, each selectable:

- ``fit``: ``vfgym fit`` on an axis with ``uncertainty:`` (default
  ``experiments/axes/loads-uncertain.yaml``), timed, then judged on its test moves ×
  ``--plants`` plants drawn within the uncertainty (seed ``--plant-seed``): the share of
  feasible (move, plant) pairs, its mean cost on the modelled plant against the robust
  per-move optima of the same moves (feasible on the axis's design plants, found by the
  per-move search of :func:`vfgym.permove.optima.move_optima` with its default, finer
  grid), its wins against the paper's settings, and the same for 8 to 64 candidates
  checked by the model on each move;
- ``sweep``: the main job's budget (``experiments/quick.yaml``) on the same axis, and on
  the axis with its uncertainty left out, each tuned setting judged on the same pairs;
- ``evaluate``: the cost of a robust evaluation, P plants of a setting in one batched
  call against one plant (the ratio should be at most P);
- ``nominal``: the ±5 % inertia line of the main job's setting on the paper axis;
- ``grid``: the per-move search the optima come from, against ``vfgym grid`` on three
  test moves (the modelled plant);
- ``pick``: a settings model's robust pick (:func:`vfgym.scoring.best_robust`, the design
  checked lazily) against ranking every candidate's :func:`vfgym.scoring.score_robust`
  score, on 24 train-distribution moves: the time of each and whether the picks agree
  (the model: ``--model FILE``, default the ``fit`` part's);
- ``bound``: on the moves where the robust per-move optimum costs more than the paper's
  settings (``--moves``), every setting of a 10-point grid (both laws) and 4000 draws
  around the paper's settings, each checked on the design plants: the cheapest feasible
  one against the paper's, a check of the bound on wins a robust tuner can reach.

    python benchmarks/bench_robust.py [--parts fit,sweep,evaluate,nominal,grid,pick]
        [--axis FILE] [--plants 16] [--plant-seed 20261204] [--runs-dir DIR] [--model FILE]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from vfgym import PAPER_AXIS, Settings, cli, evaluate, load_axis
from vfgym.axis import EXACT, VERDICT_PLANT_SEED, VERDICT_PLANTS, draw_plants, write_axis
from vfgym.commands._common import load_settings
from vfgym.moves.baselines import Baseline
from vfgym.permove.optima import OptimumSearch, move_optima
from vfgym.permove.supervised import load_settings_model
from vfgym.scoring import Move, score_robust

ROOT = Path(__file__).resolve().parents[1]


def judge(label: str, per_move: list[Settings], axis, plants, seed: int, optima=None) -> None:
    """Print one tuner's figures on the axis's test moves across the drawn plants."""
    test = axis.scenarios("test")
    variants = draw_plants(axis.uncertainty, axis.plant, plants, seed)
    chosen = {sc.name: s for sc, s in zip(test, per_move, strict=True)}
    ev = evaluate([lambda sc: chosen[sc.name], "paper"], test, axis=axis, plants=variants,
                  plant_seed=seed)  # fmt: skip
    assert ev.across is not None  # (given plants)
    s, paper = ev.across.summary(0), ev.across.summary(1)
    own, ok = ev.cost[0], ev.feasible[0]
    wins = int(np.sum(own < ev.cost[1]))
    print(f"{label}: feasible on {s.feasible}/{s.pairs} (move, plant) pairs "
          f"({100 * s.feasible / s.pairs:.1f} %), {s.moves_feasible}/{s.moves} moves on every "
          f"plant; modelled plant: feasible {ok.sum()}/{len(test)}, mean cost {own.mean():.4f}; "
          f"beats the paper's settings on {wins}/{len(test)} moves "
          f"(paper: {paper.feasible}/{paper.pairs} pairs)")  # fmt: skip
    if optima is not None:
        best = np.array([o.cost for o in optima])
        feas = sum(o.feasible for o in optima)
        print(f"  robust per-move optima: mean {best.mean():.4f} ({feas}/{len(optima)} "
              f"feasible on the design); {label} / optima = {own.mean() / best.mean():.4f}, "
              f"median per move {np.median(own / best):.4f}")  # fmt: skip
        # the most wins a tuner feasible on the design can have: where the robust optimum
        # itself costs more than the paper's settings, no robust setting beats them
        held = score_robust([Baseline("paper")] * len(test),
                            [Move.of(sc, axis.plant) for sc in test], axis.design_plants(),
                            measures=axis.measures)  # fmt: skip
        can = best < ev.cost[1]
        lost = [f"{sc.name} (optimum {b:.3f}, paper {p:.3f}, paper on the design: "
                f"{'feasible' if h.feasible else 'infeasible'})"
                for sc, b, p, h, c in zip(test, best, ev.cost[1], held, can, strict=True)
                if not c]  # fmt: skip
        print(
            f"  robust optima beat the paper's settings on {int(can.sum())}/{len(test)} moves"
            f" (the most a robust tuner can); not on: {', '.join(lost) or 'none'}"
        )


def part_fit(axis_file: str, axis, args) -> None:
    runs = Path(args.runs_dir)
    t0 = time.perf_counter()
    code = cli.main(["fit", "--axis", axis_file, "--name", "bench", "--runs-dir", str(runs),
                     "--no-progress"])  # fmt: skip
    wall = time.perf_counter() - t0
    print(f"\nfit: exit {code}, {wall:.1f} s wall (goal: within 300 s)")
    model = load_settings_model(runs / "fit" / "bench" / "settings_model.json")
    design = axis.design_plants()
    test = axis.scenarios("test")
    chosen = [model.settings(sc, axis.plant, axis.measures, design) for sc in test]
    t0 = time.perf_counter()
    optima = move_optima(test, OptimumSearch(), plant=axis.plant, measures=axis.measures,
                         plants=design)  # fmt: skip
    print(f"robust per-move optima of the {len(test)} test moves: "
          f"{time.perf_counter() - t0:.1f} s")  # fmt: skip
    judge("fit", chosen, axis, args.plants, args.plant_seed, optima)
    best = np.mean([o.cost for o in optima])
    print("candidates the model checks on a move (its check; the fit's is "
          f"{model.check}): mean cost / robust optima, time for the {len(test)} moves")  # fmt: skip
    for check in (8, 16, 32, 64):
        m = replace(model, check=check)
        t0 = time.perf_counter()
        picks = [m.settings(sc, axis.plant, axis.measures, design) for sc in test]
        dt = time.perf_counter() - t0
        ev = evaluate(picks, test, axis=axis)
        own = np.diag(ev.cost)
        print(f"  check {check}: {own.mean() / best:.4f} ({dt:.1f} s)")


def part_sweep(axis_file: str, axis, args) -> None:
    """The main job's budget on the axis, and on the same axis without its uncertainty,
    both judged on the same (move, plant) pairs."""
    runs = Path(args.runs_dir)
    exact = runs / "exact.yaml"
    write_axis(replace(axis, uncertainty=EXACT, name=f"{axis.name}-exact"), exact)
    for label, path in (("sweep", axis_file), ("sweep, uncertainty left out", str(exact))):
        t0 = time.perf_counter()
        study = "bench" if path == axis_file else "bench-exact"
        code = cli.main(["sweep", "--config", "experiments/quick.yaml", "--axis", path,
                         "--study", study, "--runs-dir", str(runs), "--no-progress"])  # fmt: skip
        print(f"\n{label}: exit {code}, {time.perf_counter() - t0:.1f} s wall")
        best = load_settings(str(runs / "sweep" / study / "best.yaml"), axis)
        judge(label, [best] * len(axis.scenarios("test")), axis, args.plants, args.plant_seed)


def part_evaluate(axis, args) -> None:
    test = axis.scenarios("test")
    s = Settings(value_rad=0.882, error_limit_rad=0.872, k=430.9, ts_over_tf=1.0)
    variants = draw_plants(axis.uncertainty, axis.plant, args.plants, args.plant_seed)
    evaluate([s], test, axis=axis)  # compiled
    one, many = [], []
    for _ in range(3):
        t0 = time.perf_counter()
        evaluate([s], test, axis=axis)
        one.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        evaluate([s], test, axis=axis, plants=variants)
        many.append(time.perf_counter() - t0)
    p = len(variants)
    ratio = min(many) / min(one)
    print(f"\nevaluate: one plant {min(one) * 1e3:.1f} ms, the modelled plant and {p} more in "
          f"one call {min(many) * 1e3:.1f} ms: {ratio:.2f}x for {p + 1} plants "
          f"({ratio / (p + 1):.2f} of {p + 1}x; goal at most 1)")  # fmt: skip


def part_nominal() -> None:
    s = Settings(value_rad=0.882, error_limit_rad=0.872, k=430.9, ts_over_tf=1.0)
    test = PAPER_AXIS.scenarios("test")
    from vfgym.axis import PlantVariant

    line = []
    for f in (0.95, 1.02, 1.05, 1.10, 1.25):
        ev = evaluate([s, "paper"], test, plants=[PlantVariant(inertia=f)])
        assert ev.across is not None
        line.append(f"x{f:g}: {ev.across.summary(0).feasible}/32 "
                    f"(paper {ev.across.summary(1).feasible}/32)")  # fmt: skip
    print("\nnominal: the main job's setting on the paper axis's test moves, feasible at "
          "inertia " + ", ".join(line))  # fmt: skip


def part_grid(axis_file: str, axis, args) -> None:
    """The per-move search (modelled plant) against ``vfgym grid`` (12 points a
    dimension, refined twice) on three test moves: the search the optima come from."""
    from vfgym.tuning import GridConfig, run_grid

    test = axis.scenarios("test")[:3]
    mine = move_optima(test, OptimumSearch(), plant=axis.plant, measures=axis.measures)
    print()
    for sc, o in zip(test, mine, strict=True):
        t0 = time.perf_counter()
        g = run_grid(GridConfig(axis=axis_file, scenarios=sc.name, progress=False))
        took = time.perf_counter() - t0
        ok = "feasible" if o.feasible else "infeasible"
        gok = "feasible" if g.best.feasible else "infeasible"
        print(f"grid check {sc.name}: per-move search {o.cost:.4f} ({ok}), grid "
              f"{g.best.cost:.4f} ({gok}): {o.cost / g.best.cost:.4f}x ({took:.0f} s)")  # fmt: skip


def part_pick(axis, args) -> None:
    from vfgym.moves.features import scenario_features
    from vfgym.permove.targets import target_settings

    path = args.model or Path(args.runs_dir) / "fit" / "bench" / "settings_model.json"
    model = load_settings_model(path)
    design = axis.design_plants()
    moves = [axis.moves.train.pick(1000 + i, "train", axis.plant) for i in range(24)]

    def rank_all(sc):  # every candidate scored on the design, then ranked
        loaded = sc.plant(axis.plant)
        order = model.ranked(scenario_features(sc, axis.plant, loaded))
        cands = [target_settings(model.library[j], loaded, model.accel_law)
                 for j in order[: model.check]]  # fmt: skip
        r = score_robust(cands, [Move.of(sc, axis.plant)] * len(cands), design,
                         measures=axis.measures)  # fmt: skip
        return cands[min(range(len(cands)), key=lambda i: (not r[i].feasible, r[i].cost, i))]

    rank_all(moves[0]), model.settings(moves[0], axis.plant, axis.measures, design)  # compiled
    for rep in range(2):
        t0 = time.perf_counter()
        a = [rank_all(sc) for sc in moves]
        t1 = time.perf_counter()
        b = [model.settings(sc, axis.plant, axis.measures, design) for sc in moves]
        t2 = time.perf_counter()
        print(f"pick, repeat {rep + 1}: rank every candidate {t1 - t0:.2f} s, lazy check "
              f"{t2 - t1:.2f} s ({(t1 - t0) / (t2 - t1):.1f}x), same picks: {a == b}")  # fmt: skip


def part_bound(axis, args) -> None:
    from vfgym import space
    from vfgym.moves.baselines import resolve

    rng = np.random.default_rng(0)
    test = {sc.name: sc for sc in axis.scenarios("test")}
    print()
    for name in args.moves.split(","):
        sc, move = test[name], Move.of(test[name], axis.plant)
        paper = resolve(Baseline("paper"), move.plant)
        cost = evaluate(["paper"], [sc], axis=axis).cost[0, 0]
        cands = space.grid(10, laws=("rise", "slew"))
        for f in np.exp(rng.normal(0.0, 0.3, (4000, 4))):  # log-normal draws, 30 %
            x = [getattr(paper, d.name) * g for d, g in zip(space.SPACE, f, strict=True)]
            if all(d.low <= v <= d.high for d, v in zip(space.SPACE, x, strict=True)):
                cands.append(Settings(*x, accel_law=paper.accel_law))
        t0 = time.perf_counter()
        r = score_robust(cands, [move] * len(cands), axis.design_plants(), measures=axis.measures)
        ok = [(s.cost, i) for i, s in enumerate(r) if s is not None and s.feasible]
        low, i = min(ok)
        print(f"bound {name}: paper's settings {cost:.4f}; of {len(cands)} candidates "
              f"{len(ok)} are feasible on the design, the cheapest {low:.4f} "
              f"({cands[i]}; {time.perf_counter() - t0:.0f} s)")  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--parts", default="fit,sweep,evaluate,nominal,grid")
    ap.add_argument("--axis", default="experiments/axes/loads-uncertain.yaml")
    ap.add_argument("--plants", type=int, default=VERDICT_PLANTS)
    ap.add_argument("--plant-seed", type=int, default=VERDICT_PLANT_SEED)
    ap.add_argument("--runs-dir", default=tempfile.mkdtemp(prefix="bench-robust-"))
    ap.add_argument("--model", default=None, help="settings model of the pick part")
    ap.add_argument("--moves", default="test-15,test-28", help="moves of the bound part")
    args = ap.parse_args()
    axis_file = str(ROOT / args.axis)
    axis = load_axis(axis_file)
    parts = args.parts.split(",")
    print(f"axis {axis.name}: uncertainty {axis.uncertainty.to_dict()}, "
          f"{len(axis.design_plants())} design plants; runs in {args.runs_dir}")  # fmt: skip
    if "nominal" in parts:
        part_nominal()
    if "evaluate" in parts:
        part_evaluate(axis, args)
    if "sweep" in parts:
        part_sweep(axis_file, axis, args)
    if "fit" in parts:
        part_fit(axis_file, axis, args)
    if "bound" in parts:
        part_bound(axis, args)
    if "grid" in parts:
        part_grid(axis_file, axis, args)
    if "pick" in parts:
        part_pick(axis, args)


if __name__ == "__main__":
    main()
