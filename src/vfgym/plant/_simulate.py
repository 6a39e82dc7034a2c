"""Public simulation entry points: the V-F pulse train alone, and the whole plant.

``params → simulate → trace``: :func:`simulate` packs the frozen parameters into the
kernel's plain float row (:func:`pack`), runs the compiled kernel once and returns a
:class:`Trace` (per-tick arrays, optionally decimated) together with the measures the
kernel streamed while it ran.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from vfgym._validate import check_finite_array, check_int, check_real
from vfgym.params import (
    ACCEL_LAWS,
    DEFAULT_MEASURES,
    PAPER_PLANT,
    PAPER_PULSE_RAD,
    PAPER_SETTINGS,
    Measures,
    Plant,
    Settings,
    in_position_rad,
)
from vfgym.plant import _kernel as K
from vfgym.plant import _layout as L
from vfgym.plant import _tick as TK
from vfgym.plant._notice import announce_compile
from vfgym.plant._two_mass import two_mass_coefficients
from vfgym.plant.measures import accel_window_ticks, command_end_s, from_acc


def vf_pulses(
    command_rad: np.ndarray,
    *,
    value_rad: float,
    error_limit_rad: float,
    k: float,
    accel_law: str = "rise",
    pulse_rad: float = PAPER_PULSE_RAD,
) -> np.ndarray:
    """The V-F controller's pulse train for a position command given per tick.

    The controller alone (docs/model.md §1): its position feedback is its own pulse
    counter, so no servo or motor is simulated.

    Parameters
    ----------
    command_rad : numpy.ndarray
        Position command P (rad), one finite value per controller tick.
    value_rad, error_limit_rad, k, accel_law
        The controller's settings, as in :class:`vfgym.Settings` (validated the same way).
    pulse_rad : float
        Pulse equivalent δ (rad per pulse), > 0.

    Returns
    -------
    numpy.ndarray
        int8, one entry per tick: +1, −1 or 0 (at most one pulse a tick).

    Raises
    ------
    ValueError
        If the command is not finite or a setting is out of its range.
    """
    cmd = check_finite_array("command_rad", command_rad)
    s = Settings(value_rad=value_rad, error_limit_rad=error_limit_rad, k=k, accel_law=accel_law)
    delta = check_real("pulse_rad", pulse_rad, 0.0, lo_open=True)
    out = np.empty(cmd.shape[0], dtype=np.int8)
    K.vf_pulses_kernel(
        cmd,
        delta,
        s.value_rad,
        s.error_limit_rad,
        s.value_rad / s.k,
        ACCEL_LAWS.index(s.accel_law),
        out,
    )
    return out


def motor_coefficients(plant: Plant) -> tuple[float, float, float, float]:
    """Exact one-tick zero-order-hold coefficients of J·dω/dt = F − b·ω (docs/model.md §3).

    Parameters
    ----------
    plant : Plant
        Gives the tick T, the total inertia J and the viscous friction b.

    Returns
    -------
    tuple of float
        ``(cww, cwf, ctw, ctf)`` such that ω(T) = cww·ω + cwf·F and
        θ(T) = θ + ctw·ω + ctf·F for a net torque F held over the tick.
    """
    m = plant.motor
    inv_j = 1.0 / m.inertia_kgm2
    T = plant.tick_s
    x = m.viscous_nm_s_rad * inv_j * T
    h = TK.phi_h.py_func(x)
    g = TK.phi_g.py_func(x)
    return math.exp(-x), T * h * inv_j, T * h, T * T * g * inv_j


def pack(
    settings: Settings,
    plant: Plant,
    measures: Measures,
    target_rad: float,
    n_ticks: int,
    use_ext: bool = False,
) -> np.ndarray:
    """The kernel's parameter row for one run (see :mod:`vfgym.plant._layout`).

    Parameters
    ----------
    settings : Settings
        The tuned settings.
    plant : Plant
        The plant.
    measures : Measures
        Windows and bands of the streamed measures.
    target_rad : float
        The command's final value: the in-position target (rad).
    n_ticks : int
        Ticks of the run (places the steady-state window at its end).
    use_ext : bool
        True when an external pulse train replaces the V-F controller.

    Returns
    -------
    numpy.ndarray
        float64, ``_layout.N_PARAMS`` entries.
    """
    m, sv = plant.motor, plant.servo
    prm = np.zeros(L.N_PARAMS, dtype=np.float64)
    T = plant.tick_s
    cww, cwf, ctw, ctf = motor_coefficients(plant)
    accw = accel_window_ticks(measures, plant, use_ext)
    prm[L.P_TICK_S] = T
    prm[L.P_DELTA] = plant.pulse_rad
    prm[L.P_VALUE] = settings.value_rad
    prm[L.P_LIMIT] = settings.error_limit_rad
    prm[L.P_STEP] = settings.value_rad / settings.k
    prm[L.P_LAW] = ACCEL_LAWS.index(settings.accel_law)
    prm[L.P_GEAR] = sv.gear
    prm[L.P_NS] = sv.sample_ticks
    prm[L.P_B] = sv.speed_gain_b
    prm[L.P_A] = settings.ts_over_tf
    prm[L.P_K3] = plant.torque_per_count_nm  # K3 in force (follows the load by default)
    prm[L.P_COUNT_RAD] = m.count_rad
    prm[L.P_INV_J] = 1.0 / m.inertia_kgm2
    prm[L.P_DAMP] = m.viscous_nm_s_rad / m.inertia_kgm2
    prm[L.P_CWW], prm[L.P_CWF], prm[L.P_CTW], prm[L.P_CTF] = cww, cwf, ctw, ctf
    prm[L.P_TC] = m.coulomb_nm
    prm[L.P_TLOAD] = m.load_torque_nm
    prm[L.P_TPEAK] = m.peak_torque_nm
    prm[L.P_WKNEE] = m.knee_speed_rad_s
    prm[L.P_WMAX] = m.max_speed_rad_s
    prm[L.P_SLOPE] = (m.torque_at_max_speed_nm - m.peak_torque_nm) / (
        m.max_speed_rad_s - m.knee_speed_rad_s
    )
    prm[L.P_TARGET] = target_rad
    prm[L.P_WIN_RAD] = in_position_rad(measures, plant, target_rad)
    prm[L.P_SS_START] = max(0, n_ticks - round(measures.steady_window_s * plant.tick_hz))
    prm[L.P_ACC_W] = accw
    prm[L.P_ACC_SCALE] = plant.pulse_rad / (accw * T) ** 2
    prm[L.P_USE_EXT] = 1.0 if use_ext else 0.0
    if plant.transmission is not None:
        prm[L.P_TWO] = 1.0
        prm[L.P_KS] = plant.transmission.stiffness_nm_rad
        prm[L.P_CS] = plant.transmission.damping_nm_s_rad
        prm[L.P_TCL] = plant.transmission.load_coulomb_nm
        prm[L.P_Z_TW : L.P_Z_LDF + 1] = two_mass_coefficients(plant)
    return prm


def check_pulses(pulses: np.ndarray, n_ticks: int) -> np.ndarray:
    """Check an external pulse train and return it as the kernel reads it.

    Parameters
    ----------
    pulses : numpy.ndarray
        One entry per tick, each −1, 0 or +1.
    n_ticks : int
        Ticks of the command the train goes with.

    Returns
    -------
    numpy.ndarray
        The train as contiguous int8.

    Raises
    ------
    ValueError
        If the train is not one-dimensional with ``n_ticks`` entries, or holds a value
        other than −1, 0, +1.
    """
    arr = np.asarray(pulses)
    if arr.ndim != 1 or arr.shape[0] != n_ticks:
        raise ValueError(
            f"pulses must hold one entry per tick of the command ({n_ticks}), got shape {arr.shape}"
        )
    if arr.size and (arr.min() < -1 or arr.max() > 1):
        raise ValueError(
            f"pulses holds {int(arr.min())}..{int(arr.max())}: allowed values are -1, 0, +1"
        )
    return np.ascontiguousarray(arr, dtype=np.int8)


def segment_kernel(prm: np.ndarray) -> Any:
    """The compiled segment loop of the plant a parameter row states: ``run_segment``'s
    rigid or two-mass loop, so that a first simulation compiles only its own."""
    return K.run_segment_two if prm[L.P_TWO] != 0.0 else K.run_segment_rigid


def run_move(
    cmd: np.ndarray, ext: np.ndarray, prm: np.ndarray, rec: np.ndarray, dec: int = 1
) -> np.ndarray:
    """One whole move through the compiled segment kernel.

    Equivalent to ``_kernel.run_one``, but the state set-up and the final read-out run as
    plain Python (the kernel functions' own ``py_func``), so a first simulation compiles
    only the hot loop: this is most of vfgym's cold-start time.

    Parameters
    ----------
    cmd : numpy.ndarray
        Position command per tick (rad), float64.
    ext : numpy.ndarray
        External pulse train (int8 per tick), or empty when the V-F controller runs.
    prm : numpy.ndarray
        The parameter row (:func:`pack`).
    rec : numpy.ndarray
        Trace rows to fill, ``(_layout.N_ROWS, n_ticks // dec)`` float64; may have no
        columns, for the measures alone.
    dec : int
        Keep every ``dec``-th tick in ``rec``.

    Returns
    -------
    numpy.ndarray
        The accumulator row the measures are decoded from (:mod:`vfgym.plant.measures`).
    """
    loop = segment_kernel(prm)
    announce_compile("simulate", "the simulation kernel", loop)
    st = np.empty(L.N_STATE, dtype=np.float64)
    ring = np.empty(K.ring_size.py_func(prm), dtype=np.float64)
    K.init_state.py_func(prm, st, ring)
    loop(cmd, ext, prm, st, ring, cmd.shape[0], rec, dec)
    acc = K.new_acc()
    K.finish.py_func(st, acc, cmd.shape[0], prm)
    return acc


@dataclass(frozen=True)
class Trace:
    """What the plant did, tick by tick (every ``decimation``-th tick), as :func:`simulate`
    returns it.

    Sample j is the state at the end of tick i = (j+1)·decimation − 1, time (i+1)·T.
    The per-tick arrays all have one entry per kept sample.

    Attributes
    ----------
    time_s : numpy.ndarray
        Time of each sample (s).
    command_rad : numpy.ndarray
        The position command P (rad).
    pulse_rad : numpy.ndarray
        Pulse position n·δ: the V-F controller's own position feedback (rad).
    motor_rad : numpy.ndarray
        Motor angle θ (rad).
    speed_rad_s : numpy.ndarray
        Motor speed ω (rad/s).
    torque_nm : numpy.ndarray
        Torque applied, after the torque–speed limit (N·m).
    servo_error_counts : numpy.ndarray
        u = pc − y, the error calculator's output (counts).
    position_counter : numpy.ndarray
        pc, the servo's position counter (counts).
    feedback_counts : numpy.ndarray
        y, the filtered speed feedback (counts).
    speed_count : numpy.ndarray
        x = B·count, the speed counter's latched output (counts).
    train_rad : numpy.ndarray
        The pulse train's unquantised position (rad): the V-F controller's
        (n + sum/value)·δ, of which ``pulse_rad`` is the whole pulses; an external train's
        n·δ (docs/model.md §5.1).
    load_rad : numpy.ndarray
        The load's angle θ_L beyond the transmission's spring, at the motor shaft (rad;
        docs/model.md §3.1); the motor's angle on a rigid plant.
    load_speed_rad_s : numpy.ndarray
        The load's speed ω_L (rad/s); the motor's on a rigid plant.
    acc : numpy.ndarray
        The measures streamed over every tick, undecoded (see :attr:`metrics`).
    settings : Settings
        The settings simulated.
    plant : Plant
        The plant simulated.
    measures : Measures
        Windows and bands of the measures.
    decimation : int
        Every ``decimation``-th tick is kept.
    target_rad : float
        The command's final value: the in-position target (rad).
    command_end_s : float
        Time at which the command reached its final value (s).
    external : bool
        An external pulse train drove the servo (``pulses`` given), not the V-F controller.
    """

    time_s: np.ndarray
    command_rad: np.ndarray
    pulse_rad: np.ndarray
    motor_rad: np.ndarray
    speed_rad_s: np.ndarray
    torque_nm: np.ndarray
    servo_error_counts: np.ndarray
    position_counter: np.ndarray
    feedback_counts: np.ndarray
    speed_count: np.ndarray
    train_rad: np.ndarray
    load_rad: np.ndarray
    load_speed_rad_s: np.ndarray
    acc: np.ndarray = field(repr=False)
    settings: Settings
    plant: Plant
    measures: Measures
    decimation: int = 1
    target_rad: float = 0.0
    command_end_s: float = 0.0
    external: bool = False

    @property
    def metrics(self) -> dict[str, Any]:
        """The measures of this move (streamed over every tick; see :mod:`vfgym.plant.measures`)."""
        return from_acc(self.acc, self.plant, self.measures, self.target_rad, self.command_end_s)

    @property
    def pulse_count(self) -> np.ndarray:
        """Signed pulses output so far (n)."""
        return np.rint(self.pulse_rad / self.plant.pulse_rad).astype(np.int64)

    @property
    def pulses(self) -> np.ndarray:
        """The pulse per tick (−1, 0, +1); only for an undecimated trace."""
        if self.decimation != 1:
            raise ValueError("pulses per tick need decimation=1")
        return np.diff(self.pulse_count, prepend=0).astype(np.int8)

    @property
    def n_ticks(self) -> int:
        """Ticks simulated."""
        return int(self.acc[L.A_TICKS])


def simulate(
    command_rad: np.ndarray,
    settings: Settings = PAPER_SETTINGS,
    plant: Plant = PAPER_PLANT,
    *,
    pulses: np.ndarray | None = None,
    measures: Measures = DEFAULT_MEASURES,
    decimation: int = 1,
) -> Trace:
    """Simulate the plant for a position command given per tick (docs/model.md §1–§3).

    ``params → simulate → trace``: the V-F controller (or an external pulse train) drives
    the digital servo, the motor and the encoder, tick by tick, in one compiled call.

    Parameters
    ----------
    command_rad : numpy.ndarray
        Position command P (rad), one finite value per controller tick; its last value is
        the in-position target.
    settings : Settings
        The tuned settings (V-F controller and the servo's filter ratio).
    plant : Plant
        The plant.
    pulses : numpy.ndarray or None
        An external pulse train (−1, 0, +1 per tick) that replaces the V-F controller,
        e.g. :func:`vfgym.moves.pulse_sources.scurve_pulses`; the command is then only
        the reference the measures compare against.
    measures : Measures
        Windows and bands of the measures.
    decimation : int
        Keep every ``decimation``-th tick in the trace (the measures always see every
        tick), from 1 to the command's length.

    Returns
    -------
    Trace
        The per-tick signals and, in :attr:`Trace.metrics`, the measures of the move.

    Raises
    ------
    ValueError
        If the command is not finite, ``decimation`` is out of range, ``settings`` or
        ``plant`` has the wrong type, or ``pulses`` does not fit the command.
    """
    cmd = check_finite_array("command_rad", command_rad)
    dec = check_int("decimation", decimation, 1, cmd.shape[0])
    if not isinstance(settings, Settings):
        raise ValueError(f"settings={settings!r} must be a vfgym.Settings")
    if not isinstance(plant, Plant):
        raise ValueError(f"plant={plant!r} must be a vfgym.Plant")
    n_ticks = cmd.shape[0]
    ext = np.zeros(0, dtype=np.int8) if pulses is None else check_pulses(pulses, n_ticks)
    prm = pack(settings, plant, measures, float(cmd[-1]), n_ticks, pulses is not None)
    rec = np.empty((L.N_ROWS, n_ticks // dec), dtype=np.float64)
    acc = run_move(cmd, ext, prm, rec, dec)
    return _trace(cmd, rec, acc, settings, plant, measures, dec, pulses is not None)


def _trace(
    cmd: np.ndarray,
    rec: np.ndarray,
    acc: np.ndarray,
    settings: Settings,
    plant: Plant,
    measures: Measures,
    dec: int,
    external: bool,
) -> Trace:
    """The :class:`Trace` of a run from its trace rows and accumulator row."""
    time_s = np.arange(1, rec.shape[1] + 1, dtype=np.float64) * dec / plant.tick_hz
    return Trace(
        time_s=time_s,
        command_rad=rec[L.R_COMMAND],
        pulse_rad=rec[L.R_PULSE],
        motor_rad=rec[L.R_THETA],
        speed_rad_s=rec[L.R_OMEGA],
        torque_nm=rec[L.R_TORQUE],
        servo_error_counts=rec[L.R_ERROR],
        position_counter=rec[L.R_PC],
        feedback_counts=rec[L.R_FEEDBACK],
        speed_count=rec[L.R_SPEED_COUNT],
        train_rad=rec[L.R_TRAIN],
        load_rad=rec[L.R_LOAD],
        load_speed_rad_s=rec[L.R_LOAD_SPEED],
        acc=acc,
        settings=settings,
        plant=plant,
        measures=measures,
        decimation=dec,
        target_rad=float(cmd[-1]),
        command_end_s=command_end_s(cmd, plant.tick_hz),
        external=external,
    )


def simulate_train(
    pulses: np.ndarray,
    settings: Settings = PAPER_SETTINGS,
    plant: Plant = PAPER_PLANT,
    *,
    start_count: float = 0.0,
    servo_error_counts: int = 0,
    servo_phase_ticks: int = 0,
    decimation: int = 1,
    measures: Measures = DEFAULT_MEASURES,
) -> Trace:
    """Simulate an external pulse train from a chosen state of rest.

    :func:`simulate` with ``pulses=`` starts the motor at rest at angle 0, exactly on an
    encoder count's edge, the servo holding no error, its speed sample due
    ``sample_ticks`` ticks later. On a machine none of these is known: the motor rests
    anywhere within a count, the servo holds whatever error the friction and a load
    torque left it with when the axis last stopped, and the servo's sample clock runs on
    its own. This runs the same train from another such state (the command is zero, so
    the measures are those of a train about 0).

    Parameters
    ----------
    pulses : numpy.ndarray
        The pulse train, −1, 0 or +1 per tick (at least one tick).
    settings : Settings
        The servo's filter ratio ``ts_over_tf`` is the one setting a train leaves in force.
    plant : Plant
        The plant.
    start_count : float
        Where within its first encoder count the motor rests at tick 0, in counts, in
        [0, 1): the motor starts at ``start_count · count_rad`` (the count still 0).
    servo_error_counts : int
        The error the servo holds at tick 0, in counts (its position counter): it pushes
        with ``servo_error_counts`` times K3, which the friction (and a load torque) hold
        at rest, or else the motor moves from tick 0.
    servo_phase_ticks : int
        How far the servo's speed-sample clock has run at tick 0, in [0, sample_ticks):
        its first sample comes ``sample_ticks − servo_phase_ticks`` ticks in (the state
        :func:`simulate` reaches after that many idle ticks at rest without a load).
    decimation : int
        Keep every ``decimation``-th tick in the trace, from 1 to the train's length.
    measures : Measures
        Windows and bands of the measures.

    Returns
    -------
    Trace
        As :func:`simulate` returns it; with the defaults, the same trace as
        ``simulate(np.zeros(n), settings, plant, pulses=pulses)``.

    Raises
    ------
    ValueError
        If the train is not −1, 0, +1 per tick, or a start or the decimation is out of
        its range.
    """
    arr = np.asarray(pulses)
    n_ticks = int(arr.shape[0]) if arr.ndim == 1 else 0
    if n_ticks == 0:
        raise ValueError(f"pulses must be a non-empty train, one entry per tick: got {arr.shape}")
    ext = check_pulses(arr, n_ticks)
    if not isinstance(settings, Settings):
        raise ValueError(f"settings={settings!r} must be a vfgym.Settings")
    if not isinstance(plant, Plant):
        raise ValueError(f"plant={plant!r} must be a vfgym.Plant")
    frac = check_real("start_count", start_count, 0.0, 1.0, hi_open=True)
    held = check_int("servo_error_counts", servo_error_counts)
    phase = check_int("servo_phase_ticks", servo_phase_ticks, 0, plant.servo.sample_ticks - 1)
    dec = check_int("decimation", decimation, 1, n_ticks)
    cmd = np.zeros(n_ticks, dtype=np.float64)
    prm = pack(settings, plant, measures, 0.0, n_ticks, True)
    rec = np.empty((L.N_ROWS, n_ticks // dec), dtype=np.float64)
    loop = segment_kernel(prm)
    announce_compile("simulate", "the simulation kernel", loop)
    st = np.empty(L.N_STATE, dtype=np.float64)
    ring = np.empty(K.ring_size.py_func(prm), dtype=np.float64)
    K.init_state.py_func(prm, st, ring)
    st[L.S_THETA] = st[L.S_THS0] = frac * plant.motor.count_rad
    st[L.S_NSLEFT] = plant.servo.sample_ticks - phase
    st[L.S_PC] = held
    st[L.S_U] = held
    loop(cmd, ext, prm, st, ring, n_ticks, rec, dec)
    acc = K.new_acc()
    K.finish.py_func(st, acc, n_ticks, prm)
    return _trace(cmd, rec, acc, settings, plant, measures, dec, True)


def step_command(distance_rad: float, n_ticks: int) -> np.ndarray:
    """A step of ``distance_rad`` at tick 0, held for ``n_ticks`` ticks.

    Parameters
    ----------
    distance_rad : float
        The step (rad), finite.
    n_ticks : int
        Length of the command in controller ticks, ≥ 1.

    Returns
    -------
    numpy.ndarray
        float64, ``n_ticks`` entries all equal to ``distance_rad``.
    """
    d = check_real("distance_rad", distance_rad)
    n = check_int("n_ticks", n_ticks, 1)
    return np.full(n, d, dtype=np.float64)
