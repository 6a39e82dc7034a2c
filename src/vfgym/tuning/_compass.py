"""The default sampler: a compass search in coordinates that fit the problem, from the warm
starts, with Gaussian-process checks for a better basin; one generation at a time.

The sweep's optimum sits on constraint edges (the acceleration limit, L = value), where a
model of the cost is poor and a compass (pattern) search is good; but the cost has several
basins, and a compass stays in the first it finds. So the search alternates:

1. ``init``: the warm starts (enqueued by the study) and ``n_init`` Latin-hypercube points.
2. ``compass``: from the best point (feasible first, then by cost; an infeasible one by
   its total violation), poll each axis of :class:`vfgym.space.Relative` both ways and a
   fifth direction, value and L/value moved together (L/value² held: the tail's
   deceleration at top speed, which the acceleration limit bounds, so on a loaded axis the
   feasible edge runs along it), plus the last move again if the last generation moved;
   move to the best poll that beats the centre; per direction widen the step ×1.5 where a
   poll beat the centre, else halve it.
3. ``model``: once the compass has spent ``compass_trials`` trials without moving, or its
   steps are below ``min_step``, ``model_batch`` points over the whole space maximising
   the expected improvement (by at least ``xi``) times the probability of feasibility
   (:mod:`vfgym.tuning._model`); until a feasible point beats the centre, where the
   compass starts again. Between batches a compass cut short with a step still at or above
   ``resume_floor`` goes on; a batch's best point of another basin within ``explore_gap``
   of the centre's cost gets a compass of its own.

Every choice is a deterministic function of the seed and the study's completed trials,
and each drawn trial records its generation (system attribute ``vfgym:compass``), so a
study resumed in a new process, or shared by several workers, continues the same search;
a worker that asks while another's generation runs gets model points that take the
running trials into account. What was tried and not kept: docs/design/sampler.md.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import optuna

from vfgym import space
from vfgym.scoring import CONSTRAINTS
from vfgym.tuning._model import Observation, propose, rank

ATTR = "vfgym:compass"
"""System attribute of each trial the sampler draws: its generation's state and role."""


@dataclass(frozen=True)
class CompassOptions:
    """Settings of :class:`CompassSampler`, as it runs by default (the module docstring
    says where each acts; step sizes in natural-log units)."""

    n_init: int = 6  # Latin-hypercube points of the first generation
    step0: float = 0.4  # the first compass step along each direction
    min_step: float = 0.1
    compass_trials: int = 50
    model_batch: int = 8
    xi: float = 0.03
    extra_batch: int = 4  # model points for a worker asking while a generation runs
    explore_gap: float = 0.1
    refit_growth: float = 1.25  # hyperparameters fitted again once the trials grow this much
    resume_floor: float = 0.025


class CompassSampler(optuna.samplers.BaseSampler):
    """An Optuna sampler running the search above, in the coordinates ``relative`` (with
    the law one more coordinate if several ``laws`` are searched), seeded by ``seed``.
    ``storage`` is the storage of the studies it samples, where each trial it draws gets
    its generation."""

    def __init__(
        self,
        relative: space.Relative,
        laws: tuple[str, ...] = ("rise",),
        seed: int | None = None,
        options: CompassOptions | None = None,
        storage: Any = None,
    ) -> None:
        self.relative = relative
        self.storage = storage
        self._study_ids: dict[str, int] = {}
        self.laws = tuple(laws)
        self.seed = 0 if seed is None else int(seed)
        self.options = options or CompassOptions()
        b = relative.bounds()
        self._lo, self._span = b[:, 0], b[:, 1] - b[:, 0]
        self._queue: list[dict[str, Any]] = []
        self._checked = -1  # the number of the next trial, when the queue was last checked
        self._seen: dict[int, Observation | None] = {}  # completed trials, by number
        self._seen_in: tuple[int, str] | None = None  # the study they are of
        # The last model batch's hyperparameters, and the trials they were fitted on.
        self._starts: tuple[dict[str, list[float]], int] = ({}, 0)
        # Poll directions: the four axes, and value and L/value moved together (L/value²
        # held: the tail's deceleration at top speed, δ²f²·L/value²).
        self._dirs = np.vstack([np.eye(4), [1.0, 1.0, 0.0, 0.0]])

    # --- Optuna's sampler interface -----------------------------------------------------
    def infer_relative_search_space(self, study: Any, trial: Any) -> dict[str, Any]:
        return space.distributions(self.laws)

    def sample_relative(self, study: Any, trial: Any, search_space: dict[str, Any]) -> dict:
        if not search_space or "fixed_params" in trial.system_attrs or trial.params:
            return {}  # an enqueued trial (a warm start, a retry) keeps its settings
        item = self._next(study, trial.number)
        self._record(study, trial.number, item["tag"])
        return self._params(item)

    def _record(self, study: Any, number: int, tag: dict[str, Any]) -> None:
        """Record a drawn trial's generation on the trial."""
        name = study.study_name
        if name not in self._study_ids:
            self._study_ids[name] = self.storage.get_study_id_from_name(name)
        study_id = self._study_ids[name]
        trial_id = self.storage.get_trial_id_from_study_id_trial_number(study_id, number)
        self.storage.set_trial_system_attr(trial_id, ATTR, tag)

    def _params(self, item: dict[str, Any]) -> dict[str, Any]:
        s = self.relative.settings(self._to_unit(np.asarray(item["x"])), item["law"])
        params = {d.name: getattr(s, d.name) for d in space.SPACE}
        if len(self.laws) > 1:
            params["accel_law"] = s.accel_law
        return params

    def planned(self) -> list[space.Settings]:
        """The settings this sampler will hand out next, as far as it has planned them
        (the rest of its generation; another worker's trials may change the plan): what
        a worker scores ahead (:attr:`vfgym.tuning.Objective.ahead`).

        Returns
        -------
        list of Settings
            In the order they will be asked for.
        """
        return [
            self.relative.settings(self._to_unit(np.asarray(item["x"])), item["law"])
            for item in self._queue
        ]

    def sample_independent(self, study: Any, trial: Any, name: str, dist: Any) -> Any:
        seed = int(np.random.default_rng([self.seed, trial.number, 7]).integers(2**31))
        return optuna.samplers.RandomSampler(seed=seed).sample_independent(study, trial, name, dist)

    def _next(self, study: Any, number: int) -> dict[str, Any]:
        # No trial made since the queue was checked but this one (numbers count the
        # study's trials): no other worker drew a generation since, the queue stands.
        fresh = self._queue and number == self._checked
        queue = self._queue if fresh else self._queue_for(study)
        if not queue:  # asked beyond the plan while it runs (another worker, a retry)
            queue = self._queue = self._extra_plan(study)
        self._checked = number + 1
        return queue.pop(0)

    def _read(self, study: Any) -> tuple[list[Any], list[Any], int]:
        """The study's trials, those the sampler drew, and the last generation (-1: none);
        the last model batch's hyperparameters taken as where the next fits start."""
        trials = study.get_trials(deepcopy=False)
        tagged = [t for t in trials if ATTR in t.system_attrs]
        self._starts = last_thetas(tagged)
        return trials, tagged, max((t.system_attrs[ATTR]["gen"] for t in tagged), default=-1)

    def _queue_for(self, study: Any) -> list[dict[str, Any]]:
        """The rest of the generation this sampler is handing out, else the next one
        (empty while another worker's generation is still running)."""
        trials, tagged, last = self._read(study)
        self._checked = len(trials)
        if self._queue and self._queue[0]["tag"]["gen"] in (last, last + 1):
            return self._queue
        if any(t.system_attrs[ATTR]["gen"] == last and not t.state.is_finished() for t in tagged):
            return []  # its retries wait, or another worker runs it
        self._queue = self._generation(self._observations(study, trials), tagged, last)
        return self._queue

    def _extra_plan(self, study: Any) -> list[dict[str, Any]]:
        """Points for a worker that asks while a generation is still running."""
        trials, _, last = self._read(study)
        running = optuna.trial.TrialState.RUNNING
        pending = [self._x_of(t) for t in trials if t.state == running and self._has_params(t)]
        obs = self._observations(study, trials)
        if len(obs) < 2:
            plan = self._sobol(max(last, 0))
            return [plan[len(trials) % len(plan)]]
        return self._model(max(last, 0), obs, min(obs, key=rank), self._fresh_steps(),
                           len(obs), pending, self.options.extra_batch, "extra")  # fmt: skip

    # --- the search ---------------------------------------------------------------------
    def _generation(
        self, obs: list[Observation], tagged: list[Any], last: int
    ) -> list[dict[str, Any]]:
        o = self.options
        by_num = {ob.number: ob for ob in obs}
        n_done = len(obs)
        if last < 0 or not obs:
            return self._sobol(last + 1)
        mine = [
            t
            for t in tagged
            if t.system_attrs[ATTR]["gen"] == last and t.system_attrs[ATTR]["role"] != "extra"
        ]
        st = mine[0].system_attrs[ATTR]
        steps = np.asarray(st["steps"], dtype=np.float64)
        if st["mode"] == "init":
            ours = {t.number for t in tagged}
            centre = min([ob for ob in obs if ob.number not in ours] or obs, key=rank)
            return self._compass(last + 1, obs, centre, None, self._fresh_steps(), n_done)
        # The centre's trial may be gone (failed): the best instead.
        centre = by_num.get(st["centre"]) or min(obs, key=rank)
        done_here = [by_num[t.number] for t in mine if t.number in by_num]
        if st["mode"] == "compass":
            improved = np.zeros(len(steps), dtype=bool)
            for t in mine:
                role = t.system_attrs[ATTR]["role"]
                ob = by_num.get(t.number)
                if ob is not None and role.startswith("axis") and rank(ob) < rank(centre):
                    improved[int(role.split(":")[1])] = True
            best = min(done_here, key=rank, default=centre)
            prev = None
            if rank(best) < rank(centre):
                prev, centre = centre, best
            steps = np.where(improved, np.minimum(steps * 1.5, 2.0), steps * 0.5)
            since = st["since"]
            # A compass whose last generation moved goes on past its budget.
            spent = n_done - since >= o.compass_trials and prev is None
            stale = steps.max() < o.min_step or spent
            if centre.feasible and stale:
                return self._model(last + 1, obs, centre, steps, since, [])
            if steps.max() < o.min_step:
                steps = self._fresh_steps()
            return self._compass(last + 1, obs, centre, prev, steps, since) or self._model(
                last + 1, obs, centre, steps, since, []
            )
        # One model batch, then the compass again: from its best point if that beats the
        # centre, else from the centre with fresh steps.
        best = min(done_here, key=rank, default=centre)
        top = min(obs, key=rank)  # a compass started from another basin may trail the best
        if rank(top) < rank(centre):
            centre = top
        if best.feasible and rank(best) < rank(centre):
            centre = best
        elif (
            best.feasible
            and best.cost <= centre.cost * (1.0 + o.explore_gap)
            and np.abs(best.x - centre.x).max() > 2.0 * o.step0
        ):
            centre = best  # another basin's point nearly as good: a compass searches it
        elif steps.max() >= o.resume_floor:
            # The compass before this batch was cut short by its budget or counted as
            # converged with steps above resume_floor; it goes on from the centre with its
            # steps (its budget still spent, its steps below min_step: a generation that
            # does not move hands over to the model again, one batch between
            # generations). No poll left (all clipped onto the centre): the model.
            return self._compass(last + 1, obs, centre, None, steps, st["since"]) or (
                self._model(last + 1, obs, centre, np.zeros_like(steps), st["since"], [])
            )
        else:
            return self._model(last + 1, obs, centre, steps, st["since"], [])
        return self._compass(last + 1, obs, centre, None, self._fresh_steps(), n_done) or (
            self._model(last + 1, obs, centre, steps, n_done, [])
        )

    def _fresh_steps(self) -> np.ndarray:
        """The first step along each poll direction."""
        return np.full(len(self._dirs), self.options.step0)

    def _tag(self, gen: int, mode: str, role: str, centre: Observation | None,
             steps: np.ndarray, since: int) -> dict[str, Any]:  # fmt: skip
        return {
            "gen": gen,
            "mode": mode,
            "role": role,
            "centre": None if centre is None else centre.number,
            "steps": [float(s) for s in steps],
            "since": since,
        }

    def _sobol(self, gen: int) -> list[dict[str, Any]]:
        n = self.options.n_init
        u = latin_hypercube(n, 4, self._rng(gen, 1))
        tag = self._tag(gen, "init", "lhs", None, self._fresh_steps(), 0)
        return [
            {"x": self._from_unit(p), "law": self.laws[i % len(self.laws)], "tag": tag}
            for i, p in enumerate(u)
        ]

    def _compass(self, gen: int, obs: list[Observation], centre: Observation,
                 prev: Observation | None, steps: np.ndarray,
                 since: int) -> list[dict[str, Any]]:  # fmt: skip
        lo, hi = self._lo, self._lo + self._span
        out: list[dict[str, Any]] = []
        seen = {(tuple(centre.x), centre.law)}

        def add(x: np.ndarray, role: str, law: str = centre.law) -> None:
            x = np.clip(x, lo, hi)
            if (tuple(x), law) in seen:
                return
            seen.add((tuple(x), law))
            out.append({"x": x, "law": law,
                        "tag": self._tag(gen, "compass", role, centre, steps, since)})  # fmt: skip

        if prev is not None:
            add(centre.x + (centre.x - prev.x), "pattern")
        for d in range(len(steps)):
            for sign in (1, -1):
                add(centre.x + sign * steps[d] * self._dirs[d], f"axis:{d}:{sign:+d}")
        for law in self.laws:
            if law != centre.law:
                add(centre.x.copy(), "law", law)
        return out

    def _law_of(self, p: np.ndarray) -> str:
        """The law a model point's fifth coordinate stands for (the only one if one)."""
        if len(self.laws) == 1:
            return self.laws[0]
        return self.laws[round(p[4] * (len(self.laws) - 1))]

    def _model(self, gen: int, obs: list[Observation], centre: Observation,
               steps: np.ndarray, since: int, pending: list[tuple[np.ndarray, str]],
               n: int | None = None, role: str = "model") -> list[dict[str, Any]]:  # fmt: skip
        o = self.options
        rng = self._rng(gen, 2 + len(pending))
        starts, fitted_at = self._starts
        # The hyperparameters are fitted again once the trials have grown by refit_growth
        # since their last fit; in between they are kept, the models only factored.
        refit = not starts or len(obs) >= o.refit_growth * fitted_at
        pts, thetas = propose(self._inputs(obs), obs,
                              [self._input(x, law) for x, law in pending],
                              n or o.model_batch, o.xi, rng, len(self.laws), starts,
                              refit)  # fmt: skip
        tag = self._tag(gen, "model", role, centre, steps, since) | {
            "theta": thetas,
            "theta_n": len(obs) if refit else fitted_at,
        }
        return [{"x": self._from_unit(p[:4]), "law": self._law_of(p), "tag": tag} for p in pts]

    # --- coordinates --------------------------------------------------------------------
    def _rng(self, gen: int, salt: int) -> np.random.Generator:
        return np.random.default_rng([self.seed, gen, salt])

    def _to_unit(self, x: np.ndarray) -> np.ndarray:
        return (x - self._lo) / self._span

    def _from_unit(self, u: np.ndarray) -> np.ndarray:
        return self._lo + np.clip(u, 0.0, 1.0) * self._span

    def _input(self, x: np.ndarray, law: str) -> np.ndarray:
        u = self._to_unit(x)
        if len(self.laws) > 1:
            u = np.r_[u, self.laws.index(law) / (len(self.laws) - 1)]
        return u

    def _inputs(self, obs: list[Observation]) -> np.ndarray:
        return np.array([self._input(o.x, o.law) for o in obs])

    def _x_of(self, trial: Any) -> tuple[np.ndarray, str]:
        s = space.Settings(**{d.name: trial.params[d.name] for d in space.SPACE},
                           accel_law=trial.params.get("accel_law", self.laws[0]))  # fmt: skip
        return self._lo + self.relative.to_unit(s) * self._span, s.accel_law

    def _has_params(self, trial: Any) -> bool:
        return all(d.name in trial.params for d in space.SPACE)

    def _observations(self, study: Any, trials: list[Any]) -> list[Observation]:
        """The completed trials as observations, each read once per study (a completed
        trial never changes: a long sweep's cost per trial does not grow with it)."""
        key = (id(study), study.study_name)
        if self._seen_in != key:
            self._seen, self._seen_in = {}, key
        seen = self._seen
        done = [t for t in trials if t.state == optuna.trial.TrialState.COMPLETE]
        for t in done:
            if t.number not in seen:
                seen[t.number] = self._observe(t)
        return [o for o in (seen[t.number] for t in done) if o is not None]

    def _observe(self, trial: Any) -> Observation | None:
        if trial.value is None or not self._has_params(trial):
            return None
        x, law = self._x_of(trial)
        named = {_constraint_name(k): v for k, v in trial.constraints.items()}
        cons = np.array([v for _, v in sorted(named.items())])
        viol = float(np.maximum(cons, 0.0).sum()) if cons.size else 0.0
        return Observation(trial.number, x, law, float(trial.value), viol, viol <= 0.0, cons)


def _constraint_name(key: str) -> str:
    """A constraint's name: ``CONSTRAINTS``' for the index Optuna's list gives it."""
    return CONSTRAINTS[int(key)] if key.isdigit() and int(key) < len(CONSTRAINTS) else key


def last_thetas(tagged: list[Any]) -> tuple[dict[str, list[float]], int]:
    """The models' log hyperparameters of the latest model batch among the trials (its
    tag's ``theta``; empty if none), and the completed trials they were fitted on: where
    the next batch's fits start (or what they keep, :attr:`CompassOptions.refit_growth`);
    read from the study, so a resumed or shared search starts them the same."""
    best: tuple[int, dict[str, list[float]], int] = (-1, {}, 0)
    for t in tagged:
        tag = t.system_attrs[ATTR]
        if "theta" in tag and tag["gen"] > best[0]:
            best = (tag["gen"], tag["theta"], int(tag.get("theta_n", 0)))
    return best[1], best[2]


def latin_hypercube(n: int, dim: int, rng: np.random.Generator) -> np.ndarray:
    """``n`` points in [0, 1]^dim, one in each of n equal slices of every axis."""
    u = (np.argsort(rng.random((dim, n)), axis=1).T + rng.random((n, dim))) / max(n, 1)
    return u
