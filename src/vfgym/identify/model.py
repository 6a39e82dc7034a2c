"""A capture on the simulator's tick grid, and the simulations of it for candidate plants.

The recorded pulse train drives the axis's servo and motor in the exact simulator (an
external pulse train, :func:`vfgym.plant.simulate_train`). The capture's pulses are placed
on the controller's tick grid: a pulse rises half a tick after its tick starts (as
:mod:`vfgym.io.vcd` writes it), so each pulse goes to the nearest tick (a sampled time
moves it by far less than half a tick at a sample clock ≥ 4× the pulse rate), and the
grid's phase is the middle of the pulses' offsets from their ticks: an analyser moves
every edge onto one of its samples, by up to half a sample either way, so the middle of
the extreme offsets is where the grid lies, known to within the width
(:attr:`Record.phase_width_s`) that the offsets leave free.

The count a sampled capture shows at an instant is the count at the middle of the
analyser's sample period holding that instant (an edge is stamped at the sample nearest
to it), so each residual compares the simulated angle moved on to that time
(:attr:`Record.read_offset_s`, within half a sample of the tick's end) at the motor's
speed then.

The simulation starts at the capture's first whole tick with the axis at rest, as it
was on the machine, in a state no capture records (:class:`Start`): where the motor rests
against the position the servo holds (the error the friction and a load torque left the
servo with when the axis last stopped), and the phase of the servo's sample clock. The
measured count (relative to its value at the capture's start) is compared with the
simulated motor angle in counts (relative to the same start), plus half a count (a count
c means θ/q in [c, c + 1)), every :data:`SAMPLE_TICKS` ticks: these are the residuals,
in encoder counts.

Below the torque limit a constant load torque only adds to the error the servo holds, at
rest as in motion, so a capture that starts with the axis already held cannot tell it
from that error. A capture may instead hold the drive's enable (or its brake's release):
the encoder still at the capture's start, then moving with no pulse (the load sagging
against a servo that starts with no error), then at rest again before the first pulse
(:attr:`Record.enabled`). The error the servo holds is then known (minus the counts the
axis sagged), which shows the load torque; the samples before the first pulse, while the
real enable's instant is unknown, are left out of the residuals.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, replace

import numpy as np

from vfgym.identify.capture import Capture
from vfgym.params import Plant, Settings
from vfgym.plant import simulate_train

SAMPLE_TICKS = 5
"""Residuals are taken every this many controller ticks."""

MOVING_STEPS = 4
"""More encoder steps than this before the first pulse: the axis was moving when the
capture started."""

SETTLE_S = 0.01
"""A capture must run at least this long after its last pulse (s), so that its last move
is seen whole."""

OFF_GRID_TICKS = 0.02
"""A rising edge of ``pulse`` farther than one analyser sample and this (ticks) from the
grid the other pulses share is a glitch, not a command pulse (a pulse on the grid is
moved by at most half a sample either way); so taken where they are few
(:data:`OFF_GRID_MOST`)."""

OFF_GRID_MOST = 0.01
"""…at most this share of the pulses (more: a pulse clock that is not the axis's tick)."""

QUIET_S = 0.01
"""A capture holds the drive's enable when its encoder is still for this long (s) after
the capture's start and before the first pulse, and moves in between."""


@dataclass(frozen=True)
class Record:
    """One capture on the simulator's tick grid.

    Attributes
    ----------
    source : str
        The capture's file.
    pulses : numpy.ndarray
        int8 per tick of the capture from its first whole tick (−1, 0, +1).
    measured : numpy.ndarray
        The measured count (relative to the capture's start) plus ½, at the end of every
        :data:`SAMPLE_TICKS`-th tick from the capture's start.
    phase : float
        The tick grid's phase: tick i starts at (i + phase)·T in the capture's time.
    misplaced : int
        Pulses moved to the next free tick because two fell on one.
    enabled : bool
        The capture holds the drive's enable (see the module doc).
    first_sample : int
        The first sample the residuals use (the one after the first pulse when
        ``enabled``, else 0).
    sag_counts : int
        The encoder's move between the capture's start and its first pulse (counts): on
        an enabled capture, minus the error the servo holds at the first pulse.
    read_offset_s : numpy.ndarray or None
        Per sample, when the measured count holds against the tick's end (s): the middle
        of the analyser's sample period (None: at the tick's end, a CSV).
    phase_width_s : float
        The width of tick-grid phases the pulses' sampled times leave possible (s).
    off_grid_s : tuple of float
        Capture times (s) of the rising edges of ``pulse`` left out as glitches: off the
        tick grid the other pulses share (:data:`OFF_GRID_TICKS`).
    """

    source: str
    pulses: np.ndarray
    measured: np.ndarray
    phase: float
    misplaced: int
    enabled: bool = False
    first_sample: int = 0
    sag_counts: int = 0
    read_offset_s: np.ndarray | None = None
    phase_width_s: float = 0.0
    off_grid_s: tuple[float, ...] = ()

    @property
    def first_tick(self) -> int:
        """The capture's first whole tick (0 or 1): record tick j starts at
        (j + first_tick + phase)·T."""
        return math.ceil(-self.phase - 1e-9)

    @property
    def n_ticks(self) -> int:
        """Ticks simulated."""
        return int(self.pulses.size)

    def held_range(self) -> tuple[float, float] | None:
        """The range of :attr:`Start.held_counts` an enabled capture allows, else None.

        Returns
        -------
        tuple of float or None
            (−sag − 1, −sag]: the servo holds minus the counts the axis sagged, the motor
            anywhere within that count.
        """
        if not self.enabled:
            return None
        return (-self.sag_counts - 1.0, float(-self.sag_counts))

    def used(self, x: np.ndarray) -> np.ndarray:
        """The part of a per-sample array that the residuals use.

        Parameters
        ----------
        x : numpy.ndarray
            One entry per sample (as :attr:`measured`).

        Returns
        -------
        numpy.ndarray
            From :attr:`first_sample` on.
        """
        return x[self.first_sample :]

    def residuals(self, response: Response) -> np.ndarray:
        """Measured minus simulated count at the samples used (counts).

        Parameters
        ----------
        response : Response
            A candidate plant's response to this record.

        Returns
        -------
        numpy.ndarray
            The residuals.
        """
        return self.used(self.measured - response.counts)


def record_of(capture: Capture, plant: Plant, from_enable: bool | None = None) -> Record:
    """Place a capture on the tick grid of ``plant`` (see the module doc).

    Parameters
    ----------
    capture : Capture
        The capture.
    plant : Plant
        Gives the controller's tick T.
    from_enable : bool or None
        True: the capture started before the drive was enabled (so the servo held no
        error then, even if nothing moved: a load torque within the friction does not
        sag the axis). False: it started with the axis already held. None: an enable
        is taken as recorded when the encoder moves before the first pulse and was
        still for :data:`QUIET_S` at the capture's start and before that pulse.

    Returns
    -------
    Record
        The pulse train per tick and the measured counts at the sample ticks.

    Raises
    ------
    ValueError
        Naming the file: the capture starts inside a move (a pulse in its first tick, or
        the encoder moving before the first pulse, other than an enable's sag), the
        axis is still moving :data:`QUIET_S` before the first pulse of a capture said
        to hold the enable, or the capture ends less than :data:`SETTLE_S` after its
        last pulse (shorter than its moves).
    """
    T = plant.tick_s
    src = capture.source
    capture, off_grid = _on_grid(capture, T)
    x = capture.pulse_s / T
    ang = 2.0 * math.pi * (x - 0.5)
    phase = math.atan2(float(np.sin(ang).mean()), float(np.cos(ang).mean())) / (2.0 * math.pi)
    off = x - 0.5 - np.rint(x - 0.5 - phase)  # each pulse's offset from its tick (ticks)
    spread = float(off.max() - off.min())
    width = 0.0
    if spread < 0.5:  # else a clock that is not quite the axis's: keep the circular mean
        phase = 0.5 * float(off.max() + off.min())
        if capture.sampled:
            width = max(0.0, capture.resolution_s - spread * T)
    ticks = np.rint(x - 0.5 - phase).astype(np.int64)
    first = math.ceil(-phase - 1e-9)  # the first whole tick
    last = math.floor(capture.end_s / T - phase) - 1
    before = capture.count_s < capture.pulse_s[0]
    early = int(np.count_nonzero(before))
    sag = int(capture.count[before][-1]) if early else 0
    settled = not early or float(capture.pulse_s[0] - capture.count_s[before][-1]) >= QUIET_S
    if from_enable is None:
        enabled = sag != 0 and float(capture.count_s[0]) >= QUIET_S and settled
    else:
        enabled = from_enable
    if enabled and not settled:
        raise ValueError(
            f"{src}: the encoder still moves {capture.pulse_s[0] - capture.count_s[before][-1]:.3g}"
            f" s before the first pulse: expected the axis at rest at least {QUIET_S:g} s "
            "before the moves, after the drive's enable"
        )
    if ticks[0] <= first or (early > MOVING_STEPS and not enabled):
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
    n_cap = (last - first + 1) // SAMPLE_TICKS * SAMPLE_TICKS
    pulses = np.zeros(n_cap, dtype=np.int8)
    idx = ticks - first
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
    read = None
    if capture.sampled:
        res = capture.resolution_s
        read = (np.floor(ends / res + 1e-9) + 0.5) * res - ends
    return Record(
        source=src,
        pulses=pulses,
        measured=measured + 0.5,
        phase=phase,
        misplaced=misplaced,
        enabled=enabled,
        first_sample=int(ticks[0] - first) // SAMPLE_TICKS if enabled else 0,
        sag_counts=sag,
        read_offset_s=read,
        phase_width_s=width,
        off_grid_s=off_grid,
    )


def _on_grid(capture: Capture, T: float) -> tuple[Capture, tuple[float, ...]]:
    """The capture without the few pulses off the tick grid the others share, and their
    times (see :data:`OFF_GRID_TICKS`)."""
    if not capture.sampled or capture.pulse_s.size < 10:
        return capture, ()
    x = capture.pulse_s / T - 0.5
    ang = 2.0 * math.pi * x
    phase = math.atan2(float(np.sin(ang).mean()), float(np.cos(ang).mean())) / (2.0 * math.pi)
    off = x - np.rint(x - phase) - phase
    off = off - float(np.median(off))
    bad = np.abs(off) > OFF_GRID_TICKS + capture.resolution_s / T
    if not np.any(bad) or np.count_nonzero(bad) > OFF_GRID_MOST * bad.size:
        return capture, ()
    times = tuple(float(t) for t in capture.pulse_s[bad])
    keep = ~bad
    return replace(
        capture, pulse_s=capture.pulse_s[keep], pulse_sign=capture.pulse_sign[keep]
    ), times


@dataclass(frozen=True)
class Response:
    """What a candidate plant does with one record's pulse train.

    Attributes
    ----------
    counts : numpy.ndarray
        Simulated motor angle in counts relative to the count at the capture's start
        (before the drive's enable on an enabled capture), at the record's sample ticks.
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


@dataclass(frozen=True)
class Start:
    """The state of rest a capture starts from, which it does not record.

    Attributes
    ----------
    held_counts : float
        Where the motor rests against the position the servo holds, in counts behind it:
        the servo's error is ⌈held_counts⌉ whole counts (its position counter) and the motor
        rests ⌈held_counts⌉ − held_counts into its count.
    servo_phase : int
        How far the servo's sample clock has run at the capture's first tick, in
        [0, sample_ticks).
    """

    held_counts: float = -0.5
    servo_phase: int = 0


def respond(record: Record, plant: Plant, settings: Settings, start: Start) -> Response:
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
    start : Start
        The state of rest the capture starts from.

    Returns
    -------
    Response
        The simulated counts and torque at the sample ticks.
    """
    held = math.ceil(start.held_counts)
    tr = simulate_train(
        record.pulses,
        settings,
        plant,
        start_count=min(max(held - start.held_counts, 0.0), 1.0 - 1e-12),
        servo_error_counts=held,
        servo_phase_ticks=start.servo_phase,
        decimation=SAMPLE_TICKS,
    )
    counts = tr.motor_rad / plant.motor.count_rad
    if record.read_offset_s is not None:  # the count a sampled capture shows (module doc)
        counts = counts + tr.speed_rad_s * record.read_offset_s / plant.motor.count_rad
    if record.enabled:
        counts = counts + record.sag_counts  # relative to the count before the enable
    tau = tr.torque_nm
    w = tr.speed_rad_s
    sat = np.abs(tau) >= torque_limit(plant, w, tau) * (1.0 - 1e-9)
    return Response(counts=counts, torque_nm=tau, saturated=sat, speed_rad_s=w)


def respond_many(
    records: Sequence[Record],
    jobs: Sequence[tuple[Plant, Sequence[Start]]],
    settings: Settings,
) -> list[list[Response]]:
    """Every record on every candidate, as one batch over threads (the kernel releases
    the GIL).

    Parameters
    ----------
    records : sequence of Record
        The captures.
    jobs : sequence of (Plant, sequence of Start)
        Each candidate plant with the state each record starts from.
    settings : Settings
        As in :func:`respond`.

    Returns
    -------
    list of list of Response
        ``out[i][k]``: candidate i, record k.
    """
    tasks = [(i, k) for i in range(len(jobs)) for k in range(len(records))]
    workers = max(1, min(len(tasks), os.cpu_count() or 1))

    def one(ik: tuple[int, int]) -> Response:
        plant, starts = jobs[ik[0]]
        return respond(records[ik[1]], plant, settings, starts[ik[1]])

    with ThreadPoolExecutor(max_workers=workers) as pool:
        done = list(pool.map(one, tasks))
    it = iter(done)
    return [[next(it) for _ in records] for _ in jobs]


__all__ = [
    "OFF_GRID_MOST",
    "OFF_GRID_TICKS",
    "QUIET_S",
    "SAMPLE_TICKS",
    "SETTLE_S",
    "Record",
    "Response",
    "Start",
    "record_of",
    "respond",
    "respond_many",
    "torque_limit",
]
