"""What an axis must hold beyond each value's own range: every listed move can arrive,
and the measures' windows mean something on the axis's encoder and moves.

Each check raises one ``ValueError`` line naming the key path, the value and the allowed
range; :class:`vfgym.axis.Axis` runs them on construction.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace

from vfgym.moves.distribution import MoveDistribution
from vfgym.moves.scenarios import Scenario
from vfgym.params import Measures, Plant
from vfgym.plant.measures import command_end_s


def check_arrives(sc: Scenario, base: Plant, key: str) -> None:
    """A listed point-to-point move must be able to arrive within its duration.

    Parameters
    ----------
    sc : Scenario
        The move.
    base : Plant
        The axis's plant (the move's load is added to it).
    key : str
        The move's key path in the axis file, for the message (``moves.train[2]``).

    Raises
    ------
    ValueError
        If the duration is not above the move's ideal move time, or its command does not
        reach its target within it.
    """
    if sc.tracking:
        return
    plant = sc.plant(base)
    ideal = sc.ideal_time_s(plant)
    if sc.duration_s <= ideal:
        raise ValueError(
            f"{key}.duration_s={sc.duration_s!r} is too short for move {sc.name!r} to "
            f"arrive: allowed more than its ideal move time on this axis, {ideal:.4g} s"
        )
    target = sum(d for d, _ in sc.moves) if sc.profile == "multi" else sc.distance_rad

    def short(s: Scenario) -> bool:
        return abs(float(s.command(plant)[-1]) - target) > plant.pulse_rad

    if short(sc):
        longer = sc
        while short(longer) and longer.duration_s < 30.0:  # when the command ends
            longer = replace(longer, duration_s=min(60.0, 2.0 * longer.duration_s))
        end = command_end_s(longer.command(plant), plant.tick_hz)
        raise ValueError(
            f"{key}.duration_s={sc.duration_s!r} is too short for move {sc.name!r} to "
            f"arrive: its {sc.profile} command reaches "
            f"{float(sc.command(plant)[-1]):.4g} of {target:.4g} rad by then; allowed "
            f"more than the {end:.4g} s the command takes"
        )


def _move_size_rad(sc: Scenario) -> float:
    """How far a move goes: its distance (a sine: its amplitude; several moves: the
    shortest non-zero one)."""
    if sc.profile == "multi":
        sizes = [abs(d) for d, _ in sc.moves if d != 0.0]
        return min(sizes) if sizes else 0.0
    return abs(sc.distance_rad)


def check_measures(
    measures: Measures,
    plant: Plant,
    listed: Mapping[str, Scenario],
    drawn: Mapping[str, MoveDistribution],
) -> None:
    """The measures' windows must fit the axis: the in-position window within one
    revolution of the encoder and below the shortest move (else every move is in position
    from its start and every cost is 0), the steady-state window shorter than every
    listed move.

    Parameters
    ----------
    measures : Measures
        The axis's measures.
    plant : Plant
        The axis's plant (its encoder).
    listed : Mapping of str to Scenario
        The listed moves by key path (``moves.train[0]``).
    drawn : Mapping of str to MoveDistribution
        The random move sets by key path (``moves.test.random``).

    Raises
    ------
    ValueError
        Naming ``measures.in_position_counts`` or ``measures.steady_window_s``, the value,
        the allowed range and the move that bounds it.
    """
    count_rad = plant.motor.count_rad
    if measures.in_position_pct is None:
        counts = measures.in_position_counts
        rev = plant.motor.counts_per_rev
        if counts > rev:
            raise ValueError(
                f"measures.in_position_counts={counts!r} is out of range: allowed (0, {rev}] "
                f"(one revolution of the {plant.motor.encoder_lines}-line encoder)"
            )
        sizes = {k: _move_size_rad(sc) for k, sc in listed.items() if not sc.tracking}
        sizes |= {k: d.distance_rad[0] for k, d in drawn.items()}
        if sizes:
            key = min(sizes, key=lambda k: sizes[k])
            most = sizes[key] / count_rad
            if counts >= most:
                raise ValueError(
                    f"measures.in_position_counts={counts!r} is out of range: allowed "
                    f"(0, {most:.6g}) counts, below the shortest move ({key}: "
                    f"{sizes[key]:.4g} rad)"
                )
    if listed:
        key = min(listed, key=lambda k: listed[k].duration_s)
        shortest = listed[key].duration_s
        if measures.steady_window_s >= shortest:
            raise ValueError(
                f"measures.steady_window_s={measures.steady_window_s!r} is out of range: "
                f"allowed (0, {shortest:g}) s, shorter than the shortest move ({key}: "
                f"duration_s={shortest:g})"
            )


UNITS_SLIP = 100.0
"""A stated acceleration limit this many times below what the motor's torque gives is taken
for a units slip (rad/s² given in krad/s²), not a choice."""


def check_limit(plant: Plant) -> None:
    """The stated acceleration limit must be within two orders of magnitude of what the
    loaded motor can do: far below, it is a units slip (``20`` meant as 20 krad/s²).

    Parameters
    ----------
    plant : Plant
        The axis's plant.

    Raises
    ------
    ValueError
        Naming ``plant.motor.accel_limit_rad_s2``, its value and the allowed range.
    """
    m = plant.motor
    reach = m.torque_accel_rad_s2
    if m.accel_limit_rad_s2 * UNITS_SLIP < reach:
        raise ValueError(
            f"plant.motor.accel_limit_rad_s2={m.accel_limit_rad_s2:g} is out of range: the "
            f"motor's peak torque gives {reach:.4g} rad/s², {reach / m.accel_limit_rad_s2:.3g} "
            f"times more (a units slip? the limit is in rad/s², not krad/s²); allowed at "
            f"least {reach / UNITS_SLIP:.4g}"
        )


def holding_counts(plant: Plant) -> tuple[float, float]:
    """The band of position errors (encoder counts) at which the servo holds the motor
    still against its friction and load torque: ``(|τ_load| − τc)/K3`` to
    ``(|τ_load| + τc)/K3`` (the lower edge at least 0).

    At rest the filtered speed decays to zero, so the torque command is K3 times the
    position counter; the motor sticks wherever that torque less the load torque stays
    within the Coulomb friction.

    Parameters
    ----------
    plant : Plant
        A plant with its load (an axis's, or a move's).

    Returns
    -------
    tuple of float
        The band's lower and upper edge, in counts.
    """
    m, k3 = plant.motor, plant.torque_per_count_nm
    load = abs(m.load_torque_nm)
    return max(0.0, load - m.coulomb_nm) / k3, (load + m.coulomb_nm) / k3


def check_holding(measures: Measures, plant: Plant, listed: Mapping[str, Scenario]) -> str | None:
    """Friction and load torque must let the servo stop inside the in-position window.

    Parameters
    ----------
    measures : Measures
        The axis's measures (a window in counts; a window in % of the move is not checked).
    plant : Plant
        The axis's plant.
    listed : Mapping of str to Scenario
        The listed moves by key path (their own load is added).

    Returns
    -------
    str or None
        A note when the motor may stick outside the window (the band's upper edge beyond
        it): moves may not arrive, whatever the controller.

    Raises
    ------
    ValueError
        When the whole band lies outside the window: no controller can arrive.
    """
    if measures.in_position_pct is not None:
        return None
    window = measures.in_position_counts
    plants = {"plant.motor": plant} | {
        k: sc.plant(plant) for k, sc in listed.items() if not sc.tracking
    }
    note = None
    for key, p in plants.items():
        lo, hi = holding_counts(p)
        what = (
            f"{key}: coulomb_nm={p.motor.coulomb_nm:g} with load_torque_nm="
            f"{p.motor.load_torque_nm:g} and K3={p.torque_per_count_nm:.4g} N·m/count"
        )
        if lo > window:
            raise ValueError(
                f"{what} hold the motor {lo:.3g} to {hi:.3g} counts from its target, outside "
                f"the in-position window of {window:g} counts: no controller can arrive; "
                f"allowed |load_torque_nm| − coulomb_nm below "
                f"{window * p.torque_per_count_nm:.4g} N·m (or a wider "
                "measures.in_position_counts)"
            )
        if hi > window and note is None:
            note = (
                f"{what} may stop the motor up to {hi:.3g} counts from its target, beyond the "
                f"in-position window of {window:g} counts: moves may not arrive, whatever the "
                "controller"
            )
    return note


STEP_PULSES = 8
"""The step the servo's stability check simulates (command pulses): small enough that
the torque does not saturate on any shipped motor, so the linear loop shows."""
SETTLE_S = 0.3
"""How long the check lets the step settle (s): about 50 time constants of the default
servo (Kv = 160 s⁻¹)."""


def check_servo(plant: Plant) -> None:
    """The servo must be stable: the model itself decides, by a small step simulated on
    the axis's plant (the paper's settings, :data:`STEP_PULSES` pulses).

    A loop whose gain K3 is too high for its sample period and speed gain does not settle:
    over the last quarter of the window the motor still swings over more than half its
    largest error (a stable loop stays within a count or so; friction may hold it still
    off target, which is no swing).

    Parameters
    ----------
    plant : Plant
        The axis's plant.

    Raises
    ------
    ValueError
        Naming ``plant.servo.torque_per_count_nm`` and ``speed_gain_b``, with the errors
        seen.
    """
    import numpy as np

    from vfgym.params import PAPER_SETTINGS
    from vfgym.plant import simulate, step_command

    n = round(SETTLE_S * plant.tick_hz)
    target = STEP_PULSES * plant.pulse_rad
    tr = simulate(step_command(target, n), PAPER_SETTINGS, plant)
    err = (np.asarray(tr.motor_rad) - target) / plant.motor.count_rad
    tail = err[-(len(err) // 4) :]
    late = float(tail.max() - tail.min())  # a swing, not an offset friction holds still
    peak = float(np.abs(err).max())
    if late > max(0.5 * peak, 2.0):
        sv = plant.servo
        raise ValueError(
            f"plant.servo: torque_per_count_nm={sv.torque_per_count_nm:g} with speed_gain_b="
            f"{sv.speed_gain_b:g} and sample_ticks={sv.sample_ticks} is unstable: after a "
            f"step of {STEP_PULSES} pulses the motor still swings over {late:.3g} counts "
            f"{SETTLE_S:g} s later (largest error {peak:.3g}); allowed a loop that "
            "settles: lower torque_per_count_nm or raise speed_gain_b"
        )
