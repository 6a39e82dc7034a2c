"""The motor and what it drives: the servomotor with its rigidly attached load, encoder
and torque-speed characteristic (:class:`Motor`, docs/model.md §3), and a compliant
transmission to a load beyond a spring (:class:`Transmission`, docs/model.md §3.1).
Frozen, validated, with units; :mod:`vfgym.params` assembles them into a
:class:`~vfgym.params.Plant`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from vfgym._limits import (
    MAX_ACCEL_RAD_S2,
    MAX_ENCODER_LINES,
    MAX_INERTIA_RATIO,
    MAX_ROTOR_INERTIA_KGM2,
)
from vfgym._validate import check_int, check_real
from vfgym._validate import set_checked as _set

PAPER_ACCEL_LIMIT_RAD_S2 = 140e3
"""The motor's acceleration limit the paper tunes against (rad/s²)."""


@dataclass(frozen=True)
class Motor:
    """A servomotor with its load, encoder and torque–speed characteristic (docs/model.md §3).

    The torque available for motoring is ``peak_torque_nm`` up to ``knee_speed_rad_s``,
    then falls linearly to ``torque_at_max_speed_nm`` at ``max_speed_rad_s``, and is zero
    above it (the drive's voltage limit). Braking torque (torque against the motion) is
    available up to ``peak_torque_nm`` at any speed. The defaults are the SGME-02A.

    Parameters
    ----------
    name : str
        A label for tables.
    rotor_inertia_kgm2 : float
        Rotor inertia (kg·m²), in (0, 1].
    inertia_ratio : float
        Load inertia over rotor inertia, in [0, 200] (a drive's settable range); total
        J = rotor·(1 + ratio).
    viscous_nm_s_rad : float
        Viscous friction b (N·m·s/rad), ≥ 0, at most the peak torque at the knee speed.
    coulomb_nm : float
        Coulomb friction τc (N·m), ≥ 0; τc + |load_torque_nm| below the peak torque.
    load_torque_nm : float
        A constant torque opposing positive motion (N·m; e.g. gravity on a vertical axis),
        its size below the peak torque.
    rated_torque_nm : float
        Rated (continuous) torque (N·m), in (0, ``peak_torque_nm``].
    peak_torque_nm : float
        Peak torque (N·m), > 0.
    knee_speed_rad_s : float
        Speed up to which the peak torque is available (rad/s), > 0.
    max_speed_rad_s : float
        Maximum speed (rad/s), above ``knee_speed_rad_s``.
    torque_at_max_speed_nm : float
        Torque available at ``max_speed_rad_s`` (N·m), in [0, ``peak_torque_nm``].
    encoder_lines : int
        Encoder lines per revolution (counts after ×4 decoding: 4 × lines), in
        [1, 2^24].
    accel_limit_rad_s2 : float
        The stated acceleration limit (rad/s²; the paper's 140 krad/s²), in (0, 1e7]. It
        caps :attr:`usable_accel_rad_s2`, the limit every move is held to; an axis sets
        its own limit here (:attr:`accel_note` says when the motor cannot reach it).

    Raises
    ------
    ValueError
        If a value is out of its range (the message names the parameter and the range).
    """

    name: str = "SGME-02A"
    rotor_inertia_kgm2: float = 0.106e-4
    inertia_ratio: float = 0.0
    viscous_nm_s_rad: float = 0.0
    coulomb_nm: float = 0.0
    load_torque_nm: float = 0.0
    rated_torque_nm: float = 0.637
    peak_torque_nm: float = 1.91
    knee_speed_rad_s: float = 3000.0 * 2.0 * math.pi / 60.0
    max_speed_rad_s: float = 4500.0 * 2.0 * math.pi / 60.0
    torque_at_max_speed_nm: float = 0.8
    encoder_lines: int = 2048
    accel_limit_rad_s2: float = PAPER_ACCEL_LIMIT_RAD_S2

    def __post_init__(self) -> None:
        for name, hi in (
            ("peak_torque_nm", None),
            ("rotor_inertia_kgm2", MAX_ROTOR_INERTIA_KGM2),
            ("knee_speed_rad_s", None),
            ("accel_limit_rad_s2", MAX_ACCEL_RAD_S2),
        ):
            _set(self, name, check_real(name, getattr(self, name), 0.0, hi, lo_open=True))
        peak = self.peak_torque_nm
        # (name, lo, hi, lo_open, hi_open): each range in the terms of the ones before it
        for name, lo, hi, lo_open, hi_open in (
            ("rated_torque_nm", 0.0, peak, True, False),
            ("inertia_ratio", 0.0, MAX_INERTIA_RATIO, False, False),
            ("coulomb_nm", 0.0, peak, False, True),
            ("load_torque_nm", -peak, peak, True, True),
            ("max_speed_rad_s", self.knee_speed_rad_s, None, True, False),
            ("viscous_nm_s_rad", 0.0, peak / self.knee_speed_rad_s, False, False),
            ("torque_at_max_speed_nm", 0.0, peak, False, False),
        ):
            value = check_real(name, getattr(self, name), lo, hi, lo_open=lo_open, hi_open=hi_open)
            _set(self, name, value)
        lines = check_int("encoder_lines", self.encoder_lines, 1, MAX_ENCODER_LINES)
        _set(self, "encoder_lines", lines)
        held = self.coulomb_nm + abs(self.load_torque_nm)
        if held >= peak:
            raise ValueError(
                f"coulomb_nm={self.coulomb_nm!r} with load_torque_nm={self.load_torque_nm!r} "
                f"is out of range: their sum ({held:g} N·m) must stay below "
                f"peak_torque_nm={peak:g}, else the motor cannot move its load"
            )

    @property
    def torque_accel_rad_s2(self) -> float:
        """What the peak torque gives the loaded motor (rad/s²): peak torque over total
        inertia, whatever the stated limit."""
        return self.peak_torque_nm / self.inertia_kgm2

    @property
    def accel_note(self) -> str | None:
        """One line when the motor cannot reach its stated limit, naming the limit it uses
        (:attr:`usable_accel_rad_s2`); ``None`` when it can."""
        reach = self.torque_accel_rad_s2
        if reach >= self.accel_limit_rad_s2:
            return None
        return (
            f"peak_torque_nm / total inertia = {reach / 1e3:.4g} krad/s² is below "
            f"accel_limit_rad_s2 = {self.accel_limit_rad_s2 / 1e3:.4g} krad/s²: moves are held "
            f"to {reach / 1e3:.4g} krad/s² (the motor's usable acceleration)"
        )

    @property
    def inertia_kgm2(self) -> float:
        """Total inertia seen by the motor shaft (kg·m²)."""
        return self.rotor_inertia_kgm2 * (1.0 + self.inertia_ratio)

    @property
    def usable_accel_rad_s2(self) -> float:
        """The acceleration a move may ask of the loaded motor (rad/s²): peak torque over
        total inertia, capped by the stated limit ``accel_limit_rad_s2``.

        The one definition of "the limit": the acceleration constraint, the measures'
        ``accel_ratio_*``, the ideal move time, the profiles' default acceleration and the
        rule of thumb all use it. The bare SGME-02A can give 180 krad/s², so its limit
        is the paper's 140 krad/s²; with 3x its rotor inertia as load, 45 krad/s².
        """
        return min(self.accel_limit_rad_s2, self.torque_accel_rad_s2)

    @property
    def counts_per_rev(self) -> int:
        """Encoder counts per revolution after ×4 quadrature decoding."""
        return 4 * self.encoder_lines

    @property
    def count_rad(self) -> float:
        """Angle of one encoder count (rad)."""
        return 2.0 * math.pi / self.counts_per_rev


# Yaskawa SGME-02A (Σ series, 200 W, 3000 rpm) — the paper's motor.
#   rated torque 0.637 N·m, instantaneous peak 1.91 N·m, rated speed 3000 rpm, maximum
#   4500 rpm, 2048-line incremental encoder: Yaskawa Σ-series servomotor catalogue,
#   SGME-02 ratings table (the figures the issue quotes).
#   rotor inertia 0.106e-4 kg·m²: the SGME datasheet was not at hand; this is the figure of
#   the nearest documented Σ-series 200 W motor, as the issue directs.
#   torque at maximum speed 0.8 N·m: read off the shape of the Σ-series 200 W
#   torque–speed curve (intermittent zone narrowing to about 40 % of peak at 4500 rpm);
#   an assumption, stated here and in docs/axes.md.
#   No friction or load by default (a bare shaft); scenarios add them.
SGME_02A = Motor()

MOTOR_PRESETS: dict[str, Motor] = {SGME_02A.name: SGME_02A}
"""Motors by name: an axis file's ``motor: {preset: NAME, ...}`` starts from one of these."""


RESONANCE_TICKS_MIN = 10.0
"""A transmission's resonance spans at least this many ticks (its frequency ≤ f/10), so
that the tick resolves it and Coulomb friction's events, at tick boundaries, stay within a
tenth of its period (docs/model.md §3.1)."""


def _reduced_inertia(jm: float, jl: float) -> float:
    """The two-mass reduced inertia μ = J_M·J_L/(J_M + J_L) (kg·m²)."""
    return jm * jl / (jm + jl)


@dataclass(frozen=True)
class Transmission:
    """A compliant transmission (belt, screw, coupling): the load J_L beyond a spring K_S
    with damping c_S, all referred to the motor shaft: a two-mass plant whose encoder reads
    the motor (docs/model.md §3.1). :meth:`from_resonance` takes a resonance instead.

    Parameters
    ----------
    load_inertia_kgm2 : float
        J_L, the load beyond the spring (kg·m²), in (0, 1].
    stiffness_nm_rad : float
        K_S, the spring's stiffness (N·m/rad), > 0.
    damping_nm_s_rad : float
        c_S, the spring's damping (N·m·s/rad), ≥ 0.
    load_coulomb_nm : float
        τc_L, Coulomb friction on the load (N·m, ≥ 0): a carriage's guide, a screw's nut
        (:attr:`Motor.coulomb_nm` stays the motor side's: its bearings, a gearbox).
    travel_mm_per_rad : float or None
        A linear axis's travel per motor radian (mm/rad), > 0: the load's residual
        vibration is then also given in µm.

    Raises
    ------
    ValueError
        If a value is out of its range (the message names the parameter and the range).
    """

    load_inertia_kgm2: float
    stiffness_nm_rad: float
    damping_nm_s_rad: float = 0.0
    load_coulomb_nm: float = 0.0
    travel_mm_per_rad: float | None = None

    def __post_init__(self) -> None:
        for name, hi, lo_open in (
            ("load_inertia_kgm2", MAX_ROTOR_INERTIA_KGM2, True),
            ("stiffness_nm_rad", None, True),
            ("damping_nm_s_rad", None, False),
            ("load_coulomb_nm", None, False),
        ):
            _set(self, name, check_real(name, getattr(self, name), 0.0, hi, lo_open=lo_open))
        if self.travel_mm_per_rad is not None:
            mm = check_real("travel_mm_per_rad", self.travel_mm_per_rad, 0.0, lo_open=True)
            _set(self, "travel_mm_per_rad", mm)

    @classmethod
    def from_resonance(
        cls,
        load_inertia_kgm2: float,
        motor_inertia_kgm2: float,
        resonance_hz: float,
        damping_ratio: float = 0.0,
        load_coulomb_nm: float = 0.0,
        travel_mm_per_rad: float | None = None,
    ) -> Transmission:
        """The transmission of a resonance f_r (seen from the motor) and damping ratio ζ:
        K_S = ω_r²·μ, c_S = 2ζ·μ·ω_r, ω_r = 2π·f_r, μ = J_M·J_L/(J_M + J_L).

        Parameters
        ----------
        load_inertia_kgm2 : float
            J_L (kg·m²), in (0, 1].
        motor_inertia_kgm2 : float
            J_M, what turns rigidly with the rotor (:attr:`Motor.inertia_kgm2`), > 0.
        resonance_hz : float
            f_r (Hz), > 0.
        damping_ratio : float
            ζ, in [0, 1].
        load_coulomb_nm, travel_mm_per_rad : float, float or None
            As in the class.

        Returns
        -------
        Transmission
            K_S and c_S from the resonance, the other fields as given.
        """
        jl = check_real("load_inertia_kgm2", load_inertia_kgm2, 0.0, lo_open=True)
        jm = check_real("motor_inertia_kgm2", motor_inertia_kgm2, 0.0, lo_open=True)
        w = 2.0 * math.pi * check_real("resonance_hz", resonance_hz, 0.0, lo_open=True)
        zeta = check_real("damping_ratio", damping_ratio, 0.0, 1.0)
        mu = _reduced_inertia(jm, jl)
        return cls(jl, w * w * mu, 2.0 * zeta * mu * w, load_coulomb_nm, travel_mm_per_rad)

    def resonance_hz(self, motor_inertia_kgm2: float) -> float:
        """The resonance seen from the motor, (1/2π)·√(K_S·(J_M + J_L)/(J_M·J_L)).

        Parameters
        ----------
        motor_inertia_kgm2 : float
            J_M (kg·m²), > 0.

        Returns
        -------
        float
            The undamped resonance (Hz).
        """
        jm, jl = motor_inertia_kgm2, self.load_inertia_kgm2
        return math.sqrt(self.stiffness_nm_rad * (jm + jl) / (jm * jl)) / (2.0 * math.pi)

    def damping_ratio(self, motor_inertia_kgm2: float) -> float:
        """The damping ratio ζ = c_S/(2·μ·ω_r), μ = J_M·J_L/(J_M + J_L), ω_r² = K_S/μ: the
        inverse of :meth:`from_resonance`'s.

        Parameters
        ----------
        motor_inertia_kgm2 : float
            J_M (kg·m²), > 0.

        Returns
        -------
        float
            ζ (0 for an undamped spring).
        """
        mu = _reduced_inertia(motor_inertia_kgm2, self.load_inertia_kgm2)
        return self.damping_nm_s_rad / (2.0 * mu * math.sqrt(self.stiffness_nm_rad / mu))

    @property
    def antiresonance_hz(self) -> float:
        """The anti-resonance (1/2π)·√(K_S/J_L) (Hz): the load ringing on a motor held still."""
        return math.sqrt(self.stiffness_nm_rad / self.load_inertia_kgm2) / (2.0 * math.pi)
