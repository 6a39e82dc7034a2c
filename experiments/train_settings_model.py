"""Train the supervised settings model on per-move optima and write it with its config
and the command that made it (the shipped one: ``src/vfgym/agents/pretrained/``):

    python experiments/train_settings_model.py --optima experiments/optima/train.csv \
        --degree 2 --ridge 1.0 --out src/vfgym/agents/pretrained

A closed-form ridge regression (:func:`vfgym.agents.supervised.fit_settings_model`):
seconds, deterministic. ``--cv K`` first prints K-fold cross-validated target errors for a
few ridge penalties on the same optima (model selection on train moves only).
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import asdict
from pathlib import Path

import numpy as np

from vfgym import PAPER_PLANT, get_scenario
from vfgym.agents.optima import read_optima
from vfgym.agents.supervised import (
    TrainConfig,
    fit_settings_model,
    settings_targets,
    train_settings_model,
)
from vfgym.envs._common import scenario_features
from vfgym.io.runs import write_text, write_yaml

ROOT = Path(__file__).resolve().parents[1]


def cross_validate(cfg: TrainConfig, folds: int) -> None:
    """K-fold target RMSE (per target) of each degree and a few ridge penalties."""
    optima = read_optima(ROOT / cfg.optima)
    scenarios = [get_scenario(o.scenario) for o in optima]
    y = np.array(
        [settings_targets(o.settings, sc.plant()) for o, sc in zip(optima, scenarios, strict=False)]
    )
    x = np.array([scenario_features(sc, PAPER_PLANT) for sc in scenarios])
    fold = np.arange(len(optima)) % folds
    for degree in (1, 2):
        for ridge in (0.1, 1.0, 10.0, 100.0):
            err = np.zeros_like(y)
            for f in range(folds):
                tr = np.flatnonzero(fold != f)
                m = fit_settings_model([scenarios[i] for i in tr], [optima[i] for i in tr],
                                       degree=degree, ridge=ridge)  # fmt: skip
                err[fold == f] = m.predict_targets(x[fold == f]) - y[fold == f]
            rmse = np.sqrt(np.mean(err**2, axis=0))
            print(f"degree {degree} ridge {ridge:6g}: target RMSE {np.round(rmse, 3).tolist()}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    d = TrainConfig()
    ap.add_argument("--optima", default=d.optima)
    ap.add_argument("--degree", type=int, default=d.degree)
    ap.add_argument("--ridge", type=float, default=d.ridge)
    ap.add_argument("--cv", type=int, default=0)
    ap.add_argument("--out", default="src/vfgym/agents/pretrained")
    args = ap.parse_args()
    cfg = TrainConfig(args.optima, args.degree, args.ridge)
    if args.cv:
        cross_validate(cfg, args.cv)
    model = train_settings_model(cfg, ROOT)
    out = Path(args.out)
    model.save(out / "settings_model.json")
    write_yaml(out / "config.yaml", asdict(cfg))
    argv = ["python", "experiments/train_settings_model.py", "--optima", cfg.optima,
            "--degree", str(cfg.degree), "--ridge", repr(cfg.ridge), "--out", args.out]  # fmt: skip
    write_text(out / "command.txt", " ".join(argv) + "\n")
    print(f"model -> {out / 'settings_model.json'}", file=sys.stderr)


if __name__ == "__main__":
    main()
