"""The identified axis, its ``uncertainty:`` block, and what the captures cannot show.

The identified axis is the nominal one with the estimates written in: the total inertia
as the load's ``inertia_ratio`` (the rotor's inertia kept; below the rotor's own, the
rotor's inertia itself is lowered, ratio 0), the friction and load torque as absolute
values, and the drive's gain so that the K3 in force is the estimate (``follows_load``
kept as set). Its ``uncertainty:`` block is what the captures warrant, relative to the
identified plant as :class:`~vfgym.axis.Uncertainty` states them: each
estimated quantity's 95 % interval widened by :data:`MARGIN`, and at least its
:attr:`~vfgym.identify.fit.Estimate.resolution` each side (the change no single reading
of the count shows). A quantity the captures leave unknown keeps its nominal value with
a wide range (:func:`vfgym.identify.fit.wide_range`).

Without a saturating move the drive's gain is left out of the block. Below the torque
limit the response fixes only J/K3 and τ/K3: a drive whose gain is g times the one set,
with g times the inertia and torques, makes the same capture. A box cannot state that
line; the smallest box holding it (the gain's wide range on the gain, the inertia and
every torque at once) holds plants g² off in J/K3 that the capture rules out, and a
tuner made robust to them is robust to plants that are not there. The inertia and
torques are stated for the gain as set, and :func:`not_excited_notes` says what that
leaves out: along the line the plants differ only where the torque reaches its limit,
which a gain g reaches at 1/g of the torque.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from vfgym.axis import FACTOR_RANGE, Axis, Uncertainty
from vfgym.identify.excite import MIN_SATURATED_S
from vfgym.identify.fit import PARAMS, QUANTISATION_FLOOR, Estimate, Fit
from vfgym.identify.model import SAMPLE_TICKS, Record, torque_limit
from vfgym.params import Plant

MARGIN = 2.0
"""The uncertainty block's half-widths are this many times the 95 % intervals' (3.9
standard errors: a normal estimate falls outside with odds of 1 in 10 000, so the block
holds all five quantities of an axis whose intervals are right but for a few percent of
its coverage, as measured in docs/results/identify.md)."""

EXPLAINED = 3.0
"""A fit whose RMS residual exceeds this many quantisation floors does not explain the
capture."""

HOT_RATIO = 3.0
"""Mean squared residual where the torque is at its limit or the speed above the knee,
over the rest's, from which the torque–speed curve is named as the likely cause."""

GEAR_TOLERANCE = 0.02
"""Counts per pulse at rest farther than this share from the gear: the gear is wrong."""


@dataclass(frozen=True)
class Identified:
    """The identified axis and what to say about it.

    Attributes
    ----------
    axis : Axis
        The nominal axis with the estimates and their uncertainty block.
    fit : Fit
        The fit it comes from.
    notes : tuple of str
        One line for each thing the captures cannot show.
    explained : bool
        False when the residual is far above the quantisation floor.
    cause : str or None
        The likely cause of a residual far above the floor.
    """

    axis: Axis
    fit: Fit
    notes: tuple[str, ...]
    explained: bool
    cause: str | None


def identified_plant(nominal: Plant, fit: Fit) -> Plant:
    """The nominal plant with the estimates written in (see the module doc).

    Parameters
    ----------
    nominal : Plant
        The nominal axis's plant.
    fit : Fit
        The fit.

    Returns
    -------
    Plant
        Simulates as :attr:`Fit.plant` does.
    """
    m, sv = nominal.motor, nominal.servo
    total = (1.0 + m.inertia_ratio) * fit.estimate("inertia").value
    rotor, ratio = m.rotor_inertia_kgm2, total - 1.0
    if ratio < 0.0:
        rotor, ratio = m.rotor_inertia_kgm2 * total, 0.0
    motor = replace(
        m,
        rotor_inertia_kgm2=rotor,
        inertia_ratio=ratio,
        coulomb_nm=fit.estimate("coulomb_nm").value,
        viscous_nm_s_rad=fit.estimate("viscous_nm_s_rad").value,
        load_torque_nm=fit.estimate("load_torque_nm").value,
    )
    k3 = nominal.torque_per_count_nm * fit.estimate("torque_per_count").value
    per = k3 / (1.0 + ratio) if sv.follows_load else k3
    return replace(nominal, motor=motor, servo=replace(sv, torque_per_count_nm=per))


def _widen(e: Estimate) -> tuple[float, float]:
    """The estimate's interval times :data:`MARGIN`, at least its resolution each side."""
    lo = e.value - max(MARGIN * (e.value - e.low), e.resolution)
    hi = e.value + max(MARGIN * (e.high - e.value), e.resolution)
    return lo, hi


def uncertainty_of(fit: Fit, nominal: Plant) -> Uncertainty:
    """The uncertainty block of the identified axis (see the module doc).

    Parameters
    ----------
    fit : Fit
        The fit.
    nominal : Plant
        The nominal plant (its motor's limits bound the torques' ranges).

    Returns
    -------
    Uncertainty
        Inertia and gain as factors on the identified values, the torques absolute; the
        gain left out where the captures do not separate it from the inertia.
    """
    m = nominal.motor
    ranges: dict[str, tuple[float, float]] = {}
    for name in PARAMS:
        e = fit.estimate(name)
        if name == "torque_per_count" and not e.excited:
            continue  # the line the captures leave open is no box (module doc)
        lo, hi = _widen(e) if e.excited else (e.low, e.high)
        if name in ("inertia", "torque_per_count"):
            ranges[name] = (max(FACTOR_RANGE[0], lo / e.value), min(FACTOR_RANGE[1], hi / e.value))
        else:
            ranges[name] = (lo if name == "load_torque_nm" else max(0.0, lo), hi)
    # every plant of the block a motor the axis can have (Uncertainty.check_motor)
    b_lo, b_hi = ranges["viscous_nm_s_rad"]
    b_most = 0.99 * m.peak_torque_nm / m.knee_speed_rad_s
    ranges["viscous_nm_s_rad"] = (min(b_lo, b_most), min(b_hi, b_most))
    c_lo, c_hi = ranges["coulomb_nm"]
    c_hi = min(c_hi, 0.5 * m.peak_torque_nm)
    ranges["coulomb_nm"] = (min(c_lo, c_hi), c_hi)
    room = 0.95 * m.peak_torque_nm - c_hi
    l_lo, l_hi = ranges["load_torque_nm"]
    ranges["load_torque_nm"] = (max(l_lo, -room), min(l_hi, room))
    return Uncertainty(**ranges)


def torque_share(fit: Fit, plant: Plant) -> float:
    """The largest share of its torque limit the fitted plant asks for over the captures.

    Parameters
    ----------
    fit : Fit
        The fit.
    plant : Plant
        The fitted plant (gives the torque–speed curve).

    Returns
    -------
    float
        Largest |torque| over the limit at its speed (1 where the torque saturates).
    """
    most = 0.0
    for r in fit.responses:
        limit = torque_limit(plant, r.speed_rad_s, r.torque_nm)
        ask = np.abs(r.torque_nm)
        at = limit > 0.0  # (none past the motor's top speed)
        if np.any(at):
            most = max(most, float(np.max(ask[at] / limit[at])))
        if np.any(~at & (ask > 0.0)):
            return 1.0
    return most


def not_excited_notes(fit: Fit) -> list[str]:
    """One line for each quantity the captures do not excite.

    Parameters
    ----------
    fit : Fit
        The fit.

    Returns
    -------
    list of str
        The lines, naming the quantity, why, and the value and range it is left with.
    """
    exc = fit.excitation
    share = torque_share(fit, fit.plant)
    why = {
        "coulomb_nm": "constant speed in one direction only: only Coulomb friction plus load "
        "torque is seen; run the moves both ways",
        "viscous_nm_s_rad": "constant speed at fewer than two speeds: run constant-speed "
        "segments at two or more speeds",
        "load_torque_nm": "no constant-speed segment: run moves that cruise",
        "torque_per_count": (
            "the torque never reaches its limit"
            if share < 1.0
            else f"the torque is at its limit for only {fit.saturated_s * 1e3:.0f} ms, under "
            f"the {MIN_SATURATED_S * 1e3:.0f} ms from which the gain separates"
        )
        + ", so the response fixes only J/K3 and torque/K3: the inertia and torques are "
        "stated for the gain as set, and the uncertainty block leaves the gain out; a drive "
        "whose gain is g times the one set (and the inertia and torques g times these) makes "
        "the same capture but where the torque reaches its limit, at 1/g of the torque"
        + (
            f"; the fastest move asked {share:.0%} of the limit, so g is below {1 / share:.3g}"
            if 0.0 < share < 1.0
            else ""
        ),
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
        if not e.excited:
            held = (
                "out of the uncertainty block"
                if e.name == "torque_per_count"
                else f"with the range [{e.low:.4g}, {e.high:.4g}]"
            )
            out.append(
                f"{e.name}: not excited ({why[e.name]}): left at its nominal value "
                f"{e.value:.4g} {held}"
            )
    return out


def likely_cause(fit: Fit, records: Sequence[Record], nominal: Plant) -> str:
    """The likely cause of a residual far above the quantisation floor.

    Checked in turn: the encoder counts per pulse at rest against the gear; a residual
    whose power sits in one narrow band (a resonance the one-mass model lacks); a
    residual :data:`HOT_RATIO` times larger (mean square) where the fitted plant is at
    its torque limit or above the motor's knee speed (its torque–speed curve: another
    motor); else the motor preset or the encoder's lines in general.

    Parameters
    ----------
    fit : Fit
        The fit.
    records : sequence of Record
        The captures it fitted.
    nominal : Plant
        The nominal plant.

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
    return (
        "a wrong motor preset (plant.motor.preset) or encoder lines "
        "(plant.motor.encoder_lines), or a capture of another axis"
    )


def counts_per_pulse(records: Sequence[Record], tick_hz: float) -> float | None:
    """Encoder counts moved per command pulse, between rests of at least 20 ms.

    Parameters
    ----------
    records : sequence of Record
        The captures.
    tick_hz : float
        The controller's tick rate (Hz).

    Returns
    -------
    float or None
        The ratio (the gear, on a machine the axis file describes), or ``None`` without
        two rests.
    """
    moved = pulses = 0.0
    for r in records:
        n = np.cumsum(r.pulses.astype(np.int64))
        rest = _rest_samples(r, tick_hz)
        rest = rest[rest >= r.first_sample]  # an enable's sag moves the axis with no pulse
        if rest.size >= 2:
            moved += float(np.abs(np.diff(r.measured[rest])).sum())
            pulses += float(np.abs(np.diff(n[(rest + 1) * SAMPLE_TICKS - 1])).sum())
    return moved / pulses if pulses > 0 else None


def _rest_samples(record: Record, tick_hz: float) -> np.ndarray:
    """The last sample of each idle stretch of at least 20 ms (the axis at rest)."""
    s = SAMPLE_TICKS
    p = record.pulses
    n = p.size // s
    busy = np.abs(p[: n * s]).reshape(n, s).sum(axis=1) > 0
    need = max(1, round(0.02 * tick_hz / s))
    out = []
    run = 0
    for j in range(n):
        run = 0 if busy[j] else run + 1
        if run >= need and (j + 1 == n or busy[j + 1]):
            out.append(j)
    return np.asarray(out, dtype=np.int64)


def identify_report(nominal_axis: Axis, fit: Fit, records: Sequence[Record]) -> Identified:
    """The identified axis and its notes.

    Parameters
    ----------
    nominal_axis : Axis
        The nominal axis.
    fit : Fit
        The fit of the captures.
    records : sequence of Record
        The captures.

    Returns
    -------
    Identified
        The axis with the estimates and the uncertainty block, and what cannot be known.
    """
    plant = identified_plant(nominal_axis.plant, fit)
    unc = uncertainty_of(fit, nominal_axis.plant)
    axis = replace(
        nominal_axis,
        plant=plant,
        uncertainty=unc,
        description=(nominal_axis.description + " " if nominal_axis.description else "")
        + f"(identified from {', '.join(r.source for r in records)})",
    )
    notes = not_excited_notes(fit)
    explained = fit.residual_rms_counts <= EXPLAINED * QUANTISATION_FLOOR
    cause = None
    if not explained:
        cause = likely_cause(fit, records, nominal_axis.plant)
        notes.append(
            f"the model does not explain the capture: residual {fit.residual_rms_counts:.3g} "
            f"counts RMS against a quantisation floor of {QUANTISATION_FLOOR:.3g}; likely "
            f"cause: {cause}"
        )
    for r in records:
        if r.misplaced:
            notes.append(
                f"{r.source}: {r.misplaced} pulses fell on a tick already holding one and were "
                "moved to the next: the pulse clock is not the axis's tick (plant.tick_hz)"
            )
    return Identified(axis=axis, fit=fit, notes=tuple(notes), explained=explained, cause=cause)


__all__ = [
    "EXPLAINED",
    "MARGIN",
    "Identified",
    "counts_per_pulse",
    "identified_plant",
    "identify_report",
    "likely_cause",
    "not_excited_notes",
    "torque_share",
    "uncertainty_of",
]
