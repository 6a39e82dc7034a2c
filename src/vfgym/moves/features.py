"""The features of a move and its plant: what a tuner knows of a move before it runs.

One public home for them: the envs' observations (:mod:`vfgym.envs`) and the per-move
tuners (the settings models of :mod:`vfgym.permove`) describe a move with the same numbers,
:func:`scenario_features`, in the order of :data:`SCENARIO_FEATURES`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from vfgym.moves import profiles
from vfgym.moves.scenarios import Scenario
from vfgym.params import Plant

# scales of the scenario features: the random distribution's ranges (vfgym.moves.scenarios)
INERTIA_RATIO_SCALE = 5.0
COULOMB_SCALE_NM = 0.004
VISCOUS_SCALE_NM_S_RAD = 3e-4
LOAD_SCALE_NM = 0.004

SCENARIO_FEATURES = (
    "direction",
    "log_distance",
    "log_ideal_time",
    "time_budget",
    *(f"profile_{p}" for p in profiles.PROFILES),
    "moves",
    "profile_speed",
    "profile_accel",
    "sine_freq",
    "inertia_ratio",
    "coulomb",
    "viscous",
    "load_torque",
    "torque_accel",
)
"""The features describing a move and its plant (definitions in :func:`scenario_features`)."""


OBS_BOUND = 10.0
"""Every observation feature of both envs is clipped to [-OBS_BOUND, OBS_BOUND]."""


def clip_feature(x: float) -> float:
    """An observation feature clipped to [-OBS_BOUND, OBS_BOUND] (NaN passes through).

    Plain comparisons, so that the envs' compiled step (``_batch._clip``, this function
    compiled by numba) computes the same numbers.

    Parameters
    ----------
    x : float
        The feature.

    Returns
    -------
    float
        ``x`` clipped.
    """
    if x > OBS_BOUND:
        return OBS_BOUND
    if x < -OBS_BOUND:
        return -OBS_BOUND
    return x


def main_move(sc: Scenario, plant: Plant) -> float:
    """The move that sets the scale of a scenario (rad, signed): the distance of a single
    move or the amplitude of a sine; for several moves, the largest one."""
    moves = sc.move_list(plant)
    if len(moves) <= 1 or sc.tracking:
        return float(sc.distance_rad)
    return float(max((d for _, d in moves), key=abs))


def scenario_features(sc: Scenario, base: Plant, plant: Plant | None = None) -> np.ndarray:
    """The move and its plant, normalised (float64, each clipped by :func:`clip_feature`).

    direction: sign of :func:`main_move`; log_distance: log10(|move| / 1 rad) / 2;
    log_ideal_time: log10(ideal time / 1 ms) / 2; time_budget: duration / ideal time / 10;
    profile_*: one-hot of the command profile; moves: point-to-point moves / 5;
    profile_speed, profile_accel: the profile's cruise speed / δ·f and acceleration / the
    motor's limit; sine_freq: frequency / 100 Hz (0 unless a sine); inertia_ratio / 5,
    coulomb / 4 mN·m, viscous / 0.3 mN·m·s/rad, load_torque / 4 mN·m (the random
    distribution's ranges); torque_accel: peak torque / (J · acceleration limit), ≥ 1 when
    the loaded motor can reach the limit.
    """
    plant = sc.plant(base) if plant is None else plant
    m = plant.motor
    d = main_move(sc, plant)
    ideal = sc.ideal_time_s(plant)
    out = [
        math.copysign(1.0, d) if d != 0.0 else 0.0,
        math.log10(max(abs(d), 1e-6)) / 2.0,
        math.log10(ideal / 1e-3) / 2.0,
        sc.duration_s / ideal / 10.0,
        *(1.0 if sc.profile == p else 0.0 for p in profiles.PROFILES),
        len(sc.move_list(plant)) / 5.0,
        sc.speed(plant) / plant.pulse_top_speed_rad_s,
        sc.accel(plant) / m.accel_limit_rad_s2,
        sc.freq_hz / 100.0 if sc.tracking else 0.0,
        m.inertia_ratio / INERTIA_RATIO_SCALE,
        m.coulomb_nm / COULOMB_SCALE_NM,
        m.viscous_nm_s_rad / VISCOUS_SCALE_NM_S_RAD,
        m.load_torque_nm / LOAD_SCALE_NM,
        m.peak_torque_nm / (m.inertia_kgm2 * m.accel_limit_rad_s2),
    ]
    return np.array([clip_feature(x) for x in out], dtype=np.float64)


def peak_speed_rad_s(sc: Scenario, plant: Plant) -> float:
    """The highest speed the move's command asks for (rad/s): its cruise speed, or for a
    move too short to reach it, the peak of a triangle at the profile's acceleration
    (``sqrt(|move| · acceleration)``); a sine's peak ``2π·f·amplitude``."""
    if sc.tracking:
        return 2.0 * math.pi * sc.freq_hz * abs(sc.distance_rad)
    reach = math.sqrt(abs(main_move(sc, plant)) * sc.accel(plant))
    return min(sc.speed(plant), reach)


SPAN_QUANTITIES = ("distance_rad", "speed_rad_s", "inertia_ratio", "load_torque_nm")
"""What :class:`MoveSpan` spans: the move's size, the speed it asks for, and its load."""
SPAN_MARGINS = (0.25, 0.10, 0.10, 0.10)
"""How far beyond each end of a span a move still counts as inside, as a share of the
end's size, per quantity: a move 25 % longer than the longest tuned on cruises at the same
top speed (its result is the same kind), one 6x longer may not."""


@dataclass(frozen=True)
class MoveSpan:
    """The range of what a set of moves asks of a plant: what a setting tuned on them has
    been tried on. A move outside it (a longer or faster move, a heavier load) is one the
    tuning never saw: its result there is an extrapolation.

    Parameters
    ----------
    lows, highs : tuple of float
        Per quantity of :data:`SPAN_QUANTITIES`: the least and the most over the moves.
    """

    lows: tuple[float, ...]
    highs: tuple[float, ...]

    @staticmethod
    def quantities(sc: Scenario, base: Plant) -> tuple[float, ...]:
        """A move's quantities of :data:`SPAN_QUANTITIES` on the axis's plant ``base``."""
        plant = sc.plant(base)
        m = plant.motor
        return (abs(main_move(sc, plant)), peak_speed_rad_s(sc, plant), m.inertia_ratio,
                m.load_torque_nm)  # fmt: skip

    @classmethod
    def of(cls, scenarios: Sequence[Scenario], base: Plant) -> MoveSpan:
        """The span of ``scenarios`` on the axis's plant ``base``.

        Parameters
        ----------
        scenarios : sequence of Scenario
            The moves (at least one).
        base : Plant
            The axis's plant; each move adds its load.

        Returns
        -------
        MoveSpan
            Their lows and highs.
        """
        q = np.array([cls.quantities(sc, base) for sc in scenarios], dtype=np.float64)
        return cls(tuple(q.min(axis=0).tolist()), tuple(q.max(axis=0).tolist()))

    def outside(self, sc: Scenario, base: Plant) -> list[str]:
        """What of a move lies outside the span, beyond :data:`SPAN_MARGINS`, one phrase
        per quantity (empty: inside).

        Parameters
        ----------
        sc : Scenario
            The move.
        base : Plant
            The axis's plant.

        Returns
        -------
        list of str
            E.g. ``distance 45.2 rad (tuned on 0.2 to 6.28)``.
        """
        units = {"distance_rad": "rad", "speed_rad_s": "rad/s", "inertia_ratio": "rotor "
                 "inertias of load", "load_torque_nm": "N·m load torque"}  # fmt: skip
        out = []
        q = self.quantities(sc, base)
        ends = zip(SPAN_QUANTITIES, SPAN_MARGINS, q, self.lows, self.highs, strict=True)
        for name, margin, x, lo, hi in ends:
            if lo - margin * abs(lo) - 1e-12 <= x <= hi + margin * abs(hi) + 1e-12:
                continue
            what = name.rsplit("_", 1)[0] if name.endswith(("_rad", "_s")) else name
            what = {"speed_rad": "speed", "load_torque_nm": "load"}.get(what, what)
            out.append(f"{what} {x:.3g} {units[name]} (tuned on {lo:.3g} to {hi:.3g})")
        return out


__all__ = [
    "OBS_BOUND",
    "SCENARIO_FEATURES",
    "SPAN_MARGINS",
    "SPAN_QUANTITIES",
    "MoveSpan",
    "clip_feature",
    "main_move",
    "peak_speed_rad_s",
    "scenario_features",
]
