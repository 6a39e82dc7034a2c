"""Move sets by name and seeded random distributions of moves, with disjoint train and
test seeds.

:class:`MoveDistribution` is a random distribution, its ranges frozen. Its defaults are
the moves of one machine, the load its own: the default axis's (:mod:`vfgym.axis`;
an axis file gives its own ranges). :data:`LOAD_DISTRIBUTION` adds a random load to each
move: what the agents learn across (:func:`random_scenario`). :func:`get_scenario` and
:func:`scenario_set` resolve names (``paper-step``, ``train-3``, ``named``, ``test``) on
the default axis.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from vfgym._validate import check_bool, check_choice, check_int, check_real
from vfgym.moves.scenarios import (
    DRAWN_PROFILES,
    SCENARIOS,
    SPLITS,
    Scenario,
    ideal_move_time_s,
)
from vfgym.params import PAPER_PLANT, Plant


def get_scenario(name: str | Scenario, distribution: MoveDistribution | None = None) -> Scenario:
    """A scenario by name.

    Parameters
    ----------
    name : str or Scenario
        A name of :data:`SCENARIOS`, or ``train-<seed>`` / ``test-<seed>`` for a random
        move; a :class:`Scenario` is returned as it is.
    distribution : MoveDistribution, optional
        What ``<split>-<seed>`` draws from: by default the default axis's moves
        (:data:`DEFAULT_DISTRIBUTION`); :data:`LOAD_DISTRIBUTION` for the environments'.

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
        return (distribution or DEFAULT_DISTRIBUTION).draw(int(seed), split)
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
    draws from ``first_seed``.

    The defaults are one machine's moves: distance, direction and profile vary, the load
    is the plant's own (no load, friction or load torque added per move), as an axis is
    one machine. :data:`LOAD_DISTRIBUTION` adds a random load to each move
    (:func:`random_scenario`, the environments' default).

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
        Default none; :data:`LOAD_DISTRIBUTION`: up to 5 rotor inertias, 0.3 mN·m·s/rad.
    coulomb_nm : tuple of (float, float)
        Coulomb friction uniform in [low, high] on a share of the moves, none on the rest
        (default none; :data:`LOAD_DISTRIBUTION`: up to 4 mN·m, as more would leave the
        P-type servo's dead band τc/K3 outside the in-position window).
    coulomb_share : float
        That share, in [0, 1] (default half).
    load_torque_nm : tuple of (float, float)
        A constant load torque uniform in [low, high] on a share of the moves (default
        none; :data:`LOAD_DISTRIBUTION`: ±4 mN·m).
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
    inertia_ratio: tuple[float, float] = (0.0, 0.0)
    coulomb_nm: tuple[float, float] = (0.0, 0.0)
    coulomb_share: float = 0.5
    viscous_nm_s_rad: tuple[float, float] = (0.0, 0.0)
    load_torque_nm: tuple[float, float] = (0.0, 0.0)
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
"""The default axis's moves: one machine, the paper's plant with no load added per move."""

LOAD_DISTRIBUTION = MoveDistribution(
    inertia_ratio=(0.0, 5.0),  # up to the heavy-load scenario's 5 rotor inertias
    coulomb_nm=(0.0, 0.004),  # τc/K3 stays inside the in-position window
    viscous_nm_s_rad=(0.0, 3e-4),
    load_torque_nm=(-0.004, 0.004),
)
"""The moves of :data:`DEFAULT_DISTRIBUTION` with a random load each: what the agents
learn across, where the best settings depend on the load (:func:`random_scenario`)."""


def random_scenario(seed: int, split: str = "train") -> Scenario:
    """A move drawn from :data:`LOAD_DISTRIBUTION` on the paper's plant: the
    environments' default distribution, across loads.

    The draw of a seed has the distance, direction and profile of the default axis's
    move of that seed (the same random numbers), with a load of its own added; it shares
    its name, ``<split>-<seed>``, which names the default axis's move elsewhere
    (:func:`get_scenario`). Train and test draws never coincide: the generator's key is
    (split, seed). Distribution: distance log-uniform in
    [0.2, 50] rad with a random sign; profile step (50 %), trapezoid (25 %) or scurve
    (25 %); added inertia ratio uniform in [0, 5]; Coulomb friction uniform in [0, 4] mN·m
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
    return LOAD_DISTRIBUTION.draw(seed, split)


def scenario_set(
    spec: str | Scenario | list | tuple,
    count: int = 16,
    first_seed: int = 0,
    distribution: MoveDistribution | None = None,
) -> list[Scenario]:
    """Scenarios from a spec.

    Parameters
    ----------
    spec : str, Scenario, list or tuple
        A scenario name, ``named`` (all eight), ``train`` / ``test`` (the default axis's
        random moves, :data:`DEFAULT_DISTRIBUTION`), a
        comma-separated list of these, a :class:`Scenario`, or a list of any of them.
    count : int
        How many random draws ``train`` / ``test`` give, ≥ 1.
    first_seed : int
        The first draw's seed; the draws use ``first_seed``, ``first_seed + 1`` …
    distribution : MoveDistribution, optional
        What ``train`` / ``test`` and ``<split>-<seed>`` draw from (its own count and
        first seed aside): by default the default axis's moves
        (:data:`DEFAULT_DISTRIBUTION`); :data:`LOAD_DISTRIBUTION` for the environments'.

    Returns
    -------
    list of Scenario
        In the order of the spec.
    """
    if isinstance(spec, Scenario):
        return [spec]
    if isinstance(spec, (list, tuple)):
        return [s for item in spec for s in scenario_set(item, count, first_seed, distribution)]
    spec = str(spec)
    if "," in spec:
        parts = [p.strip() for p in spec.split(",") if p.strip()]
        return scenario_set(parts, count, first_seed, distribution)
    if spec == "named":
        return list(SCENARIOS.values())
    if spec in SPLITS:
        dist = replace(distribution or DEFAULT_DISTRIBUTION, count=count, first_seed=first_seed)
        return dist.scenarios(spec)
    return [get_scenario(spec, distribution)]
