"""The one scoring path: controller settings → simulate → measures → constraints → cost.

:func:`evaluate` is what every part of vfgym asks "how good is this setting on this move":
the Gymnasium envs' reward, the Optuna objective and constraints, and the evaluation
reports. It takes a batch of controllers (V-F :class:`~vfgym.Settings` or a baseline pulse
source) and a list of scenarios, runs every pair in one compiled, multi-threaded call
that keeps only the streamed measures, and returns them with the constraint values, the
objectives and the scalar cost.

Cost of one run (lower is better; weights in :class:`CostWeights`; :class:`CostTerms`)::

    cost = time · move_time / ideal_time          (point-to-point moves)
         | tracking · rms_tracking / (10 % of |amplitude|)  (a moving reference)
         + overshoot · overshoot / in-position window
         + accel · max(0, accel constraint)
         + torque · time at the torque limit / ideal_time
         + [not arrived] · (unsettled + arrival · arrival constraint)
         + [a transmission] · residual · the load's residual vibration / in-position window

ideal_time is the bang–coast–bang time at δ·f and the loaded motor's usable acceleration
(:func:`vfgym.moves.scenarios.ideal_move_time_s`), so a perfect move costs about 1
whatever its length, and scenarios average fairly.

The first four terms can be known while the move runs: the VFServo-v0 env's running cost
is the same formula, compiled, on the measures streamed so far
(:mod:`vfgym.scoring._cost_compiled`). The last two are known only at the scenario's end:
the *residual term* (:func:`residual_term`) and the *arrival term*, added in one place,
:func:`arrival_term`.

Where the plant states a transmission (a compliant load, docs/model.md §3.1), the cost
judges the load, not the motor: move time, overshoot, tracking error and arrival are the
load's (``load_…`` measures, :mod:`vfgym.plant.measures`); the encoder on the motor may
read "in position" while the tool still rings (:attr:`Yardsticks.load`). There the cost
also prices the load's residual vibration, peak to peak from the motor's move time to the
run's end (``load_residual_vibration_rad``), at ``residual`` per in-position window, the
price of a window of overshoot: ringing inside the window costs no move time, and without
this term a tuner would trade it for time. A rigid plant has no such term (its cost is
bit for bit what it was before it).

Arrival. A point-to-point move *arrives* when the motor is in the in-position window at
the scenario's end (the measure ``settled``); a moving reference arrives when the motor
follows it: the RMS tracking error is at most 1/√2 of the reference's own RMS (the error
of a motor that never moves), i.e. the error's power at most half the reference's, the
reference within the −3 dB bandwidth of the loop's sensitivity. A run that does not
arrive is infeasible, and costs more than any feasible run that arrives on the same move:
its main term is already the largest any run can have (its move time is the run's whole
duration; its tracking error exceeds any follower's), and its arrival term (``unsettled``
plus ``arrival`` per in-position window still to go) exceeds what a feasible run pays for
overshoot and torque (at most overshoot · ``overshoot_windows`` + torque ·
``torque_limit_time_s`` / ideal_time: 0.1 with the defaults, against 5). A controller that
never moves is the extreme case: on the paper's 10 rad step it ends 1,630 windows short.

Constraints (feasible when ≤ 0; :class:`Bounds`):

- ``accel``: peak pulse-train acceleration / limit − 1 − the stated tolerance
  (``Measures.accel_tolerance_pct``, 1 %), the limit being the loaded motor's usable
  acceleration (:attr:`vfgym.Motor.usable_accel_rad_s2`): a feasible run never reports a
  peak above limit · (1 + tolerance). The V-F train's position is measured unquantised,
  an external train's count over a window whose one-pulse quantum is within the tolerance
  (:func:`vfgym.plant.measures.accel_window_ticks`, docs/model.md §5.1)
- ``torque``: time at the torque limit − ``Bounds.torque_limit_time_s``
- ``overshoot``: overshoot − ``Bounds.overshoot_windows`` in-position windows
- ``arrival``: point-to-point, (|final error| − window) / window, the in-position windows
  beyond the window at the scenario's end (in encoder counts if the window is zero); a
  moving reference, √2 · RMS tracking error / RMS of the reference − 1

Objectives (all minimised): overshoot in in-position windows, move time / ideal time
(tracking ratio for a moving reference), acceleration violation max(0, accel constraint).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np

from vfgym.moves.scenarios import Scenario
from vfgym.params import (
    Measures,
    Plant,
    in_position_rad,
)

CONSTRAINTS = ("accel", "torque", "overshoot", "arrival")
OBJECTIVES = ("overshoot_windows", "time_ratio", "accel_violation")
TRACKING_SCALE = 0.1
"""The tracking term's yardstick: this share of the reference's amplitude."""
FOLLOW_RATIO = 1.0 / math.sqrt(2.0)
"""A moving reference is followed when RMS error ≤ this × the reference's RMS (−3 dB)."""


@dataclass(frozen=True)
class CostWeights:
    """Weights of the scalar cost (the formula: the module docstring, docs/model.md §6).

    Parameters
    ----------
    time : float
        Weight of move time / ideal time (point-to-point moves).
    tracking : float
        Weight of RMS tracking error / 10 % of the amplitude (a moving reference).
    overshoot : float
        Weight of the overshoot in in-position windows.
    accel : float
        Weight of the acceleration violation max(0, accel constraint).
    torque : float
        Weight of the time at the torque limit / ideal time.
    unsettled : float
        The arrival term's fixed part: added when the run does not arrive.
    arrival : float
        The arrival term's price per unit of the arrival constraint (per in-position
        window still to go; for a moving reference, per unit of the tracking
        constraint): the same price per window as an overshoot.
    residual : float
        The price of the load's residual vibration (peak to peak) per in-position window,
        where the plant states a transmission: the same price per window as an
        overshoot.
    """

    time: float = 1.0
    tracking: float = 1.0
    overshoot: float = 0.1
    accel: float = 5.0
    torque: float = 1.0
    unsettled: float = 5.0
    arrival: float = 0.1
    residual: float = 0.1


@dataclass(frozen=True)
class Bounds:
    """Bounds of the constraints (feasible when each constraint ≤ 0; docs/model.md §6).

    Parameters
    ----------
    overshoot_windows : float
        Overshoot allowed, in in-position windows.
    torque_limit_time_s : float
        Time allowed at the torque limit (s).
    """

    overshoot_windows: float = 1.0
    torque_limit_time_s: float = 0.0


DEFAULT_WEIGHTS = CostWeights()
DEFAULT_BOUNDS = Bounds()


class Yardsticks(NamedTuple):
    """What a move's measures are judged against (fixed by the move, not the run).

    What :func:`yardsticks` returns; :func:`score` and the compiled running cost
    (:mod:`vfgym.scoring._cost_compiled`) both read them.

    Attributes
    ----------
    ideal_time_s : float
        Bang–coast–bang time of the moves (:meth:`vfgym.Scenario.ideal_time_s`; the
        sine's duration for a moving reference).
    window_rad : float
        In-position half-width around the final command.
    accel_limit_rad_s2 : float
        The loaded motor's usable acceleration
        (:attr:`vfgym.Motor.usable_accel_rad_s2`), the accel constraint's yardstick.
    accel_tolerance : float
        The accel constraint's tolerance as a fraction of the limit
        (``Measures.accel_tolerance_pct`` / 100).
    tracking : bool
        A moving reference, judged by tracking error.
    tracking_scale_rad : float
        :data:`TRACKING_SCALE` × |amplitude|, the tracking term's unit.
    reference_rms_rad : float
        RMS of the command over the move: the tracking error of a motor that never moves.
    arrival_unit_rad : float
        The point-to-point arrival constraint's unit: the window, or one count if it is 0.
    load : bool
        The plant states a transmission: the load's measures are judged, not the motor's.
    """

    ideal_time_s: float
    window_rad: float
    accel_limit_rad_s2: float
    accel_tolerance: float
    tracking: bool
    tracking_scale_rad: float
    reference_rms_rad: float
    arrival_unit_rad: float
    load: bool = False


_YARDSTICKS: dict[tuple[Scenario, Plant, Measures], Yardsticks] = {}
_YARDSTICKS_KEPT = 256


def yardsticks(
    scenario: Scenario, plant: Plant, measures: Measures, command: np.ndarray | None = None
) -> Yardsticks:
    """The yardsticks of ``scenario`` on ``plant`` (its loaded plant), cached.

    Parameters
    ----------
    scenario : Scenario
        The move.
    plant : Plant
        The plant it runs on (the scenario's load applied).
    measures : Measures
        The in-position window's definition.
    command : numpy.ndarray or None
        The move's command, ``scenario.command(plant)``, when the caller has built it
        already (the envs' episodes), so that it is not built twice.

    Returns
    -------
    Yardsticks
        The move's ideal time, in-position window, usable acceleration and tracking and
        arrival units.
    """
    key = (scenario, plant, measures)
    y = _YARDSTICKS.get(key)
    if y is not None:
        return y
    cmd = scenario.command(plant) if command is None else command
    window = in_position_rad(measures, plant, float(cmd[-1]))
    y = Yardsticks(
        ideal_time_s=scenario.ideal_time_s(plant),
        window_rad=window,
        accel_limit_rad_s2=plant.motor.usable_accel_rad_s2,
        accel_tolerance=measures.accel_tolerance_pct / 100.0,
        tracking=scenario.tracking,
        tracking_scale_rad=TRACKING_SCALE * abs(scenario.distance_rad),
        # numpy's pairwise sum, not np.dot: BLAS's threaded dot took ~15 ms a move on a
        # busy machine (its threads waking), and its sum depended on their number
        reference_rms_rad=math.sqrt(float(np.square(cmd).sum()) / cmd.size),
        arrival_unit_rad=window if window > 0.0 else plant.motor.count_rad,
        load=plant.transmission is not None,
    )
    if len(_YARDSTICKS) >= _YARDSTICKS_KEPT:  # the oldest goes first
        del _YARDSTICKS[next(iter(_YARDSTICKS))]
    _YARDSTICKS[key] = y
    return y


class CostTerms(NamedTuple):
    """The cost's terms, in the order they are summed (see the module docstring).

    Attributes
    ----------
    main : float
        time · move time / ideal, or tracking · RMS error / its yardstick.
    overshoot : float
        overshoot · overshoot in in-position windows.
    accel : float
        accel · max(0, accel constraint).
    torque : float
        torque · time at the torque limit / ideal time.
    arrival : float
        0 for a run that arrives, else unsettled + arrival · arrival constraint
        (:func:`arrival_term`).
    residual : float
        residual · the load's residual vibration in in-position windows where the plant
        states a transmission, else 0 (:func:`residual_term`).
    """

    main: float
    overshoot: float
    accel: float
    torque: float
    arrival: float
    residual: float = 0.0

    @property
    def running(self) -> float:
        """The four terms the compiled running cost also computes, summed in its order."""
        return self.main + self.overshoot + self.accel + self.torque

    @property
    def total(self) -> float:
        """The cost: the running terms, then the arrival term, then the residual term (0 on
        a rigid plant, which leaves the sum bit for bit what it was without it)."""
        return self.running + self.arrival + self.residual


class Score(NamedTuple):
    """One run scored: what :func:`score` returns.

    Attributes
    ----------
    cost : float
        The scalar cost (:attr:`CostTerms.total`).
    constraints : numpy.ndarray
        float, in the order of :data:`CONSTRAINTS`; feasible when each ≤ 0.
    objectives : numpy.ndarray
        float, in the order of :data:`OBJECTIVES`.
    metrics : dict
        The run's measures plus ``ideal_time_s``, ``time_ratio``, ``window_rad`` and
        ``arrived``.
    terms : CostTerms
        The cost's terms.
    """

    cost: float
    constraints: np.ndarray
    objectives: np.ndarray
    metrics: dict[str, Any]
    terms: CostTerms

    @property
    def feasible(self) -> bool:
        """Every constraint ≤ 0."""
        return bool(np.all(self.constraints <= 0.0))


def judged(m: dict[str, Any], y: Yardsticks, name: str) -> float:
    """The measure ``name`` of what the cost judges: the load's (``load_`` + ``name``)
    where the plant states a transmission (:attr:`Yardsticks.load`), else the motor's.

    Parameters
    ----------
    m : dict
        The run's measures (:mod:`vfgym.plant.measures`).
    y : Yardsticks
        The move's yardsticks.
    name : str
        A motor measure with a load counterpart: ``move_time_s``, ``overshoot_rad``,
        ``tracking_rms_rad``, ``final_error_rad``.

    Returns
    -------
    float
        The measure.
    """
    return float(m[f"load_{name}" if y.load else name])


def arrival_constraint(m: dict[str, Any], y: Yardsticks) -> float:
    """How far a run is from arriving (> 0: it did not; see the module docstring).

    Parameters
    ----------
    m : dict
        The run's measures (:mod:`vfgym.plant.measures`).
    y : Yardsticks
        The move's yardsticks.

    Returns
    -------
    float
        Point-to-point: the in-position windows beyond the window at the end, whose sign
        is exactly that of "not settled"; a moving reference: √2 · RMS error / RMS of the
        reference − 1.
    """
    if y.tracking:
        if y.reference_rms_rad <= 0.0:
            return 0.0
        return judged(m, y, "tracking_rms_rad") / (FOLLOW_RATIO * y.reference_rms_rad) - 1.0
    return (abs(judged(m, y, "final_error_rad")) - y.window_rad) / y.arrival_unit_rad


def arrival_term(c_arrival: float, weights: CostWeights) -> float:
    """The end-of-move cost term: 0 for a run that arrives (``c_arrival`` ≤ 0), else
    ``unsettled + arrival · c_arrival``.

    Parameters
    ----------
    c_arrival : float
        The arrival constraint (:func:`arrival_constraint`).
    weights : CostWeights
        Weights of the cost (``unsettled`` and ``arrival``).

    Returns
    -------
    float
        The term, ≥ 0.
    """
    if c_arrival <= 0.0:
        return 0.0
    return weights.unsettled + weights.arrival * c_arrival


def residual_term(m: dict[str, Any], y: Yardsticks, weights: CostWeights) -> float:
    """The load's residual vibration term: ``residual`` × the load's residual vibration
    (peak to peak, ``load_residual_vibration_rad``) in in-position windows, where the
    plant states a transmission (:attr:`Yardsticks.load`); 0 on a rigid plant or with a
    zero window.

    Parameters
    ----------
    m : dict
        The run's measures (:mod:`vfgym.plant.measures`).
    y : Yardsticks
        The move's yardsticks.
    weights : CostWeights
        Weights of the cost (``residual``).

    Returns
    -------
    float
        The term, ≥ 0.
    """
    if not y.load or y.window_rad <= 0.0:
        return 0.0
    return weights.residual * float(m["load_residual_vibration_rad"]) / y.window_rad


def score(
    m: dict[str, Any],
    scenario: Scenario,
    plant: Plant,
    measures: Measures,
    weights: CostWeights = DEFAULT_WEIGHTS,
    bounds: Bounds = DEFAULT_BOUNDS,
) -> Score:
    """Cost, constraints and objectives of one run's measures (docs/model.md §6).

    Parameters
    ----------
    m : dict
        The run's measures, as :attr:`vfgym.Trace.metrics` gives them
        (:func:`vfgym.plant.measures.from_acc`).
    scenario : Scenario
        The scenario run (point-to-point or a moving reference; its ideal time).
    plant : Plant
        The plant it ran on, the scenario's load applied (usable acceleration, encoder
        count).
    measures : Measures
        Windows and bands the measures were taken with (the in-position window).
    weights : CostWeights
        Weights of the cost.
    bounds : Bounds
        Bounds of the constraints.

    Returns
    -------
    Score
        The scalar cost; the constraint values in the order of :data:`CONSTRAINTS` and
        the objectives in the order of :data:`OBJECTIVES` (float arrays of 4 and 3); the
        measures merged with ``ideal_time_s``, ``time_ratio``, ``window_rad`` and
        ``arrived``; and the cost's terms.
    """
    y = yardsticks(scenario, plant, measures)
    ideal, window, limit = y.ideal_time_s, y.window_rad, y.accel_limit_rad_s2
    c_acc = m["peak_accel_pulse_rad_s2"] / limit - 1.0 - y.accel_tolerance
    c_tq = m["torque_limit_time_s"] - bounds.torque_limit_time_s
    ov_w = judged(m, y, "overshoot_rad") / window if window > 0.0 else 0.0
    c_ov = ov_w - bounds.overshoot_windows
    c_arr = arrival_constraint(m, y)
    if y.tracking:
        rms = judged(m, y, "tracking_rms_rad")
        ratio = rms / y.tracking_scale_rad if y.tracking_scale_rad > 0.0 else 0.0
        main = weights.tracking * ratio
    else:
        ratio = judged(m, y, "move_time_s") / ideal
        main = weights.time * ratio
    terms = CostTerms(
        main=main,
        overshoot=weights.overshoot * ov_w,
        accel=weights.accel * max(0.0, c_acc),
        torque=weights.torque * m["torque_limit_time_s"] / ideal,
        arrival=arrival_term(c_arr, weights),
        residual=residual_term(m, y, weights),
    )
    extra = {
        "ideal_time_s": ideal,
        "time_ratio": ratio,
        "window_rad": window,
        "arrived": bool(c_arr <= 0.0),
    }
    return Score(
        cost=float(terms.total),
        constraints=np.array([c_acc, c_tq, c_ov, c_arr]),
        objectives=np.array([ov_w, ratio, max(0.0, c_acc)]),
        metrics=m | extra,
        terms=terms,
    )
