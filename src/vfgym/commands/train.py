"""``vfgym train``: train a stable-baselines3 agent on a vfgym environment."""

from __future__ import annotations

import argparse
from pathlib import Path


def add_parser(sub: argparse._SubParsersAction) -> None:
    from vfgym.commands._common import add_axis_option

    p = sub.add_parser(
        "train",
        help="train a PPO, SAC or TD3 agent (agents extra)",
        description=__doc__ + " Hyperparameters come from "
        "agents/hyperparams/<algo>.yml (one section per env), overridable "
        "with --hyperparams key=value. Starting a run again continues it "
        "from its last checkpoint.",
    )
    p.add_argument("--algo", required=True, help="ppo, sac or td3")
    p.add_argument(
        "--env", default="vfgym/VFTune-v0", help="vfgym/VFTune-v0 (default) or vfgym/VFServo-v0"
    )
    p.add_argument("--hyperparams-file", help="YAML file (default agents/hyperparams/ALGO.yml)")
    p.add_argument(
        "--hyperparams",
        nargs="*",
        metavar="KEY=VALUE",
        help="overrides, values as YAML (e.g. n_timesteps=2000 n_envs=4)",
    )
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--runs-dir", default="runs", help="root of the run folders (default runs)")
    p.add_argument(
        "--name",
        help="run folder name (default ALGO-ENV-seedSEED); an existing "
        "run of that name is continued",
    )
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    add_axis_option(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from vfgym.agents import hyperparams as hp

    if args.hyperparams_file is None:
        local = Path("agents/hyperparams") / f"{args.algo}.yml"
        file = local if local.is_file() else None
    else:
        file = args.hyperparams_file
    params = hp.load(args.algo, args.env, file, hp.parse_overrides(args.hyperparams))
    if args.axis:  # the envs draw their moves from the axis (env_kwargs: axis=FILE)
        from vfgym.commands._common import axis_from_args

        axis_from_args(args)  # a bad file fails before a run folder is made
        params["env_kwargs"] = {**(params.get("env_kwargs") or {}), "axis": args.axis}
    from vfgym.agents.training import train
    from vfgym.io.runs import new_run_dir, record_command

    name = args.name or f"{args.algo}-{args.env.split('/')[-1]}-seed{args.seed}"
    run_dir = new_run_dir(args.runs_dir, "train", name)
    record_command(run_dir)
    print(f"run folder: {run_dir}")
    train(args.algo, args.env, params, run_dir, seed=args.seed, progress=not args.no_progress)
    print(f"best model: {run_dir / 'best_model.zip'}")
    return 0
