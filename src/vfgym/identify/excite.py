"""What a pulse train can reveal: constant-speed segments, directions, torque saturation.

The response fixes a parameter only where the moves excite it:

- viscous friction needs constant-speed segments at two or more speeds;
- Coulomb friction and a constant load torque separate only with constant-speed segments
  in both directions (one direction shows only their sum);
- inertia and the drive's gain separate only where the torque saturates: below the torque
  limit every torque is K3 times a count, so the response fixes J/K3 and τ/K3 only.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from vfgym.identify.model import Record
from vfgym.params import Plant

WINDOW_S = 0.005
"""Pulse rates are counted over windows of this length (s)."""

STEADY_S = 0.03
"""A constant-speed segment lasts at least this long (s)."""

STEADY_TOL = 0.03
"""…with its window rates within this fraction of their mean."""

SPEED_LEVEL_TOL = 0.15
"""Two segment speeds closer than this fraction are one speed level."""

MIN_PULSES_PER_WINDOW = 10
"""A constant-speed segment has at least this many pulses a window (slower is rest)."""

MIN_SATURATED_S = 15e-3
"""Time at the torque limit (s) from which the gain is taken as separable from inertia
(at 5 ms the benchmark's plants still traded a few % of inertia for gain)."""


@dataclass(frozen=True)
class Excitation:
    """The constant-speed segments of the captures and what they excite.

    Attributes
    ----------
    speeds_rad_s : tuple of float
        Motor speed of each constant-speed segment (rad/s, signed), in time order.
    directions : tuple of int
        The directions (+1, −1) with a constant-speed segment.
    levels : tuple of float
        The distinct speed levels (rad/s, unsigned).
    """

    speeds_rad_s: tuple[float, ...]
    directions: tuple[int, ...]
    levels: tuple[float, ...]

    @property
    def viscous(self) -> bool:
        """Two or more speed levels: viscous friction is seen."""
        return len(self.levels) >= 2

    @property
    def load(self) -> bool:
        """A constant-speed segment: the friction and load torque (their sum) are seen."""
        return bool(self.speeds_rad_s)

    @property
    def coulomb(self) -> bool:
        """Both directions: Coulomb friction separates from the load torque."""
        return len(self.directions) == 2


def steady_speeds(pulses: np.ndarray, plant: Plant) -> list[float]:
    """The motor speed (rad/s, signed) of each constant-speed segment of a pulse train.

    Parameters
    ----------
    pulses : numpy.ndarray
        −1, 0, +1 per controller tick.
    plant : Plant
        Gives the tick, the gear and the count angle (a pulse moves the motor
        ``gear`` counts).

    Returns
    -------
    list of float
        One speed per segment of at least :data:`STEADY_S` whose window rates stay within
        :data:`STEADY_TOL` of their mean.
    """
    w = max(1, round(WINDOW_S * plant.tick_hz))
    n = pulses.size // w
    if n == 0:
        return []
    rate = pulses[: n * w].astype(np.int64).reshape(n, w).sum(axis=1).astype(np.float64)
    need = max(2, round(STEADY_S / WINDOW_S))
    per_pulse = (
        plant.servo.gear * plant.motor.count_rad * plant.tick_hz / w
    )  # rad/s per pulse a window
    out: list[float] = []
    i = 0
    while i < n:
        if rate[i] == 0.0:
            i += 1
            continue
        j = i + 1
        while j < n and np.all(
            np.abs(rate[i : j + 1] - rate[i : j + 1].mean())
            <= STEADY_TOL * abs(rate[i : j + 1].mean()) + 1.0
        ):
            j += 1
        if j - i >= need and abs(rate[i:j].mean()) >= MIN_PULSES_PER_WINDOW:
            out.append(float(rate[i:j].mean()) * per_pulse)
            i = j
        else:
            i += 1
    return out


def excitation(records: Sequence[Record], plant: Plant) -> Excitation:
    """The constant-speed segments of every record and the speed levels among them.

    Parameters
    ----------
    records : sequence of Record
        The captures on the tick grid.
    plant : Plant
        The axis's plant.

    Returns
    -------
    Excitation
        Segments, directions and levels.
    """
    speeds = [v for r in records for v in steady_speeds(r.pulses, plant)]
    levels: list[float] = []
    for s in sorted(abs(v) for v in speeds):
        if not levels or s > levels[-1] * (1.0 + SPEED_LEVEL_TOL):
            levels.append(s)
    dirs = tuple(sorted({1 if v > 0 else -1 for v in speeds}, reverse=True))
    return Excitation(speeds_rad_s=tuple(speeds), directions=dirs, levels=tuple(levels))


__all__ = [
    "MIN_SATURATED_S",
    "STEADY_S",
    "Excitation",
    "excitation",
    "steady_speeds",
]
