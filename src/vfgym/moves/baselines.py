"""What tuned settings are judged against: the paper's settings, a rule of thumb derived on
paper, and two pulse sources that replace the V-F controller (fixed frequency, S-curve).

Pulse-source baselines are frozen dataclasses with a ``pulses(scenario, plant)`` method;
:func:`vfgym.evaluate` runs them through the same kernel and measures as V-F settings.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from vfgym._validate import check_real
from vfgym.moves.profiles import scurve_source_args
from vfgym.moves.pulse_sources import fixed_frequency_pulses, scurve_pulses
from vfgym.params import PAPER_PLANT, PAPER_SETTINGS, Plant, Settings, usable_k

BASELINE_NAMES = ("paper", "rule-of-thumb", "fixed-frequency", "scurve")


@dataclass(frozen=True)
class FixedFrequency:
    """A constant pulse frequency for the whole move (PLC practice).

    Parameters
    ----------
    frequency_hz : float
        The pulse frequency (pps), > 0; capped at the tick rate when run.
    ts_over_tf : float
        The servo's filter ratio, in (0, 1]; the paper's 1/4 by default.
    name : str
        A label for tables.

    Raises
    ------
    ValueError
        If a value is out of its range.
    """

    frequency_hz: float
    ts_over_tf: float = PAPER_SETTINGS.ts_over_tf
    name: str = "fixed-frequency"

    def __post_init__(self) -> None:
        check_real("frequency_hz", self.frequency_hz, 0.0, lo_open=True)
        check_real("ts_over_tf", self.ts_over_tf, 0.0, 1.0, lo_open=True)

    def move(self, pulses: int, plant: Plant) -> np.ndarray:
        """The source's pulse train for one move of ``pulses`` pulses, forward.

        Parameters
        ----------
        pulses : int
            Pulses of the move, ≥ 1.
        plant : Plant
            Gives the tick rate (and δ).

        Returns
        -------
        numpy.ndarray
            int8, 0 or +1 per tick, summing to ``pulses``.
        """
        return fixed_frequency_pulses(
            pulses, frequency_hz=min(self.frequency_hz, plant.tick_hz), tick_hz=plant.tick_hz
        )

    def pulses(self, scenario, plant: Plant) -> np.ndarray | None:
        """The source's train over a scenario's point-to-point moves.

        Parameters
        ----------
        scenario : Scenario
            The scenario; a move still running at the end of its command is cut off there.
        plant : Plant
            The scenario's plant.

        Returns
        -------
        numpy.ndarray or None
            int8, −1, 0 or +1 per tick of the scenario's command; ``None`` for a moving
            reference, which a fixed-pulse source cannot follow.
        """
        return _train(self, scenario, plant)


@dataclass(frozen=True)
class SCurveSource:
    """MCX514 S-curve fixed-pulse driving (docs/model.md §4).

    The top speed and peak acceleration are mapped to DV, SV = 1 % of DV and the jerk by
    :func:`vfgym.moves.profiles.scurve_source_args`.

    Parameters
    ----------
    speed_rad_s : float
        Top speed (rad/s), > 0.
    accel_rad_s2 : float
        Peak acceleration (rad/s²), > 0.
    ts_over_tf : float
        The servo's filter ratio, in (0, 1]; the paper's 1/4 by default.
    name : str
        A label for tables.

    Raises
    ------
    ValueError
        If a value is out of its range.
    """

    speed_rad_s: float
    accel_rad_s2: float
    ts_over_tf: float = PAPER_SETTINGS.ts_over_tf
    name: str = "scurve"

    def __post_init__(self) -> None:
        check_real("speed_rad_s", self.speed_rad_s, 0.0, lo_open=True)
        check_real("accel_rad_s2", self.accel_rad_s2, 0.0, lo_open=True)
        check_real("ts_over_tf", self.ts_over_tf, 0.0, 1.0, lo_open=True)

    def move(self, pulses: int, plant: Plant) -> np.ndarray:
        """The source's pulse train for one move of ``pulses`` pulses, forward.

        Parameters
        ----------
        pulses : int
            Pulses of the move, ≥ 1.
        plant : Plant
            Gives the tick rate (and δ).

        Returns
        -------
        numpy.ndarray
            int8, 0 or +1 per tick, summing to ``pulses``.
        """
        args = scurve_source_args(
            self.speed_rad_s, self.accel_rad_s2, plant.tick_hz, plant.pulse_rad
        )
        return scurve_pulses(pulses, **args)

    def pulses(self, scenario, plant: Plant) -> np.ndarray | None:
        """The source's train over a scenario's point-to-point moves.

        Parameters
        ----------
        scenario : Scenario
            The scenario; a move still running at the end of its command is cut off there.
        plant : Plant
            The scenario's plant.

        Returns
        -------
        numpy.ndarray or None
            int8, −1, 0 or +1 per tick of the scenario's command; ``None`` for a moving
            reference, which a fixed-pulse source cannot follow.
        """
        return _train(self, scenario, plant)


PulseSource = FixedFrequency | SCurveSource
Controller = Settings | FixedFrequency | SCurveSource


def _train(source: PulseSource, scenario, plant: Plant) -> np.ndarray | None:
    """The source's pulse train over the scenario's point-to-point moves, one entry per
    tick of the scenario's command (a move still running at the end is cut off there);
    ``None`` for a moving reference, which a fixed-pulse source cannot follow."""
    moves = scenario.move_list(plant)
    if not moves:
        return None
    n = scenario.command(plant).size
    out = np.zeros(n, dtype=np.int8)
    for start, dist in moves:
        pulses = round(abs(dist) / plant.pulse_rad)
        if pulses == 0 or start >= n:
            continue
        train = source.move(pulses, plant)[: n - start]
        seg = out[start : start + train.size]
        seg += np.int8(1 if dist > 0 else -1) * train
    np.clip(out, -1, 1, out=out)
    return out


def usable_accel(plant: Plant) -> float:
    """The acceleration a move may ask of the loaded motor (docs/model.md §3).

    Parameters
    ----------
    plant : Plant
        Gives the motor's limit, peak torque and total inertia.

    Returns
    -------
    float
        :attr:`vfgym.Motor.usable_accel_rad_s2`: peak torque over total inertia, capped
        by the stated limit (rad/s²); the paper's method applied to the axis uses it.
    """
    return plant.motor.usable_accel_rad_s2


def paper(plant: Plant = PAPER_PLANT) -> Settings:
    """The paper's settings: value = L = 1 rad, k = f²δ/140e3, Ts/Tf = 1/4.

    Parameters
    ----------
    plant : Plant
        The plant the baseline runs on.
        Not used: the paper's settings are the same on every plant.

    Returns
    -------
    Settings
        :data:`vfgym.PAPER_SETTINGS`.
    """
    return PAPER_SETTINGS


def rule_of_thumb(plant: Plant = PAPER_PLANT) -> Settings:
    """V-F settings derived on paper from the plant alone.

    - k = f²δ / a, a = :func:`usable_accel` (the paper's eq. 1 and 2 against the loaded
      motor, not the bare one);
    - value so that the tail's deceleration at top speed, Kv·v_max = δ²f²/value, stays
      within a: value = δ²f²/a (Kv = δ/(value·T));
    - L = value (the paper: most efficient when equal); Ts/Tf = 1/4 (the patent).

    Parameters
    ----------
    plant : Plant
        The plant the baseline runs on.

    Returns
    -------
    Settings
        The derived settings.
    """
    a = usable_accel(plant)
    f, d = plant.tick_hz, plant.pulse_rad
    value = d * d * f * f / a
    return Settings(
        value_rad=value,
        error_limit_rad=value,
        k=max(1.0, usable_k(plant)),
        ts_over_tf=PAPER_SETTINGS.ts_over_tf,
    )


def fixed_frequency(plant: Plant = PAPER_PLANT) -> FixedFrequency:
    """The fixed-frequency train at half the top pulse rate (f/2 = 70 kHz, 215 rad/s).

    The PLC practice of a safe constant speed; the servo alone shapes the acceleration.

    Parameters
    ----------
    plant : Plant
        The plant the baseline runs on.

    Returns
    -------
    FixedFrequency
        The source at f/2.
    """
    return FixedFrequency(frequency_hz=plant.tick_hz / 2.0)


def scurve(plant: Plant = PAPER_PLANT) -> SCurveSource:
    """The S-curve source set to the loaded motor's limits.

    Parameters
    ----------
    plant : Plant
        The plant the baseline runs on.

    Returns
    -------
    SCurveSource
        Top speed δ·f, peak acceleration :func:`usable_accel`.
    """
    return SCurveSource(speed_rad_s=plant.pulse_top_speed_rad_s, accel_rad_s2=usable_accel(plant))


_FACTORIES = {
    "paper": paper,
    "rule-of-thumb": rule_of_thumb,
    "fixed-frequency": fixed_frequency,
    "scurve": scurve,
}


@dataclass(frozen=True)
class Baseline:
    """A named baseline, derived from each scenario's own plant when evaluated.

    The rule of thumb and the S-curve follow the load's usable acceleration.

    Parameters
    ----------
    name : str
        One of :data:`BASELINE_NAMES`.

    Raises
    ------
    ValueError
        If the name is not known.
    """

    name: str

    def __post_init__(self) -> None:
        if self.name not in _FACTORIES:
            raise ValueError(
                f"baseline={self.name!r} is not known: choose one of {', '.join(_FACTORIES)}"
            )

    def resolve(self, plant: Plant) -> Settings | FixedFrequency | SCurveSource:
        """The concrete controller for this plant.

        Parameters
        ----------
        plant : Plant
            The plant it runs on.

        Returns
        -------
        Settings, FixedFrequency or SCurveSource
            The baseline derived from ``plant``.
        """
        return _FACTORIES[self.name](plant)


def baseline(name: str, plant: Plant | None = None) -> Baseline | Controller:
    """A baseline by name.

    Parameters
    ----------
    name : str
        ``paper``, ``rule-of-thumb``, ``fixed-frequency`` or ``scurve``.
    plant : Plant or None
        Resolve for this plant; ``None`` keeps the baseline unresolved.

    Returns
    -------
    Baseline, Settings, FixedFrequency or SCurveSource
        The controller for ``plant`` if given, else a :class:`Baseline` that follows each
        scenario's plant.
    """
    b = Baseline(name)
    return b if plant is None else b.resolve(plant)


def resolve(c: Controller | Baseline, plant: Plant) -> Controller:
    """A controller as it runs on ``plant``.

    Parameters
    ----------
    c : Settings, FixedFrequency, SCurveSource or Baseline
        The controller; a :class:`Baseline` is resolved, the others are returned as they
        are.
    plant : Plant
        The plant it runs on.

    Returns
    -------
    Settings, FixedFrequency or SCurveSource
        The concrete controller.
    """
    return c.resolve(plant) if isinstance(c, Baseline) else c


def controller_label(c: Controller | Baseline) -> str:
    """A short name for tables.

    Parameters
    ----------
    c : Settings, FixedFrequency, SCurveSource or Baseline
        The controller.

    Returns
    -------
    str
        The baseline's or source's name, or the V-F settings in one line.
    """
    if isinstance(c, Baseline):
        return c.name
    if isinstance(c, Settings):
        return (
            f"V-F value={c.value_rad:.4g} L={c.error_limit_rad:.4g} k={c.k:.4g} "
            f"A={c.ts_over_tf:.3g} {c.accel_law}"
        )
    return c.name


__all__ = [
    "BASELINE_NAMES",
    "Baseline",
    "Controller",
    "FixedFrequency",
    "SCurveSource",
    "baseline",
    "controller_label",
    "fixed_frequency",
    "paper",
    "resolve",
    "rule_of_thumb",
    "scurve",
    "usable_accel",
]
