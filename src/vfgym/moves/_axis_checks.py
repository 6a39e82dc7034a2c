"""What an axis must hold beyond each value's own range: every listed move can arrive,
and the measures' windows mean something on the axis's encoder and moves.

Each check raises one ``ValueError`` line naming the key path, the value and the allowed
range; :class:`vfgym.moves.axis.Axis` runs them on construction.
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
