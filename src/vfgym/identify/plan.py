"""The moves to run for an identification, within the axis's limits.

Every parameter must leave its mark on the encoder's count (:mod:`vfgym.identify.excite`):

- trapezoids at :data:`SPEED_FRACTIONS` of the top speed, each forward then back:
  constant-speed segments at three speeds in both directions (viscous friction, Coulomb
  friction apart from the load torque), their ramps at a quarter of the usable
  acceleration (J/K3);
- on an axis that states a compliant transmission, first, bursts of pulses at the top speed
  (:data:`RESONANCE_BURST_S` long, forward and back, the highest jerk a pulse train asks)
  each followed by :data:`RESONANCE_REST_S` at rest, long enough for the load's ringing to
  show on the motor's encoder (:mod:`vfgym.identify.resonance`); a rigid axis's plan has
  none of them;
- velocity steps at nearly the top speed (``ramp`` moves), forward then back, then
  velocity reversals at that speed (``ramp`` moves one after the other with no rest: from
  +v to −v in one tick, eight times, back to where they started): the largest change of
  speed a pulse train can ask for, twice a step's, which holds the torque at its limit
  wherever the axis allows it (inertia apart from the drive's gain). Where even they do
  not, :attr:`Plan.saturating_inertia` says from which inertia they would.

The top speed is the lower of the pulse train's δ·f and :data:`MOTOR_SPEED_SHARE` of the
motor's maximum speed. :func:`moves_pulses` is the pulse train of the moves one after the
other, each starting where the last ended: the position command of each move followed at
most at the move's speed (a pulse generator following the profile: the reversals' steps
become moves at that speed, one leg ending the tick the next begins) and quantised to
whole pulses, after :data:`LEAD_S` at rest.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from vfgym.axis import Axis, PlantVariant
from vfgym.identify.excite import MIN_SATURATED_S
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

REVERSE_S = 0.03
"""Length of each leg of the velocity reversals (s): the first and last are half of it."""

REVERSALS = 8
"""Velocity reversals in the plan."""

INERTIA_FACTORS = (1.0, 1.25, 1.5, 2.0, 3.0, 4.0, 6.0, 8.0, 12.0, 16.0)
"""Factors on the nominal total inertia tried for :attr:`Plan.saturating_inertia`."""

RESONANCE_BURST_S = 0.001
"""Length of each burst of the resonance moves at the top speed (s): shorter than half a
period of every resonance the moves are for (up to a few hundred Hz)."""

RESONANCE_REST_S = 0.15
"""Rest after each burst (s): three periods of a 20 Hz resonance."""

RESONANCE_BURSTS = 4
"""Bursts in the resonance moves, forward and back in turn (they end where they began)."""

RESONANCE_MOVE = "identify-resonance"
"""The resonance moves' name in the plan."""

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
    saturating_inertia : float or None
        The least factor on the nominal total inertia (of :data:`INERTIA_FACTORS`) from
        which the moves hold the torque at its limit for
        :data:`~vfgym.identify.excite.MIN_SATURATED_S` (1: the nominal plant already
        does), or ``None`` if none does.
    """

    moves: tuple[Scenario, ...]
    pulses: np.ndarray
    tick_hz: float
    top_speed_rad_s: float
    saturated_s: float
    peak_torque_share: float
    saturating_inertia: float | None = None

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
        On a compliant axis the resonance moves (:func:`resonance_move`); then trapezoids
        at each speed forward and back, the velocity steps, the reversals.
    """
    v_top = top_speed(plant)
    a = RAMP_ACCEL_SHARE * plant.motor.usable_accel_rad_s2
    out = [] if plant.transmission is None else [resonance_move(plant)]
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
    legs = [0.5] + [1.0] * (REVERSALS - 1) + [0.5]
    steps = tuple(
        (round((1.0 if i % 2 == 0 else -1.0) * v * leg * REVERSE_S, 6), leg * REVERSE_S)
        for i, leg in enumerate(legs)
    )
    out.append(
        Scenario(
            name="identify-reverse",
            profile="multi",
            distance_rad=0.0,
            duration_s=round(REVERSALS * REVERSE_S + DWELL_S, 4),
            speed_rad_s=round(v, 6),
            moves=steps,
            description=f"{REVERSALS} velocity reversals between {v:+.4g} and {-v:+.4g} rad/s, "
            f"{REVERSE_S:g} s apart (steps followed at {v:.4g} rad/s): the largest change of "
            "speed",
        )
    )
    return tuple(out)


def resonance_move(plant: Plant) -> Scenario:
    """The moves that excite a compliant transmission's resonance (see the module doc).

    Parameters
    ----------
    plant : Plant
        The axis's (nominal) plant.

    Returns
    -------
    Scenario
        :data:`RESONANCE_BURSTS` steps of :data:`RESONANCE_BURST_S` at the top speed,
        forward and back in turn, each followed by :data:`RESONANCE_REST_S` at rest.
    """
    v = top_speed(plant)
    d = round(v * RESONANCE_BURST_S, 6)
    steps = tuple(((d if i % 2 == 0 else -d), RESONANCE_REST_S) for i in range(RESONANCE_BURSTS))
    return Scenario(
        name=RESONANCE_MOVE,
        profile="multi",
        distance_rad=0.0,
        duration_s=round(RESONANCE_BURSTS * RESONANCE_REST_S, 4),
        speed_rad_s=round(v, 6),
        moves=steps,
        description=f"{RESONANCE_BURSTS} bursts of {RESONANCE_BURST_S * 1e3:g} ms at "
        f"{v:.4g} rad/s, forward and back, each followed by {RESONANCE_REST_S:g} s at rest: "
        "the transmission's ringing",
    )


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
    """
    parts = [np.zeros(round(lead_s * plant.tick_hz))]
    pos = 0.0
    for sc in moves:
        c = pos + np.asarray(sc.command(plant), dtype=np.float64)
        parts.append(_follow(c, pos, min(sc.speed(plant), top_speed(plant)) / plant.tick_hz))
        pos = float(parts[-1][-1])
    cmd = np.concatenate(parts)
    n = np.floor(cmd / plant.pulse_rad + 0.5)
    return np.diff(n, prepend=0.0).astype(np.int8)


def _follow(cmd: np.ndarray, start: float, most: float) -> np.ndarray:
    """A position command followed from ``start`` at most ``most`` rad a tick (a pulse
    generator at its speed: a step becomes a move at that speed)."""
    if abs(cmd[0] - start) <= most * (1 + 1e-9) and np.all(
        np.abs(np.diff(cmd)) <= most * (1 + 1e-9)
    ):
        return cmd
    out = np.empty_like(cmd)
    p = start
    for k, c in enumerate(cmd.tolist()):
        p += min(max(c - p, -most), most)
        out[k] = p
    return out


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

    def run(p: Plant) -> tuple[float, float]:
        tr = simulate(np.zeros(pulses.size), settings, p, pulses=pulses, measures=DEFAULT_MEASURES)
        m = tr.metrics
        return float(m["torque_limit_time_s"]), float(m["peak_torque_nm"]) / p.motor.peak_torque_nm

    sat, share = run(plant)
    heavy = None
    for f in INERTIA_FACTORS:
        if (sat if f == 1.0 else run(PlantVariant(inertia=f).apply(plant))[0]) >= MIN_SATURATED_S:
            heavy = f
            break
    return Plan(
        moves=moves,
        pulses=pulses,
        tick_hz=plant.tick_hz,
        top_speed_rad_s=top_speed(plant),
        saturated_s=sat,
        peak_torque_share=share,
        saturating_inertia=heavy,
    )


__all__ = [
    "CRUISE_S",
    "DWELL_S",
    "INERTIA_FACTORS",
    "LEAD_S",
    "RESONANCE_BURSTS",
    "RESONANCE_BURST_S",
    "RESONANCE_MOVE",
    "RESONANCE_REST_S",
    "REVERSALS",
    "REVERSE_S",
    "SPEED_FRACTIONS",
    "Plan",
    "make_plan",
    "moves_pulses",
    "plan_moves",
    "resonance_move",
    "top_speed",
]
