"""How many trials TPE and CMA-ES need to get within 1 % of the grid reference.

Each (sampler, seed) runs the study `vfgym sweep` runs (same objective, sampler settings,
baseline enqueued first; in memory, one worker) until its best feasible cost is within
``--within`` % of the reference's, or ``--max-trials``. Prints one row per run and the
median per sampler.

    vfgym grid --config experiments/grid-paper-step.yaml
    python experiments/trials_to_reference.py --reference runs/grid/paper-step-p12-r3k4
"""

from __future__ import annotations

import argparse
import statistics
import time
import warnings

import optuna

from vfgym import tuning


def trials_to(cfg: tuning.SweepConfig, seed: int, target: float, max_trials: int) -> tuple:
    """(trials needed or None, best cost, seconds) for one seeded study."""
    scenarios = cfg.scenario_list()
    sampler = tuning.make_sampler(cfg, seed)
    study, _ = tuning.create_or_load(None, f"{cfg.sampler}-{seed}", cfg, scenarios, sampler)
    objective = tuning.Objective(scenarios, cfg.laws, cfg.objective)
    hit: list[int] = []

    def stop_at_target(study: optuna.Study, trial: optuna.trial.FrozenTrial) -> None:
        best = tuning.best_trial(study)
        if best is not None and best.user_attrs["feasible"] and best.user_attrs["cost"] <= target:
            hit.append(len(study.trials))
            study.stop()

    t0 = time.perf_counter()
    study.optimize(objective, n_trials=max_trials, callbacks=[stop_at_target])
    best = tuning.best_trial(study)
    return (hit[0] if hit else None), best.user_attrs["cost"], time.perf_counter() - t0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--reference", required=True, help="grid reference.yaml or grid run folder")
    ap.add_argument("--scenarios", default="paper-step")
    ap.add_argument("--samplers", default="tpe,cmaes")
    ap.add_argument("--seeds", default="0,1,2,3,4")
    ap.add_argument("--within", type=float, default=1.0, help="percent above the reference")
    ap.add_argument("--max-trials", type=int, default=1500)
    args = ap.parse_args()
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    warnings.filterwarnings("ignore")

    base = tuning.SweepConfig(scenarios=args.scenarios)
    found = tuning.find_reference(args.reference, "runs", base.scenario_list(), base.laws)
    assert found is not None
    ref_cost = float(found[0]["cost"])
    target = ref_cost * (1.0 + args.within / 100.0)
    print(f"reference {found[1]}: cost {ref_cost:.6f}; target <= {target:.6f} "
          f"(+{args.within:g} %), at most {args.max_trials} trials")  # fmt: skip
    print(f"{'sampler':8s} {'seed':>4s} {'trials':>7s} {'best cost':>10s} {'gap %':>7s} {'s':>6s}")
    for name in args.samplers.split(","):
        cfg = tuning.SweepConfig(scenarios=args.scenarios, sampler=name)
        needed = []
        for seed in (int(s) for s in args.seeds.split(",")):
            n, best, secs = trials_to(cfg, seed, target, args.max_trials)
            needed.append(n if n is not None else float("inf"))
            shown = str(n) if n is not None else f">{args.max_trials}"
            print(f"{name:8s} {seed:4d} {shown:>7s} {best:10.6f} "
                  f"{tuning.gap_pct(best, ref_cost):+7.2f} {secs:6.1f}", flush=True)  # fmt: skip
        med = statistics.median(needed)
        print(f"{name:8s} median trials to within {args.within:g} %: "
              f"{med if med != float('inf') else f'>{args.max_trials}'}", flush=True)  # fmt: skip


if __name__ == "__main__":
    main()
