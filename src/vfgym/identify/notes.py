"""What to say of an identification: what the captures cannot show, what in them did not
belong, and the likely cause of a fit that does not explain them.

Each is one line. :func:`not_excited_notes`: a quantity the moves do not excite, and the
drive's gain where the captures fix only the ratios to it (:mod:`vfgym.identify.prior`).
:func:`capture_notes`: glitches taken out, A and B changing in one sample, pulses off the
tick grid or moved to the next tick, a pulse train that is not the axis's plan.
:func:`likely_cause`: why a residual is far above the quantisation floor.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from vfgym.identify.checks import PlanMatch, counts_per_pulse, rest_samples, times_text
from vfgym.identify.excite import MIN_SATURATED_S
from vfgym.identify.fit import Fit
from vfgym.identify.lines import Capture
from vfgym.identify.model import SAMPLE_TICKS, Record
from vfgym.identify.prior import Profile, torque_share
from vfgym.params import Plant

HOT_RATIO = 3.0
"""Mean squared residual where the torque is at its limit or the speed above the knee,
over the rest's, from which the torque–speed curve is named as the likely cause."""

GEAR_TOLERANCE = 0.02
"""Counts per pulse at rest farther than this share from the gear: the gear is wrong."""

SLIP_COUNTS = 2.0
"""The residual at one rest farther than this from the one before (counts): the count
slipped there (a rest's residual is the count's quantisation, within a count)."""

SLIP_MOST = 64.0
"""…and no farther than this (counts: 16 lost pulses of a line); a capture whose residual
jumps by more, or at more than half of its rests, is not explained at all."""


def _gain_note(fit: Fit, profile: Profile | None, prior_source: str) -> str:
    """The gain's line where the captures do not separate it from the inertia."""
    share = torque_share(fit, fit.plant)
    why = (
        "the torque never reaches its limit"
        + (f", the fastest move asking {share:.0%} of it" if 0.0 < share < 1.0 else "")
        if fit.saturated_s == 0.0
        else f"the torque is at its limit for only {fit.saturated_s * 1e3:.0f} ms, under "
        f"the {MIN_SATURATED_S * 1e3:.0f} ms from which the gain separates"
    )
    g = fit.estimate("torque_per_count").value
    j = fit.estimate("inertia").value / g
    text = (
        f"torque_per_count: not separated from the inertia: {why}. The captures fix the "
        f"inertia and every torque over the drive's gain (inertia/gain = {j:.4g} x nominal "
        "total per K3 as set): a drive whose gain is g times the one set on an axis with g "
        "times the inertia and torques makes the same capture"
        + (
            f"; the gain as set does not explain its moments at the limit, the gain within "
            f"its prior that does, {g:.4g}, is written"
            if g != 1.0
            else ""
        )
    )
    if profile is None:
        return text + "; the gain is left as set"
    lo, hi = profile.prior
    ends = [name for name, again in zip(("low", "high"), profile.refitted, strict=True) if again]
    refit = (
        f", fitted anew at the {' and '.join(ends)} end{'s' if len(ends) > 1 else ''} where the "
        "torque reaches its limit"
        if ends
        else ""
    )
    return (
        text + f". The estimates' intervals and the uncertainty block span the gain within "
        f"its prior [{lo:.4g}, {hi:.4g}] x K3 as set, from {prior_source}{refit}. To "
        "separate them, capture moves that hold the torque at its limit for "
        f"{MIN_SATURATED_S * 1e3:.0f} ms or more (the plan, --plan, says from which load)"
    )


def not_excited_notes(
    fit: Fit, profile: Profile | None = None, prior_source: str = "the default"
) -> list[str]:
    """One line for each quantity the captures do not excite.

    Parameters
    ----------
    fit : Fit
        The fit (at the gain as set where it is not separated).
    profile : Profile or None
        The fits along the gain's prior (:func:`vfgym.identify.prior.along_gain`).
    prior_source : str
        Where the prior on the gain comes from, for the gain's line.

    Returns
    -------
    list of str
        The lines, naming the quantity, why, and the value and range it is left with.
    """
    exc = fit.excitation
    why = {
        "coulomb_nm": "constant speed in one direction only: only Coulomb friction plus load "
        "torque is seen; run the moves both ways",
        "viscous_nm_s_rad": "constant speed at fewer than two speeds: run constant-speed "
        "segments at two or more speeds",
        "load_torque_nm": "no constant-speed segment: run moves that cruise",
        "inertia": "no move accelerates the axis",
    }
    if not exc.speeds_rad_s:
        why["coulomb_nm"] = why["load_torque_nm"]
        why["viscous_nm_s_rad"] = why["load_torque_nm"]
    else:
        why["load_torque_nm"] = (
            "the captures start with the axis already held and the torque never reaches its "
            "limit: below it a load torque only adds to the error the servo holds, at rest as "
            "in motion; start the capture before enabling the drive, so that it records the "
            "axis sagging under the load"
        )
    out = []
    for e in fit.estimates:
        if e.excited:
            continue
        if e.name == "torque_per_count":
            out.append(_gain_note(fit, profile, prior_source))
            continue
        out.append(
            f"{e.name}: not excited ({why[e.name]}): left at its nominal value "
            f"{e.value:.4g} with the range [{e.low:.4g}, {e.high:.4g}]"
        )
    return out


def capture_notes(
    captures: Sequence[Capture],
    records: Sequence[Record],
    matches: Sequence[PlanMatch | None],
    axis_name: str,
) -> list[str]:
    """One line for each thing in the captures that did not belong, or was not planned.

    Parameters
    ----------
    captures : sequence of Capture
        The captures read.
    records : sequence of Record
        The same on the tick grid.
    matches : sequence of PlanMatch or None
        Each one's pulse train against the axis's plan (``None``: not compared).
    axis_name : str
        The axis's name.

    Returns
    -------
    list of str
        The lines, with the times.
    """
    out = []
    for cap, rec, match in zip(captures, records, matches, strict=True):
        src = cap.source
        if cap.glitches:
            lines = sorted({name for name, _ in cap.glitches})
            out.append(
                f"{src}: {len(cap.glitches)} glitches (a level undone within two samples) on "
                f"{', '.join(lines)} at {times_text([t for _, t in cap.glitches])}: taken out "
                "(they leave the count as it was); check the wiring if there are many"
            )
        if cap.double_steps_s.size:
            out.append(
                f"{src}: enc_a and enc_b changed in the same sample {cap.double_steps_s.size} "
                f"times (at {times_text(cap.double_steps_s)}): each taken as two counts in the "
                "direction of travel; sample at least 4x the fastest encoder edge"
            )
        if rec.off_grid_s:
            out.append(
                f"{src}: {len(rec.off_grid_s)} rising edges of pulse off the tick grid of the "
                f"others (at {times_text(rec.off_grid_s)}): taken as glitches, not pulses"
            )
        if rec.misplaced:
            out.append(
                f"{src}: {rec.misplaced} pulses fell on a tick already holding one and were "
                "moved to the next: the pulse clock is not the axis's tick (plant.tick_hz)"
            )
        line = match.note(src, axis_name) if match is not None else None
        if line is not None:
            out.append(line)
    return out


def count_slips(fit: Fit, records: Sequence[Record], tick_hz: float) -> list[tuple[float, float]]:
    """Where the fit's residual jumps between rests by more than :data:`SLIP_COUNTS`
    (none for a capture whose residual jumps by more than :data:`SLIP_MOST` or at more
    than half of its rests: a model that explains nothing).

    Parameters
    ----------
    fit : Fit
        The fit.
    records : sequence of Record
        The captures it fitted.
    tick_hz : float
        The controller's tick rate (Hz).

    Returns
    -------
    list of (float, float)
        The time (s, at the rest after the jump) and the jump (counts).
    """
    out = []
    for rec, res in zip(records, fit.residuals, strict=True):
        rest = rest_samples(rec, tick_hz)
        rest = rest[rest >= rec.first_sample] - rec.first_sample
        if rest.size < 2:
            continue
        jump = np.diff(res[rest])
        at = np.flatnonzero(np.abs(jump) > SLIP_COUNTS)
        # a slip is a few counts at a few rests; a model that misses everything jumps at
        # most rests, or by far more
        if at.size * 2 > jump.size or np.any(np.abs(jump[at]) > SLIP_MOST):
            continue
        for k in at.tolist():
            t = (rest[k + 1] + rec.first_sample + 1) * SAMPLE_TICKS / tick_hz
            out.append((float(t), float(jump[k])))
    return out


def likely_cause(
    fit: Fit,
    records: Sequence[Record],
    nominal: Plant,
    matches: Sequence[PlanMatch | None] = (),
) -> str:
    """The likely cause of a residual far above the quantisation floor.

    Checked in turn: the encoder counts per pulse at rest against the gear; a residual
    whose power sits in one narrow band (a resonance the one-mass model lacks); a
    residual :data:`HOT_RATIO` times larger (mean square) where the fitted plant is at
    its torque limit or above the motor's knee speed (its torque–speed curve: another
    motor); a count that slips between rests (:func:`count_slips`: an edge lost or
    gained where the motor was slow, or a pulse the drive did not get); a pulse train
    that is not the axis's plan (another axis's capture); else the motor preset, the
    encoder's lines or the drive's gain in general.

    Parameters
    ----------
    fit : Fit
        The fit.
    records : sequence of Record
        The captures it fitted.
    nominal : Plant
        The nominal plant.
    matches : sequence of PlanMatch or None
        The captures' pulse trains against the plan.

    Returns
    -------
    str
        One clause naming the likely cause and the axis file's key to check.
    """
    gear = nominal.servo.gear
    ratio = counts_per_pulse(records, nominal.tick_hz)
    if ratio is not None and abs(ratio - gear) > GEAR_TOLERANCE * gear:
        return (
            f"the gear: the capture moves {ratio:.4g} encoder counts per pulse, the "
            f"axis says plant.servo.gear = {gear} (or plant.motor.encoder_lines is wrong)"
        )
    res = np.concatenate(fit.residuals)
    spec = np.abs(np.fft.rfft(res - res.mean())) ** 2
    freqs = np.fft.rfftfreq(res.size, SAMPLE_TICKS / nominal.tick_hz)
    if spec.size > 10:
        k = int(np.argmax(spec[1:])) + 1
        band = (freqs > 0.9 * freqs[k]) & (freqs < 1.1 * freqs[k])
        if freqs[k] > 5.0 and spec[band].sum() > 0.5 * spec[1:].sum():
            return (
                f"a resonance near {freqs[k]:.3g} Hz that the one-mass model lacks (a "
                "compliant coupling or belt): the residual's power sits in that band"
            )
    m = nominal.motor
    hot = np.concatenate(
        [
            rec.used(r.saturated | (np.abs(r.speed_rad_s) > m.knee_speed_rad_s))
            for rec, r in zip(records, fit.responses, strict=True)
        ]
    )
    if 0 < hot.sum() < hot.size and np.mean(res[hot] ** 2) > HOT_RATIO * np.mean(res[~hot] ** 2):
        return (
            "the motor's torque-speed curve or peak torque: the residual sits where the "
            "torque is at its limit or the speed above the knee; a wrong motor preset "
            "(plant.motor.preset)"
        )
    slips = count_slips(fit, records, nominal.tick_hz)
    if slips:
        where = ", ".join(f"{d:+.1f} near {t:.4g} s" for t, d in slips[:3])
        more = f" and {len(slips) - 3} more" if len(slips) > 3 else ""
        return (
            f"the count does not hold between rests (the residual at rest jumps by {where}"
            f"{more}): an encoder edge lost or gained where the motor was slow, or a pulse "
            "the drive did not get (or got and the capture did not show)"
        )
    if any(m is not None and m.kind == "other" for m in matches):
        return (
            "the pulse train is not this axis's plan, and the model does not explain its "
            "moves: a capture of another axis, or of this one with its drive set for another "
            "load (plant.servo.torque_per_count_nm, follows_load) or another motor "
            "(plant.motor.preset)"
        )
    return (
        "a wrong motor preset (plant.motor.preset), encoder lines "
        "(plant.motor.encoder_lines) or drive gain (plant.servo.torque_per_count_nm, "
        "follows_load: a drive set for another load), or a capture of another axis"
    )


__all__ = [
    "GEAR_TOLERANCE",
    "HOT_RATIO",
    "SLIP_COUNTS",
    "SLIP_MOST",
    "capture_notes",
    "count_slips",
    "likely_cause",
    "not_excited_notes",
]
