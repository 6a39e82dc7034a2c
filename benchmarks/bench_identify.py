"""``vfgym identify`` on captures of the planned moves from drawn plants: accuracy,
coverage of the 95 % intervals, wall time, and (``--regret N``) what tuning on the
identified axis costs against tuning on the true one.

    python benchmarks/bench_identify.py [--plants 20] [--seed 20261205] [--axis FILE]
        [--after-enable] [--regret N [--regret-plants K,K,...] [--regret-within-window]
        --runs-dir DIR]

Each plant is drawn from ``--seed`` (a stream no test uses): inertia ratio 0–8 on the
nominal axis's motor, Coulomb friction up to 5 % of the rated torque, viscous friction up
to 3e-4 N·m·s/rad, a load torque up to ±5 % of rated; the drive's gain is as set. The
planned moves (``vfgym identify --plan``) run on it and a 2 s capture at 1 MHz records
them as a logic analyser does (edges rounded to 1 µs, the encoder as A/B edges only), as
the plan's procedure asks: started 20–100 ms before the drive's enable, the moves 0.2 s
after it (``--from-enable``). ``--after-enable`` records instead a capture started at an
arbitrary instant of a 0.5 s rest after the enable, with the axis already held. The
identification (reading the VCD, placing it on the tick grid, the fit) is timed on the
wall clock.

Printed: per plant the errors, then the summary against the goals: inertia within ±2 %,
Coulomb friction and load torque within ±1 % of the rated torque, ≥ 90 % of the 95 %
intervals holding the truth, ≤ 30 s an identification on 2 cores. Coverage counts the
estimated (excited) quantities among inertia, Coulomb, viscous and load torque, and the
gain where it is estimated. It asserts nothing (the machine is shared).

``--regret N`` then runs ``vfgym fit`` (:func:`vfgym.permove.fit_axis`, its defaults)
on the first N plants (or those ``--regret-plants`` lists) twice: on the identified axis
(its uncertainty block included) and on the true axis (the true plant, exactly known).
Both settings models are judged on the true plant's 32 held-out test moves
(:func:`vfgym.evaluate` on the true axis, each model choosing the settings of a move from
its own axis). The goals, over the plants where the
fit on the true axis is feasible on every move: the identified axis's fit feasible on
every move for ≥ 95 % of them, and its mean cost at most 1.03× the true axis's. On this
distribution almost no plant is in that set: a servo without an integrator stops a move
up to (|load| + Coulomb)/K3 counts from its target, beyond the paper axis's 8-count
in-position window for all but about 1 % of the plants, whatever the controller.
``--regret-within-window`` scales each regret plant's friction and load down to fit it.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from vfgym.axis import EXACT, PAPER_AXIS, Axis, PlantVariant, load_axis
from vfgym.identify.capture import read_capture
from vfgym.identify.fit import PARAMS, fit
from vfgym.identify.model import record_of
from vfgym.identify.plan import make_plan
from vfgym.identify.simulated import record_capture
from vfgym.identify.written import Identified, identify_report
from vfgym.params import PAPER_SETTINGS

CAPTURE_S = 2.0
ENABLE_TO_MOVES_S = 0.2
"""From the drive's enable to the first move (s), as the plan's procedure asks."""

AFTER_REST_S = 0.5
"""With ``--after-enable``: the rest after the enable in which the capture starts (s)."""


@dataclass(frozen=True)
class Drawn:
    """One drawn true plant."""

    ratio: float
    truth: dict[str, float]
    variant: PlantVariant
    u: float


def draw(nominal_axis: Axis, seed: int, k: int) -> Drawn:
    """Plant ``k`` of the stream ``seed`` (see the module doc)."""
    m = nominal_axis.plant.motor
    rated = m.rated_torque_nm
    rng = np.random.default_rng([seed, k])
    ratio = rng.uniform(0.0, 8.0)
    truth = {
        "inertia": (1.0 + ratio) / (1.0 + m.inertia_ratio),
        "coulomb_nm": rng.uniform(0.0, 0.05) * rated,
        "viscous_nm_s_rad": rng.uniform(0.0, 3e-4),
        "load_torque_nm": rng.uniform(-0.05, 0.05) * rated,
        "torque_per_count": 1.0,
    }
    variant = PlantVariant(
        inertia=truth["inertia"],
        coulomb_offset_nm=truth["coulomb_nm"] - m.coulomb_nm,
        viscous_offset_nm_s_rad=truth["viscous_nm_s_rad"] - m.viscous_nm_s_rad,
        load_offset_nm=truth["load_torque_nm"] - m.load_torque_nm,
    )
    return Drawn(ratio, truth, variant, float(rng.uniform(0.4, 0.9)))


def identify_drawn(
    axis: Axis, drawn: Drawn, pulses: np.ndarray, path: Path, after_enable: bool
) -> tuple[Identified, float, float]:
    """Capture the plan on a drawn plant and identify it; returns the wall and CPU time
    (both threads') too."""
    nominal = axis.plant
    if after_enable:
        start_s, rest_s, from_enable = AFTER_REST_S * drawn.u, AFTER_REST_S, None
    else:
        start_s, rest_s, from_enable = -0.1 * drawn.u - 0.01, ENABLE_TO_MOVES_S, True
    cap_path = record_capture(
        drawn.variant.apply(nominal),
        pulses,
        path,
        start_s=start_s,
        rest_s=rest_s,
        length_s=CAPTURE_S,
    )
    t0, c0 = time.perf_counter(), time.process_time()
    rec = record_of(read_capture(cap_path), nominal, from_enable)
    result = fit([rec], nominal, PAPER_SETTINGS)
    ident = identify_report(axis, result, [rec])
    return ident, time.perf_counter() - t0, time.process_time() - c0


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--plants", type=int, default=20)
    ap.add_argument("--seed", type=int, default=20261205)
    ap.add_argument("--axis", help="the nominal axis file (default: the paper's axis)")
    ap.add_argument(
        "--after-enable",
        action="store_true",
        help="captures started with the axis already held (not the planned procedure)",
    )
    ap.add_argument("--regret", type=int, default=0, metavar="N", help="fits on N plants")
    ap.add_argument(
        "--regret-plants",
        metavar="K,K,...",
        help="the plants --regret fits (default: the first N), e.g. the lightest, whose "
        "true-axis fit is the likeliest to be feasible on every move",
    )
    ap.add_argument(
        "--regret-within-window",
        action="store_true",
        help="--regret on each plant with its Coulomb friction and load torque scaled down "
        "(ratio and sign kept) until the static error (|load| + Coulomb)/K3 is 80 %% of "
        "the in-position window: only such a plant can be feasible on every move",
    )
    ap.add_argument(
        "--regret-axes",
        choices=("both", "counted", "true", "id"),
        default="both",
        help="the fits --regret runs: both; both where the true axis's fit is feasible on "
        "every move (counted), else only the true one's; or only the true (or identified) "
        "axis's. A "
        "settings model already in --runs-dir for the same axis is kept, a fit stopped "
        "there continues from its checkpointed optima",
    )
    ap.add_argument(
        "--regret-only",
        action="store_true",
        help="identify only the plants --regret fits (the accuracy lines are theirs only)",
    )
    ap.add_argument("--runs-dir", help="where --regret's fits write (default: a temp folder)")
    args = ap.parse_args(argv)
    chosen = (
        [int(x) for x in args.regret_plants.split(",")]
        if args.regret_plants
        else list(range(args.regret))
    )
    axis = load_axis(args.axis) if args.axis else PAPER_AXIS
    nominal = axis.plant
    rated = nominal.motor.rated_torque_nm
    plan = make_plan(axis, PAPER_SETTINGS)
    how = "after the enable" if args.after_enable else "from before the drive's enable"
    print(
        f"axis {axis.name}: {len(plan.moves)} planned moves, {plan.duration_s:.3g} s; "
        f"captures of {CAPTURE_S:g} s at 1 MHz, {how}; {args.plants} plants from seed "
        f"{args.seed}"
    )
    with tempfile.TemporaryDirectory() as tmp:  # compile the kernel outside the timings
        warm = record_capture(nominal, plan.pulses[:20000], Path(tmp) / "w.vcd", start_s=0.05)
        fit([record_of(read_capture(warm), nominal)], nominal, PAPER_SETTINGS)
    rows = []
    hits = {name: 0 for name in PARAMS}
    total = {name: 0 for name in PARAMS}
    idents: list[tuple[int, Drawn, Identified]] = []
    print(
        "plant  ratio  |dJ| %   dCoulomb %rated  dviscous %rated@top  dload %rated  gain   "
        "rms counts  sat ms  wall s  cpu s  outside 95 %"
    )
    top = nominal.pulse_top_speed_rad_s
    with tempfile.TemporaryDirectory() as tmp:
        for k in range(args.plants):
            if args.regret_only and k not in chosen:
                continue
            drawn = draw(axis, args.seed, k)
            if args.regret_only and args.regret_within_window:
                idents.append((k, drawn, None))  # identified within the window below
                continue
            truth = drawn.truth
            ident, wall, cpu = identify_drawn(
                axis, drawn, plan.pulses, Path(tmp) / "c.vcd", args.after_enable
            )
            result = ident.fit
            if k in chosen:
                idents.append((k, drawn, ident))
            err = {e.name: e.value - truth[e.name] for e in result.estimates}
            outside = []
            for e in result.estimates:
                if not e.excited:
                    continue
                total[e.name] += 1
                if e.low <= truth[e.name] <= e.high:
                    hits[e.name] += 1
                else:
                    outside.append(e.name)
            row = {
                "inertia_pct": 100 * err["inertia"] / truth["inertia"],
                "coulomb_pct": 100 * err["coulomb_nm"] / rated,
                "viscous_pct": 100 * err["viscous_nm_s_rad"] * top / rated,
                "load_pct": 100 * err["load_torque_nm"] / rated,
                "load_excited": result.estimate("load_torque_nm").excited,
                "wall": wall,
                "cpu": cpu,
                "explained": ident.explained,
            }
            rows.append(row)
            gain = result.estimate("torque_per_count")
            print(
                f"{k:5d}  {drawn.ratio:5.2f}  {abs(row['inertia_pct']):6.3f}   "
                f"{row['coulomb_pct']:+14.4f}  {row['viscous_pct']:+19.4f}  "
                f"{row['load_pct']:+12.4f}{'' if row['load_excited'] else '*'}"
                f"{' ' if row['load_excited'] else ''}"
                f"{gain.value if gain.excited else float('nan'):5.3f}  "
                f"{result.residual_rms_counts:10.3f}  {result.saturated_s * 1e3:6.1f}  "
                f"{wall:6.2f}  {cpu:5.1f}  {' '.join(outside) or '-'}",
                flush=True,
            )
    if rows:
        summary(rows, hits, total)
    if idents:
        if args.regret_within_window:
            idents = [
                within_window(axis, k, d, plan.pulses, args.after_enable) for k, d, _ in idents
            ]
        regret(axis, idents, args.runs_dir, args.regret_axes)
    return 0


def summary(rows: list[dict], hits: dict[str, int], total: dict[str, int]) -> None:
    """The accuracy, coverage and time lines against the goals."""
    a = {key: np.array([r[key] for r in rows]) for key in rows[0]}
    print("(* the load torque not excited: left at its nominal value)")
    print()
    x = np.abs(a["inertia_pct"])
    print(
        f"inertia error: max {x.max():.3f} %, mean {x.mean():.3f} % (goal within 2 %): "
        f"{np.count_nonzero(x <= 2)}/{len(rows)} within"
    )
    for key, label in (("coulomb_pct", "Coulomb"), ("load_pct", "load torque")):
        x = np.abs(a[key])
        print(
            f"{label} error: max {x.max():.4f} % of rated, mean {x.mean():.4f} % (goal within "
            f"1 %): {np.count_nonzero(x <= 1)}/{len(rows)} within"
        )
    x = np.abs(a["viscous_pct"])
    print(f"viscous error (its torque at the top speed): max {x.max():.4f} % of rated")
    h, t = sum(hits.values()), sum(total.values())
    per = ", ".join(f"{n} {hits[n]}/{total[n]}" for n in PARAMS if total[n])
    print(f"coverage of the 95 % intervals: {h}/{t} = {h / max(t, 1):.1%} (goal 90 %): {per}")
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(
        f"wall time an identification (2 s capture): mean {a['wall'].mean():.2f} s, max "
        f"{a['wall'].max():.2f} s (goal 30 s on 2 cores); CPU time (both threads) mean "
        f"{a['cpu'].mean():.2f} s, max {a['cpu'].max():.2f} s; load average now {load:.1f}"
    )
    print(f"explained (residual near the floor): {int(a['explained'].sum())}/{len(rows)}")


WINDOW_SHARE = 0.8
"""With ``--regret-within-window``: the static error's share of the in-position window."""


def within_window(
    axis: Axis, k: int, drawn: Drawn, pulses: np.ndarray, after_enable: bool
) -> tuple[int, Drawn, Identified]:
    """Plant ``k`` with its Coulomb friction and load torque scaled down until its static
    error fits the in-position window (see ``--regret-within-window``), identified anew.

    A servo without an integrator stops a move (|load| + Coulomb)/K3 counts from its
    target at most, either side; past the window no controller makes every move."""
    m = axis.plant.motor
    t = dict(drawn.truth)
    room = WINDOW_SHARE * axis.measures.in_position_counts * axis.plant.torque_per_count_nm
    f = min(1.0, room / max(abs(t["load_torque_nm"]) + t["coulomb_nm"], 1e-12))
    t["coulomb_nm"] *= f
    t["load_torque_nm"] *= f
    variant = replace(
        drawn.variant,
        coulomb_offset_nm=t["coulomb_nm"] - m.coulomb_nm,
        load_offset_nm=t["load_torque_nm"] - m.load_torque_nm,
    )
    scaled = replace(drawn, truth=t, variant=variant)
    with tempfile.TemporaryDirectory() as tmp:
        ident, _, _ = identify_drawn(axis, scaled, pulses, Path(tmp) / "w.vcd", after_enable)
    worst, outside = block_check(ident, t)
    print(
        f"plant {k} within the window: Coulomb {t['coulomb_nm']:.4g} N*m, load "
        f"{t['load_torque_nm']:+.4g} N*m (x{f:.3f}); identified, residual "
        f"{ident.fit.residual_rms_counts:.3g} counts; the block's worst plant stops "
        f"{worst:.2f} counts from a target (window {axis.measures.in_position_counts:g}); "
        f"the true plant outside the block in: {' '.join(outside) or '-'}"
    )
    return k, scaled, ident


def block_check(ident: Identified, truth: dict[str, float]) -> tuple[float, list[str]]:
    """How far from its target the identified block's worst plant stops at most (counts:
    its highest Coulomb friction plus load over its lowest K3), and the quantities whose
    true value lies outside the block."""
    unc = ident.axis.uncertainty
    k3 = ident.axis.plant.torque_per_count_nm
    g_lo = unc.torque_per_count[0] if unc.torque_per_count else 1.0
    worst = (unc.coulomb_nm[1] + max(map(abs, unc.load_torque_nm))) / (k3 * g_lo)
    outside = []
    for e in ident.fit.estimates:
        value, span = truth[e.name], getattr(unc, e.name)
        if e.name in ("inertia", "torque_per_count"):
            value /= e.value  # the block's factors are on the estimates
        lo, hi = span if span is not None else (1.0, 1.0)  # (the gain as set)
        if not lo <= value <= hi:
            outside.append(e.name)
    return worst, outside


def lost_move(ev: Any, j: int, ident: Identified) -> str:
    """Why the identified axis's settings model loses test move ``j`` on the true plant:
    the limits its settings break there, on the identified plant, and on how many of the
    block's design plants (what the robust pick had to be feasible on)."""
    from vfgym.scoring import CONSTRAINTS, Move, on_plant, score_pairs

    sc, s = ev.scenarios[j], ev.chosen[0][j]
    mv = Move.of(sc, ident.axis.plant)
    design = ident.axis.design_plants()
    on = score_pairs([s] * (1 + len(design)), [mv, *(on_plant(mv, v) for v in design)],
                     measures=ident.axis.measures)  # fmt: skip
    c = ev.constraints[0, j]
    broken = ", ".join(f"{n} {v:+.4g}" for n, v in zip(CONSTRAINTS, c, strict=True) if v > 0)
    worst = max(on[1:], key=lambda r: float(np.max(r.constraints)), default=None)
    return (
        f"{sc.name}: on the true plant {broken}; on the identified plant "
        f"{float(np.max(on[0].constraints)):+.4g}; infeasible on "
        f"{sum(not r.feasible for r in on[1:])}/{len(design)} design plants"
        + (f" (worst {float(np.max(worst.constraints)):+.4g})" if worst is not None else "")
    )


FIT_SECONDS = "bench_fit_seconds.txt"
"""Where :func:`regret` records how long a fit took, beside its settings model."""


def _fitted(ax: Axis, run: Path, fit_axis: Any, cfg: Any, load_tuner: Any) -> tuple[Any, float]:
    """The settings model ``vfgym fit`` learns for ``ax`` in ``run``, and the fit's seconds
    (nan: not recorded). A model already there, learnt on the same plant, measures and
    uncertainty (no warning from ``load_tuner``), is kept: the fit is deterministic."""
    path = run / "settings_model.json"
    if path.is_file():
        said: list[str] = []
        tuner = load_tuner(path, axis=ax, warn=said.append)
        if not said:
            done = run / FIT_SECONDS
            return tuner, float(done.read_text()) if done.is_file() else float("nan")
    t0 = time.perf_counter()
    fit_axis(ax, run, cfg, progress=False)
    seconds = time.perf_counter() - t0
    (run / FIT_SECONDS).write_text(f"{seconds:.1f}\n")
    return load_tuner(path, axis=ax, warn=lambda msg: None), seconds


def regret(
    axis: Axis,
    idents: list[tuple[int, Drawn, Identified]],
    runs_dir: str | None,
    axes: str = "both",
) -> None:
    """``vfgym fit`` on the identified and on the true axis, judged on the true plant
    (``axes``: ``true`` or ``id`` runs only that one's fits, printing nothing to compare;
    ``counted`` the identified axis's only where the true axis's is feasible on every
    move, the plants the goal is stated over)."""
    import vfgym
    from vfgym.permove import FitConfig, fit_axis, load_tuner

    base = Path(runs_dir) if runs_dir else Path(tempfile.mkdtemp(prefix="bench-identify-"))
    print()
    print(f"regret: vfgym fit on the identified and on the true axis; runs in {base}")
    print("plant  ratio  feasible id/true  mean cost id  mean cost true  ratio  fit s id/true")
    ratios, feasible_id, counted = [], 0, 0
    for k, drawn, ident in idents:
        true_axis = replace(
            axis, plant=drawn.variant.apply(axis.plant), uncertainty=EXACT, name=f"true-{k}"
        )
        out, lost = {}, []
        for label, ax in (("true", true_axis), ("id", ident.axis)):
            if axes not in ("both", "counted", label):
                continue
            if label == "id" and axes == "counted" and not np.all(out["true"][0]):
                break  # outside the goal's plants: no identified-axis fit
            run = base / f"plant{k}-{label}"
            run.mkdir(parents=True, exist_ok=True)
            tuner, seconds = _fitted(ax, run, fit_axis, FitConfig(), load_tuner)
            ev = vfgym.evaluate(tuner, "test", axis=true_axis)
            out[label] = (ev.feasible[0], float(ev.mean_cost[0]), seconds)
            if label == "id":
                lost = [lost_move(ev, j, ident) for j in np.flatnonzero(~ev.feasible[0])]
        if len(out) == 1:
            (label,) = out
            f, c, s = out[label]
            print(f"{k:5d}  {drawn.ratio:5.2f}  {label}: feasible {int(f.sum())}/{f.size}, "
                  f"mean cost {c:.4g}, fit {s:.0f} s", flush=True)  # fmt: skip
            continue
        for line in lost:
            print(f"       lost {line}")
        f_id, c_id, s_id = out["id"]
        f_tr, c_tr, s_tr = out["true"]
        ok_true = bool(np.all(f_tr))
        if ok_true:
            counted += 1
            feasible_id += bool(np.all(f_id))
            ratios.append(c_id / c_tr)
        print(
            f"{k:5d}  {drawn.ratio:5.2f}  {int(f_id.sum()):2d}/{f_id.size} {int(f_tr.sum()):2d}/"
            f"{f_tr.size}      {c_id:12.4g}  {c_tr:14.4g}  {c_id / c_tr:5.3f}  "
            f"{s_id:.0f}/{s_tr:.0f}",
            flush=True,
        )
    if counted:
        print(
            f"over the {counted} plants whose true-axis fit is feasible on every move: the "
            f"identified axis's fit feasible on every move on {feasible_id}/{counted} (goal "
            f"95 %); mean cost ratio {np.mean(ratios):.4f} (max {np.max(ratios):.4f}; goal "
            "at most 1.03)"
        )
    else:
        print("no plant whose true-axis fit is feasible on every move")


if __name__ == "__main__":
    sys.exit(main())
