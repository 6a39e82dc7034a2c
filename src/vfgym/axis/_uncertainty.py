"""What an axis does not know exactly: ranges of the true plant, and plants drawn in them.

A real motor never matches its datasheet: a coupling, a table or a payload adds inertia an
engineer knows to within ten or twenty percent, and friction and the drive's real gain are
guesses. An axis file states these as ranges (its ``uncertainty:`` block, read into
:class:`Uncertainty`); the drive's gain K3 stays as set for the *modelled* plant, and the
*true* plant lies anywhere in the ranges. :class:`PlantVariant` is one such true plant,
applied to a modelled per-move plant by :meth:`PlantVariant.apply`.

Two sets of variants are drawn from a stated seed:

- :func:`plant_design`, what a tuner must stay feasible on: the ranges' corners plus
  points drawn inside (feasibility is not monotone in the inertia, so corners alone are
  not enough);
- :func:`draw_plants`, the held-out plants a verdict is judged on.

An axis without uncertainty is exactly known; its verdict still shows
:func:`sensitivity_variants`, ±5 % inertia, so a setting on the edge is visible.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, fields, replace
from typing import Any

import numpy as np

from vfgym._validate import check_int, check_real
from vfgym.params import Motor, Plant

FACTOR_RANGE = (0.05, 20.0)
"""Allowed factors on the modelled inertia and on the drive's gain K3: a factor outside it
is more likely a units slip than a real doubt."""

SENSITIVITY_INERTIA = (0.95, 1.05)
"""The inertia factors of the sensitivity line shown where an axis states no uncertainty."""

DESIGN_DRAWN = 6
"""Points drawn inside the ranges, beside their corners, in a tuner's plant design (the
issue's measurement found infeasibility between corners at factors 1.16 and 1.205 of a
0.8–1.25 range; 6 stratified points put one in every 0.075 of that range)."""

VERDICT_PLANTS = 16
"""Held-out plants a verdict is judged on by default."""

VERDICT_PLANT_SEED = 20261204
"""The default seed of a verdict's held-out plants (printed with every verdict)."""

DESIGN_SEED = 0
"""The seed of a tuner's plant design; a verdict's plants are drawn from another stream."""


def _pair(name: str, value: Any, lo: float | None, hi: float | None, *, lo_open: bool) -> Any:
    """``[lo, hi]`` checked: two real numbers in the allowed interval, in order."""
    if value is None:
        return None
    if isinstance(value, (str, bytes)) or not hasattr(value, "__len__") or len(value) != 2:
        raise ValueError(
            f"{name}={value!r} is not allowed: give [low, high] "
            f"(two numbers{_range(lo, hi, lo_open)})"
        )
    a, b = (check_real(f"{name}[{i}]", v, lo, hi, lo_open=lo_open) for i, v in enumerate(value))
    if a > b:
        raise ValueError(f"{name}={list(value)!r} is reversed: give [low, high] with low ≤ high")
    return (a, b)


def _range(lo: float | None, hi: float | None, lo_open: bool) -> str:
    if lo is None and hi is None:
        return ""
    left = "(" if lo_open else "["
    return f" in {left}{'-inf' if lo is None else f'{lo:g}'}, {'inf' if hi is None else f'{hi:g}'}]"


@dataclass(frozen=True)
class Uncertainty:
    """Ranges of the quantities of an axis that are not known exactly.

    Each field is ``None`` (known exactly) or ``(low, high)``. An axis without any range is
    exactly known (:attr:`exact`) and gives the figures of a modelled plant.

    Parameters
    ----------
    inertia : tuple of float or None
        Factors on the modelled total inertia (rotor plus load), each in [0.05, 20].
    coulomb_nm : tuple of float or None
        The axis's true Coulomb friction τc (N·m), ≥ 0 (a move's own friction is added).
    viscous_nm_s_rad : tuple of float or None
        The axis's true viscous friction b (N·m·s/rad), ≥ 0.
    load_torque_nm : tuple of float or None
        The axis's true constant load torque (N·m), either sign.
    torque_per_count : tuple of float or None
        Factors on the drive's gain K3 as set, each in [0.05, 20].
    stiffness : tuple of float or None
        Factors on the transmission's stiffness K_S, each in [0.05, 20] (a compliant
        axis only: a belt's tension, a screw's nut position).
    damping : tuple of float or None
        Factors on the transmission's damping c_S, each in [0.05, 20].
    load_coulomb_nm : tuple of float or None
        The transmission's true Coulomb friction on the load, τc_L (N·m at the motor
        shaft), ≥ 0 (a compliant axis only: a guide's or a nut's friction).

    Raises
    ------
    ValueError
        A range that is not two numbers, reversed, or outside its allowed interval (the
        message names the key, the value and the interval).
    """

    inertia: tuple[float, float] | None = None
    coulomb_nm: tuple[float, float] | None = None
    viscous_nm_s_rad: tuple[float, float] | None = None
    load_torque_nm: tuple[float, float] | None = None
    torque_per_count: tuple[float, float] | None = None
    stiffness: tuple[float, float] | None = None
    damping: tuple[float, float] | None = None
    load_coulomb_nm: tuple[float, float] | None = None

    def __post_init__(self) -> None:
        lo_f, hi_f = FACTOR_RANGE
        for name, lo, hi in (
            ("inertia", lo_f, hi_f),
            ("coulomb_nm", 0.0, None),
            ("viscous_nm_s_rad", 0.0, None),
            ("load_torque_nm", None, None),
            ("torque_per_count", lo_f, hi_f),
            ("stiffness", lo_f, hi_f),
            ("damping", lo_f, hi_f),
            ("load_coulomb_nm", 0.0, None),
        ):
            object.__setattr__(self, name, _pair(name, getattr(self, name), lo, hi, lo_open=False))

    @property
    def exact(self) -> bool:
        """True when no quantity is uncertain."""
        return all(getattr(self, f.name) is None for f in fields(self))

    def ranges(self) -> dict[str, tuple[float, float]]:
        """The stated ranges, by field name (the uncertain quantities only)."""
        return {f.name: getattr(self, f.name) for f in fields(self) if getattr(self, f.name)}

    def check_motor(self, motor: Motor) -> None:
        """Check that every plant in the ranges is a valid motor of the axis.

        Parameters
        ----------
        motor : Motor
            The axis's modelled motor.

        Raises
        ------
        ValueError
            Naming the key, when a range's extreme makes an impossible motor (friction
            and load torque over the peak torque, viscous friction over the peak torque at
            the knee speed).
        """
        self._check_held(motor)
        peak = motor.peak_torque_nm
        if self.viscous_nm_s_rad:
            most = peak / motor.knee_speed_rad_s
            if self.viscous_nm_s_rad[1] > most:
                raise ValueError(
                    f"uncertainty.viscous_nm_s_rad={list(self.viscous_nm_s_rad)!r} is out of "
                    f"range: allowed [0, {most:g}] (the peak torque at the knee speed)"
                )

    def _check_held(self, motor: Motor, load_coulomb_nm: float = 0.0) -> None:
        """The highest friction (the motor's, and the load's ``load_coulomb_nm`` or its
        range) plus load torque below the peak torque, else naming the range that breaks it."""
        c_hi = (self.coulomb_nm or (motor.coulomb_nm,) * 2)[1]
        cl_hi = (self.load_coulomb_nm or (load_coulomb_nm,) * 2)[1]
        l_lo, l_hi = self.load_torque_nm or (motor.load_torque_nm,) * 2
        held = c_hi + cl_hi + max(abs(l_lo), abs(l_hi))
        if held >= motor.peak_torque_nm:
            key = next(
                (k for k in ("load_coulomb_nm", "coulomb_nm") if getattr(self, k)),
                "load_torque_nm",
            )
            raise ValueError(
                f"uncertainty.{key}={list(getattr(self, key) or ())!r} is out of range: the "
                f"highest friction plus load torque ({held:g} N·m) must stay below "
                f"peak_torque_nm={motor.peak_torque_nm:g}, else the motor cannot move its load"
            )

    def check_plant(self, plant: Plant) -> None:
        """:meth:`check_motor` on the plant's motor, and the transmission's ranges: stated
        only where the plant has a transmission, and its resonance within f/10 at every
        corner (inertia and stiffness).

        Parameters
        ----------
        plant : Plant
            The axis's modelled plant.

        Raises
        ------
        ValueError
            Naming the key, as :meth:`check_motor` (with the load's friction too); or
            ``stiffness`` / ``damping`` / ``load_coulomb_nm`` on a plant without a
            transmission, or a corner whose resonance is too high.
        """
        if plant.transmission is None:
            for key in ("stiffness", "damping", "load_coulomb_nm"):
                if getattr(self, key) is not None:
                    raise ValueError(
                        f"uncertainty.{key}={list(getattr(self, key))!r} is not allowed: the "
                        "plant states no transmission (plant.transmission)"
                    )
            self.check_motor(plant.motor)
            return
        self.check_motor(plant.motor)
        self._check_held(plant.motor, plant.transmission.load_coulomb_nm)
        for inertia in self.inertia or (1.0,):
            for stiffness in self.stiffness or (1.0,):
                try:
                    PlantVariant(inertia=inertia, stiffness=stiffness).apply(plant)
                except ValueError as exc:
                    key = "stiffness" if self.stiffness else "inertia"
                    raise ValueError(
                        f"uncertainty.{key}={list(getattr(self, key))!r} is out of range: at "
                        f"inertia ×{inertia:g}, stiffness ×{stiffness:g}, {exc}"
                    ) from None

    def to_dict(self) -> dict[str, list[float]]:
        """The ranges as an axis file's ``uncertainty:`` mapping."""
        return {k: [float(a), float(b)] for k, (a, b) in self.ranges().items()}


EXACT = Uncertainty()
"""Nothing uncertain: the default of every axis."""


_TRANSMISSION_AT = {"stiffness": 1.0, "damping": 1.0, "load_coulomb_offset_nm": 0.0}
"""A variant's transmission fields and their values on the modelled plant."""


@dataclass(frozen=True)
class PlantVariant:
    """One true plant within an axis's uncertainty, relative to the modelled one.

    Parameters
    ----------
    inertia : float
        Factor on the modelled total inertia.
    coulomb_offset_nm : float
        True Coulomb friction minus the modelled (N·m).
    viscous_offset_nm_s_rad : float
        True viscous friction minus the modelled (N·m·s/rad).
    load_offset_nm : float
        True load torque minus the modelled (N·m).
    torque_per_count : float
        Factor on the drive's gain K3 in force on the modelled plant.
    stiffness : float
        Factor on the transmission's stiffness K_S (a compliant plant only).
    damping : float
        Factor on the transmission's damping c_S (a compliant plant only).
    load_coulomb_offset_nm : float
        True Coulomb friction on the load minus the modelled (N·m; a compliant plant
        only).
    """

    inertia: float = 1.0
    coulomb_offset_nm: float = 0.0
    viscous_offset_nm_s_rad: float = 0.0
    load_offset_nm: float = 0.0
    torque_per_count: float = 1.0
    stiffness: float = 1.0
    damping: float = 1.0
    load_coulomb_offset_nm: float = 0.0

    def __repr__(self) -> str:
        # the dataclass's own repr, without the transmission's factors at 1 and offset at
        # 0: a variant of a rigid axis reads as it did before them, so digests of it stay
        shown = (
            f
            for f in fields(self)
            if f.name not in _TRANSMISSION_AT or getattr(self, f.name) != _TRANSMISSION_AT[f.name]
        )
        parts = ", ".join(f"{f.name}={getattr(self, f.name)!r}" for f in shown)
        return f"{type(self).__qualname__}({parts})"

    @property
    def nominal(self) -> bool:
        """True for the modelled plant itself."""
        return self == NOMINAL

    def apply(self, plant: Plant) -> Plant:
        """The true plant of a modelled (per-move) plant.

        The drive keeps the K3 set for the modelled plant (times :attr:`torque_per_count`),
        so the true plant's servo no longer follows its load; the inertia factor scales the
        rotor's inertia, which scales the total with the load ratio unchanged, and the
        transmission's load inertia (where one is stated) with it.

        Parameters
        ----------
        plant : Plant
            The modelled plant, with the move's load.

        Returns
        -------
        Plant
            The true plant (``plant`` itself for :data:`NOMINAL`).

        Raises
        ------
        ValueError
            A stiffness, damping or load friction on a plant without a transmission, or a true
            plant whose resonance is above f/10 (:class:`vfgym.Plant`).
        """
        if self.nominal:
            return plant
        tr = plant.transmission
        if tr is None and any(getattr(self, k) != v for k, v in _TRANSMISSION_AT.items()):
            raise ValueError(
                f"stiffness={self.stiffness!r}, damping={self.damping!r}, "
                f"load_coulomb_offset_nm={self.load_coulomb_offset_nm!r} is not allowed: "
                "the plant states no transmission"
            )
        if tr is not None:
            tr = replace(
                tr,
                load_inertia_kgm2=tr.load_inertia_kgm2 * self.inertia,
                stiffness_nm_rad=tr.stiffness_nm_rad * self.stiffness,
                damping_nm_s_rad=tr.damping_nm_s_rad * self.damping,
                load_coulomb_nm=max(0.0, tr.load_coulomb_nm + self.load_coulomb_offset_nm),
            )
        m = plant.motor
        motor = replace(
            m,
            rotor_inertia_kgm2=m.rotor_inertia_kgm2 * self.inertia,
            coulomb_nm=max(0.0, m.coulomb_nm + self.coulomb_offset_nm),
            viscous_nm_s_rad=max(0.0, m.viscous_nm_s_rad + self.viscous_offset_nm_s_rad),
            load_torque_nm=m.load_torque_nm + self.load_offset_nm,
        )
        servo = replace(
            plant.servo,
            follows_load=False,
            torque_per_count_nm=plant.torque_per_count_nm * self.torque_per_count,
        )
        return replace(plant, motor=motor, servo=servo, transmission=tr)

    def label(self) -> str:
        """A short description for tables: the factors and offsets that differ."""
        parts = []
        if self.inertia != 1.0:
            parts.append(f"J×{self.inertia:.3g}")
        if self.torque_per_count != 1.0:
            parts.append(f"K3×{self.torque_per_count:.3g}")
        if self.stiffness != 1.0:
            parts.append(f"K_S×{self.stiffness:.3g}")
        if self.damping != 1.0:
            parts.append(f"c_S×{self.damping:.3g}")
        for name, v in (
            ("τc", self.coulomb_offset_nm),
            ("τc_L", self.load_coulomb_offset_nm),
            ("b", self.viscous_offset_nm_s_rad),
            ("τload", self.load_offset_nm),
        ):
            if v:
                parts.append(f"{name}{v:+.3g}")
        return " ".join(parts) or "modelled"


NOMINAL = PlantVariant()
"""The modelled plant."""


def _variant(unc: Uncertainty, plant: Plant, u: np.ndarray) -> PlantVariant:
    """The variant at unit-cube point ``u`` (one coordinate per uncertain range, in the
    order of :meth:`Uncertainty.ranges`), offsets taken from the modelled ``plant``."""
    motor = plant.motor
    load_c = plant.transmission.load_coulomb_nm if plant.transmission is not None else 0.0
    values = dict(zip(unc.ranges(), (float(x) for x in u), strict=True))
    at = {k: lo + values[k] * (hi - lo) for k, (lo, hi) in unc.ranges().items()}
    return PlantVariant(
        inertia=at.get("inertia", 1.0),
        coulomb_offset_nm=at.get("coulomb_nm", motor.coulomb_nm) - motor.coulomb_nm,
        viscous_offset_nm_s_rad=(
            at.get("viscous_nm_s_rad", motor.viscous_nm_s_rad) - motor.viscous_nm_s_rad
        ),
        load_offset_nm=at.get("load_torque_nm", motor.load_torque_nm) - motor.load_torque_nm,
        torque_per_count=at.get("torque_per_count", 1.0),
        stiffness=at.get("stiffness", 1.0),
        damping=at.get("damping", 1.0),
        load_coulomb_offset_nm=at.get("load_coulomb_nm", load_c) - load_c,
    )


def _stratified(n: int, d: int, rng: np.random.Generator) -> np.ndarray:
    """``n`` points of the unit cube in ``d`` dimensions, one in each of ``n`` equal
    strata of every coordinate (a Latin hypercube)."""
    pts = (rng.random((n, d)) + np.arange(n)[:, None]) / n
    for j in range(d):
        pts[:, j] = pts[rng.permutation(n), j]
    return pts


def draw_plant(unc: Uncertainty, plant: Plant, rng: np.random.Generator) -> PlantVariant:
    """One true plant drawn uniformly within the ranges from a generator (an env's
    episode; :data:`NOMINAL` where nothing is uncertain, drawing nothing).

    Parameters
    ----------
    unc : Uncertainty
        The axis's uncertainty.
    plant : Plant
        The axis's modelled plant (absolute ranges become offsets from it).
    rng : numpy.random.Generator
        The generator (an env's ``np_random``).

    Returns
    -------
    PlantVariant
        The true plant.
    """
    if unc.exact:
        return NOMINAL
    return _variant(unc, plant, rng.random(len(unc.ranges())))


def plant_design(
    unc: Uncertainty, plant: Plant, drawn: int = DESIGN_DRAWN, seed: int = DESIGN_SEED
) -> tuple[PlantVariant, ...]:
    """The true plants a tuner must stay feasible on: every corner of the ranges, then
    ``drawn`` stratified points inside them.

    Parameters
    ----------
    unc : Uncertainty
        The axis's uncertainty; exact gives no variant.
    plant : Plant
        The axis's modelled plant (absolute ranges become offsets from it).
    drawn : int
        Points drawn inside the ranges, ≥ 0.
    seed : int
        Seed of the drawn points.

    Returns
    -------
    tuple of PlantVariant
        The corners (2^d for d uncertain quantities) then the drawn points; the modelled
        plant itself is not among them.
    """
    drawn = check_int("drawn", drawn, 0)
    d = len(unc.ranges())
    if d == 0:
        return ()
    corners = [np.array(c, float) for c in itertools.product((0.0, 1.0), repeat=d)]
    inner = list(_stratified(drawn, d, np.random.default_rng([seed, 1]))) if drawn else []
    out = [_variant(unc, plant, u) for u in [*corners, *inner]]
    return tuple(dict.fromkeys(v for v in out if not v.nominal))


def draw_plants(
    unc: Uncertainty,
    plant: Plant,
    count: int = VERDICT_PLANTS,
    seed: int = VERDICT_PLANT_SEED,
) -> tuple[PlantVariant, ...]:
    """``count`` held-out true plants drawn uniformly within the ranges.

    Parameters
    ----------
    unc : Uncertainty
        The axis's uncertainty; exact gives :func:`sensitivity_variants` instead.
    plant : Plant
        The axis's modelled plant (absolute ranges become offsets from it).
    count : int
        How many, ≥ 1.
    seed : int
        The seed (printed with the verdict).

    Returns
    -------
    tuple of PlantVariant
        The plants, in draw order.
    """
    count = check_int("plants", count, 1)
    if unc.exact:
        return sensitivity_variants()
    d = len(unc.ranges())
    u = np.random.default_rng([seed, 2]).random((count, d))
    return tuple(_variant(unc, plant, row) for row in u)


def sensitivity_variants() -> tuple[PlantVariant, ...]:
    """The ±5 % inertia plants of the sensitivity line (:data:`SENSITIVITY_INERTIA`)."""
    return tuple(PlantVariant(inertia=f) for f in SENSITIVITY_INERTIA)


__all__ = [
    "DESIGN_DRAWN",
    "DESIGN_SEED",
    "EXACT",
    "NOMINAL",
    "SENSITIVITY_INERTIA",
    "VERDICT_PLANTS",
    "VERDICT_PLANT_SEED",
    "PlantVariant",
    "Uncertainty",
    "draw_plant",
    "draw_plants",
    "plant_design",
    "sensitivity_variants",
]
