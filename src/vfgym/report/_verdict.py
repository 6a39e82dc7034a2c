"""The held-out verdict: a tuned setting against the baselines on moves it was not tuned on.

What a sweep's report ends with. On the test moves (an axis's test set; the default
random ``test`` set without one) the tuned setting is run beside the paper's settings,
the rule of thumb and the S-curve source through :func:`vfgym.report.compare`, and the
verdict reads the :class:`~vfgym.report.Report` it returns: per controller the feasible
count and the cost's median [IQR] and mean (:meth:`Report.spread`), and per baseline the
tuned setting's wins / losses / ties on cost and the bootstrap interval of the mean paired
difference (:meth:`Report.win_loss`). Nothing is computed here that the report does not
hold, so the verdict's numbers are those of ``vfgym evaluate`` on the same moves.

Where the axis states a transmission (a compliant load, docs/model.md §3.1), the verdict
also reads the load's measures: each controller's load move time and residual vibration
(in µm where the transmission states its travel, else in encoder counts), and on how many
moves the tuned setting's residual vibration is no larger than each baseline's.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from vfgym.axis import (
    VERDICT_PLANT_SEED,
    VERDICT_PLANTS,
    Axis,
)
from vfgym.moves.features import MoveSpan
from vfgym.moves.scenarios import Scenario
from vfgym.params import Settings
from vfgym.report._comparison import Candidate, Column, Report, baseline_candidates, compare
from vfgym.report._stats import Spread, WinLoss
from vfgym.report._tables import _grid
from vfgym.scoring import CONSTRAINTS, AcrossPlants

VERDICT_BASELINES = ("paper", "rule-of-thumb", "scurve")
"""What a tuned setting is judged against: the paper's settings, the rule of thumb (the
paper's method applied to each move's plant) and the MCX514 S-curve source at the limits."""


@dataclass(frozen=True)
class VerdictRow:
    """One controller in the verdict.

    Attributes
    ----------
    label : str
        The controller's label.
    feasible : int
        Test moves on which every constraint holds.
    applicable : int
        Test moves on which it has a cost (a pulse source cannot follow a moving
        reference).
    cost : Spread
        Its cost over the test moves (:meth:`Report.spread`).
    versus : WinLoss or None
        The tuned setting against it (:meth:`Report.win_loss`); ``None`` for the tuned
        setting's own row.
    load_move_time : Spread or None
        Its load move time (s) over the test moves, where the axis states a transmission.
    residual : Spread or None
        Its load's residual vibration, peak to peak after the motor is in position, in
        :attr:`Verdict.residual_unit`, where the axis states a transmission.
    residual_no_larger : tuple of int or None
        (moves on which the tuned setting's residual vibration is no larger than this
        baseline's, moves both ran); ``None`` for the tuned row and a rigid axis.
    """

    label: str
    feasible: int
    applicable: int
    cost: Spread
    versus: WinLoss | None
    load_move_time: Spread | None = None
    residual: Spread | None = None
    residual_no_larger: tuple[int, int] | None = None


@dataclass(frozen=True)
class Verdict:
    """A tuned setting against the baselines on the test moves.

    Attributes
    ----------
    report : Report
        The comparison every number is read from.
    tuned : str
        The tuned setting's label.
    rows : tuple of VerdictRow
        The tuned setting first, then each baseline.
    seen : tuple of str
        Test moves that are also among the moves tuned on (empty: truly held out).
    title : str
        Which moves these are, for the printed verdict (e.g. ``the 32 test moves of axis
        paper``).
    across : AcrossPlants or None
        Every row's controllers on true plants: drawn within the axis's uncertainty (from
        a recorded seed), or, where it states none, at ±5 % inertia (the sensitivity
        line); in the order of :attr:`rows`.
    outside : tuple of (str, str)
        Test moves outside the range of the moves tuned on (distance, speed, load:
        :class:`vfgym.moves.features.MoveSpan`), each with what lies outside; empty when
        every test move is inside, or nothing was tuned on.
    worst : tuple of (str, str)
        The tuned setting's infeasible test moves, the worst first, each with the limits
        it breaks there (e.g. ``acceleration 17.8x the limit``).
    residual_unit : str
        The unit of the rows' residual vibration, ``µm`` or ``counts``; empty where the
        axis states no transmission (no load measures).
    """

    report: Report
    tuned: str
    rows: tuple[VerdictRow, ...]
    seen: tuple[str, ...] = ()
    title: str = ""
    across: AcrossPlants | None = None
    outside: tuple[tuple[str, str], ...] = ()
    worst: tuple[tuple[str, str], ...] = ()
    residual_unit: str = ""

    def row(self, label: str) -> VerdictRow:
        """A controller's row by label.

        Parameters
        ----------
        label : str
            The controller's label.

        Returns
        -------
        VerdictRow
            Its row.

        Raises
        ------
        ValueError
            If no row has that label.
        """
        for r in self.rows:
            if r.label == label:
                return r
        raise ValueError(f"controller={label!r} is not in this verdict")

    def losing_to(self) -> tuple[VerdictRow, ...]:
        """The baselines the tuned setting loses to on most moves.

        Returns
        -------
        tuple of VerdictRow
            The baselines with more losses than half the moves both run (wins, losses
            and ties; a move a baseline cannot run is left out), in row order.
        """
        return tuple(
            r
            for r in self.rows
            if r.versus is not None
            and 2 * r.versus.losses > r.versus.wins + r.versus.losses + r.versus.ties
        )

    def to_dict(self) -> dict[str, Any]:
        """The verdict as plain data (for a run folder's ``summary.yaml``).

        Returns
        -------
        dict
            The test moves' names, the moves also tuned on, and per controller its
            feasible count, cost spread and (baselines) wins, losses, ties, n/a and the
            spread of the cost difference tuned − baseline.
        """

        def spread(s: Spread) -> dict[str, float | None]:
            return {k: (None if math.isnan(v) else v) for k, v in s.__dict__.items()}

        rows = []
        for r in self.rows:
            d: dict[str, Any] = {
                "controller": r.label,
                "feasible": r.feasible,
                "applicable": r.applicable,
                "cost": spread(r.cost),
            }
            if r.versus is not None:
                w = r.versus
                d |= {"wins": w.wins, "losses": w.losses, "ties": w.ties}
                d |= {"not_applicable": w.not_applicable, "cost_diff": spread(w.cost_diff)}
            if r.load_move_time is not None and r.residual is not None:
                d |= {"load_move_time_s": spread(r.load_move_time)}
                d |= {f"residual_vibration_{_UNIT_KEY[self.residual_unit]}": spread(r.residual)}
            if r.residual_no_larger is not None:
                d |= {"residual_no_larger": list(r.residual_no_larger)}
            rows.append(d)
        out: dict[str, Any] = {
            "tuned": self.tuned,
            "title": self.title,
            "moves": [s.name for s in self.report.scenarios],
            "seen_in_tuning": list(self.seen),
            "outside_tuning": {name: why for name, why in self.outside},
            "infeasible": {name: why for name, why in self.worst},
            "controllers": rows,
        }
        if self.across is not None:
            a = self.across
            out["plants"] = {
                "seed": a.seed,
                "plants": [p.label() for p in a.plants],
                "controllers": [
                    {"controller": r.label}
                    | {
                        k: (None if isinstance(v, float) and math.isnan(v) else v)
                        for k, v in a.summary(i).__dict__.items()
                    }
                    | {"feasible_per_plant": [int(x) for x in a.feasible[i].sum(axis=1)]}
                    for i, r in enumerate(self.rows)
                ],
            }
        return out


def verdict(
    report: Report,
    tuned: str | None = None,
    tuned_on: Sequence[Scenario] = (),
    title: str = "",
) -> Verdict:
    """The verdict read off a comparison.

    Parameters
    ----------
    report : Report
        What :func:`vfgym.report.compare` returned for the tuned setting and the baselines.
    tuned : str or None
        The tuned candidate's label (default: the report's first tuned one).
    tuned_on : sequence of Scenario
        The moves tuned on; the report's moves among them (the same move, whatever its
        name) are noted as not held out.
    title : str
        Which moves the report's are, for the printed verdict.

    Returns
    -------
    Verdict
        The tuned candidate's row, then one per baseline.

    Raises
    ------
    ValueError
        If the report has no tuned candidate or no baseline.
    """
    if not report.tuned or not report.baselines:
        raise ValueError("a verdict needs a tuned candidate and at least one baseline")
    tuned = tuned or report.tuned[0].label
    unit = _residual_unit(report)
    key = f"load_residual_vibration_{_UNIT_KEY[unit]}" if unit else ""
    rows = []
    for col in [report.column(tuned), *report.baselines]:
        f = col.feasible
        row = VerdictRow(
            label=col.label,
            feasible=int(np.nansum(f)),
            applicable=int(np.isfinite(f).sum()),
            cost=report.spread(col.label, "cost"),
            versus=None if col.label == tuned else report.win_loss(tuned, col.label),
        )
        if unit:
            mine, theirs = report.column(tuned).values(key), col.values(key)
            both = np.isfinite(mine) & np.isfinite(theirs)
            row = replace(
                row,
                load_move_time=report.spread(col.label, "load_move_time_s"),
                residual=report.spread(col.label, key),
                residual_no_larger=None
                if col.label == tuned
                else (int((mine[both] <= theirs[both]).sum()), int(both.sum())),
            )
        rows.append(row)
    known = {_content(sc) for sc in tuned_on}
    seen = tuple(sc.name for sc in report.scenarios if _content(sc) in known)
    across = report.across_of([r.label for r in rows])
    plant = report.axis.plant
    span = MoveSpan.of(tuned_on, plant) if tuned_on else None
    outside = tuple(
        (sc.name, "; ".join(o))
        for sc in report.scenarios
        if span is not None and (o := span.outside(sc, plant))
    )
    worst = _worst(report.column(tuned), report.scenarios)
    return Verdict(report, tuned, tuple(rows), seen, title, across, outside, worst, unit)


def _worst(col: Column, scenarios: Sequence[Scenario]) -> tuple[tuple[str, str], ...]:
    """A column's infeasible moves, the worst break first, each with its broken limits."""
    found = []
    for sc, cons, m in zip(scenarios, col.constraints, col.metrics, strict=True):
        if np.isnan(cons).all() or bool(np.all(cons <= 0.0)):
            continue
        phrases = [breaks_phrase(name, float(c), m) for name, c in zip(CONSTRAINTS, cons,
                   strict=True) if c > 0.0]  # fmt: skip
        found.append((float(np.nanmax(cons)), sc.name, ", ".join(phrases)))
    found.sort(key=lambda t: -t[0])
    return tuple((name, why) for _, name, why in found)


def breaks_phrase(name: str, value: float, m: dict[str, Any]) -> str:
    """A broken constraint in words, with the measure behind it.

    Parameters
    ----------
    name : str
        A constraint of :data:`vfgym.scoring.CONSTRAINTS`.
    value : float
        Its value (> 0: broken).
    m : dict
        The run's measures.

    Returns
    -------
    str
        E.g. ``acceleration 17.8x the limit``, ``overshoot 6410 counts``.
    """
    if name == "accel":
        return f"acceleration {m['accel_ratio_pulse']:.3g}x the limit"
    if name == "torque":
        return f"{1e3 * m['torque_limit_time_s']:.3g} ms at the torque limit"
    if name == "overshoot":
        return f"overshoot {m['overshoot_counts']:.0f} counts"
    return f"not arrived ({value:.3g} windows beyond the in-position window at the end)"


_UNIT_KEY = {"µm": "um", "counts": "counts", "": ""}
"""The residual vibration's measure name by unit (:mod:`vfgym.plant.measures`)."""


def _residual_unit(report: Report) -> str:
    """``µm`` where the report's moves ran on a transmission that states its travel,
    ``counts`` where it states none, empty on a rigid plant (no load measures)."""
    metrics = [m for c in report.columns for m in c.metrics if m]
    if not metrics or "load_residual_vibration_rad" not in metrics[0]:
        return ""
    return "counts" if math.isnan(metrics[0]["load_residual_vibration_um"]) else "µm"


def _content(sc: Scenario) -> Scenario:
    """The move without its name: two names for one move are the same move."""
    return replace(sc, name="move", description="")


def held_out_verdict(
    settings: Settings,
    scenarios: Sequence[Scenario],
    *,
    axis: Axis,
    baselines: str | Sequence[str] = VERDICT_BASELINES,
    label: str = "tuned",
    tuned_on: Sequence[Scenario] = (),
    title: str = "",
    across: bool = True,
    plants: int = VERDICT_PLANTS,
    plant_seed: int = VERDICT_PLANT_SEED,
) -> Verdict:
    """A tuned setting against the baselines on test moves (:func:`vfgym.report.compare`),
    on the modelled plant and across plants, in one call.

    Parameters
    ----------
    settings : Settings
        The tuned setting.
    scenarios : sequence of Scenario
        The test moves.
    axis : Axis
        The axis (its plant, measures and uncertainty).
    baselines : str or sequence of str
        Baseline names (default :data:`VERDICT_BASELINES`).
    label : str
        The tuned setting's label.
    tuned_on : sequence of Scenario
        The moves tuned on (to note any test move among them).
    title : str
        Which moves these are, for the printed verdict.
    across : bool
        Also judge every row across plants (:attr:`Verdict.across`): ``plants`` drawn
        within the axis's uncertainty from ``plant_seed``, or where it states none, the
        ±5 % inertia plants of the sensitivity line.
    plants, plant_seed : int, int
        How many held-out plants, drawn from which seed.

    Returns
    -------
    Verdict
        The verdict.
    """
    report = compare(
        [Candidate(label, settings, source="sweep")],
        baseline_candidates(baselines),
        list(scenarios),
        axis=axis,
        plants=plants if across else (),
        plant_seed=plant_seed,
    )
    return verdict(report, label, tuned_on, title)


def axis_verdict(
    settings: Settings,
    axis: Axis,
    tuned_on: Sequence[Scenario] = (),
    label: str = "tuned",
) -> Verdict:
    """A tuned setting against :data:`VERDICT_BASELINES` on an axis's test moves: the
    held-out verdict a sweep ends with.

    Parameters
    ----------
    settings : Settings
        The tuned setting.
    axis : Axis
        The axis tuned on (the paper's, :data:`vfgym.axis.PAPER_AXIS`, has for test moves
        the 32 draws ``test-0`` … ``test-31`` of the default random distribution).
    tuned_on : sequence of Scenario
        The moves tuned on (to note any test move among them).
    label : str
        The tuned setting's label.

    Returns
    -------
    Verdict
        The verdict on the axis's plant and measures, and across plants.
    """
    test = axis.scenarios("test")
    title = f"the {len(test)} test moves of axis {axis.name}"
    return held_out_verdict(settings, test, axis=axis, label=label, tuned_on=tuned_on,
                            title=title)  # fmt: skip


def _num(x: float) -> str:
    return "n/a" if not math.isfinite(x) else f"{x:.3g}"


def format_verdict(v: Verdict, axis_file: str | None = None, per_move: bool = False) -> str:
    """The verdict as text: one row per controller, then the tuned setting's summary.

    Parameters
    ----------
    v : Verdict
        The verdict.
    axis_file : str or None
        The axis file tuned on, for the pointer to per-move settings (default: ``FILE``).
    per_move : bool
        The tuned side is already per-move settings (``vfgym fit``'s model): the losing
        line then names the baseline without pointing to ``vfgym fit``.

    Returns
    -------
    str
        The table and a closing line (the tuned setting's win rate against each baseline
        and its feasible share); when it loses to a baseline on most moves
        (:meth:`Verdict.losing_to`), a last line says so, names the baseline and points to
        per-move settings (``vfgym fit --axis FILE``).
    """
    n = len(v.report.scenarios)
    held = "not tuned on" if not v.seen else f"{len(v.seen)} of them also tuned on"
    lines = [
        f"held-out verdict: {v.tuned} against the baselines on {v.title or f'{n} moves'} ({held})"
    ]
    rows = [
        [
            "controller",
            "feasible",
            "cost median [IQR]",
            "mean",
            f"{v.tuned}: wins/losses/ties",
            f"cost {v.tuned} − it: mean (95 % CI)",
        ]
    ]
    for r in v.rows:
        c = r.cost
        cells = [r.label, f"{r.feasible}/{r.applicable}"]
        cells += [f"{_num(c.median)} [{_num(c.q1)}, {_num(c.q3)}]", _num(c.mean)]
        if r.versus is None:
            cells += ["", ""]
        else:
            w, d = r.versus, r.versus.cost_diff
            na = f" ({w.not_applicable} n/a)" if w.not_applicable else ""
            cells += [f"{w.wins}/{w.losses}/{w.ties}{na}"]
            cells += [f"{_num(d.mean)} ({_num(d.ci_low)}, {_num(d.ci_high)})"]
        rows.append(cells)
    lines += _grid(rows, right={1, 3})
    me = v.rows[0]
    beats = ", ".join(
        f"{r.label} on {r.versus.wins}/{r.versus.wins + r.versus.losses + r.versus.ties}"
        f" ({100 * r.versus.win_rate:.0f} %)"
        for r in v.rows[1:]
        if r.versus is not None and not math.isnan(r.versus.win_rate)
    )
    lines.append(
        f"{v.tuned} beats {beats}; feasible on {me.feasible}/{me.applicable} "
        f"({100 * me.feasible / max(me.applicable, 1):.0f} %)"
    )
    lines.append(
        "cost: lower is better; a win is a lower cost on a move (tie: equal within 1e-9; "
        "n/a: the baseline cannot run it); CI: bootstrap of the mean paired difference "
        f"({v.report.resamples} resamples)"
    )
    if 2 * me.feasible < me.applicable:
        lines.append(
            f"{v.tuned} is infeasible on {me.applicable - me.feasible}/{me.applicable} of these "
            "moves: its wins are wins among runs that break a limit or do not arrive (see "
            "the axis file's notes)"
        )
    if v.residual_unit:
        lines += format_load(v)
    if v.across is not None:
        lines += format_across([r.label for r in v.rows], v.across)
    lines += _surprise_lines(v)
    losing = v.losing_to()
    if losing:
        lines.append(_losing_line(v, losing, axis_file, per_move))
    return "\n".join(lines)


def _surprise_lines(v: Verdict, most: int = 3) -> list[str]:
    """Where a verdict may surprise: the moves it breaks a limit on, and the test moves
    outside what was tuned on (at most ``most`` of each named)."""
    lines = []
    n = len(v.report.scenarios)
    if v.worst:
        named = "; ".join(f"{name}: {why}" for name, why in v.worst[:most])
        lines.append(
            f"warning: {v.tuned} breaks a limit on {len(v.worst)}/{n} test moves, worst {named}"
        )
    if v.outside:
        named = "; ".join(f"{name}: {why}" for name, why in v.outside[:most])
        more = f" and {len(v.outside) - most} more" if len(v.outside) > most else ""
        lines.append(
            f"warning: {len(v.outside)}/{n} test moves lie outside the moves tuned on, so "
            f"the tuned setting's result there is an extrapolation: {named}{more}"
        )
    return lines


def format_load(v: Verdict) -> list[str]:
    """Lines on the load of a compliant axis (:attr:`Verdict.residual_unit` set): per
    controller its load move time and residual vibration, and on how many moves the
    tuned setting's residual vibration is no larger than each baseline's.

    Parameters
    ----------
    v : Verdict
        The verdict.

    Returns
    -------
    list of str
        A title, the table and a closing line; empty for a rigid axis.
    """
    if not v.residual_unit:
        return []
    u = v.residual_unit
    rows = [
        [
            "controller",
            "load move time mean (ms)",
            f"residual vibration median [IQR] ({u})",
            "mean",
            f"{v.tuned}'s no larger on",
        ]
    ]
    for r in v.rows:
        t, x = r.load_move_time, r.residual
        assert t is not None and x is not None  # set on every row where a unit is
        le = r.residual_no_larger
        rows.append(
            [
                r.label,
                _num(1e3 * t.mean),
                f"{_num(x.median)} [{_num(x.q1)}, {_num(x.q3)}]",
                _num(x.mean),
                "" if le is None else f"{le[0]}/{le[1]}",
            ]
        )
    head = (
        "at the load (the axis states a transmission; the encoder reads the motor): move "
        "time to the load in position, residual vibration peak to peak after the motor is:"
    )
    return [head, *_grid(rows, right={1, 3, 4})]


def format_across(labels: Sequence[str], a: AcrossPlants) -> list[str]:
    """Lines across true plants (:attr:`Verdict.across`, ``vfgym evaluate --plants``).

    Parameters
    ----------
    labels : sequence of str
        The controllers' labels, in the order of ``a``'s first axis.
    a : AcrossPlants
        Their results on the true plants.

    Returns
    -------
    list of str
        Where the axis states uncertainty: a title naming the plants' count and seed,
        then per row the feasible (move, plant) pairs, the moves feasible on every plant
        and the mean cost over the pairs. Where it states none: the sensitivity line, each
        row's feasible moves at each inertia factor.
    """
    if a.seed is None:
        per = [f"×{p.inertia:g}" for p in a.plants]
        rows = [["controller", *(f"feasible at inertia {x}" for x in per)]]
        for i, label in enumerate(labels):
            n = int(np.isfinite(a.cost[i, 0]).sum())
            rows.append([label, *(f"{int(a.feasible[i, p].sum())}/{n}" for p in range(len(per)))])
        head = (
            "sensitivity (the axis states no uncertainty): the same moves with "
            + " and ".join(per)
            + " the modelled inertia, the drive's gain as set for the modelled plant:"
        )
        return [head, *_grid(rows, right=set(range(1, len(per) + 1)))]
    rows = [["controller", "feasible (move, plant)", "moves feasible on all", "mean cost"]]
    for i, label in enumerate(labels):
        s = a.summary(i)
        pct = 100 * s.feasible / max(s.pairs, 1)
        rows.append(
            [
                label,
                f"{s.feasible}/{s.pairs} ({pct:.1f} %)",
                f"{s.moves_feasible}/{s.moves}",
                _num(s.mean_cost),
            ]
        )
    head = (
        f"across {len(a.plants)} plants drawn within the axis's uncertainty "
        f"(plant seed {a.seed}), the drive's gain as set for the modelled plant:"
    )
    return [head, *_grid(rows, right={1, 2, 3})]


def _losing_line(
    v: Verdict, losing: Sequence[VerdictRow], axis_file: str | None, per_move: bool
) -> str:
    """The plain statement a verdict ends with when the tuned setting loses on most moves:
    the baselines it loses to (the most losses first), on how many moves."""

    def share(r: VerdictRow) -> float:
        w = r.versus
        assert w is not None  # losing_to keeps baselines only
        return w.losses / (w.wins + w.losses + w.ties)

    ranked = sorted(losing, key=share, reverse=True)
    parts = []
    for r in ranked:
        w = r.versus
        assert w is not None
        mean = " (though its mean cost is lower)" if w.cost_diff.mean < 0 else ""
        parts.append(f"{r.label} on {w.losses}/{w.wins + w.losses + w.ties}{mean}")
    head = f"{v.tuned} loses to {' and to '.join(parts)} of the held-out moves: "
    if per_move:
        return head + f"{ranked[0].label} does better on most of these moves than the fitted model"
    return head + (
        f"{ranked[0].label} does better on most of these moves than the one tuned setting; "
        f"for settings fitted per move, run vfgym fit --axis {axis_file or 'FILE'}"
    )
