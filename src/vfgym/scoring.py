"""The one scoring path: controller settings → simulate → measures → constraints → cost.

:func:`evaluate` is what every part of vfgym asks "how good is this setting on this move":
the Gymnasium envs' reward, the Optuna objective and constraints, and the evaluation
reports. It takes a batch of controllers (V-F :class:`~vfgym.Settings` or a baseline pulse
source) and a list of scenarios, runs every pair in one compiled, multi-threaded call
that keeps only the streamed measures, and returns them with the constraint values, the
objectives and the scalar cost.

Cost of one run (lower is better; weights in :class:`CostWeights`)::

    cost = time · move_time / ideal_time          (point-to-point moves)
         | tracking · rms_tracking / (10 % of |amplitude|)  (a moving reference)
         + overshoot · overshoot / in-position window
         + accel · max(0, accel constraint)
         + torque · time at the torque limit / ideal_time
         + unsettled · [not settled at the end]

ideal_time is the bang–coast–bang time at δ·f and the motor's acceleration limit, so a
perfect move costs about 1 whatever its length, and scenarios average fairly.

Constraints (feasible when ≤ 0; :class:`Bounds`):

- ``accel``: peak pulse-train acceleration / limit − 1 − its one-pulse quantisation / limit
- ``torque``: time at the torque limit − ``Bounds.torque_limit_time_s``
- ``overshoot``: overshoot − ``Bounds.overshoot_windows`` in-position windows

Objectives (all minimised): overshoot in in-position windows, move time / ideal time
(tracking ratio for a moving reference), acceleration violation max(0, accel constraint).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from vfgym import _kernel as K
from vfgym.baselines import (
    Baseline,
    Controller,
    FixedFrequency,
    SCurveSource,
    controller_label,
    resolve,
)
from vfgym.metrics import NAMES as METRIC_NAMES
from vfgym.metrics import from_acc
from vfgym.params import (
    DEFAULT_MEASURES,
    PAPER_PLANT,
    Measures,
    Plant,
    Settings,
    in_position_rad,
)
from vfgym.scenarios import Scenario, scenario_set
from vfgym.simulate import Trace, command_end_s, pack, simulate

CONSTRAINTS = ("accel", "torque", "overshoot")
OBJECTIVES = ("overshoot_windows", "time_ratio", "accel_violation")


@dataclass(frozen=True)
class CostWeights:
    """Weights of the scalar cost (see the module docstring)."""

    time: float = 1.0
    tracking: float = 1.0
    overshoot: float = 0.1
    accel: float = 5.0
    torque: float = 1.0
    unsettled: float = 5.0


@dataclass(frozen=True)
class Bounds:
    """Constraint bounds: overshoot in in-position windows, time at the torque limit (s)."""

    overshoot_windows: float = 1.0
    torque_limit_time_s: float = 0.0


DEFAULT_WEIGHTS = CostWeights()
DEFAULT_BOUNDS = Bounds()


@dataclass
class Evaluation:
    """Measures, constraints, objectives and cost of each (controller, scenario) pair.

    ``metrics[c][s]`` is a dict of the named measures (:mod:`vfgym.metrics`) plus
    ``ideal_time_s``, ``time_ratio`` and ``window_rad``; arrays are shaped
    (controllers, scenarios[, 3]). A pulse source on a moving reference is not applicable:
    its entries are NaN.
    """

    controllers: list[Controller]
    scenarios: list[Scenario]
    metrics: list[list[dict[str, Any]]]
    cost: np.ndarray
    constraints: np.ndarray
    objectives: np.ndarray
    traces: list[list[Trace | None]] | None = field(default=None, repr=False)

    @property
    def mean_cost(self) -> np.ndarray:
        """Mean cost over the scenarios, per controller (NaN entries skipped)."""
        return np.nanmean(self.cost, axis=1)

    @property
    def feasible(self) -> np.ndarray:
        """All constraints ≤ 0, per pair."""
        return np.all(self.constraints <= 0.0, axis=-1)

    def metric(self, name: str) -> np.ndarray:
        """One measure as a (controllers, scenarios) float array."""
        return np.array([[float(m[name]) for m in row] for row in self.metrics])

    def labels(self) -> list[str]:
        return [controller_label(c) for c in self.controllers]


def _check_controllers(controllers: Any) -> list[Controller]:
    kinds = (Settings, FixedFrequency, SCurveSource, Baseline)
    if isinstance(controllers, (*kinds, str)):
        controllers = [controllers]
    out = [Baseline(c) if isinstance(c, str) else c for c in controllers]
    for i, c in enumerate(out):
        if not isinstance(c, kinds):
            raise ValueError(
                f"settings[{i}]={c!r} is not allowed: give vfgym.Settings or a baseline "
                "pulse source (FixedFrequency, SCurveSource)"
            )
    if not out:
        raise ValueError("settings=[] is not allowed: give at least one")
    return out


def score(
    m: dict[str, Any],
    scenario: Scenario,
    plant: Plant,
    measures: Measures,
    weights: CostWeights = DEFAULT_WEIGHTS,
    bounds: Bounds = DEFAULT_BOUNDS,
) -> tuple[float, np.ndarray, np.ndarray, dict[str, float]]:
    """Cost, constraints and objectives of one run's measures."""
    ideal = scenario.ideal_time_s(plant)
    window = in_position_rad(measures, plant, scenario.command(plant)[-1])
    limit = plant.motor.accel_limit_rad_s2
    c_acc = m["accel_ratio_pulse"] - 1.0 - m["accel_quantum_rad_s2"] / limit
    c_tq = m["torque_limit_time_s"] - bounds.torque_limit_time_s
    ov_w = m["overshoot_rad"] / window if window > 0 else 0.0
    c_ov = ov_w - bounds.overshoot_windows
    if scenario.tracking:
        ratio = m["tracking_rms_rad"] / (0.1 * abs(scenario.distance_rad))
        main = weights.tracking * ratio
    else:
        ratio = m["move_time_s"] / ideal
        main = weights.time * ratio + (0.0 if m["settled"] else weights.unsettled)
    cost = (
        main
        + weights.overshoot * ov_w
        + weights.accel * max(0.0, c_acc)
        + weights.torque * m["torque_limit_time_s"] / ideal
    )
    extra = {"ideal_time_s": ideal, "time_ratio": ratio, "window_rad": window}
    return cost, np.array([c_acc, c_tq, c_ov]), np.array([ov_w, ratio, max(0.0, c_acc)]), extra


@dataclass(frozen=True)
class Move:
    """A scenario made ready to simulate: its plant, its command and when that ends."""

    scenario: Scenario
    plant: Plant
    command: np.ndarray
    command_end_s: float

    @classmethod
    def of(cls, scenario: Scenario, base: Plant = PAPER_PLANT) -> Move:
        plant = scenario.plant(base)
        cmd = scenario.command(plant)
        return cls(scenario, plant, cmd, command_end_s(cmd, plant.tick_hz))


def _as_run(c: Controller, move: Any) -> tuple[Settings, np.ndarray | None] | None:
    """The settings and external pulse train a controller runs with on a move (``None``
    pulses: the V-F controller makes them), or ``None`` if it cannot run it."""
    c = resolve(c, move.plant)
    if isinstance(c, Settings):
        return c, None
    train = c.pulses(move.scenario, move.plant)
    return None if train is None else (Settings(ts_over_tf=c.ts_over_tf), train)


def score_pairs(
    controllers: Sequence[Controller],
    moves: Sequence[Any],
    *,
    measures: Measures = DEFAULT_MEASURES,
    weights: CostWeights = DEFAULT_WEIGHTS,
    bounds: Bounds = DEFAULT_BOUNDS,
) -> list[tuple[float, np.ndarray, np.ndarray, dict[str, Any]] | None]:
    """Score ``controllers[i]`` on ``moves[i]`` for every i in one compiled, multi-threaded
    call: (cost, constraints, objectives, measures) per pair, ``None`` where a pulse source
    cannot run the move. A move is a :class:`Move` or anything with its attributes (the
    envs' episodes); moves sharing a command array share it in the batch."""
    if len(controllers) != len(moves):
        raise ValueError(f"{len(controllers)} controllers for {len(moves)} moves")
    slots: dict[int, int] = {}
    cmds: list[np.ndarray] = []
    ext_parts: list[np.ndarray] = [np.zeros(0, np.int8)]
    prm, cmd_idx, ext_idx, rows = [], [], [], []
    for r, (c, mv) in enumerate(zip(controllers, moves, strict=True)):
        run = _as_run(c, mv)
        if run is None:
            continue
        settings, train = run
        j = slots.setdefault(id(mv.command), len(cmds))
        if j == len(cmds):
            cmds.append(mv.command)
        e = 0
        if train is not None:
            ext_parts.append(train)
            e = len(ext_parts) - 1
        cmd = mv.command
        prm.append(pack(settings, mv.plant, measures, float(cmd[-1]), cmd.size, e > 0))
        cmd_idx.append(j)
        ext_idx.append(e)
        rows.append(r)
    out: list[tuple[float, np.ndarray, np.ndarray, dict[str, Any]] | None] = [None] * len(moves)
    if not rows:
        return out
    acc = K.new_acc(len(rows))
    K.run_batch(
        np.concatenate(cmds),
        np.concatenate([[0], np.cumsum([c.size for c in cmds])]).astype(np.int64),
        np.array(cmd_idx, np.int64),
        np.concatenate(ext_parts),
        np.concatenate([[0], np.cumsum([x.size for x in ext_parts])]).astype(np.int64),
        np.array(ext_idx, np.int64),
        np.stack(prm),
        acc,
    )
    for k, r in enumerate(rows):
        mv = moves[r]
        m = from_acc(acc[k], mv.plant, measures, float(mv.command[-1]), mv.command_end_s)
        cost, cons, objs, extra = score(m, mv.scenario, mv.plant, measures, weights, bounds)
        out[r] = (float(cost), cons, objs, m | extra)
    return out


def evaluate(
    settings: Controller | Sequence[Controller],
    scenarios: str | Scenario | Sequence[str | Scenario] = "paper-step",
    *,
    plant: Plant = PAPER_PLANT,
    measures: Measures = DEFAULT_MEASURES,
    weights: CostWeights = DEFAULT_WEIGHTS,
    bounds: Bounds = DEFAULT_BOUNDS,
    keep_traces: bool = False,
    decimation: int = 1,
) -> Evaluation:
    """Score every controller on every scenario through one batched kernel call.

    settings: V-F :class:`Settings`, a baseline pulse source, a baseline name or
        :class:`~vfgym.baselines.Baseline` (derived per scenario plant), or a sequence.
    scenarios: names, :class:`Scenario` objects, or a set spec (``named``, ``train``, ...).
    plant: the base plant; each scenario applies its load to it.
    keep_traces: also return per-tick traces (simulated one by one; the measures are the
        batch's, and equal the traces' own).
    """
    ctrls = _check_controllers(settings)
    scens = scenario_set(scenarios)
    moves = [Move.of(sc, plant) for sc in scens]
    nc, ns = len(ctrls), len(scens)
    results = score_pairs(
        [c for c in ctrls for _ in moves],
        [mv for _ in ctrls for mv in moves],
        measures=measures,
        weights=weights,
        bounds=bounds,
    )
    nan_m = dict.fromkeys(METRIC_NAMES, math.nan)
    metrics = [[dict(nan_m) for _ in range(ns)] for _ in range(nc)]
    cost = np.full((nc, ns), np.nan)
    cons = np.full((nc, ns, len(CONSTRAINTS)), np.nan)
    objs = np.full((nc, ns, len(OBJECTIVES)), np.nan)
    traces: list[list[Trace | None]] | None = (
        [[None] * ns for _ in range(nc)] if keep_traces else None
    )
    for r, res in enumerate(results):
        ci, si = divmod(r, ns)
        if res is None:
            continue
        cost[ci, si], cons[ci, si], objs[ci, si], metrics[ci][si] = res
        if traces is not None:
            s, ext = _as_run(ctrls[ci], moves[si])
            traces[ci][si] = simulate(
                moves[si].command,
                s,
                moves[si].plant,
                pulses=ext,
                measures=measures,
                decimation=decimation,
            )
    return Evaluation(ctrls, scens, metrics, cost, cons, objs, traces)
