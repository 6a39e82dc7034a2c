"""Figures of what the pulse train and the motor did: pure functions returning matplotlib
:class:`~matplotlib.figure.Figure` objects (no pyplot, no global state, headless).

Inputs are traces from :func:`vfgym.simulate` / ``vfgym.evaluate(..., keep_traces=True)``
and, for the numbers in titles and legends, the measures :func:`vfgym.evaluate` returned;
nothing here scores a move. Save a figure with ``fig.savefig("out.png")`` (Agg).

Derived signals (what the panels draw):

- pulse-train speed: (n_i − n_(i−w))·δ/(w·T), pulses counted over a window of w ticks,
  drawn at the window's centre;
- pulse-train acceleration: (x_i − 2·x_(i−w) + x_(i−2w))·δ/(w·T)² of the train's position x
  (``Trace.train_rad``), the signed version of :mod:`vfgym.plant.measures`' peak_accel_pulse
  (same window by default, so the drawn peak is the measured one), drawn at the centre i − w;
- pulse frequency: pulses of either sign per window, over the window (Hz);
- motor acceleration: the mean over each drawn interval, Δω/Δt from the trace's speed.

The train is at rest before tick 0 (n = 0), as in the measures.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from matplotlib.figure import Figure
from matplotlib.ticker import NullLocator

from vfgym.moves.baselines import usable_accel
from vfgym.params import PAPER_PLANT, Plant, in_position_rad
from vfgym.report._style import COLORS
from vfgym.report._sweep_figures import (
    history_figure,
    importances_figure,
    objective_points,
    pareto_figure,
    pareto_mask,
)

if TYPE_CHECKING:
    from matplotlib.axes import Axes

    from vfgym.plant import Trace

MAX_POINTS = 4000
"""Points drawn per curve at most (longer curves are thinned by a stride)."""


# --- derived signals --------------------------------------------------------------------


def _window_samples(trace: Trace, window_s: float) -> int:
    """The window in trace samples (at least one): w ticks rounded to the decimation."""
    w_ticks = max(1, round(window_s * trace.plant.tick_hz))
    return max(1, round(w_ticks / trace.decimation))


def _padded_counts(trace: Trace, pad: int) -> np.ndarray:
    return np.concatenate([np.zeros(pad, dtype=np.int64), trace.pulse_count])


def _accel_window_samples(trace: Trace, window_s: float | None) -> int:
    """``window_s`` in trace samples; None: the window w the run's measure used."""
    return _window_samples(trace, trace.metrics["accel_window_s"] if window_s is None else window_s)


def pulse_speed(trace: Trace, window_s: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Pulse-train speed (rad/s) over a window (default: the acceleration measure's w), at
    the window's centre time (s)."""
    ws = _accel_window_samples(trace, window_s)
    dt = trace.decimation * trace.plant.tick_s
    n = _padded_counts(trace, ws)
    v = (n[ws:] - n[:-ws]) * trace.plant.pulse_rad / (ws * dt)
    return trace.time_s - 0.5 * ws * dt, v


def pulse_accel(trace: Trace, window_s: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Pulse-train acceleration (rad/s²): the windowed second difference of the train's
    position ``train_rad`` (docs/model.md §5.1) at the centre time.

    With the default window (the one the run's measure used, ``accel_window_s``,
    :func:`vfgym.plant.measures.accel_window_ticks`) and an undecimated trace, max |a|
    equals the measure ``peak_accel_pulse_rad_s2``.
    """
    ws = _accel_window_samples(trace, window_s)
    dt = trace.decimation * trace.plant.tick_s
    x = np.concatenate([np.zeros(2 * ws), trace.train_rad])
    d2 = x[2 * ws :] - 2.0 * x[ws:-ws] + x[: -2 * ws]
    return trace.time_s - ws * dt, d2 / (ws * dt) ** 2


def pulse_frequency(trace: Trace, window_s: float = 0.5e-3) -> tuple[np.ndarray, np.ndarray]:
    """Pulse frequency (Hz, pulses of either sign) over a window, at its centre time (s).

    Undecimated traces count every pulse; a decimated one counts |Δn| per window (a
    reversal inside the window then nets out)."""
    ws = _window_samples(trace, window_s)
    dt = trace.decimation * trace.plant.tick_s
    if trace.decimation == 1:
        c = np.cumsum(np.abs(trace.pulses.astype(np.int64)))
        c = np.concatenate([np.zeros(ws, dtype=np.int64), c])
        k = c[ws:] - c[:-ws]
    else:
        n = _padded_counts(trace, ws)
        k = np.abs(n[ws:] - n[:-ws])
    return trace.time_s - 0.5 * ws * dt, k / (ws * dt)


def motor_accel(trace: Trace, stride: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """Motor acceleration (rad/s²): Δω/Δt over every ``stride`` samples (the exact mean
    acceleration over each interval), at the interval's centre; ω = 0 before tick 0."""
    stride = max(1, int(stride))
    dt = trace.decimation * trace.plant.tick_s
    w = np.concatenate([[0.0], trace.speed_rad_s])[::stride]
    t = np.concatenate([[0.0], trace.time_s])[::stride]
    return 0.5 * (t[1:] + t[:-1]), np.diff(w) / (stride * dt)


def _stride(n: int, max_points: int) -> int:
    return max(1, math.ceil(n / max(1, max_points)))


def _thin(t: np.ndarray, y: np.ndarray, max_points: int) -> tuple[np.ndarray, np.ndarray]:
    s = _stride(t.size, max_points)
    return t[::s], y[::s]


def _fmt_metrics(m: Mapping[str, Any] | None, tracking: bool) -> str:
    if not m:
        return ""
    if tracking:
        return f"tracking rms {m['tracking_rms_rad']:.3g} rad"
    return (
        f"overshoot {m['overshoot_counts']:.3g} counts, move {1e3 * m['move_time_s']:.1f} ms, "
        f"peak acc {m['accel_ratio_pulse']:.2f}× (pulses) / {m['accel_ratio_motor']:.2f}× "
        f"(motor) of the limit"
    )


def _symlog(ax: Axes, lin: float, data: Sequence[np.ndarray]) -> None:
    """Symmetric log y axis, linear inside ±lin (the in-position window), ticked at 0 and
    at the decades beyond the window (matplotlib's own ticks crowd the linear part)."""
    lin = max(float(lin), 1e-12)
    ax.set_yscale("symlog", linthresh=lin, linscale=1.0)
    top = max([float(np.nanmax(np.abs(d))) for d in data if d.size] + [lin])
    ticks = [0.0]
    for k in range(math.ceil(math.log10(lin * 1.5)), math.ceil(math.log10(top)) + 1):
        ticks += [10.0**k, -(10.0**k)]
    ticks.sort()
    ax.set_yticks(ticks, [f"{v:g}" for v in ticks])
    ax.yaxis.set_minor_locator(NullLocator())


def _limit_lines(ax: Axes, plant: Plant, scale: float) -> None:
    lim = plant.motor.accel_limit_rad_s2
    for sgn in (1, -1):
        ax.axhline(
            sgn * lim * scale,
            color="red",
            ls="--",
            lw=1,
            label=f"motor limit ±{lim / 1e3:.0f} krad/s²" if sgn > 0 else None,
        )
    ua = usable_accel(plant)
    if ua < lim * 0.999:
        for sgn in (1, -1):
            ax.axhline(
                sgn * ua * scale,
                color="red",
                ls=":",
                lw=1,
                label=f"peak torque / J = {ua / 1e3:.0f} krad/s²" if sgn > 0 else None,
            )


# --- the paper's Fig. 4 / Fig. 5 ---------------------------------------------------------


def response_figure(
    trace: Trace,
    *,
    title: str = "",
    metrics: Mapping[str, Any] | None = None,
    tracking: bool = False,
    max_points: int = MAX_POINTS,
) -> Figure:
    """Command, pulse train and motor on one move (the paper's Fig. 4 step / Fig. 5 sine):
    position; error against the command (symlog, linear inside the in-position window);
    speed; acceleration with the motor's limit."""
    plant = trace.plant
    ms = 1e3
    fig = Figure(figsize=(8.0, 9.0), layout="constrained")
    axs = fig.subplots(4, 1, sharex=True)
    t = trace.time_s
    tt, P = _thin(t, trace.command_rad, max_points)
    _, npos = _thin(t, trace.pulse_rad, max_points)
    _, th = _thin(t, trace.motor_rad, max_points)
    ax = axs[0]
    ax.plot(tt * ms, P, color="black", ls="--", lw=1.2, label="command P")
    ax.plot(tt * ms, npos, color=COLORS[0], lw=1.2, label="pulse train n·δ")
    ax.plot(tt * ms, th, color=COLORS[1], lw=1.2, label="motor θ")
    ax.set_ylabel("position [rad]")
    ax.legend(loc="best", fontsize=8)

    ax = axs[1]
    win = in_position_rad(trace.measures, plant, trace.target_rad)
    ax.plot(tt * ms, npos - P, color=COLORS[0], lw=1.0, label="n·δ − P")
    ax.plot(tt * ms, th - P, color=COLORS[1], lw=1.0, label="θ − P")
    if tracking:
        ax.axhline(0.0, color="gray", lw=0.6)
    else:
        _symlog(ax, win, [npos - P, th - P])
        ax.axhspan(-win, win, color="green", alpha=0.12, label=f"in-position ±{win:.2g} rad")
    ax.set_ylabel("error [rad]")
    ax.legend(loc="best", fontsize=8)

    ax = axs[2]
    ts, vs = _thin(*pulse_speed(trace), max_points)
    w_ms = trace.metrics["accel_window_s"] * 1e3
    ax.plot(ts * ms, vs, color=COLORS[0], lw=1.0, label=f"pulse train ({w_ms:.3g} ms window)")
    tw, w = _thin(t, trace.speed_rad_s, max_points)
    ax.plot(tw * ms, w, color=COLORS[1], lw=1.0, label="motor ω")
    vmax = plant.pulse_top_speed_rad_s
    ax.axhline(vmax, color="gray", ls=":", lw=1, label=f"δ·f = {vmax:.0f} rad/s")
    if np.min(trace.speed_rad_s) < -0.05 * vmax:
        ax.axhline(-vmax, color="gray", ls=":", lw=1)
    ax.set_ylabel("speed [rad/s]")
    ax.legend(loc="best", fontsize=8)

    ax = axs[3]
    k = 1e-3
    ta, a = _thin(*pulse_accel(trace), max_points)
    ax.plot(
        ta * ms, a * k, color=COLORS[0], lw=1.0, label=f"pulse train (2nd diff., {w_ms:.3g} ms)"
    )
    tm, am = motor_accel(trace, _stride(t.size, max_points))
    ax.plot(tm * ms, am * k, color=COLORS[1], lw=1.0, label="motor dω/dt")
    _limit_lines(ax, plant, k)
    ax.set_ylabel("acceleration [krad/s²]")
    ax.set_xlabel("time [ms]")
    ax.legend(loc="best", fontsize=8)
    ax.set_xlim(0, t[-1] * ms)
    sub = _fmt_metrics(metrics, tracking)
    fig.suptitle(title + ("\n" + sub if sub else ""), fontsize=10)
    return fig


# --- S-curve fixed-pulse driving (MCX514 manual Fig. 2.2-9) -------------------------------


def scurve_figure(
    plant: Plant = PAPER_PLANT,
    *,
    short_rad: float = 1.0,
    long_rad: float = 10.0,
    speed_rad_s: float | None = None,
    accel_rad_s2: float | None = None,
    window_s: float = 0.5e-3,
) -> Figure:
    """S-curve speed and acceleration of a short move with and without triangle form
    prevention (rule of 1/12), and of a long move that reaches the drive speed.

    Smooth lines are the exact profile (:func:`vfgym.moves.pulse_sources.scurve_profile`); thin
    lines are the pulse train (:func:`~vfgym.moves.pulse_sources.scurve_pulses`) over a window.
    Default drive: the :func:`vfgym.moves.baselines.scurve` baseline for ``plant``.
    """
    from vfgym.moves.baselines import scurve as scurve_baseline
    from vfgym.moves.profiles import scurve_source_args
    from vfgym.moves.pulse_sources import scurve_profile, scurve_pulses

    base = scurve_baseline(plant)
    v = base.speed_rad_s if speed_rad_s is None else speed_rad_s
    acc = base.accel_rad_s2 if accel_rad_s2 is None else accel_rad_s2
    args = scurve_source_args(v, acc, plant.tick_hz, plant.pulse_rad)
    d = plant.pulse_rad
    ms = 1e3
    fig = Figure(figsize=(10.0, 6.5), layout="constrained")
    axs = fig.subplots(2, 2, sharex="col")
    cases = [
        (0, short_rad, True, COLORS[0], "triangle prevention on (rule of 1/12)"),
        (0, short_rad, False, COLORS[3], "prevention off (triangle)"),
        (1, long_rad, True, COLORS[0], "reaches drive speed"),
    ]
    w = max(1, round(window_s * plant.tick_hz))
    for col, dist, prevent, color, label in cases:
        pulses = round(abs(dist) / d)
        prof = scurve_profile(pulses, **args, triangle_prevention=prevent)
        t = np.linspace(0.0, prof.t_end * 1.05, 1500)
        ax_v, ax_a = axs[0, col], axs[1, col]
        ax_v.plot(t * ms, prof.speed(t) * d, color=color, lw=1.6, label=label)
        ax_a.plot(t * ms, prof.acceleration(t) * d / 1e3, color=color, lw=1.6, label=label)
        train = scurve_pulses(pulses, **args, triangle_prevention=prevent)
        c = np.concatenate([np.zeros(w, np.int64), np.cumsum(train, dtype=np.int64)])
        tw = (np.arange(train.size) + 1 - 0.5 * w) / plant.tick_hz
        vw = (c[w:] - c[:-w]) * plant.tick_hz / w * d
        s = _stride(tw.size, MAX_POINTS)
        ax_v.plot(tw[::s] * ms, vw[::s], color=color, lw=0.7, alpha=0.5)
        if prevent and not prof.reached_drive_speed:
            ti = prof.t_acc_increase
            ax_v.plot(
                [ti * ms],
                [float(prof.speed(ti)) * d],
                "o",
                color=color,
                ms=5,
                label=f"P/12 pulses out: acceleration turns down ({ti * ms:.2f} ms)",
            )
        ax_v.set_title(
            f"{'short' if col == 0 else 'long'} move: {dist:g} rad = {pulses} pulses", fontsize=10
        )
    for col in (0, 1):
        axs[0, col].axhline(
            args["drive_speed_pps"] * d,
            color="gray",
            ls=":",
            lw=1,
            label=f"drive speed DV = {args['drive_speed_pps'] * d:.0f} rad/s",
        )
        axs[0, col].set_ylabel("speed [rad/s]")
        axs[0, col].legend(fontsize=8, loc="upper left" if col == 0 else "center")
        axs[1, col].axhline(
            acc / 1e3,
            color="red",
            ls="--",
            lw=1,
            label=f"peak acceleration set {acc / 1e3:.0f} krad/s²",
        )
        axs[1, col].axhline(-acc / 1e3, color="red", ls="--", lw=1)
        axs[1, col].set_ylabel("acceleration [krad/s²]")
        axs[1, col].set_xlabel("time [ms]")
        axs[1, col].legend(fontsize=8, loc="lower left")
    fig.suptitle(
        "S-curve fixed-pulse driving (MCX514): SV = "
        f"{args['initial_speed_pps'] * d:.1f} rad/s, DV = {args['drive_speed_pps'] * d:.0f} "
        f"rad/s, jerk = {args['jerk_pps3'] * d:.3g} rad/s³\nsmooth: exact profile; thin: "
        f"the pulse train's speed over {window_s * 1e3:g} ms",
        fontsize=10,
    )
    return fig


# --- pulse frequency, overlays -------------------------------------------------------------


def frequency_figure(
    traces: Mapping[str, Trace],
    *,
    window_s: float = 0.5e-3,
    title: str = "",
    max_points: int = MAX_POINTS,
) -> Figure:
    """Pulse frequency against time for each labelled trace (e.g. the V-F controller and
    the fixed-frequency baseline), with the top rate f (one pulse a tick)."""
    fig = Figure(figsize=(8.0, 4.0), layout="constrained")
    ax = fig.subplots()
    f_top = None
    for i, (label, tr) in enumerate(traces.items()):
        t, f = _thin(*pulse_frequency(tr, window_s), max_points)
        ax.plot(t * 1e3, f / 1e3, color=COLORS[i % len(COLORS)], lw=1.2, label=label)
        f_top = tr.plant.tick_hz
    if f_top:
        ax.axhline(
            f_top / 1e3,
            color="gray",
            ls=":",
            lw=1,
            label=f"f = {f_top / 1e3:.0f} kHz (one pulse a tick)",
        )
    ax.set_xlabel("time [ms]")
    ax.set_ylabel(f"pulse frequency [kHz] ({window_s * 1e3:g} ms window)")
    ax.set_ylim(bottom=0)
    ax.legend(fontsize=8, loc="best")
    ax.set_title(title, fontsize=10)
    return fig


def compare_figure(
    traces: Mapping[str, Trace],
    *,
    title: str = "",
    tracking: bool = False,
    max_points: int = MAX_POINTS,
) -> Figure:
    """Several controllers on the same move, overlaid: motor error against the command
    (symlog, in-position window shaded), motor speed, motor acceleration with the limit,
    and torque with the peak torque."""
    fig = Figure(figsize=(8.0, 8.5), layout="constrained")
    axs = fig.subplots(4, 1, sharex=True)
    ms = 1e3
    first = next(iter(traces.values()))
    plant = first.plant
    win = in_position_rad(first.measures, plant, first.target_rad)
    for i, (label, tr) in enumerate(traces.items()):
        c = COLORS[i % len(COLORS)]
        t, e = _thin(tr.time_s, tr.motor_rad - tr.command_rad, max_points)
        axs[0].plot(t * ms, e, color=c, lw=1.0, label=label)
        t, w = _thin(tr.time_s, tr.speed_rad_s, max_points)
        axs[1].plot(t * ms, w, color=c, lw=1.0, label=label)
        t, a = motor_accel(tr, _stride(tr.time_s.size, max_points))
        axs[2].plot(t * ms, a / 1e3, color=c, lw=1.0, label=label)
        t, q = _thin(tr.time_s, tr.torque_nm, max_points)
        axs[3].plot(t * ms, q, color=c, lw=1.0, label=label)
    if tracking:
        axs[0].axhline(0.0, color="gray", lw=0.6)
    else:
        _symlog(axs[0], win, [tr.motor_rad - tr.command_rad for tr in traces.values()])
        axs[0].axhspan(-win, win, color="green", alpha=0.12, label=f"in-position ±{win:.2g} rad")
    axs[0].set_ylabel("motor θ − P [rad]")
    axs[1].set_ylabel("motor speed [rad/s]")
    _limit_lines(axs[2], plant, 1e-3)
    axs[2].set_ylabel("motor accel. [krad/s²]")
    pk = plant.motor.peak_torque_nm
    axs[3].axhline(pk, color="red", ls="--", lw=1, label=f"peak torque ±{pk:g} N·m")
    axs[3].axhline(-pk, color="red", ls="--", lw=1)
    axs[3].set_ylabel("torque [N·m]")
    axs[3].set_xlabel("time [ms]")
    axs[3].set_xlim(0, first.time_s[-1] * ms)
    for ax in axs:
        ax.legend(fontsize=7, loc="best")
    fig.suptitle(title, fontsize=10)
    return fig


__all__ = [
    "MAX_POINTS",
    "compare_figure",
    "frequency_figure",
    "history_figure",
    "importances_figure",
    "motor_accel",
    "objective_points",
    "pareto_figure",
    "pareto_mask",
    "pulse_accel",
    "pulse_frequency",
    "pulse_speed",
    "response_figure",
    "scurve_figure",
]
