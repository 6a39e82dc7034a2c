"""Parameters of the plant and of the tuned controller: frozen, validated, with units.

Every default lives here. The four tuned settings (``value``, error limit, ``k``,
``Ts/Tf``, plus the acceleration law) are kept apart from the plant's physical data, so a
search varies :class:`Settings` and never touches :class:`Plant`.

Units: angles in rad (``_rad``), speeds in rad/s, accelerations in rad/s², torques in
N·m, inertia in kg·m², time in s or in controller ticks (``_ticks``), encoder positions
in counts (quadrature ×4).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields, replace
from typing import Any

from vfgym._limits import (
    MAX_ACCEL_RAD_S2,
    MAX_ENCODER_LINES,
    MAX_INERTIA_RATIO,
    MAX_PULSE_RAD,
    MAX_ROTOR_INERTIA_KGM2,
    MAX_SAMPLE_S,
    TICK_HZ_RANGE,
)
from vfgym._validate import check_bool, check_choice, check_int, check_real


def _set(obj: object, name: str, value: Any) -> None:
    """Store a validated (normalised) value on a frozen dataclass."""
    object.__setattr__(obj, name, value)


# --- the paper's set-up (seed 000, §4) -------------------------------------------------
PAPER_TICK_HZ = 140_000.0
"""Controller sampling frequency f (Hz): the SGME-02A's highest pulse frequency."""
PAPER_PULSE_RAD = 2.0 * math.pi / 2048.0
"""Pulse equivalent δ (rad per command pulse): one encoder line of a 2048-line encoder."""
PAPER_ACCEL_LIMIT_RAD_S2 = 140e3
"""The motor's acceleration limit the paper tunes against (rad/s²)."""
PAPER_K = PAPER_TICK_HZ**2 * PAPER_PULSE_RAD / PAPER_ACCEL_LIMIT_RAD_S2
"""k = a_max / a_motor with a_max = f²·δ (paper eq. 1): ≈ 429.5."""
PAPER_STEP_RAD = 10.0
"""The step of the paper's Fig. 4 (rad)."""

ACCEL_LAWS = ("rise", "slew")
"""``rise``: the error may grow away from zero by at most value/k a tick (the paper's
reading, default); ``slew``: |e_i − e_prev| ≤ value/k both ways (see docs/model.md §1)."""


@dataclass(frozen=True)
class Settings:
    """The tuned settings of the V-F controller and the servo's filter (docs/model.md §1).

    Parameters
    ----------
    value_rad : float
        V-F transformer threshold ``value`` (rad), > 0: a pulse per ``value`` of
        accumulated error, so the position gain is Kv = δ/(value·T).
    error_limit_rad : float
        Error limit ``L`` (rad), > 0, applied to the error before the accumulator.
    k : float
        Acceleration ratio a_max/a_motor, ≥ 1: the error may rise by value/k a tick.
    ts_over_tf : float
        The servo's digital filter ratio A = Ts/Tf in (0, 1] (1: no filtering).
    accel_law : str
        ``"rise"`` (default, the paper's reading) or ``"slew"`` (see :data:`ACCEL_LAWS`).

    Raises
    ------
    ValueError
        If a value is out of its range (the message names the parameter and the range).
    """

    value_rad: float = 1.0
    error_limit_rad: float = 1.0
    k: float = PAPER_K
    ts_over_tf: float = 0.25
    accel_law: str = "rise"

    def __post_init__(self) -> None:
        _set(self, "value_rad", check_real("value_rad", self.value_rad, 0.0, lo_open=True))
        _set(
            self,
            "error_limit_rad",
            check_real("error_limit_rad", self.error_limit_rad, 0.0, lo_open=True),
        )
        _set(self, "k", check_real("k", self.k, 1.0))
        _set(self, "ts_over_tf", check_real("ts_over_tf", self.ts_over_tf, 0.0, 1.0, lo_open=True))
        check_choice("accel_law", self.accel_law, ACCEL_LAWS)

    def replace(self, **changes: Any) -> Settings:
        """A copy with some fields changed (validated again).

        Parameters
        ----------
        **changes
            Fields of :class:`Settings` and their new values.

        Returns
        -------
        Settings
            The new settings.
        """
        return replace(self, **changes)


PAPER_SETTINGS = Settings()
"""The paper's baseline: value = L = 1 rad, k = f²δ/140e3, Ts/Tf = 1/4 (the patent's A)."""


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


@dataclass(frozen=True)
class Servo:
    """The patent's digital servo, less its tuned filter ratio (docs/model.md §2).

    Parameters
    ----------
    gear : int
        Electronic gear g, encoder counts per command pulse (whole number, ≥ 1).
    sample_ticks : int
        Ns, the speed counter's sample period Ts = Ns controller ticks (≥ 1).
    speed_gain_b : float
        B, the speed counter's output multiplier (x = B·count), > 0; K2 = B·Ts, so the
        servo's position gain is Kv = 1/(B·Ts).
    torque_per_count_nm : float
        K3, the PWM + power amplifier gain (N·m per count of error), > 0, tuned for the
        bare motor (see docs/axes.md, "Motor preset and servo defaults").
    follows_load : bool
        True (default): the drive scales K3 with the total inertia, K3·(1 + inertia_ratio),
        as a drive does once its inertia ratio is set, so a loaded loop keeps the bare
        loop's natural frequency ωn = sqrt(K3·K4) and damping ζ = K2·ωn/2
        (K4 = counts per rad / J). False: K3 stays as tuned for the bare motor, so load
        lowers ωn by sqrt(1 + ratio) and ζ with it (a mis-tuned drive, to study
        mis-tuning). :attr:`Plant.torque_per_count_nm` is the K3 in force.

    Raises
    ------
    ValueError
        If a value is out of its range (the message names the parameter and the range).
    """

    gear: int = 4
    sample_ticks: int = 70
    speed_gain_b: float = 12.5
    torque_per_count_nm: float = 5.3e-4
    follows_load: bool = True

    def __post_init__(self) -> None:
        _set(self, "gear", check_int("gear", self.gear, 1))
        _set(self, "sample_ticks", check_int("sample_ticks", self.sample_ticks, 1))
        _set(self, "speed_gain_b", check_real("speed_gain_b", self.speed_gain_b, 0.0, lo_open=True))
        _set(
            self,
            "torque_per_count_nm",
            check_real("torque_per_count_nm", self.torque_per_count_nm, 0.0, lo_open=True),
        )
        _set(self, "follows_load", check_bool("follows_load", self.follows_load))


RESONANCE_TICKS_MIN = 10.0
"""A transmission's resonance spans at least this many ticks (its frequency ≤ f/10), so
that the tick resolves it and Coulomb friction's events, at tick boundaries, stay within a
tenth of its period (docs/model.md §3.1)."""


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
        mu = jm * jl / (jm + jl)
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

    @property
    def antiresonance_hz(self) -> float:
        """The anti-resonance (1/2π)·√(K_S/J_L) (Hz): the load ringing on a motor held still."""
        return math.sqrt(self.stiffness_nm_rad / self.load_inertia_kgm2) / (2.0 * math.pi)


@dataclass(frozen=True)
class Plant:
    """Everything physical: time base, pulse equivalent, servo, motor (docs/model.md).

    Parameters
    ----------
    tick_hz : float
        Controller tick rate f (Hz), in [1 kHz, 10 MHz] ; one tick
        is T = 1/f.
    pulse_rad : float
        Pulse equivalent δ (rad per command pulse), in (0, π/2].
    servo : Servo
        The digital servo.
    motor : Motor
        The motor, its load and encoder: with a transmission, what turns rigidly with the
        rotor.
    transmission : Transmission or None
        A compliant load beyond the motor (a two-mass plant, docs/model.md §3.1), or
        ``None`` (default): the load turns rigidly with the motor.

    Raises
    ------
    ValueError
        If a value is out of its range, the servo's sample period Ts exceeds 10 ms,
        ``servo`` / ``motor`` / ``transmission`` is not a :class:`Servo` /
        :class:`Motor` / :class:`Transmission`, or the transmission's resonance is above
        f/10 (:data:`RESONANCE_TICKS_MIN`).
    """

    tick_hz: float = PAPER_TICK_HZ
    pulse_rad: float = PAPER_PULSE_RAD
    servo: Servo = field(default_factory=Servo)
    motor: Motor = field(default_factory=Motor)
    transmission: Transmission | None = None

    def __post_init__(self) -> None:
        _set(self, "tick_hz", check_real("tick_hz", self.tick_hz, *TICK_HZ_RANGE))
        _set(
            self,
            "pulse_rad",
            check_real("pulse_rad", self.pulse_rad, 0.0, MAX_PULSE_RAD, lo_open=True),
        )
        if not isinstance(self.servo, Servo):
            raise ValueError(f"servo={self.servo!r} must be a vfgym.Servo")
        if not isinstance(self.motor, Motor):
            raise ValueError(f"motor={self.motor!r} must be a vfgym.Motor")
        tr = self.transmission
        if tr is not None:
            if not isinstance(tr, Transmission):
                raise ValueError(f"transmission={tr!r} must be a vfgym.Transmission or None")
            m = self.motor
            held = m.coulomb_nm + tr.load_coulomb_nm + abs(m.load_torque_nm)
            if held >= m.peak_torque_nm:
                raise ValueError(
                    f"transmission.load_coulomb_nm={tr.load_coulomb_nm!r} is out of range: with "
                    f"the motor's friction and load torque ({held:g} N·m) it must stay below "
                    f"peak_torque_nm={m.peak_torque_nm:g}, else the motor cannot move its load"
                )
            most = self.tick_hz / RESONANCE_TICKS_MIN
            if tr.resonance_hz(self.motor.inertia_kgm2) > most:
                raise ValueError(
                    f"transmission.stiffness_nm_rad={tr.stiffness_nm_rad!r} is out of range: "
                    f"its resonance ({tr.resonance_hz(self.motor.inertia_kgm2):.6g} Hz) must "
                    f"be at most f/{RESONANCE_TICKS_MIN:g} = {most:.6g} Hz"
                )
        if self.sample_s > MAX_SAMPLE_S:
            most = math.floor(MAX_SAMPLE_S * self.tick_hz + 1e-9)
            raise ValueError(
                f"servo.sample_ticks={self.servo.sample_ticks!r} is out of range at tick_hz="
                f"{self.tick_hz:g}: allowed whole numbers in [1, {most}] (a sample period "
                f"Ts of at most {MAX_SAMPLE_S * 1e3:g} ms)"
            )

    def __repr__(self) -> str:
        # the dataclass's own repr, without ``transmission`` when there is none: a rigid
        # plant reads as it did before transmissions, so digests of it (the per-move
        # optima's moves-key) stay
        shown = (f for f in fields(self) if f.name != "transmission" or self.transmission)
        parts = ", ".join(f"{f.name}={getattr(self, f.name)!r}" for f in shown)
        return f"{type(self).__qualname__}({parts})"

    @property
    def tick_s(self) -> float:
        """Controller tick T = 1/f (s)."""
        return 1.0 / self.tick_hz

    @property
    def sample_s(self) -> float:
        """Servo sample period Ts = Ns·T (s)."""
        return self.servo.sample_ticks / self.tick_hz

    @property
    def pulse_top_speed_rad_s(self) -> float:
        """v_max = δ·f: one pulse per tick."""
        return self.pulse_rad * self.tick_hz

    @property
    def torque_per_count_nm(self) -> float:
        """K3 in force on this plant (N·m per count): the servo's K3 times
        (1 + inertia_ratio) when it follows its load (:class:`Servo`), else as tuned; with
        a transmission, times the whole inertia over the rotor's, (J_M + J_L)/J_rotor."""
        sv = self.servo
        if not sv.follows_load:
            return sv.torque_per_count_nm
        if self.transmission is not None:  # the drive is set for the whole load
            return sv.torque_per_count_nm * (self.inertia_kgm2 / self.motor.rotor_inertia_kgm2)
        return sv.torque_per_count_nm * (1.0 + self.motor.inertia_ratio)

    @property
    def inertia_kgm2(self) -> float:
        """The whole inertia the motor moves (kg·m²): :attr:`Motor.inertia_kgm2`, plus the
        transmission's load J_L where one is stated."""
        tr = self.transmission
        return self.motor.inertia_kgm2 + (0.0 if tr is None else tr.load_inertia_kgm2)

    @property
    def resonance_hz(self) -> float | None:
        """The transmission's resonance seen from the motor (Hz); ``None`` for a rigid load."""
        tr = self.transmission
        return None if tr is None else tr.resonance_hz(self.motor.inertia_kgm2)

    @property
    def servo_kv(self) -> float:
        """The servo's position gain Kv = 1/(B·Ts) (1/s), the patent's velocity constant."""
        return 1.0 / (self.servo.speed_gain_b * self.sample_s)

    def replace(self, **changes: Any) -> Plant:
        """A copy with some fields changed (validated again).

        Parameters
        ----------
        **changes
            Fields of :class:`Plant` and their new values.

        Returns
        -------
        Plant
            The new plant.
        """
        return replace(self, **changes)

    def with_motor(self, **changes: Any) -> Plant:
        """A copy whose motor has some fields changed.

        Parameters
        ----------
        **changes
            Fields of :class:`Motor` and their new values.

        Returns
        -------
        Plant
            The new plant.
        """
        return replace(self, motor=replace(self.motor, **changes))

    def whole_ticks(self, name: str, duration_s: float) -> int:
        """A duration as a whole number (≥ 1) of controller ticks.

        Parameters
        ----------
        name : str
            The parameter the duration was given as, for the error message.
        duration_s : float
            The duration (s); within 1e-9 (relative) of a whole multiple of T.

        Returns
        -------
        int
            The number of ticks.

        Raises
        ------
        ValueError
            Naming ``name``, if ``duration_s`` is not a whole number (≥ 1) of ticks.
        """
        ticks = check_real(name, duration_s, 0.0, lo_open=True) * self.tick_hz
        if abs(ticks - round(ticks)) > 1e-9 * max(1.0, ticks) or round(ticks) < 1:
            raise ValueError(
                f"{name}={duration_s!r} is not a whole number of ticks "
                f"(T = {self.tick_s:.6g} s): allowed whole multiples of T"
            )
        return round(ticks)

    def with_sample_period(self, sample_period_s: float) -> Plant:
        """A copy whose servo samples every ``sample_period_s`` (a whole number of ticks).

        Parameters
        ----------
        sample_period_s : float
            The servo's sample period Ts (s), > 0.

        Returns
        -------
        Plant
            The new plant, with ``servo.sample_ticks = Ts·f``.

        Raises
        ------
        ValueError
            If ``sample_period_s`` is not a whole number (≥ 1) of controller ticks (raised
            by :meth:`whole_ticks`).
        """
        return self.with_servo(sample_ticks=self.whole_ticks("sample_period_s", sample_period_s))

    def with_servo(self, **changes: Any) -> Plant:
        """A copy whose servo has some fields changed.

        Parameters
        ----------
        **changes
            Fields of :class:`Servo` and their new values.

        Returns
        -------
        Plant
            The new plant.
        """
        return replace(self, servo=replace(self.servo, **changes))


PAPER_PLANT = Plant()
"""The paper's plant: 140 kHz, δ = 2π/2048, SGME-02A, the servo defaults below."""


def paper_k(plant: Plant = PAPER_PLANT, accel_limit_rad_s2: float | None = None) -> float:
    """k that holds the pulse train's acceleration to the motor's limit: f²δ / a_motor.

    Parameters
    ----------
    plant : Plant
        Gives f, δ and (by default) the motor's acceleration limit.
    accel_limit_rad_s2 : float or None
        The acceleration to hold to (rad/s²); default the motor's ``accel_limit_rad_s2``.

    Returns
    -------
    float
        k = f²δ / a (docs/model.md §1: a_max = f²δ is the uncontrolled peak).
    """
    limit = plant.motor.accel_limit_rad_s2 if accel_limit_rad_s2 is None else accel_limit_rad_s2
    return plant.tick_hz**2 * plant.pulse_rad / limit


def usable_k(plant: Plant = PAPER_PLANT) -> float:
    """k that holds the pulse train to the loaded motor's usable acceleration.

    The one home of "the loaded motor's k": the rule of thumb's k, the settings models'
    k_a and the compass sampler's k reference. A step's optimal k sits near it, on the
    acceleration limit.

    Parameters
    ----------
    plant : Plant
        The plant with the move's load.

    Returns
    -------
    float
        :func:`paper_k` at :attr:`Motor.usable_accel_rad_s2` (equal to :func:`paper_k`
        on the bare paper motor, 5x it with 5 rotor inertias of load).
    """
    return paper_k(plant, plant.motor.usable_accel_rad_s2)


@dataclass(frozen=True)
class Measures:
    """Windows and bands of the measures of a move (docs/model.md §5).

    The measures themselves are defined in :mod:`vfgym.plant.measures`.

    Parameters
    ----------
    in_position_counts : float
        Half-width of the in-position window around the final command, in encoder counts
        (a servo drive's "positioning completed width"), > 0; an axis also holds it
        within one revolution and below its shortest move.
    accel_tolerance_pct : float
        The acceleration constraint's stated tolerance (% of the limit), in (0, 5]: a run
        is feasible only if the pulse train's peak acceleration is at most the limit times
        (1 + this/100). An external train's window is lengthened until one pulse's
        quantum 2δ/w² is at most this share of the limit (docs/model.md §5.1).
    accel_window_s : float
        Window w (s) over which the pulse train's acceleration is taken as the second
        difference of its position: the V-F controller's unquantised position (no
        quantum), or an external train's count over at least this window
        (:func:`vfgym.plant.measures.accel_window_ticks`). > 0.
    steady_window_s : float
        The steady-state error is the mean error over this last stretch (s), > 0.
    in_position_pct : float or None
        If set, the in-position half-width is this % of the move instead (as
        python-control's ``step_info``), in (0, 50].

    Raises
    ------
    ValueError
        If a value is out of its range (the message names the parameter and the range).
    """

    in_position_counts: float = 8.0
    accel_tolerance_pct: float = 1.0
    accel_window_s: float = 1e-3
    steady_window_s: float = 5e-3
    in_position_pct: float | None = None

    def __post_init__(self) -> None:
        if self.in_position_pct is not None:
            _set(
                self,
                "in_position_pct",
                check_real("in_position_pct", self.in_position_pct, 0.0, 50.0, lo_open=True),
            )
        for name, hi in (
            ("in_position_counts", None),
            ("accel_tolerance_pct", 5.0),
            ("accel_window_s", None),
            ("steady_window_s", None),
        ):
            _set(self, name, check_real(name, getattr(self, name), 0.0, hi, lo_open=True))


DEFAULT_MEASURES = Measures()


def in_position_rad(measures: Measures, plant: Plant, distance_rad: float) -> float:
    """Half-width of the in-position window (rad) for a move of ``distance_rad``."""
    if measures.in_position_pct is not None:
        return abs(distance_rad) * measures.in_position_pct / 100.0
    return measures.in_position_counts * plant.motor.count_rad
