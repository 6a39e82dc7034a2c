"""Figures of a sweep's study: optimisation history, Pareto front, parameter importances
(what ``vfgym sweep`` writes into its run folder and ``vfgym plot history|pareto`` draws).

Pure functions returning matplotlib :class:`~matplotlib.figure.Figure` objects (no
pyplot); Optuna is imported only when a figure is drawn.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np
from matplotlib.figure import Figure

from vfgym.report._style import COLORS

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from optuna import Study
    from optuna.trial import FrozenTrial


def _feasible(trial: FrozenTrial) -> bool:
    cons = getattr(trial, "constraints", None)
    if isinstance(cons, Mapping):
        vals = list(cons.values())
    elif cons is not None:
        vals = list(cons)
    else:
        vals = list(trial.system_attrs.get("constraints", []) or [])
    return all(float(c) <= 0.0 for c in vals)


def _complete(study: Study) -> list[FrozenTrial]:
    import optuna

    return [t for t in study.trials if t.state == optuna.trial.TrialState.COMPLETE]


def _attr_objectives(trial: FrozenTrial, names: Sequence[str]) -> list[float] | None:
    """A trial's objectives from its user attributes: one attribute per name, or
    ``objectives`` as a list in that order or a mapping by name (as vfgym sweeps store)."""
    ua = dict(trial.user_attrs)
    if isinstance(ua.get("result"), Mapping):  # a vfgym sweep's result, one attribute
        ua |= ua["result"]
    if all(n in ua for n in names):
        return [float(ua[n]) for n in names]
    obj = ua.get("objectives")
    if isinstance(obj, Mapping) and all(n in obj for n in names):
        return [float(obj[n]) for n in names]
    if isinstance(obj, (list, tuple)) and len(obj) == len(names):
        return [float(x) for x in obj]
    return None


def objective_points(
    study: Study, names: Sequence[str] | None = None
) -> tuple[list[str], np.ndarray, np.ndarray, np.ndarray]:
    """Objective values of a study's complete trials: (names, values (n, k), feasible (n,),
    trial numbers (n,)).

    A multi-objective study gives its values (named by ``study.metric_names``, else
    :data:`vfgym.scoring.OBJECTIVES` when there are three, else ``objective i``). A
    single-objective study (a cost sweep) gives the objectives its trials stored as user
    attributes, named ``names`` (default :data:`vfgym.scoring.OBJECTIVES`; see
    :func:`_attr_objectives`), if every complete trial has them.
    """
    from vfgym.scoring import OBJECTIVES

    trials = _complete(study)
    if not trials:
        raise ValueError(f"study {study.study_name!r} has no complete trials")
    if len(study.directions) > 1:
        k = len(study.directions)
        metric = getattr(study, "metric_names", None)
        labels = (
            list(metric)
            if metric
            else (
                list(OBJECTIVES) if k == len(OBJECTIVES) else [f"objective {i}" for i in range(k)]
            )
        )
        vals = np.array([t.values for t in trials], dtype=float)
    else:
        labels = list(names or OBJECTIVES)
        rows = [_attr_objectives(t, labels) for t in trials]
        if any(r is None for r in rows):
            raise ValueError(
                f"study {study.study_name!r} has one objective and its trials lack the "
                f"objectives {', '.join(labels)} among their user attributes: no Pareto "
                "front to draw"
            )
        vals = np.array(rows, dtype=float)
    feas = np.array([_feasible(t) for t in trials])
    nums = np.array([t.number for t in trials])
    return labels, vals, feas, nums


def pareto_mask(points: np.ndarray) -> np.ndarray:
    """Rows not dominated by any other row (all objectives minimised)."""
    p = np.asarray(points, dtype=float)
    keep = np.ones(len(p), dtype=bool)
    for i in range(len(p)):
        dominated = np.all(p <= p[i], axis=1) & np.any(p < p[i], axis=1)
        keep[i] = not dominated.any()
    return keep


def _auto_scale(setter: Callable[..., object], v: np.ndarray) -> None:
    """Log scale for positive values spanning more than 20×, symlog when they reach 0."""
    v = v[np.isfinite(v)]
    pos = v[v > 0]
    if not pos.size or v.min() < 0 or v.max() / pos.min() <= 20:
        return
    if v.min() > 0:
        setter("log")
    else:
        setter("symlog", linthresh=max(float(pos.min()), float(v.max()) * 1e-4))


def history_figure(study: Study, *, title: str = "") -> Figure:
    """Optimisation history: each complete trial's objective value(s) by trial number,
    feasible trials filled, infeasible hollow, and the best feasible value so far."""
    import optuna

    trials = _complete(study)
    if not trials:
        raise ValueError(f"study {study.study_name!r} has no complete trials")
    k = len(study.directions)
    if k > 1:
        labels, vals, feas, nums = objective_points(study)
    else:
        labels = list(getattr(study, "metric_names", None) or ["objective"])
        vals = np.array([[t.value] for t in trials], dtype=float)
        feas = np.array([_feasible(t) for t in trials])
        nums = np.array([t.number for t in trials])
    fig = Figure(figsize=(8.0, 2.2 + 2.0 * k), layout="constrained")
    axs = np.atleast_1d(fig.subplots(k, 1, sharex=True))
    for j, ax in enumerate(axs):
        y = vals[:, j]
        ax.plot(nums[feas], y[feas], "o", ms=3.5, color=COLORS[0], label="feasible trial")
        ax.plot(
            nums[~feas], y[~feas], "o", ms=3.5, mfc="none", color="gray", label="infeasible trial"
        )
        maximise = study.directions[j] == optuna.study.StudyDirection.MAXIMIZE
        yy = np.where(feas, y, -np.inf if maximise else np.inf)
        best = np.maximum.accumulate(yy) if maximise else np.minimum.accumulate(yy)
        ok = np.isfinite(best)
        if ok.any():
            ax.step(
                nums[ok],
                best[ok],
                where="post",
                color=COLORS[3],
                lw=1.5,
                label="best feasible so far",
            )
        _auto_scale(ax.set_yscale, y)
        ax.set_ylabel(labels[j])
        ax.legend(fontsize=8, loc="best")
    axs[-1].set_xlabel("trial")
    fig.suptitle(title or f"optimisation history: study {study.study_name}", fontsize=10)
    return fig


def pareto_figure(
    study: Study, *, x: str | None = None, y: str | None = None, title: str = ""
) -> Figure:
    """Trials in the plane of two objectives (default: the first two), the feasible
    Pareto front in that plane as a staircase, colour = a third objective if any."""
    labels, vals, feas, nums = objective_points(study)
    if len(labels) < 2:
        raise ValueError("a Pareto front needs at least two objectives")
    for name in (x, y):
        if name and name not in labels:
            raise ValueError(f"objective={name!r} is not known: choose one of {', '.join(labels)}")
    xi = labels.index(x) if x else 0
    yi = labels.index(y) if y else 1
    fig = Figure(figsize=(7.0, 5.5), layout="constrained")
    ax = fig.subplots()
    rest = [i for i in range(len(labels)) if i not in (xi, yi)]
    X, Y = vals[:, xi], vals[:, yi]
    third = vals[feas, rest[0]] if rest else np.zeros(0)
    if third.size and np.ptp(third) > 0:
        sc = ax.scatter(X[feas], Y[feas], c=third, s=18, cmap="viridis", label="feasible trial")
        fig.colorbar(sc, ax=ax, label=labels[rest[0]])
    elif third.size:
        ax.scatter(
            X[feas],
            Y[feas],
            s=18,
            color=COLORS[0],
            label=f"feasible trial ({labels[rest[0]]} = {third[0]:.3g})",
        )
    else:
        ax.scatter(X[feas], Y[feas], s=18, color=COLORS[0], label="feasible trial")
    ax.scatter(
        X[~feas], Y[~feas], s=14, facecolors="none", edgecolors="gray", label="infeasible trial"
    )
    if feas.any():
        pts = np.column_stack([X[feas], Y[feas]])
        front = pts[pareto_mask(pts)]
        front = front[np.argsort(front[:, 0])]
        ax.step(
            front[:, 0],
            front[:, 1],
            where="post",
            color=COLORS[3],
            lw=1.5,
            label=f"Pareto front ({len(front)} trials)",
        )
        ax.plot(front[:, 0], front[:, 1], "s", mfc="none", color=COLORS[3], ms=7)
    ax.set_xlabel(labels[xi])
    ax.set_ylabel(labels[yi])
    _auto_scale(ax.set_xscale, X)
    _auto_scale(ax.set_yscale, Y)
    ax.legend(fontsize=8, loc="best")
    ax.set_title(
        title or f"Pareto front: study {study.study_name} ({len(nums)} trials)", fontsize=10
    )
    return fig


def importances_figure(
    study: Study,
    *,
    target: Callable[[FrozenTrial], float] | None = None,
    target_name: str = "objective",
    title: str = "",
) -> Figure:
    """Each parameter's importance, by Optuna's default evaluator
    (:func:`optuna.importance.get_param_importances`), as horizontal bars, the most
    important on top.

    Parameters
    ----------
    study : optuna.Study
        At least two complete trials.
    target : callable, optional
        The value ranked (a multi-objective study needs one); default: the objective.
    target_name : str
        What ``target`` is, for the axis label.
    title : str
        The figure's title (default: the study's name and trial count).

    Returns
    -------
    matplotlib.figure.Figure
    """
    import optuna

    n = len(_complete(study))
    if n < 2:
        raise ValueError(f"study {study.study_name!r} has fewer than 2 complete trials")
    imp = optuna.importance.get_param_importances(study, target=target)
    if not imp:
        raise ValueError(f"study {study.study_name!r} has no parameters to rank")
    names, vals = list(imp)[::-1], list(imp.values())[::-1]
    fig = Figure(figsize=(8.0, 1.6 + 0.45 * len(names)), layout="constrained")
    ax: Axes = fig.subplots()
    bars = ax.barh(names, vals, color=COLORS[0])
    ax.bar_label(bars, labels=[f"{v:.2f}" for v in vals], padding=3, fontsize=8)
    ax.set_xlim(0.0, max(1.0, 1.15 * max(vals)))
    ax.set_xlabel(f"importance for {target_name}")
    ax.set_title(
        title or f"parameter importances: study {study.study_name} ({n} trials)", fontsize=10
    )
    return fig
