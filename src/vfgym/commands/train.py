"""``vfgym train``: train a stable-baselines3 agent on a vfgym environment."""

from __future__ import annotations

import argparse
import os
from pathlib import Path

CORES = os.cpu_count() or 1
"""The most threads ``--threads`` allows: this machine's cores."""


def add_parser(sub: argparse._SubParsersAction) -> None:
    from vfgym.commands._common import SEED, add_axis_option, whole

    p = sub.add_parser(
        "train",
        help="train a PPO, SAC, TD3 or recurrent PPO agent (agents extra)",
        description=__doc__ + " Hyperparameters come from the "
        "<algo>.yml file shipped with vfgym (one section per env; "
        "agents/hyperparams/<algo>.yml in the working folder instead, if there is one), "
        "overridable with --hyperparams key=value. Starting a run again continues it "
        "from its last checkpoint.",
    )
    p.add_argument("--algo", required=True, help="ppo, sac, td3 or ppo_lstm (RecurrentPPO)")
    p.add_argument(
        "--env", default="vfgym/VFTune-v0", help="vfgym/VFTune-v0 (default) or vfgym/VFServo-v0"
    )
    p.add_argument(
        "--hyperparams-file",
        help="YAML file (default: agents/hyperparams/ALGO.yml in the working folder if "
        "there is one, else the one shipped with vfgym)",
    )
    p.add_argument(
        "--hyperparams",
        nargs="*",
        metavar="KEY=VALUE",
        help="overrides, values as YAML (e.g. n_timesteps=2000 n_envs=4)",
    )
    p.add_argument("--seed", type=SEED, default=0, help="seed (default 0)")
    p.add_argument("--runs-dir", default="runs", help="root of the run folders (default runs)")
    p.add_argument(
        "--name",
        help="run folder name (default ALGO-ENV-seedSEED); an existing "
        "run of that name is continued",
    )
    p.add_argument(
        "--threads",
        type=whole(1, CORES),
        default=1,
        help="threads of this training: torch's intra-op threads and numba's (the "
        "simulations of VFTune-v0 and of vector envs from 512 envs), whole number in "
        f"[1, {CORES}] (default 1: small policies on CPU train fastest so, and two "
        "trainings side by side do not slow each other down)",
    )
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    add_axis_option(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from vfgym._validate import check_name, check_output_path
    from vfgym.agents import hyperparams as hp
    from vfgym.commands._common import Interrupted

    file = args.hyperparams_file
    params = hp.load(args.algo, args.env, file, hp.parse_overrides(args.hyperparams))
    if args.axis:  # the envs draw their moves from the axis (env_kwargs: axis=FILE)
        from vfgym.commands._common import axis_from_args

        axis = axis_from_args(args)  # a bad file fails before a run folder is made
        params["env_kwargs"] = {**(params.get("env_kwargs") or {}), "axis": args.axis}
        _axis_base(params["env_kwargs"], axis, args)
    if args.name is not None:
        check_name("--name", args.name)
    name = args.name or f"{args.algo}-{args.env.split('/')[-1]}-seed{args.seed}"
    check_output_path(
        "--runs-dir",
        Path(args.runs_dir) / "train" / name,
        folder=True,
        shown=args.runs_dir,
        root=args.runs_dir,
    )
    from vfgym.agents.training import check_same_run, train
    from vfgym.io.runs import new_run_dir, record_command

    check_same_run(Path(args.runs_dir) / "train" / name, args.algo, args.env, args.seed,
                   params.get("env_kwargs") or {})  # fmt: skip
    _check_env_kwargs(args.env, params.get("env_kwargs") or {})
    run_dir = new_run_dir(args.runs_dir, "train", name)
    record_command(run_dir)
    print(f"run folder: {run_dir}")
    try:
        train(
            args.algo,
            args.env,
            params,
            run_dir,
            seed=args.seed,
            progress=not args.no_progress,
            threads=args.threads,
        )
    except KeyboardInterrupt:
        raise Interrupted(
            f"the steps trained are saved in {run_dir / 'checkpoints'}; the same command "
            "continues from the last checkpoint"
        ) from None
    print(f"best model: {run_dir / 'best_model.zip'}")
    return 0


def _axis_base(env_kwargs: dict, axis: object, args: argparse.Namespace) -> None:
    """On an axis, a residual base of ``model`` (the shipped model, fitted on the paper's
    axis) becomes the axis's own settings model, ``RUNS/fit/AXIS/settings_model.json``
    (``vfgym fit --axis FILE --name AXIS`` makes it); without it, one line says so."""
    base = env_kwargs.get("residual_base")
    if base not in ("model", "model-lookup"):
        return
    name = getattr(axis, "name", "")
    own = Path(args.runs_dir) / "fit" / name / "settings_model.json"
    if not own.is_file():
        raise ValueError(
            f"residual_base={base!r} on axis {name!r}: this axis's settings model {own} is "
            f"missing (the shipped one is fitted on the paper's axis); make it with vfgym fit "
            f"--axis {args.axis} --name {name}, or set env_kwargs.residual_base (paper, "
            "FILE.json) in a --hyperparams-file"
        )
    env_kwargs["residual_base"] = f"{base}:{own}"


def _check_env_kwargs(env_id: str, env_kwargs: dict) -> None:
    """Make the environment once with ``env_kwargs``, so that a value it refuses stops the
    command before a run folder is made (the env's own checks say what is allowed)."""
    from vfgym.agents import make_env

    if not env_kwargs:
        return
    try:
        make_env(env_id, env_kwargs).close()
    except (TypeError, ValueError) as exc:
        raise ValueError(f"env_kwargs={env_kwargs!r} is not allowed for {env_id}: {exc}") from None
