"""The moves to run for an identification, within the axis's limits.

Every parameter must leave its mark on the encoder's count (:mod:`vfgym.identify.excite`):

- trapezoids at :data:`SPEED_FRACTIONS` of the top speed, each forward then back:
  constant-speed segments at three speeds in both directions (viscous friction, Coulomb
  friction apart from the load torque), their ramps at a quarter of the usable
  acceleration (J/K3);
- velocity steps at nearly the top speed (``ramp`` moves), forward then back: the
  shortest acceleration the pulse train can ask for, which saturates the torque where the
  axis allows it (inertia apart from the drive's gain).

The top speed is the lower of the pulse train's δ·f and :data:`MOTOR_SPEED_SHARE` of the
motor's maximum speed. :func:`plan_pulses` is the pulse train of the moves one after the
other, each starting where the last ended: the position command of each move quantised
to whole pulses, at most one a tick (a pulse generator following the profile), after
:data:`LEAD_S` at rest.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from vfgym.axis import Axis
from vfgym.moves.scenarios import Scenario
from vfgym.params import DEFAULT_MEASURES, PAPER_SETTINGS, Plant, Settings
from vfgym.plant import simulate

SPEED_FRACTIONS = (0.25, 0.5, 0.75)
"""Cruise speeds of the trapezoids, as fractions of the top speed."""

STEP_FRACTION = 0.97
"""Speed of the velocity steps, as a fraction of the top speed."""

MOTOR_SPEED_SHARE = 0.95
"""The top speed is at most this share of the motor's maximum speed."""

RAMP_ACCEL_SHARE = 0.25
"""The trapezoids' acceleration, as a share of the loaded motor's usable acceleration."""

CRUISE_S = 0.18
"""Cruise time of each trapezoid (s): several servo time constants of constant speed."""

STEP_S = 0.03
"""Length of each velocity step (s)."""

DWELL_S = 0.05
"""Rest after each move (s), included in its duration."""

LEAD_S = 0.02
"""Rest before the first move (s)."""


@dataclass(frozen=True)
class Plan:
    """The identification moves of an axis.

    Attributes
    ----------
    moves : tuple of Scenario
        The moves in the order to run them.
    pulses : numpy.ndarray
        The pulse train of all of them (−1, 0, +1 per controller tick).
    tick_hz : float
        The controller's tick rate (Hz).
    top_speed_rad_s : float
        The top speed the moves use (rad/s).
    saturated_s : float
        Time the nominal plant spends at its torque limit during the moves (s).
    peak_torque_share : float
        The largest torque of the nominal plant over its peak torque.
    """

    moves: tuple[Scenario, ...]
    pulses: np.ndarray
    tick_hz: float
    top_speed_rad_s: float
    saturated_s: float
    peak_torque_share: float

    @property
    def duration_s(self) -> float:
        """Length of the pulse train (s)."""
        return float(self.pulses.size) / self.tick_hz


def top_speed(plant: Plant) -> float:
    """The top speed of the identification moves (rad/s).

    Parameters
    ----------
    plant : Plant
        The axis's plant.

    Returns
    -------
    float
        The lower of δ·f and :data:`MOTOR_SPEED_SHARE` of the motor's maximum speed.
    """
    return min(plant.pulse_top_speed_rad_s, MOTOR_SPEED_SHARE * plant.motor.max_speed_rad_s)


def plan_moves(plant: Plant) -> tuple[Scenario, ...]:
    """The identification moves (see the module doc).

    Parameters
    ----------
    plant : Plant
        The axis's (nominal) plant.

    Returns
    -------
    tuple of Scenario
        Trapezoids at each speed forward and back, then the velocity steps.
    """
    v_top = top_speed(plant)
    a = RAMP_ACCEL_SHARE * plant.motor.usable_accel_rad_s2
    out = []
    for i, frac in enumerate(SPEED_FRACTIONS, start=1):
        v = frac * v_top
        d = v * CRUISE_S + v * v / a
        dur = d / v + v / a + DWELL_S
        for sign, word in ((1.0, "fwd"), (-1.0, "back")):
            out.append(
                Scenario(
                    name=f"identify-speed{i}-{word}",
                    profile="trapezoid",
                    distance_rad=round(sign * d, 6),
                    duration_s=round(dur, 4),
                    speed_rad_s=round(v, 6),
                    accel_rad_s2=round(a, 3),
                    description=f"constant speed {v:.4g} rad/s for {CRUISE_S:g} s ({word})",
                )
            )
    v = STEP_FRACTION * v_top
    d = v * STEP_S
    for sign, word in ((1.0, "fwd"), (-1.0, "back")):
        out.append(
            Scenario(
                name=f"identify-step-{word}",
                profile="ramp",
                distance_rad=round(sign * d, 6),
                duration_s=round(STEP_S + DWELL_S, 4),
                speed_rad_s=round(v, 6),
                description=f"velocity step to {v:.4g} rad/s for {STEP_S:g} s ({word}): "
                "the shortest acceleration",
            )
        )
    return tuple(out)


def moves_pulses(moves: tuple[Scenario, ...], plant: Plant, lead_s: float = LEAD_S) -> np.ndarray:
    """The pulse train of moves run one after the other (see the module doc).

    Parameters
    ----------
    moves : tuple of Scenario
        The moves.
    plant : Plant
        Gives the tick rate and the pulse equivalent δ.
    lead_s : float
        Rest before the first move (s).

    Returns
    -------
    numpy.ndarray
        int8, −1, 0, +1 per tick.

    Raises
    ------
    ValueError
        If a move asks for more than one pulse a tick (faster than δ·f).
    """
    parts = [np.zeros(round(lead_s * plant.tick_hz))]
    pos = 0.0
    for sc in moves:
        c = np.asarray(sc.command(plant), dtype=np.float64)
        parts.append(pos + c)
        pos += float(c[-1])
    parts[0] = np.zeros(parts[0].size)
    cmd = np.concatenate(parts)
    n = np.floor(cmd / plant.pulse_rad + 0.5)
    p = np.diff(n, prepend=0.0)
    if np.any(np.abs(p) > 1):
        raise ValueError(
            "a move asks for more than one pulse a tick: its speed exceeds delta*f "
            f"= {plant.pulse_top_speed_rad_s:.4g} rad/s"
        )
    return p.astype(np.int8)


def make_plan(axis: Axis, settings: Settings = PAPER_SETTINGS) -> Plan:
    """The identification plan of an axis, checked on its nominal plant.

    Parameters
    ----------
    axis : Axis
        The nominal axis.
    settings : Settings
        The servo's filter ratio in force.

    Returns
    -------
    Plan
        The moves, their pulse train and how far they load the nominal plant.
    """
    plant = axis.plant
    moves = plan_moves(plant)
    pulses = moves_pulses(moves, plant)
    tr = simulate(np.zeros(pulses.size), settings, plant, pulses=pulses, measures=DEFAULT_MEASURES)
    m = tr.metrics
    return Plan(
        moves=moves,
        pulses=pulses,
        tick_hz=plant.tick_hz,
        top_speed_rad_s=top_speed(plant),
        saturated_s=float(m["torque_limit_time_s"]),
        peak_torque_share=float(m["peak_torque_nm"]) / plant.motor.peak_torque_nm,
    )


__all__ = [
    "CRUISE_S",
    "DWELL_S",
    "LEAD_S",
    "SPEED_FRACTIONS",
    "Plan",
    "make_plan",
    "moves_pulses",
    "plan_moves",
    "top_speed",
]
