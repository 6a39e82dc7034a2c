"""Named, frozen scenarios (a command and the plant it drives), and a seeded random
distribution of moves with disjoint train and test seeds.

A scenario is data: a profile with its numbers, a duration, and the load it adds to the
base plant (load inertia, friction, load torque). ``command()`` and ``plant()`` build
what the simulator needs; both are cached, so every caller (env, objective, evaluation)
simulates exactly the same arrays. :class:`MoveDistribution` is the random distribution,
its ranges frozen (the defaults are :func:`random_scenario`'s); an axis file
(:mod:`vfgym.moves.axis`) gives its own.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from vfgym._validate import check_bool, check_choice, check_int, check_real
from vfgym.moves import profiles
from vfgym.params import PAPER_PLANT, PAPER_STEP_RAD, Plant

PAPER_SINE_AMPLITUDE_RAD = 5.0
"""Fig. 5's sine: the text gives no numbers. 5 rad at 10 Hz peaks at 314 rad/s (73 % of
v_max) and 19.7 krad/s² (14 % of the motor's limit): well inside both."""
PAPER_SINE_FREQ_HZ = 10.0

SPLITS = ("train", "test")
DRAWN_PROFILES = ("step", "ramp", "trapezoid", "scurve")
"""The profiles a :class:`MoveDistribution` may draw: single point-to-point moves."""


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
        """
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


def get_scenario(name: str | Scenario) -> Scenario:
    """A scenario by name.

    Parameters
    ----------
    name : str or Scenario
        A name of :data:`SCENARIOS`, or ``train-<seed>`` / ``test-<seed>`` for a random
        draw; a :class:`Scenario` is returned as it is.

    Returns
    -------
    Scenario
        The scenario.

    Raises
    ------
    ValueError
        If the name is not known.
    """
    if isinstance(name, Scenario):
        return name
    if name in SCENARIOS:
        return SCENARIOS[name]
    split, _, seed = str(name).partition("-")
    if split in SPLITS and seed.isdigit():
        return random_scenario(int(seed), split)
    raise ValueError(
        f"scenario={name!r} is not known: choose one of {', '.join(SCENARIOS)}, "
        "or train-<seed> / test-<seed>"
    )


def _range(name: str, value: Any, lo: float | None = None, lo_open: bool = False) -> tuple:
    """A (low, high) pair of floats with low <= high, each inside ``lo``."""
    if isinstance(value, (str, bytes)) or not hasattr(value, "__len__") or len(value) != 2:
        raise ValueError(f"{name}={value!r} is not allowed: give [low, high]")
    a = check_real(f"{name}[0]", value[0], lo, lo_open=lo_open)
    b = check_real(f"{name}[1]", value[1], a)
    return (a, b)


@dataclass(frozen=True)
class MoveDistribution:
    """A seeded distribution of single point-to-point moves, and its set of ``count``
    draws from ``first_seed``; the defaults are :func:`random_scenario`'s distribution.

    Train and test draws never coincide: the generator's key is (split, seed) and a move
    is named ``<split>-<seed>``. Every draw takes the same random numbers whatever the
    ranges, so changing one range changes that quantity alone.

    Parameters
    ----------
    count, first_seed : int
        The set (:meth:`scenarios`): seeds first_seed … first_seed+count−1 (count ≥ 1).
    distance_rad : tuple of (float, float)
        [low, high] of the distance, drawn log-uniform (0 < low).
    both_directions : bool
        A random sign (default), else forward moves only.
    profiles : tuple of str
        Each move's profile, drawn uniformly from this list (repeat a name to weight it);
        from :data:`DRAWN_PROFILES`. Default: step 50 %, trapezoid and scurve 25 % each.
    inertia_ratio, viscous_nm_s_rad : tuple of (float, float)
        [low, high], uniform: load added to the axis's own (rotor inertias; N·m·s/rad).
        Default up to 5 rotor inertias, 0.3 mN·m·s/rad.
    coulomb_nm : tuple of (float, float)
        Coulomb friction uniform in [low, high] on a share of the moves, none on the rest
        (default up to 4 mN·m: more would leave the P-type servo's dead band τc/K3
        outside the in-position window).
    coulomb_share : float
        That share, in [0, 1] (default half).
    load_torque_nm : tuple of (float, float)
        A constant load torque uniform in [low, high] on a share of the moves (default
        ±4 mN·m).
    load_torque_share : float
        That share, in [0, 1] (default a quarter).
    time_factor, settle_s : float
        A move lasts time_factor × its ideal move time (:func:`ideal_move_time_s` on its
        loaded plant) + settle_s (default 2 × + 80 ms); time_factor ≥ 1, settle_s ≥ 0.

    Raises
    ------
    ValueError
        If a value is out of its range, or a range's low exceeds its high.
    """

    count: int = 16
    first_seed: int = 0
    distance_rad: tuple[float, float] = (0.2, 50.0)
    both_directions: bool = True
    profiles: tuple[str, ...] = ("step", "step", "trapezoid", "scurve")
    inertia_ratio: tuple[float, float] = (0.0, 5.0)
    coulomb_nm: tuple[float, float] = (0.0, 0.004)
    coulomb_share: float = 0.5
    viscous_nm_s_rad: tuple[float, float] = (0.0, 3e-4)
    load_torque_nm: tuple[float, float] = (-0.004, 0.004)
    load_torque_share: float = 0.25
    time_factor: float = 2.0
    settle_s: float = 0.08

    def __post_init__(self) -> None:
        s = object.__setattr__
        s(self, "count", check_int("count", self.count, 1))
        s(self, "first_seed", check_int("first_seed", self.first_seed, 0, 2**63 - 1))
        s(self, "distance_rad", _range("distance_rad", self.distance_rad, 0.0, lo_open=True))
        s(self, "both_directions", check_bool("both_directions", self.both_directions))
        if isinstance(self.profiles, str) or not self.profiles:
            raise ValueError(
                f"profiles={self.profiles!r} is not allowed: give a list of one or more of "
                f"{', '.join(DRAWN_PROFILES)}"
            )
        for i, p in enumerate(self.profiles):
            check_choice(f"profiles[{i}]", p, DRAWN_PROFILES)
        s(self, "profiles", tuple(self.profiles))
        for name in ("inertia_ratio", "coulomb_nm", "viscous_nm_s_rad"):
            s(self, name, _range(name, getattr(self, name), 0.0))
        s(self, "load_torque_nm", _range("load_torque_nm", self.load_torque_nm))
        for name in ("coulomb_share", "load_torque_share"):
            s(self, name, check_real(name, getattr(self, name), 0.0, 1.0))
        s(self, "time_factor", check_real("time_factor", self.time_factor, 1.0))
        s(self, "settle_s", check_real("settle_s", self.settle_s, 0.0))

    def draw(self, seed: int, split: str = "train", base: Plant = PAPER_PLANT) -> Scenario:
        """The move of ``seed`` in ``split``.

        Parameters
        ----------
        seed : int
            A whole number in [0, 2**63 − 1].
        split : str
            ``train`` or ``test``.
        base : Plant
            The axis's plant: the drawn load is added to its own, and the duration follows
            from the loaded plant's ideal move time.

        Returns
        -------
        Scenario
            Named ``<split>-<seed>``.
        """
        check_choice("split", split, SPLITS)
        seed = check_int("seed", seed, 0, 2**63 - 1)
        rng = np.random.default_rng([SPLITS.index(split), seed])
        lo, hi = self.distance_rad
        # the draws, in this order, whatever the ranges; rng.integers(0, k) draws what
        # rng.choice from k items would, without building an array
        dist = float(np.exp(rng.uniform(math.log(lo), math.log(hi))))
        if rng.integers(0, 2) == 0 and self.both_directions:
            dist = -dist
        profile = self.profiles[rng.integers(0, len(self.profiles))]
        ratio = float(rng.uniform(*self.inertia_ratio))
        coulomb = float(rng.uniform(*self.coulomb_nm)) if rng.random() < self.coulomb_share else 0.0
        viscous = float(rng.uniform(*self.viscous_nm_s_rad))
        load = (
            float(rng.uniform(*self.load_torque_nm))
            if rng.random() < self.load_torque_share
            else 0.0
        )
        loaded = base.with_motor(inertia_ratio=base.motor.inertia_ratio + ratio)
        duration = round(self.time_factor * ideal_move_time_s(dist, loaded) + self.settle_s, 4)
        return Scenario(
            name=f"{split}-{seed}",
            profile=profile,
            distance_rad=round(dist, 6),
            duration_s=duration,
            inertia_ratio=round(ratio, 4),
            coulomb_nm=round(coulomb, 5),
            viscous_nm_s_rad=round(viscous, 7),
            load_torque_nm=round(load, 4),
            description=f"random {split} move, seed {seed}",
        )

    def scenarios(self, split: str, base: Plant = PAPER_PLANT) -> list[Scenario]:
        """The set: ``count`` draws of ``split`` from ``first_seed``.

        Parameters
        ----------
        split : str
            ``train`` or ``test``.
        base : Plant
            The axis's plant, as :meth:`draw` takes it.

        Returns
        -------
        list of Scenario
            The draws, in seed order.
        """
        return [self.draw(self.first_seed + i, split, base) for i in range(self.count)]


DEFAULT_DISTRIBUTION = MoveDistribution()


def random_scenario(seed: int, split: str = "train") -> Scenario:
    """A move drawn from the default distribution (:class:`MoveDistribution`) on the
    paper's plant.

    Train and test draws never coincide: the generator's key is (split, seed) and the
    drawn scenario is named after both. Distribution: distance log-uniform in
    [0.2, 50] rad with a random sign; profile step (50 %), trapezoid (25 %) or scurve
    (25 %); inertia ratio uniform in [0, 5]; Coulomb friction uniform in [0, 4] mN·m
    (half of the draws: none; more would leave the P-type servo's dead band τc/K3 outside
    the in-position window); viscous friction uniform in [0, 3e-4] N·m·s/rad; load torque
    uniform in [−4, 4] mN·m (a quarter of the draws, else none). Duration: the ideal
    move time (for the loaded motor's usable acceleration) times 2, plus 80 ms to settle.

    Parameters
    ----------
    seed : int
        The draw's seed, ≥ 0.
    split : str
        ``"train"`` or ``"test"``.

    Returns
    -------
    Scenario
        Named ``<split>-<seed>``; the same for the same arguments, in every version.
    """
    return DEFAULT_DISTRIBUTION.draw(seed, split)


def scenario_set(
    spec: str | Scenario | list | tuple, count: int = 16, first_seed: int = 0
) -> list[Scenario]:
    """Scenarios from a spec.

    Parameters
    ----------
    spec : str, Scenario, list or tuple
        A scenario name, ``named`` (all eight), ``train`` / ``test`` (random draws), a
        comma-separated list of these, a :class:`Scenario`, or a list of any of them.
    count : int
        How many random draws ``train`` / ``test`` give, ≥ 1.
    first_seed : int
        The first draw's seed; the draws use ``first_seed``, ``first_seed + 1`` …

    Returns
    -------
    list of Scenario
        In the order of the spec.
    """
    if isinstance(spec, Scenario):
        return [spec]
    if isinstance(spec, (list, tuple)):
        return [s for item in spec for s in scenario_set(item, count, first_seed)]
    spec = str(spec)
    if "," in spec:
        return scenario_set([p.strip() for p in spec.split(",") if p.strip()], count, first_seed)
    if spec == "named":
        return list(SCENARIOS.values())
    if spec in SPLITS:
        return MoveDistribution(count=count, first_seed=first_seed).scenarios(spec)
    return [get_scenario(spec)]
