"""Named, frozen scenarios: a command and the plant it drives.

A scenario is data: a profile with its numbers, a duration, and the load it adds to the
base plant (load inertia, friction, load torque). ``command()`` and ``plant()`` build
what the simulator needs; both are cached, so every caller (env, objective, evaluation)
simulates exactly the same arrays. Random moves and the resolution of names are in
:mod:`vfgym.moves.distribution`.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from vfgym._limits import MAX_MOVE_TICKS
from vfgym._validate import check_choice, check_real
from vfgym.moves import profiles
from vfgym.params import PAPER_PLANT, PAPER_STEP_RAD, Plant

PAPER_SINE_AMPLITUDE_RAD = 5.0
"""Fig. 5's sine: the text gives no numbers. 5 rad at 10 Hz peaks at 314 rad/s (73 % of
v_max) and 19.7 krad/s² (14 % of the motor's limit): well inside both."""
PAPER_SINE_FREQ_HZ = 10.0

SPLITS = ("train", "test")
DRAWN_PROFILES = ("step", "ramp", "trapezoid", "scurve")
"""The profiles a :class:`~vfgym.moves.distribution.MoveDistribution` may draw: single
point-to-point moves."""


def ideal_move_time_s(distance_rad: float, plant: Plant) -> float:
    """The shortest time for one move: bang–coast–bang at the pulse train's top speed δ·f
    and the loaded motor's usable acceleration (:attr:`vfgym.Motor.usable_accel_rad_s2`).

    Parameters
    ----------
    distance_rad : float
        The move (its sign does not matter).
    plant : Plant
        The plant with its load (``Scenario.plant(base)``).

    Returns
    -------
    float
        The time (s): ``d/v + v/a`` when the move reaches v, else ``2·sqrt(d/a)``.
    """
    v = plant.pulse_top_speed_rad_s
    a = plant.motor.usable_accel_rad_s2
    d = abs(distance_rad)
    return d / v + v / a if d * a >= v * v else 2.0 * math.sqrt(d / a)


@dataclass(frozen=True)
class Scenario:
    """One move: a command profile and the plant it drives.

    Parameters
    ----------
    name : str
        The scenario's name (``paper-step``, ``train-3`` …).
    profile : str
        One of :data:`vfgym.moves.profiles.PROFILES`.
    distance_rad : float
        The move (the amplitude for ``sine``), nonzero except for ``multi``; negative moves
        go backwards.
    duration_s : float
        How long to simulate (s), including time to settle; in (0, 60].
    speed_rad_s, accel_rad_s2 : float or None
        Cruise speed and acceleration of ramp / trapezoid / scurve profiles (default: the
        pulse train's top speed δ·f and the loaded motor's usable
        acceleration).
    freq_hz : float
        Sine frequency (Hz).
    moves : tuple of (float, float)
        For ``multi``: (relative distance rad, dwell s) pairs.
    inertia_ratio, coulomb_nm, viscous_nm_s_rad, load_torque_nm : float
        The load this move adds to the base plant's own (a payload; the paper's plant has
        none), as in :class:`vfgym.Motor`.
    description : str
        One line for listings (not compared).

    Raises
    ------
    ValueError
        If the profile is unknown, the distance is zero for a single move, the duration
        is out of range, or ``multi`` has no moves.
    """

    name: str
    profile: str = "step"
    distance_rad: float = PAPER_STEP_RAD
    duration_s: float = 0.15
    speed_rad_s: float | None = None
    accel_rad_s2: float | None = None
    freq_hz: float = PAPER_SINE_FREQ_HZ
    moves: tuple[tuple[float, float], ...] = ()
    inertia_ratio: float = 0.0
    coulomb_nm: float = 0.0
    viscous_nm_s_rad: float = 0.0
    load_torque_nm: float = 0.0
    description: str = field(default="", compare=False)

    def __post_init__(self) -> None:
        check_choice("profile", self.profile, profiles.PROFILES)
        d = check_real("distance_rad", self.distance_rad)
        if d == 0.0 and self.profile != "multi":
            raise ValueError(
                f"distance_rad={self.distance_rad!r} is not allowed for profile "
                f"{self.profile!r}: allowed any nonzero distance (rad)"
            )
        check_real("duration_s", self.duration_s, 0.0, 60.0, lo_open=True)
        if self.profile == "multi" and not self.moves:
            raise ValueError("moves=() is not allowed for profile 'multi': give (distance, dwell)")
        object.__setattr__(self, "moves", _pairs(self.moves))
        for name in ("speed_rad_s", "accel_rad_s2"):
            if getattr(self, name) is not None:
                check_real(name, getattr(self, name), 0.0, lo_open=True)
        check_real("freq_hz", self.freq_hz, 0.0, lo_open=True)
        for name in ("inertia_ratio", "coulomb_nm", "viscous_nm_s_rad"):
            check_real(name, getattr(self, name), 0.0)
        check_real("load_torque_nm", self.load_torque_nm)

    @property
    def tracking(self) -> bool:
        """True for a moving reference (sine), judged by tracking error, not settling."""
        return self.profile == "sine"

    def plant(self, base: Plant = PAPER_PLANT) -> Plant:
        """The base plant with this scenario's load added to its own.

        Parameters
        ----------
        base : Plant
            The plant before the load.

        Returns
        -------
        Plant
            ``base`` with this scenario's inertia ratio, friction and load torque added.
        """
        m = base.motor
        return base.with_motor(
            inertia_ratio=m.inertia_ratio + self.inertia_ratio,
            coulomb_nm=m.coulomb_nm + self.coulomb_nm,
            viscous_nm_s_rad=m.viscous_nm_s_rad + self.viscous_nm_s_rad,
            load_torque_nm=m.load_torque_nm + self.load_torque_nm,
        )

    def command(self, plant: Plant = PAPER_PLANT) -> np.ndarray:
        """The position command per tick (rad), read-only and cached.

        Parameters
        ----------
        plant : Plant
            Gives the tick rate, pulse equivalent and default speed and acceleration.

        Returns
        -------
        numpy.ndarray
            float64, read-only: every caller simulates the same array.

        Raises
        ------
        ValueError
            If the move is longer than a simulation holds (2^24 ticks at the
            plant's tick rate: 120 s at 140 kHz).
        """
        span = self.duration_s
        if self.profile == "multi":
            span = max(span, sum(dwell for _, dwell in self.moves))
        ticks = span * plant.tick_hz
        if ticks > MAX_MOVE_TICKS:
            raise ValueError(
                f"duration_s={span:g} at tick_hz={plant.tick_hz:g} is out of range: "
                f"{ticks:.4g} ticks; allowed at most {MAX_MOVE_TICKS} ticks a move "
                f"({MAX_MOVE_TICKS / plant.tick_hz:.4g} s at this tick rate)"
            )
        return _command(self, plant)

    def speed(self, plant: Plant) -> float:
        """The profile's cruise speed (rad/s).

        Parameters
        ----------
        plant : Plant
            Gives the default, the pulse train's top speed δ·f.

        Returns
        -------
        float
            ``speed_rad_s`` if set, else δ·f.
        """
        return self.speed_rad_s if self.speed_rad_s is not None else plant.pulse_top_speed_rad_s

    def accel(self, plant: Plant) -> float:
        """The profile's acceleration (rad/s²).

        Parameters
        ----------
        plant : Plant
            Gives the default, the loaded motor's usable acceleration.

        Returns
        -------
        float
            ``accel_rad_s2`` if set, else the motor's ``accel_limit_rad_s2``.
        """
        return (
            self.accel_rad_s2 if self.accel_rad_s2 is not None else plant.motor.usable_accel_rad_s2
        )

    def move_list(self, plant: Plant = PAPER_PLANT) -> list[tuple[int, float]]:
        """Point-to-point moves, for pulse sources that replace the V-F controller.

        Parameters
        ----------
        plant : Plant
            Gives the tick rate (dwells in ticks).

        Returns
        -------
        list of (int, float)
            (start tick, relative distance rad) per move; empty for a moving reference.
        """
        if self.tracking:
            return []
        if self.profile != "multi":
            return [(0, self.distance_rad)]
        out, tick = [], 0
        for dist, dwell in self.moves:
            out.append((tick, dist))
            tick += max(1, round(dwell * plant.tick_hz))
        return out

    def ideal_time_s(self, plant: Plant = PAPER_PLANT) -> float:
        """Shortest time for the moves: the yardstick for move times (docs/model.md §6).

        Parameters
        ----------
        plant : Plant
            Gives the pulse train's top speed δ·f and the motor's acceleration limit.

        Returns
        -------
        float
            :func:`ideal_move_time_s` on ``plant`` (this scenario's loaded plant); for
            ``multi`` the last move's start plus its ideal time; for a moving reference
            the duration.
        """
        moves = self.move_list(plant)
        if not moves:
            return self.duration_s
        start, dist = moves[-1]
        return start / plant.tick_hz + ideal_move_time_s(dist, plant)

    def with_(self, **changes: Any) -> Scenario:
        """A copy with some fields changed (validated again).

        Parameters
        ----------
        **changes
            Fields of :class:`Scenario` and their new values.

        Returns
        -------
        Scenario
            The new scenario.
        """
        return replace(self, **changes)


def _pairs(moves: Any) -> tuple[tuple[float, float], ...]:
    """A ``multi`` scenario's moves as (distance rad, dwell s) pairs of floats."""
    out = []
    for i, pair in enumerate(moves):
        if isinstance(pair, (str, bytes)) or not hasattr(pair, "__len__") or len(pair) != 2:
            raise ValueError(
                f"moves[{i}]={pair!r} is not allowed: give a pair [distance_rad, dwell_s]"
            )
        d = check_real(f"moves[{i}].distance_rad", pair[0])
        out.append((d, check_real(f"moves[{i}].dwell_s", pair[1], 0.0, lo_open=True)))
    return tuple(out)


@functools.lru_cache(maxsize=256)
def _command(sc: Scenario, plant: Plant) -> np.ndarray:
    v, a = sc.speed(plant), sc.accel(plant)
    tick_hz, pulse_rad = plant.tick_hz, plant.pulse_rad
    d, dur = sc.distance_rad, sc.duration_s
    if sc.profile == "step":
        c = profiles.step(d, dur, tick_hz)
    elif sc.profile == "sine":
        c = profiles.sine(d, sc.freq_hz, dur, tick_hz)
    elif sc.profile == "ramp":
        c = profiles.ramp(d, v, dur, tick_hz)
    elif sc.profile == "trapezoid":
        c = profiles.trapezoid(d, v, a, dur, tick_hz)
    elif sc.profile == "scurve":
        c = profiles.scurve(d, v, a, dur, tick_hz, pulse_rad)
    else:
        c = profiles.multi(sc.moves, tick_hz)
        n = max(1, round(dur * tick_hz))
        c = np.concatenate([c, np.full(max(0, n - c.size), c[-1])])[:n]
    c.setflags(write=False)
    return c


SCENARIOS: dict[str, Scenario] = {
    s.name: s
    for s in (
        Scenario(
            "paper-step",
            "step",
            PAPER_STEP_RAD,
            0.15,
            description="the paper's Fig. 4: a 10 rad step, bare SGME-02A",
        ),
        Scenario(
            "paper-sine",
            "sine",
            PAPER_SINE_AMPLITUDE_RAD,
            0.3,
            description="the paper's Fig. 5: 5 rad, 10 Hz sine (3 periods)",
        ),
        Scenario(
            "short-move",
            "step",
            0.5,
            0.06,
            description="0.5 rad: too short to reach top speed (triangle regime)",
        ),
        Scenario(
            "long-move", "step", 100.0, 0.40, description="100 rad: a long cruise at top speed"
        ),
        Scenario(
            "reversal",
            "multi",
            0.0,
            0.20,
            moves=((5.0, 0.02), (-10.0, 0.18)),
            description="to +5 rad, then straight back to −5 rad after 20 ms",
        ),
        Scenario(
            "heavy-load",
            "step",
            PAPER_STEP_RAD,
            0.30,
            inertia_ratio=5.0,
            description="the paper step with a load of 5× the rotor's inertia",
        ),
        Scenario(
            "friction",
            "step",
            PAPER_STEP_RAD,
            0.15,
            coulomb_nm=0.003,
            viscous_nm_s_rad=2e-4,
            description="the paper step with Coulomb 3 mN·m and viscous 0.2 mN·m·s/rad "
            "(the P-type servo's dead band τc/K3 stays inside the in-position window)",
        ),
        Scenario(
            "multi-move",
            "multi",
            0.0,
            0.36,
            moves=((3.0, 0.06), (-6.0, 0.07), (1.5, 0.05), (8.0, 0.08), (-6.5, 0.10)),
            description="five moves with dwells, both directions",
        ),
    )
}
