"""Every ``vfgym`` command line README.md and the documentation pages show runs and exits 0.

``README_RUNS`` maps each command line of README.md and of ``docs/**/*.md`` (as shown,
whitespace collapsed) to the
concrete runs that stand for it: a template (``--algo ppo|sac|td3``, ``NAME``) is filled in
with real values, and lines that take minutes are budget-trimmed by appending options that
override the README's (argparse keeps an option's last value, ``--hyperparams`` its last
key). Every trim is listed in ``TRIMS`` with the reason. A README line without an entry
here, or an entry whose line left every page, fails ``test_every_readme_command_has_a_run``.

The runs share one working folder (``experiments/`` and ``agents/`` linked in from the
repository, run folders under ``runs/``) and depend on each other as a user's would:
``evaluate --settings best.yaml`` reads the main job's ``best.yaml``, ``plot history`` its
study, ``predict`` and ``evaluate --model`` the trained PPO agent; the README's worked
examples read the files earlier examples wrote (``runs/sweep/belt``, ``test-3.yaml``).
"""

from __future__ import annotations

import importlib.util
import os
import re
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path

import pytest

from vfgym.cli import main

REPO = Path(__file__).resolve().parents[2]
PAGES = ("README.md", "docs")  # the README and every Markdown page under docs/
HAS_SB3 = importlib.util.find_spec("stable_baselines3") is not None

TRIMS = {
    "evaluate-axis": (
        "evaluate on an uncertain axis: 2 test moves, 2 plants, 200 bootstrap resamples "
        "(the axis's 32 moves x 16 plants: the adaptive scheduler's tables take ~2 min)"
    ),
    "trials": (
        "sweeps: 4 trials (quick.yaml asks 300, ~35 s here; the cmaes line 500, minutes); "
        "the sampler, storage, workers and report paths run all the same"
    ),
    "grid": (
        "grid: 3 points per dimension and 1 refinement round (the README's 12 and 3 "
        "evaluate 269 543 settings in ~3 min)"
    ),
    "evaluate": "evaluate: 4 test scenarios and 200 bootstrap resamples (README: 32 and 2000)",
    "fit": "fit: 8 training moves (the default 160 take ~7 min here)",
    "refine": "refine: 3 trials (the docs' 150 on a long belt move take a minute or more)",
    "train": (
        "train: 64 timesteps on 2 envs with tiny batches, one held-out scenario (README: "
        "50 k-400 k timesteps, 25 min)"
    ),
}
SWEEP_TRIM = ["--trials", "4"]
FIT_TRIM = ["--moves", "8", "--no-progress"]
GRID_TRIM = ["--points", "3", "--refine", "1"]
EVAL_TRIM = ["--count", "4", "--bootstrap", "200"]
AXIS_EVAL_TRIM = ["--scenarios", "test-0,test-1", "--plants", "2", "--bootstrap", "200"]
EVERY = [
    "eval_freq=64",
    "n_eval_scenarios=1",
    "n_eval_scenarios_uncertain=1",
    "checkpoint_freq=64",
    "n_timesteps=64",
    "n_envs=2",
]
TRAIN_TRIM = {
    "ppo": [*EVERY, "n_steps=32", "batch_size=32", "n_epochs=1"],
    "sac": [*EVERY, "learning_starts=16", "batch_size=16", "buffer_size=1000"],
    "td3": [*EVERY, "learning_starts=16", "batch_size=16", "buffer_size=1000"],
    "ppo_lstm": [*EVERY, "n_steps=32", "batch_size=32", "n_epochs=1"],
}
AGAINST = "paper,rule-of-thumb,fixed-frequency,scurve"
LU = "experiments/axes/loads-uncertain.yaml"
ADAPTIVE = [
    "--env",
    "vfgym/VFServo-v0",
    "--seed",
    "1",
    "--axis",
    "experiments/axes/loads-uncertain.yaml",
]
LONG = ["--hyperparams", "n_timesteps=500000"]


def train_trim(argv: list[str]) -> list[str]:
    """``argv`` with the training budget trimmed: overrides appended to --hyperparams
    (last in every README line, so the trims come after the README's own values)."""
    algo = argv[argv.index("--algo") + 1]
    extra = TRAIN_TRIM[algo]
    if "--hyperparams" in argv:
        assert not any(a.startswith("--") for a in argv[argv.index("--hyperparams") + 1 :])
        return [*argv, *extra]
    return [*argv, "--hyperparams", *extra]


@dataclass(frozen=True)
class Run:
    """One concrete run: ``argv`` (placeholders in braces filled from earlier runs), the
    runs it needs first, files it must write (relative to the working folder), and the
    trim applied (a key of TRIMS) if any."""

    key: str
    argv: list[str]
    needs: tuple[str, ...] = ()
    writes: tuple[str, ...] = ()
    trim: str | None = None
    agents: bool = False
    env: dict[str, str] = field(default_factory=dict)


def _sweep(key: str, *extra: str, needs: tuple[str, ...] = ()) -> Run:
    argv = ["sweep", "--config", "experiments/quick.yaml", *extra, "--study", key]
    return Run(key, argv, needs, (f"runs/sweep/{key}/best.yaml",))


BELT = "runs/sweep/belt/best.yaml"
README_RUNS: dict[str, list[Run]] = {
    # the README's worked examples, in the order a user runs them
    "vfgym sweep --config experiments/quick.yaml --axis experiments/axes/belt.yaml --study belt": [
        Run(
            "belt",
            [
                "sweep",
                "--config",
                "experiments/quick.yaml",
                "--axis",
                "experiments/axes/belt.yaml",
                "--study",
                "belt",
                *SWEEP_TRIM,
            ],
            writes=(BELT, "runs/sweep/belt/study.db"),
            trim="trials",
        ),
    ],
    # the compliant axis (docs/guide/compliant.md, docs/results/compliant.md)
    "vfgym sweep --config experiments/quick.yaml --axis experiments/axes/belt-compliant.yaml "
    "--study belt-compliant": [
        Run(
            "belt-compliant",
            [
                "sweep",
                "--config",
                "experiments/quick.yaml",
                "--axis",
                "experiments/axes/belt-compliant.yaml",
                "--study",
                "belt-compliant",
                *SWEEP_TRIM,
            ],
            writes=("runs/sweep/belt-compliant/best.yaml",),
            trim="trials",
        ),
    ],
    "vfgym evaluate --settings runs/sweep/belt-compliant/best.yaml --axis "
    "experiments/axes/belt-compliant.yaml": [
        Run(
            "eval-belt-compliant",
            [
                "evaluate",
                "--settings",
                "runs/sweep/belt-compliant/best.yaml",
                "--axis",
                "experiments/axes/belt-compliant.yaml",
                "--bootstrap",
                "200",
            ],
            ("belt-compliant",),
            trim="evaluate",
        ),
    ],
    "vfgym fit --axis experiments/axes/belt-compliant.yaml": [
        Run(
            "fit-belt-compliant",
            ["fit", "--axis", "experiments/axes/belt-compliant.yaml", *FIT_TRIM],
            writes=("runs/fit/belt-compliant/settings_model.json",),
            trim="fit",
        ),
    ],
    "vfgym predict --model runs/fit/belt-compliant/settings_model.json --axis "
    "experiments/axes/belt-compliant.yaml --scenario test-10 --refine 150": [
        Run(
            "predict-fit-belt-compliant-refine",
            [
                "predict",
                "--model",
                "runs/fit/belt-compliant/settings_model.json",
                "--axis",
                "experiments/axes/belt-compliant.yaml",
                "--scenario",
                "test-10",
                "--refine",
                "150",
                "--refine",
                "3",
            ],
            ("fit-belt-compliant",),
            trim="refine",
        ),
    ],
    "vfgym sweep --config experiments/quick.yaml --axis "
    "experiments/axes/belt-compliant-uncertain.yaml --trials 30 --study belt-compliant-uncertain": [
        Run(
            "belt-compliant-uncertain",
            [
                "sweep",
                "--config",
                "experiments/quick.yaml",
                "--axis",
                "experiments/axes/belt-compliant-uncertain.yaml",
                "--trials",
                "30",
                "--study",
                "belt-compliant-uncertain",
                *SWEEP_TRIM,
            ],
            writes=("runs/sweep/belt-compliant-uncertain/best.yaml",),
            trim="trials",
        ),
    ],
    "vfgym sweep --axis experiments/axes/loads-uncertain.yaml --trials 60 --study lu60": [
        Run(
            "lu60",
            [
                "sweep",
                "--axis",
                "experiments/axes/loads-uncertain.yaml",
                "--trials",
                "60",
                "--study",
                "lu60",
                *SWEEP_TRIM,
            ],
            writes=("runs/sweep/lu60/best.yaml",),
            trim="trials",
        ),
    ],
    "vfgym sweep --config experiments/quick.yaml --axis experiments/axes/loads-uncertain.yaml "
    "--study lu": [
        Run(
            "lu",
            [
                "sweep",
                "--config",
                "experiments/quick.yaml",
                "--axis",
                "experiments/axes/loads-uncertain.yaml",
                "--study",
                "lu",
                *SWEEP_TRIM,
            ],
            writes=("runs/sweep/lu/best.yaml",),
            trim="trials",
        ),
    ],
    "vfgym evaluate --settings runs/sweep/lu/best.yaml --axis "
    "experiments/axes/loads-uncertain.yaml --plants 16 --plant-seed 1": [
        Run(
            "eval-lu",
            [
                "evaluate",
                "--settings",
                "runs/sweep/lu/best.yaml",
                "--axis",
                "experiments/axes/loads-uncertain.yaml",
                "--plants",
                "16",
                "--plant-seed",
                "1",
                "--bootstrap",
                "200",
            ],
            ("lu",),
            trim="evaluate",
        ),
    ],
    "vfgym identify --plan --axis experiments/axes/paper.yaml --out id-plan": [
        Run(
            "identify-plan",
            ["identify", "--plan", "--axis", "experiments/axes/paper.yaml", "--out", "id-plan"],
            writes=(
                "id-plan/identify-moves.yaml",
                "id-plan/identify-moves.vcd",
                "id-plan/identify-moves-nominal.vcd",
            ),
        ),
    ],
    "vfgym identify --axis experiments/axes/paper.yaml --capture "
    "id-plan/identify-moves-nominal.vcd --from-enable --out identified.yaml": [
        Run(
            "identify-dry-run",
            [
                "identify",
                "--axis",
                "experiments/axes/paper.yaml",
                "--capture",
                "id-plan/identify-moves-nominal.vcd",
                "--from-enable",
                "--out",
                "identified.yaml",
            ],
            ("identify-plan",),
            ("identified.yaml",),
        ),
    ],
    "vfgym evaluate --settings runs/sweep/belt/best.yaml --axis experiments/axes/belt.yaml": [
        Run(
            "eval-belt",
            [
                "evaluate",
                "--settings",
                BELT,
                "--axis",
                "experiments/axes/belt.yaml",
                "--bootstrap",
                "200",
            ],
            ("belt",),
            trim="evaluate",
        ),
    ],
    "vfgym evaluate --settings runs/sweep/belt/best.yaml --against paper,scurve "
    "--scenarios named": [
        Run(
            "eval-belt-named",
            [
                "evaluate",
                "--settings",
                BELT,
                "--against",
                "paper,scurve",
                "--scenarios",
                "named",
                "--bootstrap",
                "200",
            ],
            ("belt",),
            trim="evaluate",
        ),
    ],
    "vfgym plot compare --scenario paper-step --settings runs/sweep/belt/best.yaml": [
        Run(
            "plot-belt",
            ["plot", "compare", "--scenario", "paper-step", "--settings", BELT],
            ("belt",),
            ("compare-paper-step.png",),
        ),
    ],
    "vfgym plot history --sweep runs/sweep/belt": [
        Run("history-belt", ["plot", "history", "--sweep", "runs/sweep/belt"], ("belt",)),
    ],
    "vfgym fit --axis experiments/axes/belt.yaml --name belt": [
        Run(
            "fit-belt",
            ["fit", "--axis", "experiments/axes/belt.yaml", "--name", "belt", *FIT_TRIM],
            writes=("runs/fit/belt/settings_model.json",),
            trim="fit",
        ),
    ],
    "vfgym predict --model runs/fit/belt/settings_model.json --axis experiments/axes/belt.yaml "
    "--scenario test-3": [
        Run(
            "predict-fit-belt",
            [
                "predict",
                "--model",
                "runs/fit/belt/settings_model.json",
                "--axis",
                "experiments/axes/belt.yaml",
                "--scenario",
                "test-3",
            ],
            ("fit-belt",),
        ),
    ],
    "vfgym predict --model runs/fit/belt/settings_model.json --axis experiments/axes/belt.yaml "
    "--scenario test-10 --refine 150": [
        Run(
            "predict-fit-belt-refine",
            [
                "predict",
                "--model",
                "runs/fit/belt/settings_model.json",
                "--axis",
                "experiments/axes/belt.yaml",
                "--scenario",
                "test-10",
                "--refine",
                "150",
                "--refine",
                "3",
            ],
            ("fit-belt",),
            trim="refine",
        ),
    ],
    "vfgym predict --scenario test-3 --out test-3.yaml": [
        Run(
            "predict-out",
            ["predict", "--scenario", "test-3", "--out", "test-3.yaml"],
            writes=("test-3.yaml",),
        ),
    ],
    "vfgym predict --scenario short-move --refine 20": [
        Run("predict-refine-20", ["predict", "--scenario", "short-move", "--refine", "20"]),
    ],
    "vfgym simulate --scenario test-3 --settings test-3.yaml": [
        Run(
            "sim-test-3",
            ["simulate", "--scenario", "test-3", "--settings", "test-3.yaml"],
            ("predict-out",),
        ),
    ],
    "vfgym plot compare --scenario test-3 --settings test-3.yaml": [
        Run(
            "plot-test-3",
            ["plot", "compare", "--scenario", "test-3", "--settings", "test-3.yaml"],
            ("predict-out",),
            ("compare-test-3.png",),
        ),
    ],
    "vfgym train --algo ppo --env vfgym/VFTune-v0 --name tune-ppo": [
        Run(
            "tune-ppo",
            train_trim(
                ["train", "--algo", "ppo", "--env", "vfgym/VFTune-v0", "--name", "tune-ppo"]
            ),
            writes=("runs/train/tune-ppo/best_model.zip", "runs/train/tune-ppo/tb"),
            trim="train",
            agents=True,
        ),
    ],
    "vfgym predict --model runs/train/tune-ppo/best_model.zip --scenario test-3": [
        Run(
            "predict-tune-ppo",
            ["predict", "--model", "runs/train/tune-ppo/best_model.zip", "--scenario", "test-3"],
            ("tune-ppo",),
            agents=True,
        ),
    ],
    "vfgym export --format vcd --scenario paper-step": [
        Run(
            "export-vcd-readme",
            ["export", "--format", "vcd", "--scenario", "paper-step"],
            writes=("paper-step-paper.vcd",),
        ),
    ],
    "vfgym sweep --config experiments/quick.yaml": [
        Run("quick", ["sweep", "--config", "experiments/quick.yaml", *SWEEP_TRIM], trim="trials"),
    ],
    "vfgym sweep --config experiments/quick.yaml --axis experiments/axes/loads.yaml": [
        Run(
            "loads",
            [
                "sweep",
                "--config",
                "experiments/quick.yaml",
                "--axis",
                "experiments/axes/loads.yaml",
                *SWEEP_TRIM,
                "--study",
                "loads",
            ],
            writes=("runs/sweep/loads/best.yaml",),
            trim="trials",
        ),
    ],
    "vfgym simulate --scenario NAME [--settings F | --baseline B]": [
        Run("sim-paper", ["simulate", "--scenario", "paper-step"]),
        Run("sim-rot", ["simulate", "--scenario", "short-move", "--baseline", "rule-of-thumb"]),
        Run(
            "sim-best", ["simulate", "--scenario", "long-move", "--settings", "{best}"], ("quick",)
        ),
    ],
    "vfgym sweep --config experiments/quick.yaml "
    "[--sampler compass|tpe|cmaes|gp|nsga2|grid|random] [--trials N] [--workers N] "
    "[--storage sqlite|journal|postgresql://…] [--study NAME]": [
        _sweep("t-compass", "--sampler", "compass", "--trials", "12", "--storage", "journal"),
        _sweep("t-random", "--sampler", "random", "--trials", "3"),
        # postgresql://… needs a server: tests/tuning covers it where one runs
        _sweep("t-tpe", "--sampler", "tpe", "--trials", "3", "--storage", "sqlite"),
        _sweep("t-cmaes", "--sampler", "cmaes", "--trials", "4", "--storage", "journal"),
        _sweep("t-nsga2", "--sampler", "nsga2", "--trials", "4", "--workers", "2"),
        _sweep("t-grid", "--sampler", "grid", "--trials", "4"),
        _sweep("t-gp", "--sampler", "gp", "--trials", "3"),
    ],
    "vfgym grid --config experiments/grid-paper-step.yaml": [
        Run(
            "grid",
            ["grid", "--config", "experiments/grid-paper-step.yaml", *GRID_TRIM],
            trim="grid",
        ),
    ],
    "vfgym evaluate --settings best.yaml [--model M.zip] [--adaptive M.json] --against "
    "paper,rule-of-thumb,fixed-frequency,scurve --scenarios test": [
        Run(
            "eval",
            [
                "evaluate",
                "--settings",
                "{best}",
                "--against",
                AGAINST,
                "--scenarios",
                "test",
                *EVAL_TRIM,
            ],
            ("quick",),
            trim="evaluate",
        ),
        Run(
            "eval-model",
            [
                "evaluate",
                "--settings",
                "{best}",
                "--model",
                "{model}",
                "--against",
                AGAINST,
                "--scenarios",
                "test",
                *EVAL_TRIM,
            ],
            ("quick", "train-ppo"),
            trim="evaluate",
            agents=True,
        ),
    ],
    "vfgym plot response|scurve|frequency|compare|history|pareto …": [
        Run("plot-response", ["plot", "response"], writes=("response-paper-step.png",)),
        Run("plot-scurve", ["plot", "scurve"], writes=("scurve.png",)),
        Run("plot-frequency", ["plot", "frequency"], writes=("frequency-paper-step.png",)),
        Run("plot-compare", ["plot", "compare"], writes=("compare-paper-step.png",)),
        Run(
            "plot-history", ["plot", "history", "--sweep", "{quick}"], ("quick",), ("history.png",)
        ),
        Run(
            "plot-pareto",
            ["plot", "pareto", "--sweep", "runs/sweep/t-nsga2"],
            ("t-nsga2",),
            ("pareto.png",),
        ),
    ],
    "vfgym export --format csv": [
        Run("export-default", ["export", "--format", "csv"], writes=("paper-step-paper.csv",)),
    ],
    "vfgym export --format vcd|csv --scenario NAME": [
        Run(
            "export-vcd",
            ["export", "--format", "vcd", "--scenario", "paper-step"],
            writes=("paper-step-paper.vcd",),
        ),
        Run(
            "export-csv",
            ["export", "--format", "csv", "--scenario", "short-move"],
            writes=("short-move-paper.csv",),
        ),
    ],
    # each algorithm once on VFTune-v0; VFServo-v0 through the two servo lines below (a
    # full 3 x 2 product would add three trainings of ~20 s for nothing the CLI does anew)
    "vfgym train --algo ppo|sac|td3 --env vfgym/VFTune-v0|vfgym/VFServo-v0 [--hyperparams k=v …] "
    "[--threads N]": [
        Run(
            f"train-{algo}",
            train_trim(["train", "--algo", algo, "--env", "vfgym/VFTune-v0", "--threads", "1"]),
            writes=(f"runs/train/{algo}-VFTune-v0-seed0/best_model.zip",),
            trim="train",
            agents=True,
        )
        for algo in ("ppo", "sac", "td3")
    ],
    "vfgym predict --scenario NAME [--model M.json|RUN/best_model.zip] [--refine N]": [
        Run(
            "predict-shipped",
            ["predict", "--scenario", "test-3", "--out", "p.yaml"],
            writes=("p.yaml",),
        ),
        Run("predict-refine", ["predict", "--scenario", "short-move", "--refine", "5"]),
        Run(
            "predict",
            ["predict", "--model", "{model}", "--scenario", "test-3"],
            ("train-ppo",),
            agents=True,
        ),
    ],
    "vfgym predict --scenario test-3": [Run("predict-test-3", ["predict", "--scenario", "test-3"])],
    "vfgym predict --scenario NAME --refine N": [
        Run("predict-refine-3", ["predict", "--scenario", "test-5", "--refine", "3"]),
    ],
    "vfgym plot response --scenario paper-step": [
        Run(
            "fig4",
            ["plot", "response", "--scenario", "paper-step"],
            writes=("response-paper-step.png",),
        ),
    ],
    "vfgym sweep --scenarios paper-step --sampler cmaes --trials 500": [
        Run(
            "cmaes-500",
            [
                "sweep",
                "--scenarios",
                "paper-step",
                "--sampler",
                "cmaes",
                "--trials",
                "500",
                *SWEEP_TRIM,
            ],
            trim="trials",
        ),
    ],
    "vfgym train --algo ppo --env vfgym/VFTune-v0 --seed 1 --name amortised-ppo-big "
    "--hyperparams n_timesteps=400000 learning_rate=0.0001 "
    '"policy_kwargs={net_arch: [128, 128], activation_fn: tanh, log_std_init: -1.0}"': [
        Run(
            "amortised",
            train_trim(
                [
                    "train",
                    "--algo",
                    "ppo",
                    "--env",
                    "vfgym/VFTune-v0",
                    "--seed",
                    "1",
                    "--name",
                    "amortised-ppo-big",
                    "--hyperparams",
                    "n_timesteps=400000",
                    "learning_rate=0.0001",
                    "policy_kwargs={net_arch: [128, 128], activation_fn: tanh, log_std_init: -1.0}",
                ]
            ),
            writes=("runs/train/amortised-ppo-big/best_model.zip",),
            trim="train",
            agents=True,
        ),
    ],
    "vfgym train --algo ppo --env vfgym/VFServo-v0 --name servo-ppo": [
        Run(
            "servo-ppo",
            train_trim(
                ["train", "--algo", "ppo", "--env", "vfgym/VFServo-v0", "--name", "servo-ppo"]
            ),
            writes=("runs/train/servo-ppo/best_model.zip",),
            trim="train",
            agents=True,
        ),
    ],
    # docs/guide/train.md: an adaptive agent on an uncertain axis, its base fitted first
    "vfgym fit --axis experiments/axes/loads-uncertain.yaml": [
        Run(
            "fit-lu",
            ["fit", "--axis", "experiments/axes/loads-uncertain.yaml", *FIT_TRIM],
            writes=("runs/fit/loads-uncertain/settings_model.json",),
            trim="fit",
        ),
    ],
    "vfgym evaluate --axis experiments/axes/loads-uncertain.yaml --adaptive "
    "runs/fit/loads-uncertain/settings_model.json --model "
    "runs/fit/loads-uncertain/settings_model.json": [
        Run(
            "eval-adaptive",
            [
                "evaluate",
                "--axis",
                "experiments/axes/loads-uncertain.yaml",
                "--adaptive",
                "runs/fit/loads-uncertain/settings_model.json",
                "--model",
                "runs/fit/loads-uncertain/settings_model.json",
                *AXIS_EVAL_TRIM,
            ],
            needs=("fit-lu",),
            trim="evaluate-axis",
        ),
    ],
    "vfgym train --algo ppo --env vfgym/VFServo-v0 --axis experiments/axes/loads-uncertain.yaml "
    "--name adaptive": [
        Run(
            "servo-lu",
            train_trim(
                [
                    "train",
                    "--algo",
                    "ppo",
                    "--env",
                    "vfgym/VFServo-v0",
                    "--axis",
                    "experiments/axes/loads-uncertain.yaml",
                    "--name",
                    "adaptive",
                ]
            ),
            needs=("fit-lu",),
            writes=("runs/train/adaptive/best_model.zip",),
            trim="train",
            agents=True,
        ),
    ],
    # docs/results/agents.md: the adaptive agents' benchmark runs (their base fitted first):
    # PPO and RecurrentPPO for 500 k steps, SAC and TD3 on their shipped hyperparameters
    **{
        " ".join(["vfgym train --algo", algo, *ADAPTIVE, *extra]): [
            Run(
                f"adaptive-{algo}",
                train_trim(["train", "--algo", algo, *ADAPTIVE, *extra]),
                needs=("fit-lu",),
                writes=(f"runs/train/{algo}-VFServo-v0-seed1/best_model.zip",),
                trim="train",
                agents=True,
            )
        ]
        for algo, extra in (("ppo", LONG), ("ppo_lstm", LONG), ("sac", []), ("td3", []))
    },
    "vfgym train --algo ppo --env vfgym/VFTune-v0 --seed 3": [
        Run(
            "tune-seed3",
            train_trim(["train", "--algo", "ppo", "--env", "vfgym/VFTune-v0", "--seed", "3"]),
            writes=("runs/train/ppo-VFTune-v0-seed3/best_model.zip",),
            trim="train",
            agents=True,
        ),
    ],
    # run as the shell line it is (the variable must reach libgomp at start-up)
    "GOMP_SPINCOUNT=300000 vfgym train --algo ppo --env vfgym/VFServo-v0": [
        Run(
            "gomp",
            train_trim(["train", "--algo", "ppo", "--env", "vfgym/VFServo-v0"]),
            writes=("runs/train/ppo-VFServo-v0-seed0/best_model.zip",),
            trim="train",
            agents=True,
            env={"GOMP_SPINCOUNT": "300000"},
        ),
    ],
}
RUNS = {r.key: r for runs in README_RUNS.values() for r in runs}


def readme_commands(text: str) -> set[str]:
    """The ``vfgym`` command lines README.md shows: on a line of a code block, or in an
    inline code span (also across a line end; ``\\|`` read as ``|``), naming a
    sub-command and giving it at least one argument (a bare ``vfgym sweep`` in a sentence
    names the command, it is not a command line). The blocks ``docs/_reference.py`` writes
    (``<!-- vfgym:NAME:begin -->`` ... ``end``: the commands' ``--help``, the axis keys)
    are the code's own text, kept equal to it by ``tests/test_docs.py``: left out."""
    from vfgym.cli import build_parser

    subs = "|".join(build_parser().subcommands)
    text = re.sub(r"<!-- vfgym:([\w-]+):begin -->.*?<!-- vfgym:\1:end -->", "", text, flags=re.S)
    fence = re.compile(r"^```[^\n]*\n(.*?)^```", flags=re.S | re.M)
    items = [ln for block in fence.findall(text) for ln in block.splitlines()]
    items += re.findall(r"`([^`]+)`", fence.sub("", text))
    command = re.compile(rf"((?:[A-Z_]+=\S+ )*vfgym (?:{subs}) \S.*)$")
    found = set()
    for item in items:
        item = " ".join(item.replace("\\|", "|").split()).split(" # ")[0].strip()
        m = command.search(item.split(" && ")[-1])
        if m:
            found.add(m.group(1))
    return found


def pages(root: Path) -> list[Path]:
    """README.md and every Markdown page of the documentation under ``root``."""
    found = []
    for name in PAGES:
        path = root / name
        found += sorted(path.rglob("*.md")) if path.is_dir() else [path]
    return found


def test_every_readme_command_has_a_run(repo_root):
    shown: set[str] = set()
    for page in pages(repo_root):
        lines = readme_commands(page.read_text(encoding="utf-8"))
        missing = lines - set(README_RUNS)
        assert not missing, f"{page.name}: lines without a run in README_RUNS: {missing}"
        shown |= lines
    assert set(README_RUNS) - shown == set(), "README_RUNS lines on no page any more"
    for run in RUNS.values():
        assert run.trim is None or run.trim in TRIMS


@pytest.fixture(scope="module")
def workspace(tmp_path_factory):
    """The shared working folder; ``done`` holds each run's exit status."""
    ws = tmp_path_factory.mktemp("readme")
    for name in ("experiments", "agents"):
        (ws / name).symlink_to(REPO / name)
    return {"path": ws, "done": {}}


def _fill(argv: list[str], ws: Path) -> list[str]:
    def quick() -> str:
        (run,) = [p for p in (ws / "runs" / "sweep").glob("quick-*") if p.is_dir()]
        return str(run)

    values = {
        "{quick}": quick,
        "{best}": lambda: f"{quick()}/best.yaml",
        "{model}": lambda: str(ws / "runs/train/ppo-VFTune-v0-seed0/best_model.zip"),
    }
    return [values[a]() if a in values else a for a in argv]


def _run(key: str, state: dict, monkeypatch) -> int:
    if key in state["done"]:
        return state["done"][key]
    run = RUNS[key]
    for need in run.needs:
        assert _run(need, state, monkeypatch) == 0, f"{key} needs {need}, which failed"
    ws = state["path"]
    argv = _fill(run.argv, ws)
    with monkeypatch.context() as m:
        m.chdir(ws)
        if run.env:  # a shell line with a variable: run it as a process
            env = {**os.environ, **run.env, "MPLBACKEND": "Agg"}
            env["PYTHONPATH"] = str(REPO / "src") + os.pathsep + env.get("PYTHONPATH", "")
            code = subprocess.run(
                [sys.executable, "-c", "import sys; from vfgym.cli import main; sys.exit(main())",
                 *argv],
                env=env, timeout=900,
            ).returncode  # fmt: skip
        else:
            code = main(argv)
    state["done"][key] = code
    return code


@pytest.mark.parametrize("key", list(RUNS))
def test_readme_command_runs(key, workspace, monkeypatch):
    run = RUNS[key]
    if run.agents and not HAS_SB3:
        pytest.skip("needs the agents extra")
    if key == "t-gp" and importlib.util.find_spec("torch") is None:
        pytest.skip("the gp sampler needs torch")
    assert _run(key, workspace, monkeypatch) == 0
    for path in run.writes:
        assert (workspace["path"] / path).exists(), path
