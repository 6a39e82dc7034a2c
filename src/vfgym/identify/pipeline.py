"""``vfgym identify``'s steps from the captures read to the identified axis.

:func:`identify_axis` checks each capture (:func:`~vfgym.identify.checks.check_capture`:
edges lost on the encoder), places it on the tick grid, checks that its encoder counts
with its pulses and compares its pulse train with the axis's plan; fits the captures;
where a train differs from the plan at a few ticks, fits them again with the plan's train
there and keeps whichever explains the count better (the analyser or the drive may have
seen the difference: the encoder says which); where the captures do not separate the
gain and the gain as set does not explain them (a torque at its limit too briefly), fits
the gain within its prior; fits the plants along the gain's prior where the captures do
not separate the gain; on an axis that states a transmission, guesses its resonance from
the plan's resonance moves before the fit, fits on that guess, and refines the resonance
and damping on the fitted plant (:mod:`vfgym.identify.resonance`); and writes the
identified axis with its
notes (:func:`~vfgym.identify.written.identify_report`). Whether that axis may be written
is :attr:`~vfgym.identify.written.Identified.explained`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from vfgym.axis import Axis
from vfgym.identify.checks import PlanMatch, check_capture, check_direction, plan_match
from vfgym.identify.fit import EXPLAINED, QUANTISATION_FLOOR, Fit, fit
from vfgym.identify.lines import Capture
from vfgym.identify.model import Record, record_of
from vfgym.identify.plan import RESONANCE_BURSTS, RESONANCE_MOVE, Plan, make_plan
from vfgym.identify.prior import along_gain, gain_prior
from vfgym.identify.resonance import Guess, Resonance, guess_resonance, refine_resonance
from vfgym.identify.resonance_problem import resonance_segment, with_resonance
from vfgym.identify.ringing import ringing_floor
from vfgym.identify.written import Identified, identify_report
from vfgym.params import Plant, Settings


def prior_source(axis: Axis, share: float | None) -> str:
    """Where the gain's prior comes from, for the notes.

    Parameters
    ----------
    axis : Axis
        The nominal axis.
    share : float or None
        ``--gain-prior``.

    Returns
    -------
    str
        A few words.
    """
    if share is not None:
        return "--gain-prior"
    if axis.uncertainty.torque_per_count is not None:
        return "the nominal file's uncertainty.torque_per_count"
    return "the default (set it with --gain-prior)"


def _planned(record: Record, match: PlanMatch, plan_pulses: np.ndarray) -> Record:
    """The record with the plan's train at the ticks where its own differs."""
    first = int(np.flatnonzero(plan_pulses)[0])
    body = np.asarray(plan_pulses[first:], dtype=np.int8)
    pulses = record.pulses.copy()
    at = match.start_tick
    n = min(body.size, pulses.size - at)
    pulses[at : at + n] = body[:n]
    pulses[:at] = 0
    return replace(record, pulses=pulses)


def _resonance_ticks(plan: Plan, plant: Plant) -> int:
    """The length of the plan's resonance moves (ticks)."""
    move = next(m for m in plan.moves if m.name == RESONANCE_MOVE)
    return round(move.duration_s * plant.tick_hz)


def resonance_of(
    records: Sequence[Record], plan: Plan, plant: Plant, settings: Settings
) -> tuple[Guess, Plant]:
    """The resonance guessed from the plan's resonance moves, before the fit.

    Parameters
    ----------
    records : sequence of Record
        The captures on the tick grid.
    plan : Plan
        The axis's plan (its resonance moves first).
    plant : Plant
        The nominal (compliant) plant.
    settings : Settings
        The servo's filter ratio in force.

    Returns
    -------
    tuple of (Guess, Plant)
        The guess, and the nominal plant with the guessed transmission (the plant the fit
        starts from).
    """
    ticks = _resonance_ticks(plan, plant)
    guess = guess_resonance(records, plant, settings, ticks, ticks // RESONANCE_BURSTS)
    return guess, with_resonance(plant, guess.resonance_hz, guess.damping_ratio)


def refined_resonance(
    records: Sequence[Record],
    plan: Plan,
    plant: Plant,
    settings: Settings,
    result: Fit,
    guess: Guess,
) -> Resonance:
    """The resonance refined on the fitted plant, over the captures' resonance moves.

    Parameters
    ----------
    records : sequence of Record
        The captures on the tick grid.
    plan : Plan
        The axis's plan.
    plant : Plant
        The nominal (compliant) plant.
    settings : Settings
        The servo's filter ratio in force.
    result : Fit
        The fit (on the guessed transmission): its plant and states of rest.
    guess : Guess
        :func:`resonance_of`'s guess.

    Returns
    -------
    Resonance
        As :func:`~vfgym.identify.resonance.refine_resonance`.
    """
    ticks = _resonance_ticks(plan, plant)
    segs = [resonance_segment(r, ticks) for r in records]
    return refine_resonance(
        segs,
        result.plant,
        settings,
        result.starts,
        guess,
        nominal=plant,
        ticks=ticks,
        bursts=RESONANCE_BURSTS,
        evaluations=guess.evaluations,
    )


def identify_axis(
    axis: Axis,
    captures: Sequence[Capture],
    settings: Settings,
    *,
    from_enable: bool | None = None,
    gain_share: float | None = None,
) -> tuple[Identified, list[Record], list[PlanMatch]]:
    """Identify an axis from its captures (module doc).

    Parameters
    ----------
    axis : Axis
        The nominal axis.
    captures : sequence of Capture
        The captures read.
    settings : Settings
        The servo's filter ratio in force.
    from_enable : bool or None
        As :func:`~vfgym.identify.model.record_of`'s.
    gain_share : float or None
        ``--gain-prior`` (:func:`~vfgym.identify.prior.gain_prior`).

    Returns
    -------
    tuple
        The identified axis with its notes, the records fitted and each one's comparison
        with the plan.

    Raises
    ------
    ValueError
        One line naming the file, for a capture that cannot be fitted (lost encoder
        edges, the encoder counting against the pulses, or any of
        :func:`~vfgym.identify.model.record_of`'s).
    """
    plant = axis.plant
    prior = gain_prior(axis, gain_share)
    for cap in captures:
        check_capture(cap, plant)
    records = [record_of(cap, plant, from_enable) for cap in captures]
    check_direction(records, plant)
    plan = make_plan(axis, settings)
    matches = [plan_match(r, plan.pulses, plant.tick_hz) for r in records]
    nominal = plant
    guess: Guess | None = None
    if nominal.transmission is None:
        result = fit(records, plant, settings)
    else:  # the resonance moves saw the ratio of the inertia to the gain: start there
        guess, plant = resonance_of(records, plan, nominal, settings)
        phases = [st.servo_phase for st in guess.starts]
        result = fit(records, plant, settings, start_inertia=1.0 / guess.gain, start_phases=phases)
    if any(m.kind == "differs" for m in matches):
        other = [
            _planned(r, m, plan.pulses) if m.kind == "differs" else r
            for r, m in zip(records, matches, strict=True)
        ]
        alt = fit(other, plant, settings)
        if alt.residual_rms_counts < result.residual_rms_counts:
            records, result = other, alt
            matches = [replace(m, fitted="plan") if m.kind == "differs" else m for m in matches]
    floor = QUANTISATION_FLOOR
    refined: tuple[Fit, Resonance] | None = None  # the resonance refined on a fit, kept
    if guess is not None:  # a servo that rings: its own spread is the floor (its module doc)
        floor = max(floor, ringing_floor(records, result.plant, result.starts, settings))
        if result.residual_rms_counts > EXPLAINED * floor:
            # the fit's residual is sharp in the transmission (2 % off the resonance: ten
            # times the residual): fitted again from its optimum on the resonance refined
            # on the fitted plant, the better kept
            res = refined_resonance(records, plan, nominal, settings, result, guess)
            refined = (result, res)
            again = fit(
                records,
                with_resonance(plant, res.resonance_hz, res.damping_ratio),
                settings,
                near=result,
            )
            if again.residual_rms_counts < result.residual_rms_counts:
                result = again
                again_floor = ringing_floor(records, result.plant, result.starts, settings)
                floor = max(QUANTISATION_FLOOR, again_floor)
    if (
        not result.estimate("torque_per_count").excited
        and result.residual_rms_counts > EXPLAINED * floor
    ):
        # the gain as set does not explain captures whose torque saturates too briefly to
        # separate the gain: fitted within its prior, the best plant along the line
        alt = fit(records, plant, settings, near=result, gain_range=prior)
        if alt.residual_rms_counts < result.residual_rms_counts:
            result = alt
    profile = along_gain(records, plant, settings, result, prior)
    resonance = None
    if refined is not None and refined[0] is result:  # refined on the fit kept: not again
        resonance = refined[1]
    elif guess is not None:
        resonance = refined_resonance(records, plan, nominal, settings, result, guess)
    ident = identify_report(
        axis,
        result,
        records,
        profile=profile,
        prior_source=prior_source(axis, gain_share),
        captures=captures,
        matches=matches,
        resonance=resonance,
        floor_counts=floor,
    )
    return ident, records, matches


__all__ = ["identify_axis", "prior_source", "refined_resonance", "resonance_of"]
