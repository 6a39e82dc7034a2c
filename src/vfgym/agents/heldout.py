"""The result a training run ends with: its agent on held-out moves (the test split, never
drawn in training nor in the choice of ``best_model.zip``) against the paper's settings
and the base it started from (its residual base, else the shipped per-move settings
model), through the one scoring path; on an axis also
the verdict ``vfgym fit`` gives its settings model (:func:`agent_verdict`)."""

from __future__ import annotations

from dataclasses import dataclass
from os import PathLike
from pathlib import Path
from typing import Any

import numpy as np

from vfgym.axis import Axis
from vfgym.params import Settings

from .loaded import agent_policy, env_options

HELDOUT_COUNT = 16
"""Held-out moves a run is judged on when its hyperparameters set no ``n_eval_scenarios``."""


@dataclass(frozen=True)
class HeldOutResult:
    """Mean costs on the held-out moves.

    Parameters
    ----------
    moves : int
        Held-out moves scored.
    agent_cost, paper_cost, model_cost : float
        Mean cost of the agent, of the paper's settings and of its base (its residual base,
        else the shipped per-move model).
    agent_feasible : int
        Moves on which the agent met every constraint.
    beats_paper, beats_model : int
        Moves on which the agent's cost is lower than the paper's / the model's.
    """

    moves: int
    agent_cost: float
    paper_cost: float
    model_cost: float
    agent_feasible: int
    beats_paper: int
    beats_model: int
    base: str = "shipped per-move model"

    def text(self) -> str:
        """One paragraph, as a training run prints it."""
        n = self.moves
        return (
            f"held-out ({n} test moves): agent mean cost {self.agent_cost:.4g} "
            f"(feasible {self.agent_feasible}/{n}); paper's settings {self.paper_cost:.4g} "
            f"(agent {self.agent_cost / self.paper_cost:.3f}x, lower on {self.beats_paper}/{n}); "
            f"{self.base} {self.model_cost:.4g} "
            f"(agent {self.agent_cost / self.model_cost:.3f}x, lower on {self.beats_model}/{n})"
        )

    def as_dict(self) -> dict[str, Any]:
        """The fields, as plain numbers (for ``heldout.yaml``)."""
        return {
            k: v if isinstance(v, str) else float(v) if isinstance(v, float) else int(v)
            for k, v in vars(self).items()
        }


def heldout_result(model_path: str | Path, params: dict[str, Any]) -> HeldOutResult:
    """Score a saved agent on the test split's first ``n_eval_scenarios`` moves (on its
    axis's test moves if it trained on one) against the paper's settings and the shipped
    per-move settings model.

    Parameters
    ----------
    model_path : str or Path
        The agent (``RUN/best_model.zip``).
    params : dict
        Its hyperparameters (``n_eval_scenarios``, ``env_kwargs.axis``).

    Returns
    -------
    HeldOutResult
        The mean costs and win counts.
    """
    from vfgym.permove import load_settings_model
    from vfgym.report import Candidate, compare

    n = int(params.get("n_eval_scenarios", HELDOUT_COUNT))
    kw = params.get("env_kwargs") or {}
    options = env_options(kw)  # the axis it trained on, resolved once (the envs' default)
    axis = options["axis"]
    scenarios = axis.scenario_set("test")[:n]
    if kw.get("residual"):  # the agent's own start: its residual base, as its env makes it
        label = f"its residual base ({kw.get('residual_base', 'paper')})"
        base = options["residual_base"]
        if isinstance(base, Settings):
            start = Candidate("model", base)
        else:  # a per-move base: (move, the base plant) -> settings
            start = Candidate("model", policy=lambda sc: base(sc, axis.plant))
    else:
        label, shipped = "shipped per-move model", load_settings_model()
        start = Candidate(
            "model", policy=lambda sc: shipped.settings(sc, axis.plant, axis.measures)
        )
    cands = [Candidate("agent", policy=agent_policy(model_path, axis)), start]
    rep = compare(cands, "paper", scenarios, resamples=1, axis=axis)
    agent, model, paper = (rep.column(c).cost for c in ("agent", "model", "paper"))
    feasible = np.all(rep.column("agent").constraints <= 0.0, axis=1)
    return HeldOutResult(
        moves=len(scenarios),
        agent_cost=float(agent.mean()),
        paper_cost=float(paper.mean()),
        model_cost=float(model.mean()),
        agent_feasible=int(feasible.sum()),
        beats_paper=int(np.sum(agent < paper)),
        beats_model=int(np.sum(agent < model)),
        base=label,
    )


def agent_verdict(
    model_path: str | Path, axis: Axis | str | PathLike[str], sweep_trials: int | None = None
) -> tuple[Any, Settings]:
    """A trained agent's verdict on its axis's test moves, as ``vfgym fit`` judges its
    settings model (:func:`vfgym.permove.fit.fit_axis`): against the best fixed setting a
    short sweep finds on the axis's train moves (:func:`vfgym.permove.fit.best_fixed`), the
    paper's settings and the S-curve source, through :func:`vfgym.report.compare` and
    :func:`vfgym.report.verdict`.

    Parameters
    ----------
    model_path : str or Path
        The agent (``RUN/best_model.zip``), trained on the axis.
    axis : Axis, str or os.PathLike
        The axis (or its file).
    sweep_trials : int or None
        Trials of the fixed-setting sweep (default
        :attr:`vfgym.permove.FitConfig.sweep_trials`).

    Returns
    -------
    tuple of (vfgym.report.Verdict, Settings)
        The verdict, and the best fixed setting it was judged against.
    """
    from vfgym.axis import VERDICT_PLANTS, as_axis
    from vfgym.permove import FitConfig, best_fixed
    from vfgym.report import Candidate, baseline_candidates, compare, verdict

    from .tuners import load_tuner

    axis = as_axis(axis)
    trials = FitConfig().sweep_trials if sweep_trials is None else sweep_trials
    train = axis.scenarios("train")
    fixed = best_fixed(train, axis, trials)
    test = axis.scenarios("test")
    report = compare(
        [Candidate("agent", policy=load_tuner(model_path, axis), source=str(model_path))],
        [
            Candidate("best-fixed", fixed, source="sweep", role="baseline"),
            *baseline_candidates(("paper", "scurve")),
        ],
        test,
        axis=axis,
        plants=VERDICT_PLANTS,  # the verdict across plants, in the same call
    )
    v = verdict(report, "agent", train, f"the {len(test)} test moves of axis {axis.name}")
    return v, fixed
