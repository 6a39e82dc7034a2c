"""Agents benchmark, as rl-baselines3-zoo's ``benchmark.md``: trains every algorithm × env ×
seed for a budget with the shipped hyperparameters and judges each best model on held-out
moves.

    python benchmarks/bench_agents.py [--algos ppo,sac,td3] [--envs VFTune-v0,VFServo-v0]
        [--seeds 0,1,2] [--steps 200000] [--moves 16] [--out runs/bench-agents]
        [--hyperparams KEY=VALUE ...]

Each training is ``vfgym train`` in its own process (the command is printed under the
table, so a row can be measured again from the repository alone). Held-out moves: the
test split's first ``--moves`` moves (``test-0`` ...), whose per-move optima are in
experiments/optima/test.csv. Per row: steps, wall time per training (mean over seeds),
the held-out mean cost ± its standard deviation over seeds, and the mean cost's ratio to:

* the per-move optima (each optimum's settings re-scored on its move now, so the ratio
  follows today's scoring path);
* the best fixed setting: the one setting, among the per-move optima's and the paper's,
  with the lowest mean cost on these moves (chosen on them, so a baseline in hindsight).

With residual actions (the run's ``env_kwargs``) the row names its base (``model``: the
shipped per-move settings model, its candidates checked on the move; ``model-lookup``: its
look-up alone; ``paper``; a settings file) and the base's own ratio to the per-move optima
on the same moves, the mark an agent that starts as its base must beat.

"worst validation" is the largest validation mean cost a run logged (``evaluations.csv``)
over its first one, the agent as it started, the worst seed's: above 1 the policy got
worse while training; the best model is still chosen on validation, so a held-out cost
at its base's shows a run that never improved on it.

``--combine RUN [RUN ...]`` trains nothing: it prints the rows of run folders already
trained (one folder per seed, e.g. seeds trained by separate ``--seeds N --out DIR``
processes), one row per algorithm × env × hyperparameters (as each folder's
``config.yaml`` has them, the seed aside), judged as above; their wall time is not known
there (nan). With ``--out`` it also writes that folder's ``benchmark.md`` and
``learning_curves.png`` (one line per row).

Writes ``benchmark.md`` (the table and the commands), ``benchmark.json`` and
``learning_curves.png`` (each run's held-out validation cost from its
``evaluations.csv`` against steps, mean over seeds) into ``--out``.
"""

from __future__ import annotations

import argparse
import json
import shlex
import subprocess
import sys
import time
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
OPTIMA = ROOT / "experiments" / "optima" / "test.csv"


@dataclass(frozen=True)
class Row:
    """One algo × env over its seeds."""

    algo: str
    env: str
    base: str
    base_vs_optima: float
    steps: int
    wall_s: float
    mean_cost: float
    std_cost: float
    vs_optima: float
    vs_best_fixed: float
    feasible: float
    seeds: int
    worst_validation: float


def train_command(algo: str, env: str, seed: int, steps: int, out: Path, extra: list[str]):
    """The ``vfgym train`` command of one run (as shown) and its run folder."""
    name = f"{algo}-{env}-seed{seed}"
    args = ["vfgym", "train", "--algo", algo, "--env", f"vfgym/{env}", "--seed", str(seed),
            "--runs-dir", str(out), "--name", name, "--no-progress",
            "--hyperparams", f"n_timesteps={steps}", *extra]  # fmt: skip
    return args, out / "train" / name


def run_training(args: list[str]) -> float:
    """Run ``vfgym train`` (this interpreter's vfgym) and return its wall time (s)."""
    code = "import sys; from vfgym.cli import main; sys.exit(main(sys.argv[1:]))"
    t = time.perf_counter()
    done = subprocess.run([sys.executable, "-c", code, *args[1:]], capture_output=True, text=True)
    wall = time.perf_counter() - t
    if done.returncode != 0:
        raise SystemExit(f"{shlex.join(args)} failed:\n{done.stderr[-2000:]}")
    return wall


def baselines(n: int):
    """(held-out scenarios, each move's optimum cost, the best fixed setting's costs)."""
    from vfgym import PAPER_SETTINGS, evaluate, random_scenario
    from vfgym.permove.optima import read_optima

    optima = {o.scenario: o.settings for o in read_optima(OPTIMA)}
    names = [f"test-{i}" for i in range(n)]
    missing = [x for x in names if x not in optima]
    if missing:
        raise SystemExit(f"--moves {n}: {OPTIMA} has no optimum for {', '.join(missing[:3])}")
    scenarios = [random_scenario(i, "test") for i in range(n)]
    candidates = [PAPER_SETTINGS, *(optima[x] for x in names)]
    costs = evaluate(candidates, scenarios).cost  # (settings, moves)
    optimum = np.array([costs[1 + i, i] for i in range(n)])
    best = costs[int(np.argmin(costs.mean(axis=1)))]
    return scenarios, optimum, best


def judge(model: Path, scenarios) -> tuple[float, float]:
    """(mean cost, share feasible) of a trained agent on the held-out moves."""
    from vfgym.agents import agent_policy
    from vfgym.report import Candidate, compare

    rep = compare([Candidate("agent", policy=agent_policy(model))], [], scenarios, resamples=1)
    col = rep.column("agent")
    return float(col.cost.mean()), float(np.mean(np.all(col.constraints <= 0.0, axis=1)))


def residual_base(folder: Path) -> str:
    """The run's residual base as written in its hyperparameters ('' without residual)."""
    from vfgym.io.runs import read_yaml

    kw = (read_yaml(folder / "config.yaml").get("hyperparams") or {}).get("env_kwargs") or {}
    return str(kw.get("residual_base") or "paper") if kw.get("residual") else ""


def base_cost(base: str, scenarios) -> float:
    """Mean cost of a residual base on the held-out moves (NaN without a base)."""
    if not base:
        return float("nan")
    from vfgym.agents import env_options
    from vfgym.params import PAPER_PLANT
    from vfgym.report import Candidate, compare

    b = env_options({"residual_base": base})["residual_base"]
    policy = b if not callable(b) else (lambda sc: b(sc, PAPER_PLANT))
    cand = Candidate("base", b) if not callable(b) else Candidate("base", policy=policy)
    return float(compare([cand], [], scenarios, resamples=1).column("base").cost.mean())


def worst_validation(folders: list[Path]) -> float:
    """The largest validation mean cost over the first one, the worst of the runs."""
    out = []
    for f in folders:
        data = np.genfromtxt(f / "evaluations.csv", delimiter=",", names=True, ndmin=1)
        cost = np.atleast_1d(data["mean_cost"])
        out.append(float(cost.max() / cost[0]))
    return max(out)


def curves(runs: dict[tuple[str, str], list[Path]], path: Path) -> None:
    """Held-out validation cost against steps, mean over seeds, one line per row (a log
    scale when the costs span more than a factor 3)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4))
    low, high = np.inf, 0.0
    for (algo, env), folders in runs.items():
        series = []
        for f in folders:
            data = np.genfromtxt(f / "evaluations.csv", delimiter=",", names=True, ndmin=1)
            series.append((np.atleast_1d(data["timesteps"]), np.atleast_1d(data["mean_cost"])))
        n = min(len(s[0]) for s in series)
        steps, mean = series[0][0][:n], np.mean([s[1][:n] for s in series], axis=0)
        low, high = min(low, float(mean.min())), max(high, float(mean.max()))
        ax.plot(steps, mean, marker=".", label=f"{algo} {env}")
    ax.set_xlabel("steps")
    ax.set_ylabel("validation mean cost")
    if high > 3 * low:  # a log scale for divergence; within a factor 3 its ticks would be few
        ax.set_yscale("log")
    ax.legend()
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def table(rows: list[Row], commands: list[str]) -> str:
    """The benchmark.md text."""
    head = ("| algo | env | base (vs optima) | steps | wall time [s] | held-out mean cost "
            "| vs per-move optima | vs best fixed | feasible | seeds "
            "| worst validation |")  # fmt: skip
    lines = [head, "|" + "---|" * 11]
    for r in rows:
        base = f"{r.base} ({r.base_vs_optima:.3f}x)" if r.base else ""
        std = r.std_cost if r.std_cost > 1e-12 * abs(r.mean_cost) else 0.0  # rounding only
        lines.append(
            f"| {r.algo} | {r.env} | {base} | {r.steps} | {r.wall_s:.0f} | {r.mean_cost:.4g} ± "
            f"{std:.2g} | {r.vs_optima:.3f}x | {r.vs_best_fixed:.3f}x | "
            f"{100 * r.feasible:.0f} % | {r.seeds} | {r.worst_validation:.3f}x |"
        )
    return "\n".join([*lines, "", "Commands:", "", *(f"    {c}" for c in commands), ""])


def groups(folders: list[Path]) -> dict[tuple[str, str], list[Path]]:
    """Run folders by (algo, env label), one group per algorithm × env × hyperparameters
    (the seed aside), in the order first met; a label is ``algo`` and the env without
    its ``vfgym/``, numbered (``#2`` ...) when hyperparameters differ within one pair."""
    from vfgym.io.runs import read_yaml

    keyed: dict[tuple[str, str, str], list[Path]] = {}
    for f in folders:
        cfg = read_yaml(f / "config.yaml")
        hp = json.dumps(cfg.get("hyperparams") or {}, sort_keys=True, default=str)
        keyed.setdefault((cfg["algo"], str(cfg["env"]).removeprefix("vfgym/"), hp), []).append(f)
    out: dict[tuple[str, str], list[Path]] = {}
    for (algo, env, _), fs in keyed.items():
        n = sum(1 for a, e in out if a == algo and e.split(" #")[0] == env)
        out[(algo, env if n == 0 else f"{env} #{n + 1}")] = fs
    return out


def combine(folders: list[Path], moves: int, out: Path | None = None) -> None:
    """Print the rows of trained run folders (one row per algorithm × env ×
    hyperparameters, one folder per seed); with ``out``, write its ``benchmark.md`` and
    ``learning_curves.png`` there."""
    from vfgym.io.runs import read_yaml

    scenarios, optimum, best = baselines(moves)
    rows, runs = [], groups(folders)
    for (algo, env), fs in runs.items():
        steps = int(read_yaml(fs[0] / "config.yaml")["hyperparams"]["n_timesteps"])
        judged = [judge(f / "best_model.zip", scenarios) for f in fs]
        costs = [c for c, _ in judged]
        mean = float(np.mean(costs))
        base = residual_base(fs[0])
        rows.append(Row(algo, env, base, base_cost(base, scenarios) / float(optimum.mean()),
                        steps, float("nan"), mean, float(np.std(costs)),
                        mean / float(optimum.mean()), mean / float(best.mean()),
                        float(np.mean([f for _, f in judged])), len(fs),
                        worst_validation(fs)))  # fmt: skip
        for f, c in zip(fs, costs, strict=True):
            print(f"{f}: held-out mean cost {c:.4g}")
    text = table(rows, [f"(run folders: {', '.join(map(str, folders))})"])
    print(text)
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
        (out / "benchmark.md").write_text(text)
        curves(runs, out / "learning_curves.png")
        print(f"wrote {out}/benchmark.md, learning_curves.png")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--algos", default="ppo,sac,td3")
    ap.add_argument("--envs", default="VFTune-v0,VFServo-v0")
    ap.add_argument("--seeds", default="0,1,2")
    ap.add_argument("--steps", type=int, default=200_000)
    ap.add_argument("--moves", type=int, default=16, help="held-out test moves (≤ 64)")
    ap.add_argument("--out", help="output folder (default runs/bench-agents; with --combine none)")
    ap.add_argument("--hyperparams", nargs="*", default=[], metavar="KEY=VALUE",
                    help="extra overrides for every training")  # fmt: skip
    ap.add_argument("--combine", nargs="+", metavar="RUN", help="judge these run folders")
    args = ap.parse_args()
    if args.combine:
        combine([Path(f) for f in args.combine], args.moves, args.out and Path(args.out))
        return
    out = Path(args.out or "runs/bench-agents")
    out.mkdir(parents=True, exist_ok=True)
    scenarios, optimum, best = baselines(args.moves)
    seeds = [int(s) for s in args.seeds.split(",")]
    rows, commands, runs = [], [], {}
    for env in args.envs.split(","):
        for algo in args.algos.split(","):
            costs, walls, feas = [], [], []
            for seed in seeds:
                cmd, folder = train_command(algo, env, seed, args.steps, out, args.hyperparams)
                commands.append(shlex.join(cmd))
                walls.append(run_training(cmd))
                c, f = judge(folder / "best_model.zip", scenarios)
                costs.append(c)
                feas.append(f)
                runs.setdefault((algo, env), []).append(folder)
                print(f"{algo} {env} seed {seed}: held-out mean cost {c:.4g} "
                      f"({walls[-1]:.0f} s)", flush=True)  # fmt: skip
            mean = float(np.mean(costs))
            ratios = (mean / float(optimum.mean()), mean / float(best.mean()))
            spread = (float(np.mean(walls)), mean, float(np.std(costs)))
            base = residual_base(folder)
            base_ratio = base_cost(base, scenarios) / float(optimum.mean())
            worst = worst_validation(runs[(algo, env)])
            rows.append(Row(algo, env, base, base_ratio, args.steps, *spread, *ratios,
                            float(np.mean(feas)), len(seeds), worst))  # fmt: skip
    text = table(rows, commands)
    head = (f"Held-out: test-0 … test-{args.moves - 1}; per-move optima mean cost "
            f"{optimum.mean():.4g}, best fixed setting {best.mean():.4g}.\n\n")  # fmt: skip
    print("\n" + head + text)
    (out / "benchmark.md").write_text(head + text)
    (out / "benchmark.json").write_text(
        json.dumps({"rows": [asdict(r) for r in rows], "commands": commands}, indent=1)
    )
    curves(runs, out / "learning_curves.png")
    print(f"wrote {out}/benchmark.md, benchmark.json, learning_curves.png")


if __name__ == "__main__":
    main()
