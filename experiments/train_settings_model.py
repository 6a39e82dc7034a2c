"""Train a settings model on per-move optima and write it with its config and the
command that made it. The model vfgym ships (``src/vfgym/permove/pretrained/``) is rebuilt
from nothing by one command:

    python experiments/train_settings_model.py --build 320 --check 8

``--build N`` first makes the inputs: the per-move optima of ``train-0 ... train-<N-1>`` of
the environments' distribution (varied loads on the paper's plant), the full search
(:class:`vfgym.permove.optima.OptimumSearch`), checkpointed into ``--optima`` 16 moves at a
time (:func:`vfgym.permove.fit.checkpointed_optima`: an interrupted build loses nothing, the
same command continues it, and optima already there for the same moves and search are
kept; about 30 min from scratch on 2 cores), then their cost table ``--costs``
(:func:`vfgym.permove.fit.candidate_costs`, about a minute). For any axis file the whole
pipeline with a held-out verdict is ``vfgym fit --axis FILE``
(:func:`vfgym.permove.fit.fit_axis`, the same code). Without ``--build`` the model is
trained on the files as they are:

    python experiments/train_settings_model.py --kind ridge --degree 2 --ridge 1.0 \
        --out runs/ridge-model

``pick`` (:class:`vfgym.permove.supervised.PickModel`): the library candidate with the
least mean cost ratio over the move's nearest training moves, with ``--check K`` the best
on the move itself of the K best-ranked; ``ridge``
(:class:`~vfgym.permove.supervised.SettingsModel`): a ridge regression from the features
to the optimal settings. Both fit in seconds, deterministically. ``--cv K`` first prints,
for the pick model, K-fold cross-validated figures on the training moves (costs looked
up in the table, no simulation): the mean cost over the optima's, the median gap and the
feasible share, for a few neighbour counts and library sizes (model selection on train
moves only).
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import asdict
from pathlib import Path

import numpy as np

from vfgym import PAPER_PLANT, get_scenario, scenario_set
from vfgym.io.runs import write_text, write_yaml
from vfgym.moves import LOAD_DISTRIBUTION
from vfgym.moves.features import scenario_features
from vfgym.permove.fit import candidate_costs, checkpointed_optima
from vfgym.permove.optima import OptimumSearch, read_optima
from vfgym.permove.supervised import (
    TrainConfig,
    fit_pick_model,
    greedy_library,
    ratio_table,
    train_settings_model,
)

ROOT = Path(__file__).resolve().parents[1]


def cross_validate(cfg: TrainConfig, folds: int) -> None:
    """K-fold figures of the pick model for a few neighbour counts and library sizes."""
    optima = read_optima(ROOT / cfg.optima)
    scenarios = [get_scenario(o.scenario, LOAD_DISTRIBUTION) for o in optima]
    table = np.load(ROOT / cfg.costs)
    cost, feas = table["cost"], table["feasible"]
    best = np.array([o.cost for o in optima])
    n = len(optima)
    fold = np.arange(n) % folds
    for nb in (3, 4, 6, 8):
        for lib in (32, 64, 128):
            got = np.zeros(n, dtype=np.int64)
            for f in range(folds):
                tr, te = np.flatnonzero(fold != f), np.flatnonzero(fold == f)
                m = fit_pick_model([scenarios[i] for i in tr], [optima[i] for i in tr],
                                   cost[np.ix_(tr, tr)], feas[np.ix_(tr, tr)],
                                   neighbours=nb, library=min(lib, len(tr)),
                                   ignore=cfg.ignore)  # fmt: skip
                lib_cols = _library_columns(m, cost[np.ix_(tr, tr)], feas[np.ix_(tr, tr)], best[tr])
                for i in te:
                    got[i] = tr[lib_cols[m.pick(scenario_features(scenarios[i], PAPER_PLANT))]]
            c = cost[np.arange(n), got]
            gap = c / best - 1.0
            print(
                f"neighbours {nb} library {lib}: mean cost / optima {c.mean() / best.mean():.4f}, "
                f"median gap {100 * np.median(gap):.2f} %, feasible "
                f"{feas[np.arange(n), got].mean():.3f}"
            )


def _library_columns(model, cost, feas, best) -> list[int]:
    """The table columns the model's library rows came from (as fit_pick_model picks)."""
    return list(greedy_library(np.round(ratio_table(cost, feas, best), 6), model.library.shape[0]))


def build_inputs(cfg: TrainConfig, count: int) -> None:
    """The optima of train-0 ... train-<count-1> (checkpointed, resumed) and their costs."""
    scenarios = scenario_set("train", count, 0, LOAD_DISTRIBUTION)
    t0 = time.time()

    def progress(done: int) -> None:
        print(f"{time.time() - t0:7.1f} s  +{done} optima", file=sys.stderr, flush=True)

    optima = checkpointed_optima(scenarios, OptimumSearch(), ROOT / cfg.optima, progress=progress)
    cost, feas = candidate_costs(scenarios, optima)
    names = np.array([o.scenario for o in optima])
    np.savez_compressed(ROOT / cfg.costs, scenarios=names, cost=cost, feasible=feas)
    print(f"{time.time() - t0:7.1f} s  {count} x {count} costs -> {cfg.costs}", file=sys.stderr)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    d = TrainConfig()
    ap.add_argument("--kind", default=d.kind)
    ap.add_argument("--optima", default=d.optima)
    ap.add_argument("--costs", default=d.costs)
    ap.add_argument("--neighbours", type=int, default=d.neighbours)
    ap.add_argument("--library", type=int, default=d.library)
    ap.add_argument("--ignore", default=",".join(d.ignore))
    ap.add_argument("--degree", type=int, default=d.degree)
    ap.add_argument("--ridge", type=float, default=d.ridge)
    ap.add_argument("--check", type=int, default=d.check)
    ap.add_argument("--cv", type=int, default=0)
    ap.add_argument("--build", type=int, default=0, metavar="N",
                    help="first build the optima of N train moves and their costs")  # fmt: skip
    ap.add_argument("--out", default="src/vfgym/permove/pretrained")
    args = ap.parse_args()
    ignore = tuple(x for x in args.ignore.split(",") if x)
    cfg = TrainConfig(args.kind, args.optima, args.costs, args.neighbours, args.library,
                      ignore, args.degree, args.ridge, args.check)  # fmt: skip
    if args.build:
        build_inputs(cfg, args.build)
    if args.cv:
        cross_validate(cfg, args.cv)
    model = train_settings_model(cfg, ROOT)
    out = Path(args.out)
    model.save(out / "settings_model.json")
    write_yaml(out / "config.yaml", asdict(cfg) | {"ignore": list(cfg.ignore)})
    argv = ["python", "experiments/train_settings_model.py", "--kind", cfg.kind,
            "--optima", cfg.optima, "--costs", cfg.costs, "--neighbours", str(cfg.neighbours),
            "--library", str(cfg.library), "--ignore", ",".join(cfg.ignore),
            "--degree", str(cfg.degree), "--ridge", repr(cfg.ridge), "--check", str(cfg.check),
            *(["--build", str(args.build)] if args.build else []), "--out", args.out]  # fmt: skip
    write_text(out / "command.txt", " ".join(argv) + "\n")
    print(f"model -> {out / 'settings_model.json'}", file=sys.stderr)


if __name__ == "__main__":
    main()
