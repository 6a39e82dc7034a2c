"""Trained VFServo-v0 runs judged with other env arguments than they were trained with:
each run's files copied into ``--out`` with ``eval_env_kwargs`` set (the hyperparameter
files' own key for env arguments at validation and deployment), then
``benchmarks/bench_adaptive.py`` on the copies. What a change of the shield alone gives
an agent already trained, before it is trained again:

    PYTHONPATH=src python experiments/judged_with.py --set shield_gentler=3 \\
        --runs runs/train/s48-ppo-seed1-lu-grid --out runs/judged-gentler

Arguments after ``--`` go to ``bench_adaptive.py`` (e.g. ``-- --model final_model.zip``).
"""

from __future__ import annotations

import argparse
import shutil
import sys
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[1]
KEEP = ("*.zip", "*.pkl", "*.yaml", "*.txt", "*.csv", "*.json")


def copy_run(run: Path, dest: Path, settings: dict) -> Path:
    """``run``'s models and records copied to ``dest``, its config's ``eval_env_kwargs``
    updated with ``settings``."""
    dest.mkdir(parents=True, exist_ok=True)
    for pattern in KEEP:
        for f in run.glob(pattern):
            shutil.copy2(f, dest / f.name)
    cfg_path = dest / "config.yaml"
    cfg = yaml.safe_load(cfg_path.read_text())
    hp = cfg.setdefault("hyperparams", {})
    hp["eval_env_kwargs"] = {**(hp.get("eval_env_kwargs") or {}), **settings}
    cfg_path.write_text(yaml.safe_dump(cfg, sort_keys=False))
    return dest


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    cut = argv.index("--") if "--" in argv else len(argv)
    own, rest = argv[:cut], argv[cut + 1 :]
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", nargs="+", required=True, help="trained VFServo-v0 run folders")
    ap.add_argument("--set", nargs="+", required=True, metavar="KEY=VALUE",
                    help="env arguments, values as YAML")  # fmt: skip
    ap.add_argument("--axis", default="experiments/axes/loads-uncertain.yaml")
    ap.add_argument("--out", required=True)
    args = ap.parse_args(own)
    settings = {}
    for item in args.set:
        key, sep, value = item.partition("=")
        if not sep:
            ap.error(f"--set {item!r}: give KEY=VALUE")
        settings[key] = yaml.safe_load(value)
    out = Path(args.out)
    copies = [copy_run(Path(r), out / "runs" / Path(r).name, settings) for r in args.runs]
    sys.path.insert(0, str(ROOT / "benchmarks"))
    from bench_adaptive import main as bench

    return bench(["--axis", args.axis, "--runs", *map(str, copies), "--no-oracle",
                  "--out", str(out), *rest])  # fmt: skip


if __name__ == "__main__":
    raise SystemExit(main())
