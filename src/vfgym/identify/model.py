"""A capture on the simulator's tick grid, and the simulations of it for candidate plants.

The recorded pulse train drives the axis's servo and motor in the exact simulator (an
external pulse train, ``pulses=`` of :func:`vfgym.plant.simulate`). The capture's pulses
are placed on the controller's tick grid: a pulse rises half a tick after its tick
starts (as :mod:`vfgym.io.vcd` writes it), so the grid's phase is the circular mean of
the pulse times modulo T, and each pulse goes to the nearest tick (a rounded time stamp
moves it by far less than half a tick at a sample clock ≥ 4× the pulse rate).

The simulation starts :data:`PREROLL_S` before the capture, at rest, so that a load
torque has sagged the axis to its held position when the capture begins, as it had on
the machine. The measured count (relative to its value at the capture's start) is
compared with the simulated motor angle in counts (relative to the simulated count at
the same instant), plus half a count (a count c means θ/q in [c, c + 1)), every
:data:`SAMPLE_TICKS` ticks: these are the residuals, in encoder counts.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np

from vfgym.identify.capture import Capture
from vfgym.params import Plant, Settings
from vfgym.plant import simulate

PREROLL_S = 0.2
"""Idle time simulated before the capture's start (s): the held position settles."""

SAMPLE_TICKS = 5
"""Residuals are taken every this many controller ticks."""

MOVING_STEPS = 4
"""More encoder steps than this before the first pulse: the axis was moving when the
capture started."""

SETTLE_S = 0.01
"""A capture must run at least this long after its last pulse (s), so that its last move
is seen whole."""


@dataclass(frozen=True)
class Record:
    """One capture on the simulator's tick grid.

    Attributes
    ----------
    source : str
        The capture's file.
    pulses : numpy.ndarray
        int8 per simulated tick (−1, 0, +1), the pre-roll's idle ticks first.
    preroll_ticks : int
        Idle ticks simulated before the capture's first whole tick (a multiple of
        :data:`SAMPLE_TICKS`).
    measured : numpy.ndarray
        The measured count (relative to the capture's start) plus ½, at the end of every
        :data:`SAMPLE_TICKS`-th tick from the capture's start.
    phase : float
        The tick grid's phase: tick i starts at (i + phase)·T in the capture's time.
    misplaced : int
        Pulses moved to the next free tick because two fell on one.
    """

    source: str
    pulses: np.ndarray
    preroll_ticks: int
    measured: np.ndarray
    phase: float
    misplaced: int

    @property
    def n_ticks(self) -> int:
        """Ticks simulated."""
        return int(self.pulses.size)


def record_of(capture: Capture, plant: Plant) -> Record:
    """Place a capture on the tick grid of ``plant`` (see the module doc).

    Parameters
    ----------
    capture : Capture
        The capture.
    plant : Plant
        Gives the controller's tick T.

    Returns
    -------
    Record
        The pulse train per tick and the measured counts at the sample ticks.

    Raises
    ------
    ValueError
        Naming the file: the capture starts inside a move (a pulse in its first tick, or
        the encoder moving before the first pulse) or
        ends less than :data:`SETTLE_S` after its last pulse (shorter than its moves).
    """
    T = plant.tick_s
    src = capture.source
    x = capture.pulse_s / T
    ang = 2.0 * math.pi * (x - 0.5)
    phase = math.atan2(float(np.sin(ang).mean()), float(np.cos(ang).mean())) / (2.0 * math.pi)
    ticks = np.rint(x - 0.5 - phase).astype(np.int64)
    first = math.ceil(-phase - 1e-9)  # the first whole tick
    last = math.floor(capture.end_s / T - phase) - 1
    early = int(np.count_nonzero(capture.count_s < capture.pulse_s[0]))
    if ticks[0] <= first or early > MOVING_STEPS:
        raise ValueError(
            f"{src}: the capture starts inside a move (its first pulse at "
            f"{capture.pulse_s[0]:.6g} s, {early} encoder steps before it): expected it to "
            "start before the moves, with the axis at rest"
        )
    settle = round(SETTLE_S / T)
    if ticks[-1] > last - settle:
        raise ValueError(
            f"{src}: the capture ends {capture.end_s - capture.pulse_s[-1]:.4g} s after its "
            f"last pulse: expected it to run at least {SETTLE_S:g} s after the last move's "
            "last pulse (a capture shorter than a move)"
        )
    pre = SAMPLE_TICKS * math.ceil(PREROLL_S / T / SAMPLE_TICKS)
    n_cap = (last - first + 1) // SAMPLE_TICKS * SAMPLE_TICKS
    pulses = np.zeros(pre + n_cap, dtype=np.int8)
    idx = ticks - first + pre
    misplaced = 0
    # two pulses on one tick (a clock that is not quite the axis's): the later one moves on
    for j in np.flatnonzero(np.diff(idx) <= 0):
        if idx[j + 1] <= idx[j]:
            idx[j + 1] = idx[j] + 1
            misplaced += 1
    keep = idx < pulses.size
    pulses[idx[keep]] = capture.pulse_sign[keep]
    ends = (np.arange(SAMPLE_TICKS, n_cap + 1, SAMPLE_TICKS) + first + phase) * T
    measured = capture.count_at(ends).astype(np.float64) - float(capture.count_at(np.zeros(1))[0])
    return Record(
        source=src,
        pulses=pulses,
        preroll_ticks=pre,
        measured=measured + 0.5,
        phase=phase,
        misplaced=misplaced,
    )


@dataclass(frozen=True)
class Response:
    """What a candidate plant does with one record's pulse train.

    Attributes
    ----------
    counts : numpy.ndarray
        Simulated motor angle in counts relative to the simulated count at the capture's
        start, at the record's sample ticks.
    torque_nm : numpy.ndarray
        The torque applied at the sample ticks (N·m).
    saturated : numpy.ndarray
        bool, the torque at its limit (the torque–speed curve or the peak) at the sample.
    speed_rad_s : numpy.ndarray
        Motor speed at the sample ticks (rad/s).
    """

    counts: np.ndarray
    torque_nm: np.ndarray
    saturated: np.ndarray
    speed_rad_s: np.ndarray


def torque_limit(plant: Plant, speed_rad_s: np.ndarray, torque_nm: np.ndarray) -> np.ndarray:
    """The torque available at each speed in the torque's direction (docs/model.md §3).

    Parameters
    ----------
    plant : Plant
        Gives the motor's torque–speed characteristic.
    speed_rad_s : numpy.ndarray
        Motor speed (rad/s).
    torque_nm : numpy.ndarray
        The torque's sign decides motoring (with the speed) or braking (the peak).

    Returns
    -------
    numpy.ndarray
        The limit (N·m), ≥ 0.
    """
    m = plant.motor
    w = np.abs(speed_rad_s)
    slope = (m.torque_at_max_speed_nm - m.peak_torque_nm) / (m.max_speed_rad_s - m.knee_speed_rad_s)
    curve = np.where(
        w <= m.knee_speed_rad_s,
        m.peak_torque_nm,
        np.where(w < m.max_speed_rad_s, m.peak_torque_nm + slope * (w - m.knee_speed_rad_s), 0.0),
    )
    return np.where(torque_nm * speed_rad_s > 0.0, curve, m.peak_torque_nm)


def _run_from(
    pulses: np.ndarray, plant: Plant, settings: Settings, theta0_rad: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`vfgym.plant.simulate`'s run of an external train, the motor starting at
    ``theta0_rad`` (within the first count) instead of 0: (θ, τ, ω) every
    :data:`SAMPLE_TICKS`-th tick."""
    from vfgym.params import DEFAULT_MEASURES
    from vfgym.plant import _kernel as K
    from vfgym.plant import _layout as L
    from vfgym.plant import pack

    n = pulses.size
    prm = pack(settings, plant, DEFAULT_MEASURES, 0.0, n, True)
    st = np.empty(L.N_STATE, dtype=np.float64)
    ring = np.empty(K.ring_size.py_func(prm), dtype=np.float64)
    K.init_state.py_func(prm, st, ring)
    st[L.S_THETA] = theta0_rad
    rec = np.empty((L.N_ROWS, n // SAMPLE_TICKS), dtype=np.float64)
    ext = np.ascontiguousarray(pulses, dtype=np.int8)
    K.run_segment(np.zeros(n), ext, prm, st, ring, n, rec, SAMPLE_TICKS)
    return rec[L.R_THETA], rec[L.R_TORQUE], rec[L.R_OMEGA]


def respond(
    record: Record,
    plant: Plant,
    settings: Settings,
    delay_ticks: int = 0,
    start_count: float = 0.0,
) -> Response:
    """Simulate one record's pulse train on one plant.

    Parameters
    ----------
    record : Record
        The capture on the tick grid.
    plant : Plant
        The candidate plant.
    settings : Settings
        The servo's filter ratio (``ts_over_tf``) is the one setting an external train
        leaves in force.
    delay_ticks : int
        Idle ticks added before the pre-roll, a multiple of :data:`SAMPLE_TICKS`: they
        move the servo's sample clock against the pulses (its phase on the machine is
        not recorded).
    start_count : float
        Where within its first count the motor starts, in [0, 1) counts (on the machine
        it is not known).

    Returns
    -------
    Response
        The simulated counts and torque at the sample ticks.
    """
    pulses = record.pulses
    if delay_ticks:
        pulses = np.concatenate([np.zeros(delay_ticks, dtype=np.int8), pulses])
    q = plant.motor.count_rad
    if start_count == 0.0:
        tr = simulate(
            np.zeros(pulses.size), settings, plant, pulses=pulses, decimation=SAMPLE_TICKS
        )
        theta_rad, tau_nm, w_rad_s = tr.motor_rad, tr.torque_nm, tr.speed_rad_s
    else:
        theta_rad, tau_nm, w_rad_s = _run_from(pulses, plant, settings, start_count * q)
    j0 = (record.preroll_ticks + delay_ticks) // SAMPLE_TICKS - 1  # the capture's start
    theta = theta_rad / q
    counts = theta[j0 + 1 :] - math.floor(theta[j0])
    tau = tau_nm[j0 + 1 :]
    w = w_rad_s[j0 + 1 :]
    sat = np.abs(tau) >= torque_limit(plant, w, tau) * (1.0 - 1e-9)
    return Response(counts=counts, torque_nm=tau, saturated=sat, speed_rad_s=w)


def respond_many(
    records: Sequence[Record],
    plants: Sequence[Plant],
    settings: Settings,
    delay_ticks: int = 0,
    start_count: float = 0.0,
) -> list[list[Response]]:
    """Every record on every plant, as one batch over threads (the kernel releases the GIL).

    Parameters
    ----------
    records : sequence of Record
        The captures.
    plants : sequence of Plant
        The candidate plants.
    settings : Settings
        As in :func:`respond`.
    delay_ticks, start_count
        As in :func:`respond`.

    Returns
    -------
    list of list of Response
        ``out[i][k]``: plant i, record k.
    """
    jobs = [(i, k) for i in range(len(plants)) for k in range(len(records))]
    workers = max(1, min(len(jobs), os.cpu_count() or 1))

    def one(ik: tuple[int, int]) -> Response:
        return respond(records[ik[1]], plants[ik[0]], settings, delay_ticks, start_count)

    with ThreadPoolExecutor(max_workers=workers) as pool:
        done = list(pool.map(one, jobs))
    it = iter(done)
    return [[next(it) for _ in records] for _ in plants]


__all__ = [
    "PREROLL_S",
    "SAMPLE_TICKS",
    "SETTLE_S",
    "Record",
    "Response",
    "record_of",
    "respond",
    "respond_many",
    "torque_limit",
]
