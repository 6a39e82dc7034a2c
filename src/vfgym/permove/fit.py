"""A per-move settings model for one axis (``vfgym fit``): per-move optima of many moves
drawn from the axis's move distribution, the cost of every optimum on every move, then
the pick model (:func:`vfgym.permove.pick.fit_pick_model`) over them, judged on the axis's
held-out test moves against the best fixed setting (a short sweep on its train moves),
the paper's settings and the S-curve source.

The training moves: the axis's ``random:`` train set as given (``count`` raised to
:attr:`FitConfig.moves`); for a listed train set, a distribution spanning the distances,
profiles, directions and loads it lists, each move as long as its ideal move time plus
the listed moves' median time to spare (:func:`fit_distribution`). The per-move optima are
written to the run folder as they are found (``optima.csv``), so an interrupted fit
loses nothing it finished and the same call continues it.
"""

from __future__ import annotations

import hashlib
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from vfgym._validate import check_int
from vfgym.axis import Axis, PlantVariant
from vfgym.moves.distribution import MoveDistribution
from vfgym.moves.scenarios import DRAWN_PROFILES, Scenario, ideal_move_time_s
from vfgym.params import DEFAULT_MEASURES, PAPER_PLANT, Measures, Plant, Settings
from vfgym.scoring import Move, score_robust

from .optima import MoveOptimum, OptimumSearch, move_optima, read_optima, write_optima
from .pick import PickModel, fit_pick_model
from .targets import settings_targets, target_settings

OPTIMA_FILE = "optima.csv"
FIT_SEARCH = OptimumSearch()
"""The per-move search of a fit: :class:`OptimumSearch`'s default, the reference search (a
6⁴ grid, 8 rounds around the 3 best points, 3240 settings a move). A third of it (a 4⁴
grid) misses the optimum's basin on short steps, and the models fitted from it cost 0.7 to
2.3 % more on held-out moves (docs/results/compliant.md)."""


@dataclass(frozen=True)
class FitConfig:
    """How ``vfgym fit`` learns an axis's settings model; every default here.

    Parameters
    ----------
    moves : int
        Training moves, 8 to 5000.
    search : OptimumSearch
        The per-move search (default :data:`FIT_SEARCH`).
    neighbours, library : int
        The pick model's neighbours and library size (at most ``moves``).
    check : int
        Best-ranked candidates the model simulates on each new move, the best returned
        (:class:`vfgym.permove.pick.PickModel`), 0 to ``library``. On an axis with
        uncertainty feasibility on its design prunes more candidates, so more are checked
        (how many: docs/results/robust.md). The default checks the whole library: the best
        of more candidates is never dearer on the move, for about 0.1 s a move.
    sweep_trials : int
        Trials of the sweep for the best fixed setting, 1 to 10000.
    chunk : int
        Moves searched between checkpoints, ≥ 1.
    """

    moves: int = 160
    search: OptimumSearch = FIT_SEARCH
    neighbours: int = 6
    library: int = 64
    check: int = 64
    sweep_trials: int = 60
    chunk: int = 16

    def __post_init__(self) -> None:
        s = object.__setattr__
        s(self, "moves", check_int("moves", self.moves, 8, 5000))
        s(self, "neighbours", check_int("neighbours", self.neighbours, 1, self.moves))
        s(self, "library", check_int("library", self.library, 1, self.moves))
        s(self, "check", check_int("check", self.check, 0, self.library))
        s(self, "sweep_trials", check_int("sweep_trials", self.sweep_trials, 1, 10_000))
        s(self, "chunk", check_int("chunk", self.chunk, 1))
        if isinstance(self.search, dict):
            s(self, "search", OptimumSearch(**self.search))


@dataclass(frozen=True)
class FitResult:
    """What :func:`fit_axis` made.

    Attributes
    ----------
    model : PickModel
        The fitted settings model.
    optima : tuple of MoveOptimum
        The training moves' optima.
    fixed : Settings
        The best fixed setting the sweep found on the axis's train moves.
    verdict : Any
        The held-out verdict (:class:`vfgym.report.Verdict`) of the model.
    seconds : dict
        Wall time of each stage (optima, costs, model, sweep, verdict).
    """

    model: PickModel
    optima: tuple[MoveOptimum, ...]
    fixed: Settings
    verdict: Any
    seconds: dict[str, float] = field(default_factory=dict)


def fit_distribution(axis: Axis) -> MoveDistribution:
    """The distribution of the axis's training moves (module doc).

    Parameters
    ----------
    axis : Axis
        The axis.

    Returns
    -------
    MoveDistribution
        Its train set's ``random:`` distribution, or one spanning its listed moves.
    """
    ms = axis.moves.train
    if ms.random is not None:
        return ms.random
    single = [sc for sc in ms.moves if sc.profile != "multi"]
    legs = [abs(d) for sc in ms.moves if sc.profile == "multi" for d, _ in sc.moves]
    dist = [abs(sc.distance_rad) for sc in single] + legs
    profiles = tuple(sorted({sc.profile for sc in single} & set(DRAWN_PROFILES)))
    signs = {np.sign(sc.distance_rad) for sc in single} | {np.sign(d) for sc in ms.moves
                                                          for d, _ in sc.moves}  # fmt: skip
    loads = [sc.inertia_ratio for sc in ms.moves]
    # as long as the listed moves: their ideal move time plus their median time to settle
    spare = [sc.duration_s - ideal_move_time_s(sc.distance_rad, sc.plant(axis.plant))
             for sc in single]  # fmt: skip
    default = MoveDistribution()
    return MoveDistribution(
        distance_rad=(min(dist), max(dist)) if dist else default.distance_rad,
        both_directions=len(signs) > 1,
        profiles=profiles or default.profiles,
        inertia_ratio=(min(loads), max(loads)),
        time_factor=1.0 if spare else default.time_factor,
        settle_s=max(float(np.median(spare)), 0.0) if spare else default.settle_s,
    )


def fit_moves(axis: Axis, count: int) -> list[Scenario]:
    """``count`` training moves of the axis (``train-0`` …; never a test move).

    Parameters
    ----------
    axis : Axis
        The axis.
    count : int
        How many.

    Returns
    -------
    list of Scenario
        The moves, on the axis's plant.
    """
    dist = replace(fit_distribution(axis), count=count, first_seed=0)
    return dist.scenarios("train", axis.plant)


def candidate_costs(
    scenarios: Sequence[Scenario],
    optima: Sequence[MoveOptimum],
    *,
    plant: Plant = PAPER_PLANT,
    measures: Measures = DEFAULT_MEASURES,
    batch: int = 20_000,
    progress: Callable[[int, int], None] | None = None,
    plants: Sequence[PlantVariant] = (),
) -> tuple[np.ndarray, np.ndarray]:
    """The cost on move i of move j's optimum in the model's coordinates, made settings
    on move i's plant (:func:`vfgym.permove.targets.target_settings`), for every pair.

    Parameters
    ----------
    scenarios : sequence of Scenario
        The training moves.
    optima : sequence of MoveOptimum
        Their optima, in order.
    plant, measures : Plant, Measures
        The axis's plant and measures.
    batch : int
        Pairs per compiled call.
    progress : callable or None
        Called with (pairs done, pairs) after each batch.
    plants : sequence of PlantVariant
        True plants a candidate must also be feasible on (the axis's design).

    Returns
    -------
    tuple of numpy.ndarray
        ``cost`` (moves, moves) and ``feasible`` (bool, the same shape).
    """
    moves = [Move.of(sc, plant) for sc in scenarios]
    cand = [settings_targets(o.settings, mv.plant) for o, mv in zip(optima, moves, strict=True)]
    law = optima[0].settings.accel_law
    n = len(moves)
    pairs = [(i, j) for i in range(n) for j in range(n)]
    cost = np.empty((n, n))
    feas = np.empty((n, n), dtype=bool)
    for a in range(0, len(pairs), batch):
        chunk = pairs[a : a + batch]
        ctrls = [target_settings(cand[j], moves[i].plant, law) for i, j in chunk]
        res = score_robust(ctrls, [moves[i] for i, _ in chunk], plants, measures=measures)
        for (i, j), r in zip(chunk, res, strict=True):
            assert r is not None  # V-F settings run every move
            cost[i, j] = r.cost
            feas[i, j] = r.feasible
        if progress:
            progress(a + len(chunk), len(pairs))
    return cost, feas


def optima_key(
    scenarios: Sequence[Scenario],
    search: OptimumSearch,
    plant: Plant,
    measures: Measures,
    plants: Sequence[PlantVariant] = (),
) -> str:
    """The first line of a checkpointed optima file: a digest of what they were searched
    for (the moves, the search, the plant, the measures and the true plants they must be
    feasible on).

    Parameters
    ----------
    scenarios : sequence of Scenario
        The moves, in order.
    search : OptimumSearch
        The per-move search.
    plant, measures : Plant, Measures
        The axis's plant and measures.
    plants : sequence of PlantVariant
        The axis's design plants (none: the key of an exactly known axis, as before).

    Returns
    -------
    str
        ``moves-key: `` and 16 hex digits.
    """
    what: tuple = (search, plant, measures, [asdict(sc) for sc in scenarios])
    text = repr(what + ((tuple(plants),) if plants else ()))
    return f"moves-key: {hashlib.sha256(text.encode()).hexdigest()[:16]}"


def checkpointed_optima(
    scenarios: Sequence[Scenario],
    search: OptimumSearch,
    path: Path,
    *,
    plant: Plant = PAPER_PLANT,
    measures: Measures = DEFAULT_MEASURES,
    chunk: int = 16,
    progress: Callable[[int], object] | None = None,
    plants: Sequence[PlantVariant] = (),
) -> list[MoveOptimum]:
    """Per-move optima, ``chunk`` moves at a time, each chunk appended to ``path``; the
    optima already there (of the same moves, in order) are kept, not searched again.

    Parameters
    ----------
    scenarios : sequence of Scenario
        The moves.
    search : OptimumSearch
        The per-move search.
    path : Path
        The optima CSV (:func:`vfgym.permove.optima.write_optima`).
    plant, measures : Plant, Measures
        The axis's plant and measures.
    chunk : int
        Moves per checkpoint.
    progress : callable or None
        Called with the number of moves done (the kept ones first).
    plants : sequence of PlantVariant
        True plants the optima must be feasible on (:func:`move_optima`).

    Returns
    -------
    list of MoveOptimum
        One per move, in order.
    """

    def key(n: int) -> str:  # what the first n optima were searched for
        return optima_key(scenarios[:n], search, plant, measures, plants)

    done: list[MoveOptimum] = read_optima(path) if path.is_file() else []
    first = path.read_text().partition("\n")[0] if done else ""
    if len(done) > len(scenarios) or first != f"# {key(len(done))}":
        done = []  # the optima of other moves, search or axis: start again
    header = f"per-move optima: {search}"
    if progress:
        progress(len(done))
    for a in range(len(done), len(scenarios), chunk):
        part = list(scenarios[a : a + chunk])
        done += move_optima(part, search, plant=plant, measures=measures, plants=plants)
        write_optima(path, done, header=f"{key(len(done))}\n{header}")
        if progress:
            progress(len(part))
    return done


def best_fixed(scenarios: Sequence[Scenario], axis: Axis, trials: int) -> Settings:
    """The best fixed setting a short sweep finds on moves, as ``vfgym sweep`` would with
    as many trials: the default sampler on the axis's plant, the sweep's warm starts first
    (the paper's settings, the rule of thumb), feasible on the axis's plant design.

    Parameters
    ----------
    scenarios : sequence of Scenario
        The moves (an axis's train set).
    axis : Axis
        The axis (plant, measures).
    trials : int
        The sweep's trials.

    Returns
    -------
    Settings
        The best trial's settings (feasible first).
    """
    from vfgym.tuning import warm_starts

    from .refine import short_sweep

    # the sweep's own warm starts: the paper's settings, then the rule of thumb
    (_, first), *rest = warm_starts(list(scenarios), axis.plant)
    return short_sweep(
        scenarios,
        first,
        trials,
        axis=axis,
        also=[s for _, s in rest],
    ).settings


def fit_axis(
    axis: Axis,
    run_dir: str | Path,
    cfg: FitConfig = FitConfig(),
    *,
    progress: bool = True,
) -> FitResult:
    """Fit an axis's settings model and judge it on the axis's test moves (module doc).

    Writes ``optima.csv`` (as it goes), ``costs.npz`` and ``settings_model.json`` to
    ``run_dir``.

    Parameters
    ----------
    axis : Axis
        The axis.
    run_dir : str or Path
        The run folder (exists).
    cfg : FitConfig
        Training moves, search, model and sweep sizes.
    progress : bool
        Show a progress bar (tqdm, on stderr).

    Returns
    -------
    FitResult
        The model, the optima, the best fixed setting and the verdict.
    """
    from tqdm.auto import tqdm

    from vfgym.axis import VERDICT_PLANTS
    from vfgym.report import Candidate, baseline_candidates, compare, verdict

    from .tuners import Tuner, trained_on

    run = Path(run_dir)
    seconds: dict[str, float] = {}
    t0 = time.perf_counter()
    train = fit_moves(axis, cfg.moves)
    design = axis.design_plants()
    kw: dict[str, Any] = {"plant": axis.plant, "measures": axis.measures, "plants": design}
    steps = len(train) + 3
    with tqdm(total=steps, desc=f"fit {axis.name}", unit="move", disable=not progress) as bar:
        optima = checkpointed_optima(
            train, cfg.search, run / OPTIMA_FILE, chunk=cfg.chunk, progress=bar.update, **kw
        )
        seconds["optima"] = time.perf_counter() - t0
        bar.set_postfix_str("costs")
        cost, feas = candidate_costs(train, optima, **kw)
        np.savez_compressed(run / "costs.npz", scenarios=[sc.name for sc in train],
                            cost=cost, feasible=feas)  # fmt: skip
        bar.update(1)
        seconds["costs"] = time.perf_counter() - t0 - sum(seconds.values())
        model = fit_pick_model(train, optima, cost, feas, neighbours=cfg.neighbours,
                               library=cfg.library, plant=axis.plant)  # fmt: skip
        model = replace(model, trained_on=trained_on(axis), check=cfg.check)
        model.save(run / "settings_model.json")
        seconds["model"] = time.perf_counter() - t0 - sum(seconds.values())
        bar.set_postfix_str("fixed-setting sweep")
        fixed = best_fixed(axis.scenarios("train"), axis, cfg.sweep_trials)
        bar.update(1)
        seconds["sweep"] = time.perf_counter() - t0 - sum(seconds.values())
        bar.set_postfix_str("verdict")
        tuner = Tuner("fitted", axis, axis.name,
                      lambda sc: model.settings(sc, axis.plant, axis.measures, design),
                      lambda sc: None, lambda msg: None)  # fmt: skip
        test = axis.scenarios("test")
        report = compare(
            [Candidate("fitted", policy=tuner, source="settings_model.json")],
            [Candidate("best-fixed", fixed, source="sweep", role="baseline"),
             *baseline_candidates(("paper", "scurve"))],
            test,
            axis=axis,
            plants=VERDICT_PLANTS,  # the verdict across plants, in the same call
        )  # fmt: skip
        v = verdict(report, "fitted", train, f"the {len(test)} test moves of axis {axis.name}")
        bar.update(1)
        seconds["verdict"] = time.perf_counter() - t0 - sum(seconds.values())
    return FitResult(model, tuple(optima), fixed, v, seconds)


def config_dict(cfg: FitConfig) -> dict[str, Any]:
    """The config as plain data (a run folder's ``config.yaml``).

    Parameters
    ----------
    cfg : FitConfig
        The config.

    Returns
    -------
    dict
        Its fields, the search's as a mapping.
    """
    return asdict(cfg)


__all__ = [
    "FIT_SEARCH",
    "OPTIMA_FILE",
    "FitConfig",
    "FitResult",
    "best_fixed",
    "candidate_costs",
    "checkpointed_optima",
    "config_dict",
    "fit_axis",
    "fit_distribution",
    "fit_moves",
    "optima_key",
]
