"""``vfgym identify`` on simulated captures of the planned moves: whether the written axis
is safe to act on.

    python benchmarks/bench_identify.py [--part blocks,faults,payload,regret,resonance]
        [--plants 20] [--seed 20261205] [--after-enable] [--faults-plants 4]
        [--regret-plants K,K,...] [--regret-gains 0.9,1.07,1.1] [--runs-dir DIR]

Each plant is drawn from ``--seed`` (a stream no test uses): inertia ratio 0–15 on the
nominal axis's motor, the drive's gain ×0.9–1.1 of the one set, Coulomb friction up to
5 % of the rated torque, viscous friction up to 3e-4 N·m·s/rad, a load torque up to ±5 %
of rated. The planned moves (``vfgym identify --plan``) run on it and a capture at 1 MHz
records them as a logic analyser does (edges rounded to 1 µs, the encoder as A/B edges
only), as the plan's procedure asks: started 10–100 ms before the drive's enable, the
moves 0.2 s after it, 0.1 s after the last one (``--from-enable``); ``--after-enable``
starts it instead at an arbitrary instant of a 0.5 s rest after the enable. Every
identification runs :func:`vfgym.identify.pipeline.identify_axis`, the command's path.

The parts, each printing its goal line:

``blocks``
    Every written block holds the true plant (its inertia and gain as factors on the
    identified ones, the torques absolute); where the torque is at its limit long enough
    to separate the gain, the inertia and the gain within 2 %. Also accuracy, the 95 %
    intervals' coverage and the time an identification takes.
``faults``
    The first ``--faults-plants`` plants captured with faults (:func:`with_faults`):
    1, 5 and 20 encoder edges lost, 1, 5 and 20 one-sample glitches, A and B swapped,
    another axis's plan (the belt axis's) run on the plant, the file cut mid-line and cut
    at a line (a file that ends early). Goal: no written axis whose block misses the truth
    without a line (a note, or the refusal) naming the cause.
``payload``
    A nominal axis stating a payload's range (``inertia: [0.95, 1.25]``, a load torque
    range) and a drive gain's prior: plants inside it and just outside it, gains off.
    Goal: the written range holds the stated one (and the truth).
``regret``
    ``vfgym fit`` (:func:`vfgym.permove.fit_axis`, its defaults) on the identified axis
    and on the true axis, both judged on the true plant's 32 held-out test moves, for each
    of ``--regret-plants`` at each of ``--regret-gains``, the plant's Coulomb friction and
    load torque scaled down (ratio and sign kept) until their static error is 80 % of the
    in-position window (``--window-share``; beyond it no controller makes every move).
    Goal: the identified axis's fit feasible on every move and its mean cost at most 1.05×
    the true axis's.

``resonance``
    A compliant transmission's resonance, on ``belt-compliant.yaml``
    (``bench_identify_resonance.py``): within 5 % on ``--resonance-plants`` plants with
    resonances drawn in 20-200 Hz, each identification within 30 s.

It asserts nothing (the machine is shared).
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

from vfgym.axis import EXACT, PAPER_AXIS, Axis, PlantVariant, Uncertainty, load_axis
from vfgym.identify.capture import read_capture
from vfgym.identify.fit import PARAMS
from vfgym.identify.pipeline import identify_axis
from vfgym.identify.plan import make_plan
from vfgym.identify.simulated import record_capture, with_faults
from vfgym.identify.written import Identified
from vfgym.params import PAPER_SETTINGS

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_identify_resonance import part_resonance

ENABLE_TO_MOVES_S = 0.2
"""From the drive's enable to the first move (s), as the plan's procedure asks."""

AFTER_REST_S = 0.5
"""With ``--after-enable``: the rest after the enable in which the capture starts (s)."""

AFTER_MOVES_S = 0.1
"""The capture runs this long after the last pulse (s)."""

REPO = Path(__file__).resolve().parents[1]


@dataclass(frozen=True)
class Drawn:
    """One drawn true plant."""

    ratio: float
    truth: dict[str, float]
    variant: PlantVariant
    u: float


def draw(axis: Axis, seed: int, k: int) -> Drawn:
    """Plant ``k`` of the stream ``seed`` (see the module doc)."""
    m = axis.plant.motor
    rated = m.rated_torque_nm
    rng = np.random.default_rng([seed, k])
    ratio = rng.uniform(0.0, 15.0)
    truth = {
        "inertia": (1.0 + ratio) / (1.0 + m.inertia_ratio),
        "coulomb_nm": rng.uniform(0.0, 0.05) * rated,
        "viscous_nm_s_rad": rng.uniform(0.0, 3e-4),
        "load_torque_nm": rng.uniform(-0.05, 0.05) * rated,
        "torque_per_count": rng.uniform(0.9, 1.1),
    }
    return Drawn(ratio, truth, variant_of(axis, truth), float(rng.uniform(0.4, 0.9)))


def variant_of(axis: Axis, truth: dict[str, float]) -> PlantVariant:
    """The true plant of ``truth`` relative to the axis's modelled one."""
    m = axis.plant.motor
    return PlantVariant(
        inertia=truth["inertia"],
        coulomb_offset_nm=truth["coulomb_nm"] - m.coulomb_nm,
        viscous_offset_nm_s_rad=truth["viscous_nm_s_rad"] - m.viscous_nm_s_rad,
        load_offset_nm=truth["load_torque_nm"] - m.load_torque_nm,
        torque_per_count=truth["torque_per_count"],
    )


def capture(
    axis: Axis, drawn: Drawn, pulses: np.ndarray, path: Path, after_enable: bool = False
) -> Path:
    """The planned moves on a drawn plant, recorded as the procedure asks."""
    f = axis.plant.tick_hz
    if after_enable:
        start, rest = AFTER_REST_S * drawn.u, AFTER_REST_S
    else:
        start, rest = -0.1 * drawn.u - 0.01, ENABLE_TO_MOVES_S
    length = rest - start + pulses.size / f + AFTER_MOVES_S
    return record_capture(drawn.variant.apply(axis.plant), pulses, path, start_s=start,
                          rest_s=rest, length_s=length)  # fmt: skip


@dataclass(frozen=True)
class Outcome:
    """One identification: the identified axis (``None`` if refused), the refusal's line,
    the wall and CPU time (s)."""

    ident: Identified | None
    refused: str | None
    wall: float
    cpu: float

    @property
    def written(self) -> bool:
        return self.ident is not None and self.ident.explained

    def lines(self) -> str:
        """Every line the command prints that can name a cause."""
        text = [self.refused or ""]
        if self.ident is not None:
            text += [*self.ident.notes, *self.ident.kept, self.ident.cause or ""]
        return "\n".join(text)


def identify(
    axis: Axis, path: Path, after_enable: bool = False, gain_share: float | None = None
) -> Outcome:
    """Identify one capture as ``vfgym identify`` does (a ``ValueError`` is a refusal)."""
    t0, c0 = time.perf_counter(), time.process_time()
    try:
        ident, _, _ = identify_axis(
            axis,
            [read_capture(path)],
            PAPER_SETTINGS,
            from_enable=None if after_enable else True,
            gain_share=gain_share,
        )
        refused = None if ident.explained else f"not explained: {ident.cause}"
    except ValueError as exc:
        ident, refused = None, str(exc)
    return Outcome(ident, refused, time.perf_counter() - t0, time.process_time() - c0)


def outside(ident: Identified, truth: dict[str, float]) -> list[str]:
    """The quantities whose true value lies outside the written block."""
    unc = ident.axis.uncertainty
    out = []
    for name in PARAMS:
        value, span = truth[name], getattr(unc, name)
        if name in ("inertia", "torque_per_count"):
            value /= ident.fit.estimate(name).value  # the block's factors are on the estimates
        lo, hi = span if span is not None else (1.0, 1.0)
        if not lo - 1e-12 <= value <= hi + 1e-12:
            out.append(name)
    return out


def part_blocks(axis: Axis, args: argparse.Namespace) -> None:
    """Goal 1: every written block holds the true plant; saturating, J and gain within 2 %."""
    nominal = axis.plant
    rated = nominal.motor.rated_torque_nm
    top = nominal.pulse_top_speed_rad_s
    plan = make_plan(axis, PAPER_SETTINGS)
    print(
        f"\n== blocks: {args.plants} plants of seed {args.seed}, "
        f"{'after the enable' if args.after_enable else 'from before the enable'}; "
        f"plan {plan.duration_s:.3g} s"
    )
    print(
        "plant  ratio  gain   sat ms  sep  |dJ| %  |dgain| %  dCoul %r  dvisc %r  dload %r  "
        "rms    wall s  outside the block (outside the 95 % interval)"
    )
    rows, hits, total = [], dict.fromkeys(PARAMS, 0), dict.fromkeys(PARAMS, 0)
    with tempfile.TemporaryDirectory() as tmp:
        for k in range(args.plants):
            d = draw(axis, args.seed, k)
            o = identify(axis, capture(axis, d, plan.pulses, Path(tmp) / "c.vcd",
                                       args.after_enable), args.after_enable)  # fmt: skip
            t = d.truth
            if not o.written:
                rows.append({"written": False, "wall": o.wall, "cpu": o.cpu})
                print(f"{k:5d}  {d.ratio:5.2f}  {t['torque_per_count']:.3f}  refused: {o.refused}")
                continue
            assert o.ident is not None
            f = o.ident.fit
            g = f.estimate("torque_per_count")
            miss_ci = []
            for e in f.estimates:
                if e.excited:
                    total[e.name] += 1
                    if e.low <= t[e.name] <= e.high:
                        hits[e.name] += 1
                    else:
                        miss_ci.append(e.name)
            fit1 = o.ident.profile.fits[1] if o.ident.profile is not None else f
            row = {
                "written": True,
                "separated": g.excited,
                "dj": 100 * (f.estimate("inertia").value / t["inertia"] - 1),
                "dg": 100 * (g.value / t["torque_per_count"] - 1),
                "dc": 100 * (f.estimate("coulomb_nm").value - t["coulomb_nm"]) / rated,
                "dv": 100
                * (f.estimate("viscous_nm_s_rad").value - t["viscous_nm_s_rad"])
                * top
                / rated,
                "dl": 100 * (f.estimate("load_torque_nm").value - t["load_torque_nm"]) / rated,
                "rms": fit1.residual_rms_counts,
                "outside": outside(o.ident, t),
                "wall": o.wall,
                "cpu": o.cpu,
            }
            rows.append(row)
            print(
                f"{k:5d}  {d.ratio:5.2f}  {t['torque_per_count']:.3f}  "
                f"{fit1.saturated_s * 1e3:6.1f}  {'yes' if g.excited else 'no ':3s}  "
                f"{abs(row['dj']):6.3f}  "
                f"{abs(row['dg']) if g.excited else float('nan'):9.3f}  {row['dc']:+8.4f}  "
                f"{row['dv']:+8.4f}  {row['dl']:+8.4f}  {row['rms']:.3f}  {o.wall:6.1f}  "
                f"{' '.join(row['outside']) or '-'} ({' '.join(miss_ci) or '-'})",
                flush=True,
            )
    done = [r for r in rows if r["written"]]
    held = sum(not r["outside"] for r in done)
    sep = [r for r in done if r["separated"]]
    within = sum(abs(r["dj"]) <= 2 and abs(r["dg"]) <= 2 for r in sep)
    print(
        f"goal: every written block holds the true plant: {held}/{len(done)} "
        f"({len(rows) - len(done)} refused)"
    )
    print(
        f"goal: where the torque saturates (gain separated), inertia and gain within 2 %: "
        f"{within}/{len(sep)}"
        + (
            f" (max |dJ| {max(abs(r['dj']) for r in sep):.3f} %, max |dgain| "
            f"{max(abs(r['dg']) for r in sep):.3f} %)"
            if sep
            else ""
        )
    )
    h, n = sum(hits.values()), sum(total.values())
    per = ", ".join(f"{p} {hits[p]}/{total[p]}" for p in PARAMS if total[p])
    print(f"coverage of the printed 95 % intervals: {h}/{n} = {h / max(n, 1):.1%}: {per}")
    if done:
        print(
            f"max errors: |dJ| {max(abs(r['dj']) for r in done):.3f} %, Coulomb "
            f"{max(abs(r['dc']) for r in done):.4f} % of rated, load "
            f"{max(abs(r['dl']) for r in done):.4f} % of rated; residual max "
            f"{max(r['rms'] for r in done):.3f} counts RMS"
        )
    wall = np.array([r["wall"] for r in rows])
    cpu = np.array([r["cpu"] for r in rows])
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(
        f"time an identification: wall mean {wall.mean():.1f} s, max {wall.max():.1f} s; "
        f"CPU mean {cpu.mean():.1f} s, max {cpu.max():.1f} s; load average now {load:.1f}"
    )


FAULTS: dict[str, tuple[dict[str, Any], tuple[str, ...]]] = {
    "lost-1": ({"lost": 1}, ("lost", "reverses", "slips")),
    "lost-5": ({"lost": 5}, ("lost", "reverses", "slips")),
    "lost-20": ({"lost": 20}, ("lost", "reverses", "slips")),
    "glitch-1": ({"glitches": 1}, ("glitch", "differs from the plan", "slips")),
    "glitch-5": ({"glitches": 5}, ("glitch", "differs from the plan", "slips")),
    "glitch-20": ({"glitches": 20}, ("glitch", "differs from the plan", "slips")),
    "swapped": ({"swap": True}, ("swapped",)),
    "another-plan": ({}, ("not the plan",)),
    "cut-mid-line": ({"cut": True}, ("truncated",)),
    "cut-at-a-line": ({"cut": False}, ("first", "after its last pulse", "truncated")),
}
"""Each fault: how :func:`with_faults` makes it, and words of a line that names it."""


def part_faults(axis: Axis, args: argparse.Namespace) -> None:
    """Goal 3: no written axis whose block misses the truth without a line naming why."""
    plan = make_plan(axis, PAPER_SETTINGS)
    other = make_plan(load_axis(REPO / "experiments" / "axes" / "belt.yaml"), PAPER_SETTINGS)
    print(f"\n== faults: plants 0-{args.faults_plants - 1} of seed {args.seed}")
    tally = {"refused": 0, "held": 0, "missed-named": 0, "missed-unnamed": 0}
    with tempfile.TemporaryDirectory() as tmp:
        for k in range(args.faults_plants):
            d = draw(axis, args.seed, k)
            clean = capture(axis, d, plan.pulses, Path(tmp) / "clean.vcd")
            for n_fault, (name, (kw, words)) in enumerate(FAULTS.items()):
                rng = np.random.default_rng([args.seed, k, n_fault])
                path = Path(tmp) / f"{name}.vcd"
                if name == "another-plan":
                    capture(axis, d, other.pulses, path)
                elif "cut" in kw:
                    length = ENABLE_TO_MOVES_S + plan.duration_s
                    with_faults(clean, path, rng, cut_s=0.6 * length, mid_line=kw["cut"])
                else:
                    with_faults(clean, path, rng, **kw)
                o = identify(axis, path)
                named = any(w in o.lines() for w in words)
                if not o.written:
                    kind = "refused"
                    said = o.refused or ""
                else:
                    assert o.ident is not None
                    miss = outside(o.ident, d.truth)
                    kind = "held" if not miss else ("missed-named" if named else
                                                    "missed-unnamed")  # fmt: skip
                    said = "; ".join(n for n in o.ident.notes if any(w in n for w in words))
                    said = (f"outside: {' '.join(miss)}; " if miss else "") + (said or "-")
                tally[kind] += 1
                print(f"plant {k} ({d.ratio:5.2f}) {name:14s} {kind:14s} "
                      f"{'named' if named else 'unnamed'}: {said[:230]}", flush=True)  # fmt: skip
    n = sum(tally.values())
    print(
        f"goal: written axes whose block misses the truth without a line naming the cause: "
        f"{tally['missed-unnamed']}/{n} (refused {tally['refused']}, written and holding the "
        f"truth {tally['held']}, written, missing it, the cause named {tally['missed-named']})"
    )


def part_payload(axis: Axis, args: argparse.Namespace) -> None:
    """Goal 4: a nominal payload range survives identification (the written range holds it)."""
    plan = make_plan(axis, PAPER_SETTINGS)
    rated = axis.plant.motor.rated_torque_nm
    stated = Uncertainty(inertia=(0.95, 1.25), load_torque_nm=(-0.01 * rated, 0.01 * rated))
    with_prior = replace(stated, torque_per_count=(0.95, 1.05))
    cases = [
        ("payload inside, gain as set", stated, 1.10, 1.00, None),
        ("payload inside, gain x1.07", stated, 1.10, 1.07, None),
        ("payload just outside (1.30), gain x0.93", stated, 1.30, 0.93, None),
        ("payload just below (0.92), gain x1.1", stated, 0.92, 1.10, None),
        ("heavy payload (4.0), gain x1.07", stated, 4.0, 1.07, None),
        ("prior stated +-5 %, gain x1.03", with_prior, 1.10, 1.03, None),
        ("prior stated +-5 %, gain x1.08 (outside it)", with_prior, 1.10, 1.08, None),
        ("--gain-prior 0.2, gain x1.15", stated, 1.10, 1.15, 0.2),
    ]
    print("\n== payload: the nominal file states inertia [0.95, 1.25] and a load within 1 % "
          "of rated")  # fmt: skip
    ok = 0
    with tempfile.TemporaryDirectory() as tmp:
        for k, (label, unc, j, g, share) in enumerate(cases):
            nom = replace(axis, uncertainty=unc)
            rng = np.random.default_rng([args.seed, 1000 + k])
            truth = {
                "inertia": j,
                "coulomb_nm": rng.uniform(0.0, 0.02) * rated,
                "viscous_nm_s_rad": rng.uniform(0.0, 1e-4),
                "load_torque_nm": rng.uniform(-0.01, 0.01) * rated,
                "torque_per_count": g,
            }
            d = Drawn(j - 1.0, truth, variant_of(axis, truth), float(rng.uniform(0.4, 0.9)))
            o = identify(nom, capture(axis, d, plan.pulses, Path(tmp) / "p.vcd"),
                         gain_share=share)  # fmt: skip
            if not o.written:
                print(f"{label}: refused: {o.refused}")
                continue
            assert o.ident is not None
            w = o.ident.axis.uncertainty
            v = o.ident.fit.estimate("inertia").value
            j_abs = (w.inertia[0] * v, w.inertia[1] * v)
            keeps = j_abs[0] <= 0.95 + 1e-9 and j_abs[1] >= 1.25 - 1e-9
            keeps &= w.load_torque_nm[0] <= unc.load_torque_nm[0] + 1e-12
            keeps &= w.load_torque_nm[1] >= unc.load_torque_nm[1] - 1e-12
            miss = outside(o.ident, truth)
            ok += keeps
            print(
                f"{label}: written inertia [{j_abs[0]:.4g}, {j_abs[1]:.4g}] x nominal, load "
                f"[{w.load_torque_nm[0]:.4g}, {w.load_torque_nm[1]:.4g}] N*m, gain "
                f"{w.torque_per_count}: holds the stated ranges: {'yes' if keeps else 'NO'}; "
                f"the truth outside: {' '.join(miss) or '-'}"
            )
            for line in o.ident.kept:
                print(f"    kept: {line}")
    print(f"goal: a nominal payload range survives identification: {ok}/{len(cases)}")


WINDOW_SHARE = 0.8
"""``regret``: the static error's share of the in-position window (``--window-share``)."""


def within_window(axis: Axis, drawn: Drawn, gain: float, share: float = WINDOW_SHARE) -> Drawn:
    """The plant at ``gain``, its Coulomb friction and load torque scaled down until its
    static error (|load| + Coulomb)/K3 (K3 as in force) is ``share`` of the in-position
    window."""
    t = dict(drawn.truth, torque_per_count=gain)
    room = share * axis.measures.in_position_counts * axis.plant.torque_per_count_nm * gain
    f = min(1.0, room / max(abs(t["load_torque_nm"]) + t["coulomb_nm"], 1e-12))
    t["coulomb_nm"] *= f
    t["load_torque_nm"] *= f
    return replace(drawn, truth=t, variant=variant_of(axis, t))


FIT_SECONDS = "bench_fit_seconds.txt"
"""Where the regret part records how long a fit took, beside its settings model."""


def fitted(ax: Axis, run: Path) -> tuple[Any, float]:
    """``vfgym fit``'s settings model for ``ax`` in ``run`` and the fit's seconds; a model
    already there, learnt on the same plant, measures and uncertainty, is kept (the fit
    is deterministic)."""
    from vfgym.permove import FitConfig, fit_axis, load_tuner

    path = run / "settings_model.json"
    if path.is_file():
        said: list[str] = []
        tuner = load_tuner(path, axis=ax, warn=said.append)
        if not said:
            done = run / FIT_SECONDS
            return tuner, float(done.read_text()) if done.is_file() else float("nan")
    t0 = time.perf_counter()
    fit_axis(ax, run, FitConfig(), progress=False)
    seconds = time.perf_counter() - t0
    (run / FIT_SECONDS).write_text(f"{seconds:.1f}\n")
    return load_tuner(path, axis=ax, warn=lambda msg: None), seconds


def part_regret(axis: Axis, args: argparse.Namespace) -> None:
    """Goal 2: identify, fit on the written file, judged on the true plant."""
    import vfgym

    plan = make_plan(axis, PAPER_SETTINGS)
    plants = [int(x) for x in args.regret_plants.split(",")]
    gains = [float(x) for x in args.regret_gains.split(",")]
    base = Path(args.runs_dir) if args.runs_dir else Path(tempfile.mkdtemp(prefix="bench-id-"))
    print(f"\n== regret: vfgym fit on the identified and on the true axis; runs in {base}")
    print("plant  ratio  gain   sep  feasible id/true  mean cost id/true   ratio  fit s id/true")
    ratios, good, n = [], 0, 0
    for k in plants:
        for g in gains:
            d = within_window(axis, draw(axis, args.seed, k), g, args.window_share)
            tag = "" if args.window_share == WINDOW_SHARE else f"-window{args.window_share:g}"
            run = base / f"plant{k}-gain{g:g}{tag}"
            run.mkdir(parents=True, exist_ok=True)
            o = identify(axis, capture(axis, d, plan.pulses, run / "capture.vcd"))
            if not o.written:
                print(f"{k:5d}  {d.ratio:5.2f}  {g:.3f}  refused: {o.refused}")
                continue
            assert o.ident is not None
            true_axis = replace(axis, plant=d.variant.apply(axis.plant), uncertainty=EXACT,
                                name=f"true-{k}-{g:g}")  # fmt: skip
            out = {}
            for label, ax in (("true", true_axis), ("id", o.ident.axis)):
                (run / label).mkdir(exist_ok=True)
                tuner, seconds = fitted(ax, run / label)
                ev = vfgym.evaluate(tuner, "test", axis=true_axis)
                out[label] = (ev.feasible[0], float(ev.mean_cost[0]), seconds)
            (f_id, c_id, s_id), (f_tr, c_tr, s_tr) = out["id"], out["true"]
            n += 1
            good += bool(np.all(f_id)) and c_id <= 1.05 * c_tr
            ratios.append(c_id / c_tr)
            print(
                f"{k:5d}  {d.ratio:5.2f}  {g:.3f}  "
                f"{'yes' if o.ident.fit.estimate('torque_per_count').excited else 'no ':3s}  "
                f"{int(f_id.sum()):2d}/{f_id.size} {int(f_tr.sum()):2d}/{f_tr.size}        "
                f"{c_id:8.4g} / {c_tr:8.4g}  {c_id / c_tr:6.3f}  {s_id:.0f}/{s_tr:.0f}",
                flush=True,
            )
    if n:
        print(
            f"goal: the identified axis's fit feasible on every held-out move and at most "
            f"1.05x the true axis's mean cost: {good}/{n}; cost ratio mean "
            f"{np.mean(ratios):.4f}, max {np.max(ratios):.4f}"
        )


def part_resonance_(axis: Axis, args: argparse.Namespace) -> None:
    """A compliant transmission's resonance (``bench_identify_resonance.py``; its own axis)."""
    part_resonance(args)


PARTS = {"blocks": part_blocks, "faults": part_faults, "payload": part_payload,
         "regret": part_regret, "resonance": part_resonance_}  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n\n")[0])
    ap.add_argument("--part", default="blocks,faults,payload", help="comma-separated parts")
    ap.add_argument("--plants", type=int, default=20)
    ap.add_argument("--seed", type=int, default=20261205)
    ap.add_argument("--axis", help="the nominal axis file (default: the paper's axis)")
    ap.add_argument("--after-enable", action="store_true",
                    help="blocks: captures started with the axis already held")  # fmt: skip
    ap.add_argument("--faults-plants", type=int, default=4)
    ap.add_argument("--resonance-plants", type=int, default=10)
    ap.add_argument("--regret-plants", default="0,1")
    ap.add_argument("--regret-gains", default="0.9,1.07,1.1")
    ap.add_argument(
        "--window-share",
        type=float,
        default=WINDOW_SHARE,
        help="regret: the plants' static error as a share of the in-position window",
    )
    ap.add_argument(
        "--runs-dir",
        help="where the regret part's fits write (default: a temp folder); a settings model "
        "already there for the same axis is kept",
    )
    args = ap.parse_args(argv)
    axis = load_axis(args.axis) if args.axis else PAPER_AXIS
    parts = [p.strip() for p in args.part.split(",") if p.strip()]
    for p in parts:
        if p not in PARTS:
            ap.error(f"--part={p!r} is not a part: choose among {', '.join(PARTS)}")
    with tempfile.TemporaryDirectory() as tmp:  # compile the kernels outside the timings
        plan = make_plan(axis, PAPER_SETTINGS)
        warm = record_capture(axis.plant, plan.pulses[:20000], Path(tmp) / "w.vcd", start_s=0.05)
        identify(axis, warm)
    for p in parts:
        PARTS[p](axis, args)
    return 0


if __name__ == "__main__":
    sys.exit(main())
