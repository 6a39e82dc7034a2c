"""Adaptive agents on an uncertain axis, as rl-baselines3-zoo's ``benchmark.md``: VFServo-v0
agents that schedule the settings during the move, judged on held-out (move, plant) pairs
against the robust per-move base they started from and against an oracle.

    python benchmarks/bench_adaptive.py --runs RUN [RUN ...]
        [--axis experiments/axes/loads-uncertain.yaml] [--plants 16] [--plant-seed S]
        [--moves 32] [--out runs/bench-adaptive]
    python benchmarks/bench_adaptive.py --train --algos ppo --seeds 1,2,3 --steps 200000 ...
    python benchmarks/bench_adaptive.py --runs RUN [RUN ...] --base own [--no-oracle]
    python benchmarks/bench_adaptive.py --runs RUN [RUN ...] --exact --moves 256 --no-oracle
    python benchmarks/bench_adaptive.py --runs RUN [RUN ...] --checkpoints
    python benchmarks/bench_adaptive.py --eval-time 32,256 [--fit-runs RUNS]
    python benchmarks/bench_adaptive.py --runs RUN [RUN ...] --scheduler --curves

Held-out pairs: the axis's test moves (the first ``--moves``) × ``--plants`` true plants
drawn within its uncertainty from ``--plant-seed`` (default
:data:`vfgym.axis.VERDICT_PLANT_SEED`); agents are trained on the train split
and select their best model on validation pairs of other seeds
(:func:`vfgym.agents.selection.validation_plants`), so none of these pairs was seen.

Every tuner is judged in one :func:`vfgym.evaluate` call on those pairs:

* **base**: the axis's robust per-move settings model (``vfgym fit``'s, the agents'
  residual base: ``RUNS/fit/AXIS/settings_model.json``, or ``--base FILE``); with
  ``--base own``, the runs' own residual base as their env makes it (one for all runs: a
  VFTune-v0 agent's is the model's look-up, unchecked);
* **oracle**: each (move, true plant)'s own optimum, found knowing the true plant
  (:func:`vfgym.permove.optima.move_optima` with ``true_plants``); cached in ``--out``;
* with ``--scheduler``, :class:`vfgym.permove.adaptive.EstimatingScheduler` on the fit's
  model (its default options), the hand-written reference; cached in ``--out``;
* each run's ``best_model.zip`` (a :class:`vfgym.scoring.Scheduler`).

``--curves`` judges each run's checkpoints on the same held-out pairs (for the picture
only: the runs chose their best model on their validation pairs) and draws
``learning_curves.png``: the held-out mean cost over the base's against steps, mean over
seeds (the band: the seeds' range), one line per algorithm, with the base, the scheduler
and the oracle as reference lines.

``--exact``: the plant known exactly (runs trained without ``--axis``, on the agents' own
move distribution); the held-out moves are the first ``--moves`` of that distribution's
test split (``random_scenario(i, "test")``), each on the modelled plant.

``--checkpoints`` judges nothing held out: it scores each run's checkpoints on the run's
own validation pairs, as the run chose its best model, and prints for each the mean cost
over the start's, the paired gain in standard errors, the pairs where it breaks a limit
the start holds, and whether the shipping rule (:func:`vfgym.agents.selection.beats`)
takes it over the start: why a run shipped what it shipped.

``--eval-time N,M`` times one validation evaluation (a run's ``HeldOutEval`` call) of
an untrained residual PPO agent on N, then M validation pairs of the axis, VFServo-v0 and
VFTune-v0, each on its shipped env arguments with the fit's model as the base: the first
call (which computes each move's base) and the next.

Per seed: the held-out mean cost, the pairs feasible, the ratio to the base, the pairs
where the agent is cheaper / dearer than the base, and the pairs where it breaks a limit
the base holds (the shipping rule's pairwise feasibility, held out). Per algorithm (as
rl-baselines3-zoo's ``benchmark.md``): the env, steps, wall time of a run (its TensorBoard
log's first to last event), mean ± std over seeds, the worst seed's feasibility and
breaks where the base holds, and the ratios of the mean to the base, the scheduler and
the oracle. Writes ``benchmark.md`` (the tables and each run's command) and
``benchmark.json`` into ``--out``.
"""

from __future__ import annotations

import argparse
import json
import shlex
import sys
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent))


@dataclass(frozen=True)
class Judged:
    """One tuner on the held-out pairs."""

    label: str
    cost: list[float]  # per pair, plant-major
    feasible: list[bool]
    command: str
    wall_s: float = float("nan")

    @property
    def mean(self) -> float:
        return float(np.mean(self.cost))


def pairs(axis, moves: int, plants: int, seed: int):
    """(held-out moves, true plants)."""
    from vfgym.axis import draw_plants

    if axis.uncertainty.exact:
        raise SystemExit(f"--axis {axis.name}: states no uncertainty; adaptive agents need one")
    test = axis.scenarios("test")[:moves]
    return test, draw_plants(axis.uncertainty, axis.plant, plants, seed)


def judge(tuners, axis, test, variants) -> list[tuple[np.ndarray, np.ndarray]]:
    """Each tuner's (cost, feasible) on the pairs, plant-major, in one evaluate call (no
    ``variants``: on the modelled plant)."""
    from vfgym import evaluate

    ev = evaluate(list(tuners), test, axis=axis, plants=list(variants))
    if not variants:
        return [(ev.cost[i].ravel(), ev.feasible[i].ravel()) for i in range(len(tuners))]
    a = ev.across
    return [(a.cost[i].ravel(), a.feasible[i].ravel()) for i in range(len(tuners))]


def own_base(folders: list[Path], axis):
    """The runs' residual base as their env makes it (move → settings), and its label;
    every run must have the same one."""
    from vfgym.agents import make_env, run_config

    cfgs = [run_config(f / "best_model.zip") for f in folders]
    kws = [(c.get("hyperparams") or {}) for c in cfgs]
    envs = {c.get("env") for c in cfgs}
    bases = {str(k.get("env_kwargs", {}).get("residual_base")) for k in kws}
    if len(bases) != 1 or len(envs) != 1 or not kws[0].get("env_kwargs", {}).get("residual"):
        raise SystemExit(f"--base own: the runs have residual bases {sorted(bases)}; give one")
    env = make_env(envs.pop(), kws[0]["env_kwargs"]).unwrapped
    config = env.core.config if hasattr(env, "core") else env.config  # VFServo-v0, VFTune-v0
    return (lambda sc: config.base_settings(sc)), bases.pop()


def oracle(axis, test, variants, out: Path) -> Judged:
    """Each pair's own optimum on its true plant (cached in ``out``)."""
    from vfgym.permove.optima import move_optima

    cache = out / "oracle.json"
    key = {"axis": axis.name, "moves": [s.name for s in test],
           "plants": [asdict(v) for v in variants]}  # fmt: skip
    if cache.is_file():
        data = json.loads(cache.read_text())
        if data["key"] == key:
            return Judged("oracle", data["cost"], data["feasible"], data["command"])
    scens = [sc for _ in variants for sc in test]
    on = [v for v in variants for _ in test]
    opt = move_optima(scens, plant=axis.plant, measures=axis.measures, true_plants=on)
    how = "each pair's optimum on its true plant (vfgym.permove.optima.move_optima)"
    j = Judged("oracle", [o.cost for o in opt], [bool(o.feasible) for o in opt], how)
    cache.write_text(json.dumps({"key": key, **asdict(j)}))
    return j


def scheduler(axis, fit: Path, test, variants, out: Path) -> Judged:
    """The EstimatingScheduler (default options) on the fit's model, on the pairs (cached
    in ``out``: its tables take minutes)."""
    from vfgym.permove import load_settings_model
    from vfgym.permove.adaptive import AdaptiveOptions, EstimatingScheduler

    cache = out / "scheduler.json"
    key = {
        "axis": axis.name,
        "moves": [s.name for s in test],
        "fit": str(fit),
        "plants": [asdict(v) for v in variants],
        "options": asdict(AdaptiveOptions()),
    }
    if cache.is_file():
        data = json.loads(cache.read_text())
        if data["key"] == key:
            return Judged("scheduler", data["cost"], data["feasible"], data["command"])
    sched = EstimatingScheduler(axis, load_settings_model(fit))
    ((c, ok),) = judge([sched], axis, test, variants)
    how = f"vfgym.permove.EstimatingScheduler on {fit}, default options"
    j = Judged("scheduler", c.tolist(), [bool(x) for x in ok], how)
    cache.write_text(json.dumps({"key": key, **asdict(j)}))
    return j


def wall_time(folder: Path) -> float:
    """A run's training time (s): its TensorBoard log's first to last event."""
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

    times = []
    for d in (folder / "tb").glob("*"):
        ea = EventAccumulator(str(d))
        ea.Reload()
        for tag in ea.Tags()["scalars"]:
            times += [e.wall_time for e in ea.Scalars(tag)]
    return max(times) - min(times) if times else float("nan")


def curves(runs, axis, test, variants, base: Judged, refs: list[Judged], path: Path) -> str:
    """Each run's checkpoints judged on the held-out pairs; the learning curves (held-out
    mean cost over the base's against steps, mean over seeds and their range) with the
    reference lines, as a picture at ``path``; returns a markdown table of the points."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from vfgym.agents import load_tuner

    series: dict[str, list[tuple[np.ndarray, np.ndarray]]] = {}
    for folder in runs:
        algo = run_label(folder)[0]
        found = (folder / "checkpoints").glob("model_*_steps.zip")
        ckpts = sorted((int(q.stem.split("_")[1]), q) for q in found)
        tuners = [load_tuner(q, axis) for _, q in ckpts]
        scored = judge(tuners, axis, test, variants)
        steps = np.array([0] + [k for k, _ in ckpts])
        ratio = np.array([1.0] + [c.mean() / base.mean for c, _ in scored])
        series.setdefault(algo, []).append((steps, ratio))
    fig, ax = plt.subplots(figsize=(7, 4))
    rows = ["| algorithm | steps | held-out cost / base, mean over seeds | seeds' range |",
            "| --- | --- | --- | --- |"]  # fmt: skip
    for algo, runs_ in series.items():
        n = min(len(s) for s, _ in runs_)
        steps, ys = runs_[0][0][:n], np.array([r[:n] for _, r in runs_])
        ax.plot(steps, ys.mean(axis=0), marker=".", label=f"{algo} ({len(runs_)} seeds)")
        ax.fill_between(steps, ys.min(axis=0), ys.max(axis=0), alpha=0.2)
        points = zip(steps, ys.mean(axis=0), ys.min(axis=0), ys.max(axis=0), strict=True)
        rows += [f"| {algo} | {k} | {m:.4f} | {lo:.4f}–{hi:.4f} |" for k, m, lo, hi in points]
    for ref, style in zip([base, *refs], ["-", "--", ":"], strict=False):
        ax.axhline(ref.mean / base.mean, color="k", ls=style, lw=1, label=ref.label)
    ax.set_xlabel("steps")
    ax.set_ylabel("held-out mean cost / base")
    ax.legend()
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return "\n".join(rows) + "\n"


def start_costs(env, moves, plants) -> tuple[np.ndarray, np.ndarray]:
    """The residual start's (the base's: action 0 throughout) cost and feasibility on
    each validation pair."""
    cost, ok = [], []
    for move, plant in zip(moves, plants, strict=True):
        env.reset(options={"scenario": move, "plant": plant})
        while True:
            *_, terminated, truncated, info = env.step(np.zeros(env.action_space.shape))
            if terminated or truncated:
                break
        cost.append(float(info["cost"]))
        ok.append(bool(info["feasible"]))
    return np.array(cost), np.array(ok)


def checkpoints(folder: Path) -> str:
    """Each checkpoint of a residual run on its validation pairs against its start (the
    base): a markdown table."""
    from vfgym.agents import load_agent, make_env, run_config
    from vfgym.agents.selection import (
        MIN_GAIN,
        SIGNIFICANCE,
        beats,
        validation_plants,
        validation_scenarios,
        validation_size,
    )
    from vfgym.agents.training import evaluate_policy_costs

    cfg = run_config(folder / "best_model.zip")  # (a run of an earlier vfgym read as today's)
    params = cfg["hyperparams"]
    kw = params.get("env_kwargs") or {}
    n = validation_size(params, kw.get("axis"))
    moves, plants = validation_scenarios(n, kw.get("axis")), validation_plants(n, kw.get("axis"))
    env = make_env(cfg["env"], kw)
    c0, ok0 = start_costs(env, moves, plants)
    rows = [
        f"{folder.name}: {n} validation pairs; the start (the base) {c0.mean():.4f}, "
        f"feasible on {int(ok0.sum())}",
        "",
        "| steps | mean / start | gain (standard errors) | limits broken where the start "
        f"holds | replaces the start (> {SIGNIFICANCE:g} s.e. and {100 * MIN_GAIN:g} %, no new "
        "break) |",
        "| --- | --- | --- | --- | --- |",
    ]
    ckpts = sorted(
        (int(q.stem.split("_")[1]), q) for q in (folder / "checkpoints").glob("model_*_steps.zip")
    )
    for k, path in ckpts:
        agent = load_agent(path)
        cost, ok = evaluate_policy_costs(agent.model, env, moves, agent.normalizer, plants)
        ok = ok.astype(bool)
        diff = c0 - cost
        z = float(diff.mean() / (diff.std(ddof=1) / np.sqrt(len(diff))))
        wins = beats(cost, c0, SIGNIFICANCE, ok, ok0)
        rows.append(
            f"| {k} | {cost.mean() / c0.mean():.4f} | {z:.2f} | {int(np.sum(ok0 & ~ok))} | "
            f"{'yes' if wins else 'no'} |"
        )
    return "\n".join(rows) + "\n"


def eval_time(axis_file: str, base_file: Path, counts: list[int]) -> str:
    """Seconds of one validation evaluation of a fresh residual PPO agent, first and
    second call, on each count of validation pairs (VFServo-v0, VFTune-v0)."""
    import time

    from vfgym.agents import hyperparams as hp
    from vfgym.agents import make_env
    from vfgym.agents.selection import validation_plants, validation_scenarios
    from vfgym.agents.training import evaluate_policy_costs, start_at_base

    lines = []
    for env_id, base in (("vfgym/VFServo-v0", "model"), ("vfgym/VFTune-v0", "model-lookup")):
        kw = dict(hp.load("ppo", env_id)["env_kwargs"])
        kw |= {"axis": axis_file, "residual_base": f"{base}:{base_file}"}
        env = make_env(env_id, kw)
        model = hp.algo_class("ppo")("MlpPolicy", env, seed=0, device="cpu")
        start_at_base(model)
        for n in counts:
            moves, plants = validation_scenarios(n, axis_file), validation_plants(n, axis_file)
            took = []
            for _ in range(2):
                t0 = time.perf_counter()
                evaluate_policy_costs(model, env, moves, None, plants)
                took.append(time.perf_counter() - t0)
            lines.append(f"{env_id}: {n} pairs, first call {took[0]:.1f} s, next {took[1]:.1f} s")
    return "\n".join(lines)


def run_label(folder: Path) -> tuple[str, int, int, str, str]:
    """(algo, seed, steps, command, env) of a run folder."""
    from vfgym.io.runs import read_yaml

    cfg = read_yaml(folder / "config.yaml")
    steps = int((cfg.get("hyperparams") or {}).get("n_timesteps", 0))
    cmd = (folder / "command.txt").read_text().strip() if (folder / "command.txt").is_file() else ""
    env = str(cfg.get("env", "")).split("/")[-1]
    return str(cfg.get("algo")), int(cfg.get("seed", 0)), steps, cmd, env


def fmt(x: float, d: int = 3) -> str:
    return "nan" if not np.isfinite(x) else f"{x:.{d}f}"


def report(
    base: Judged,
    orc: Judged | None,
    runs: list[tuple[Path, Judged]],
    n_pairs: int,
    sched: Judged | None = None,
) -> str:
    """The markdown tables (``orc`` None: no oracle row or ratio; ``sched`` None: no
    scheduler row or ratio)."""
    bc, bok = np.array(base.cost), np.array(base.feasible, bool)
    lines = [
        f"Held-out (move, plant) pairs: {n_pairs}.",
        "",
        "| tuner | seed | steps | held-out mean cost | feasible pairs | / base | "
        "cheaper / dearer than base | limits broken where the base holds |",
        "| --- | --- | --- | --- | --- | --- | --- | --- |",
        f"| base ({base.command}) | | | {fmt(base.mean)} | {sum(base.feasible)}/{n_pairs} | "
        "1.000 | | |",
    ]
    for ref in (r for r in (orc, sched) if r is not None):
        c, ok = np.array(ref.cost), np.array(ref.feasible, bool)
        lines.append(
            f"| {ref.label} | | | {fmt(ref.mean)} | {sum(ref.feasible)}/{n_pairs} | "
            f"{fmt(ref.mean / base.mean)} | {int(np.sum(c < bc - 1e-9))} / "
            f"{int(np.sum(c > bc + 1e-9))} | {int(np.sum(bok & ~ok))} |"
        )
    groups: dict[tuple[str, int, str], list[tuple[int, Judged, float]]] = {}
    for folder, j in runs:
        algo, seed, steps, _, env = run_label(folder)
        c, ok = np.array(j.cost), np.array(j.feasible, bool)
        lines.append(
            f"| {algo} | {seed} | {steps} | {fmt(j.mean)} | {sum(j.feasible)}/{n_pairs} | "
            f"{fmt(j.mean / base.mean)} | {int(np.sum(c < bc - 1e-9))} / "
            f"{int(np.sum(c > bc + 1e-9))} | {int(np.sum(bok & ~ok))} |"
        )
        groups.setdefault((algo, steps, env), []).append((seed, j, j.wall_s))
    lines += [
        "",
        "| algorithm | env | steps | wall time / run (s) | mean cost ± std over seeds | "
        "worst seed feasible | most breaks where the base holds | / base | / scheduler | "
        "/ oracle | seeds |",
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for (algo, steps, env), rows in groups.items():
        means = np.array([j.mean for _, j, _ in rows])
        feas = min(sum(j.feasible) for _, j, _ in rows)
        breaks = max(int(np.sum(bok & ~np.array(j.feasible, bool))) for _, j, _ in rows)
        wall = float(np.mean([w for *_, w in rows]))
        to_orc = "" if orc is None else fmt(means.mean() / orc.mean)
        to_sched = "" if sched is None else fmt(means.mean() / sched.mean)
        lines.append(
            f"| {algo} | {env} | {steps} | {fmt(wall, 0)} | {fmt(means.mean())} ± "
            f"{fmt(means.std())} | {feas}/{n_pairs} | {breaks} | "
            f"{fmt(means.mean() / base.mean)} | {to_sched} | {to_orc} | {len(rows)} |"
        )
    lines += ["", "Commands:", "", "```"]
    lines += [run_label(f)[3] for f, _ in runs] + ["```"]
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    from bench_agents import run_training, train_command

    from vfgym import PAPER_AXIS, load_axis
    from vfgym.agents import load_tuner
    from vfgym.axis import VERDICT_PLANT_SEED
    from vfgym.moves.distribution import random_scenario

    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--axis", default="experiments/axes/loads-uncertain.yaml")
    p.add_argument("--runs", nargs="*", default=[], help="trained run folders")
    p.add_argument("--train", action="store_true", help="train --algos x --seeds first")
    p.add_argument("--algos", default="ppo")
    p.add_argument("--seeds", default="1,2,3")
    p.add_argument("--steps", type=int, default=200_000)
    p.add_argument(
        "--base",
        default=None,
        help="the base settings model (default: the fit's); own: the runs' own residual base",
    )
    p.add_argument("--exact", action="store_true", help="the plant known exactly (no --axis)")
    p.add_argument("--no-oracle", action="store_true", help="no oracle row")
    p.add_argument(
        "--model",
        default="best_model.zip",
        help="which of each run's models to judge (default best_model.zip; final_model.zip: "
        "the last, as shipped without the choice)",
    )
    p.add_argument("--eval-time", default=None, help="time validation calls on N,M pairs")
    p.add_argument(
        "--checkpoints",
        action="store_true",
        help="only score each run's checkpoints on its validation pairs against its start",
    )
    p.add_argument("--fit-runs", default="runs", help="runs dir holding fit/AXIS (default runs)")
    p.add_argument("--scheduler", action="store_true", help="the EstimatingScheduler's row")
    p.add_argument("--curves", action="store_true", help="checkpoints held out: the curves")
    p.add_argument("--plants", type=int, default=16)
    p.add_argument("--plant-seed", type=int, default=VERDICT_PLANT_SEED)
    p.add_argument("--moves", type=int, default=32)
    p.add_argument("--out", default="runs/bench-adaptive")
    args = p.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    folders = [Path(r) for r in args.runs]
    if args.checkpoints:
        text = "\n".join(checkpoints(f) for f in folders)
        print(text)
        (out / "checkpoints.md").write_text(text)
        return 0
    axis = PAPER_AXIS if args.exact else load_axis(args.axis)
    if args.eval_time:
        fit = Path(args.fit_runs) / "fit" / axis.name / "settings_model.json"
        print(eval_time(args.axis, fit, [int(x) for x in args.eval_time.split(",")]))
        return 0
    base_file = Path(args.base or Path(args.fit_runs) / "fit" / axis.name / "settings_model.json")
    if args.base != "own" and not base_file.is_file():
        raise SystemExit(f"--base {base_file}: no such file; make it: vfgym fit --axis {args.axis}")
    walls: dict[Path, float] = {}
    if args.train:
        for algo in args.algos.split(","):
            for seed in map(int, args.seeds.split(",")):
                cmd, folder = train_command(algo, "VFServo-v0", seed, args.steps, out,
                                            ["--axis", args.axis])  # fmt: skip
                print(shlex.join(cmd), flush=True)
                walls[folder] = run_training(cmd)
                folders.append(folder)
    if args.exact:
        test, variants = [random_scenario(i, "test") for i in range(args.moves)], []
    else:
        test, variants = pairs(axis, args.moves, args.plants, args.plant_seed)
    n = len(test) * max(1, len(variants))
    if args.base == "own":
        first, how = own_base(folders, axis)
        where = axis if args.exact else args.axis
    else:
        first, how = load_tuner(base_file, axis, warn=print), f"vfgym fit --axis {args.axis}"
        where = axis
    tuners = [first] + [load_tuner(f / args.model, where, warn=print) for f in folders]
    scored = judge(tuners, axis, test, variants)
    c0, f0 = scored[0]
    base = Judged("base", c0.tolist(), f0.tolist(), how)
    runs = [
        (f, Judged(f.name, c.tolist(), ok.tolist(), run_label(f)[3], walls.get(f, wall_time(f))))
        for f, (c, ok) in zip(folders, scored[1:], strict=True)
    ]
    orc = None if args.no_oracle else oracle(axis, test, variants, out)
    sched = scheduler(axis, base_file, test, variants, out) if args.scheduler else None
    text = report(base, orc, runs, n, sched)
    if args.curves:
        refs = [r for r in (sched, orc) if r is not None]
        text += "\nLearning curves (learning_curves.png), checkpoints held out:\n\n"
        text += curves(folders, where, test, variants, base, refs, out / "learning_curves.png")
    head = (f"Axis {axis.name} ({args.axis}); {len(test)} test moves x {len(variants)} plants "
            f"(plant seed {args.plant_seed}).\n\n")  # fmt: skip
    if args.exact:
        head = f"The plant known exactly; the agents' first {len(test)} test moves.\n\n"
    print(head + text)
    (out / "benchmark.md").write_text(head + text)
    data = {"base": asdict(base), "oracle": None if orc is None else asdict(orc),
            "scheduler": None if sched is None else asdict(sched),
            "runs": [{"folder": str(f), **asdict(j)} for f, j in runs]}  # fmt: skip
    (out / "benchmark.json").write_text(json.dumps(data))
    return 0


if __name__ == "__main__":
    sys.exit(main())
