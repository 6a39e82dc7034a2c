"""Parameters of the plant and of the tuned controller: frozen, validated, with units.

Every default lives here (the motor's and a transmission's in :mod:`vfgym.mechanics`,
re-exported here). The four tuned settings (``value``, error limit, ``k``,
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
    MAX_PULSE_RAD,
    MAX_SAMPLE_S,
    TICK_HZ_RANGE,
)
from vfgym._validate import check_bool, check_choice, check_int, check_real
from vfgym._validate import set_checked as _set
from vfgym.mechanics import MOTOR_PRESETS as MOTOR_PRESETS  # (re-exported: the plant's parts)
from vfgym.mechanics import PAPER_ACCEL_LIMIT_RAD_S2 as PAPER_ACCEL_LIMIT_RAD_S2
from vfgym.mechanics import RESONANCE_TICKS_MIN as RESONANCE_TICKS_MIN
from vfgym.mechanics import SGME_02A as SGME_02A
from vfgym.mechanics import Motor as Motor
from vfgym.mechanics import Transmission as Transmission

# --- the paper's set-up (seed 000, §4) -------------------------------------------------
PAPER_TICK_HZ = 140_000.0
"""Controller sampling frequency f (Hz): the SGME-02A's highest pulse frequency."""
PAPER_PULSE_RAD = 2.0 * math.pi / 2048.0
"""Pulse equivalent δ (rad per command pulse): one encoder line of a 2048-line encoder."""
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
