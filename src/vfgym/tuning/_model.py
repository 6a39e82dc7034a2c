"""The compass sampler's model step: Gaussian processes on the completed trials (log cost,
and each constraint some trial broke), and batches of points over the whole space chosen
by the log of expected improvement times probability of feasibility, each believed at its
predicted values before the next (:class:`vfgym.tuning._gp.Believer`).

The Gaussian processes (:mod:`vfgym.tuning._gp`: scikit-learn's, and scipy's optimiser,
special functions and distances, over a second to import on a loaded machine) are
imported by the first model batch: a compass search's polls, and its first trial, wait
for none of it (:func:`prepare` imports them beside the trials).
"""

from __future__ import annotations

import importlib
import math
import os
import sys
import threading
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from typing import TYPE_CHECKING, Any, NamedTuple, TypeVar

import numpy as np
from threadpoolctl import threadpool_limits  # type: ignore[import-untyped]

if TYPE_CHECKING:
    from vfgym.tuning._gp import GaussianProcess

GP_MODULE = "vfgym.tuning._gp"
"""The model's module, imported when a batch needs it."""


def prepare() -> None:
    """Import the model's module (:data:`GP_MODULE`) on a thread of its own while the
    caller goes on, once a process (a model batch that comes first waits for it on the
    import's lock)."""
    if GP_MODULE in sys.modules or any(t.name == _IMPORTING for t in threading.enumerate()):
        return
    threading.Thread(
        target=importlib.import_module, args=(GP_MODULE,), name=_IMPORTING, daemon=True
    ).start()


_IMPORTING = "vfgym-import-model"


class Observation(NamedTuple):
    """A completed trial as the sampler sees it."""

    number: int
    x: np.ndarray  # log coordinates of :class:`vfgym.space.Relative`
    law: str
    cost: float
    violation: float  # sum of the positive constraint values
    feasible: bool
    constraints: np.ndarray


def rank(o: Observation) -> tuple:
    """Feasible first, by cost; then infeasible ones by total violation, then cost."""
    return (0, o.cost, 0.0) if o.feasible else (1, o.violation, o.cost)


MODEL_POINTS = 160
"""At most this many observations inform the model (the best half and the latest half)."""


class Proposal(NamedTuple):
    """A model batch's points (unit coordinates) and each model's log hyperparameters."""

    points: list[np.ndarray]
    thetas: dict[str, list[float]]


@threadpool_limits.wrap(limits=1, user_api="blas")
def propose(x: np.ndarray, obs: list[Observation], pending: list[np.ndarray], n: int,
            xi: float, rng: np.random.Generator, n_laws: int = 1,
            starts: dict[str, list[float]] | None = None,
            refit: bool = True) -> Proposal:  # fmt: skip
    """``n`` points of highest expected improvement (by at least ``xi`` over the best
    feasible cost) times probability of feasibility, each believed at its predicted values
    (:meth:`_Fit.choose`), as ``pending`` first. Each model's fit starts from
    ``starts`` (a previous batch's :attr:`Proposal.thetas`), or keeps it unless ``refit``.
    The linear algebra runs on one thread: OpenBLAS's threads spin on matrices this
    small, 30x slower on a busy machine."""
    if len(obs) > MODEL_POINTS:
        order = sorted(range(len(obs)), key=lambda i: rank(obs[i]))
        keep = sorted(set(order[: MODEL_POINTS // 2]) | set(range(len(obs))[-MODEL_POINTS // 2 :]))
        x, obs = x[keep], [obs[i] for i in keep]
    fit = _fit(x, obs, xi, starts, refit)
    feas = np.array([o.feasible for o in obs])
    y = np.log(np.maximum([o.cost for o in obs], 1e-12))
    top = x[np.argsort(np.where(feas, y, np.inf), kind="stable")[:3]]
    dim = x.shape[1]

    def candidates() -> np.ndarray:
        cand = [rng.random((1024, dim))]
        for t in top:
            for scale in (0.1, 0.03):
                dz = np.zeros((200, dim))
                dz[np.arange(200), rng.integers(0, 4, 200)] = rng.normal(0.0, scale, 200)
                cand.append(np.clip(t + dz, 0.0, 1.0))
        c = np.vstack(cand)
        if n_laws > 1:
            c[:, 4] = np.round(c[:, 4] * (n_laws - 1)) / (n_laws - 1)
        return c

    return Proposal(fit.choose(n, candidates, pending), fit.thetas())


class _Fit(NamedTuple):
    """The models a proposal is chosen by; ``best``: the log cost to improve on (None: none
    feasible)."""

    gp: GaussianProcess
    cgps: list[GaussianProcess]
    best: float | None
    keys: tuple[str, ...] = ()

    def thetas(self) -> dict[str, list[float]]:
        """Each model's log hyperparameters, by name (``cost``, then :attr:`keys`)."""
        models = zip(("cost", *self.keys), (self.gp, *self.cgps), strict=False)
        return {k: [float(t) for t in m.theta] for k, m in models}

    def choose(self, n: int, candidates: Any, pending: Sequence[np.ndarray] = ()) -> list:
        """``n`` distinct points of one set of ``candidates()``, each believed at its
        predicted values before the next is chosen, as the ``pending`` points first."""
        from scipy.special import log_ndtr

        from vfgym.tuning._gp import Believer, log_expected_improvement

        c = np.vstack([*pending, candidates()])
        cost, *cons = each(lambda m: Believer(m, c), [self.gp, *self.cgps])
        taken = np.arange(len(c)) < len(pending)
        for j in range(len(pending)):
            for m in (cost, *cons):
                m.believe(j)
        out = []
        for _ in range(min(n, len(c) - len(pending))):
            sd = cost.sd()
            log_pf = np.zeros(len(c))
            for m in cons:
                log_pf += log_ndtr(-m.mean / np.maximum(m.sd(), 1e-9))
            # In logs: EI × P(feasible) underflows to 0 on every candidate far from the
            # best, where argmax would silently take the first.
            acq = log_pf
            if self.best is not None:
                acq = acq + log_expected_improvement(self.best, cost.mean, sd)
            acq[taken] = -np.inf
            j = int(np.argmax(acq))
            taken[j] = True
            out.append(c[j])
            for m in (cost, *cons):
                m.believe(j)
        return out


def _fit(x: np.ndarray, obs: list[Observation], xi: float,
         starts: dict[str, list[float]] | None = None, refit: bool = True) -> _Fit:  # fmt: skip
    """Gaussian processes on log cost (on the feasible points once there are three) and on
    the broken constraints (signed log), each from ``starts``' hyperparameters of its name
    (kept unless ``refit``)."""
    from vfgym.tuning._gp import GaussianProcess

    y = np.log(np.maximum([o.cost for o in obs], 1e-12))
    feas = np.array([o.feasible for o in obs])
    cons = np.array([o.constraints for o in obs])
    fit = feas if feas.sum() >= 3 else np.ones(len(obs), dtype=bool)
    yf = y[fit]
    starts = starts or {}

    def model(data: tuple[np.ndarray, np.ndarray, str]) -> GaussianProcess:
        xs, ys, key = data
        start = starts.get(key)
        return GaussianProcess(xs, ys, start=start, fit=refit or start is None)

    keyed = _constraint_models(cons)
    gp, *cgps = each(model, [(x[fit], yf, "cost"), *((x, _signed_log(c), k) for k, c in keyed)])
    best = y[feas].min() + math.log1p(-xi) if feas.any() else None
    return _Fit(gp, cgps, best, tuple(k for k, _ in keyed))


T = TypeVar("T")
R = TypeVar("R")


def each(fn: Callable[[T], R], items: Sequence[T]) -> list[R]:
    """``[fn(i) for i in items]`` on up to as many threads as cores: a batch's models are
    independent and their numpy work releases the GIL; each gives the same bits on
    whichever thread."""
    threads = min(len(items), os.cpu_count() or 1)
    if threads < 2:
        return [fn(i) for i in items]
    with ThreadPoolExecutor(threads, "vfgym-model") as pool:
        return list(pool.map(fn, items))


def _constraint_models(cons: np.ndarray) -> list[tuple[str, np.ndarray]]:
    """Each constraint some observation violates, named ``c<i>``: each alone is smoother
    than their maximum, which jumps from one constraint's surface to another's."""
    if not cons.size:
        return []
    return [(f"c{i}", c) for i, c in enumerate(cons.T) if (c > 0).any()]


def _signed_log(v: np.ndarray) -> np.ndarray:
    return np.sign(v) * np.log1p(np.abs(v))
