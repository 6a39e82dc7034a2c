"""The identified axis written: the estimates, an ``uncertainty:`` block safe to tune on,
and what the captures cannot show.

The identified axis is the nominal one with the estimates written in: the total inertia
as the load's ``inertia_ratio`` (the rotor's inertia kept; below the rotor's own, the
rotor's inertia itself is lowered, ratio 0), the friction and load torque as absolute
values, and the drive's gain so that the K3 in force is the estimate (``follows_load``
kept as set); where the captures do not separate the gain, the one set. A transmission's
load inertia scales with the inertia's estimate (as :class:`~vfgym.axis.PlantVariant`
scales it); its stiffness and damping are the resonance's estimates
(:mod:`vfgym.identify.resonance`) where the captures show the resonance, else the
nominal's, with a note (``vfgym identify`` then refuses to write the axis).

Its ``uncertainty:`` block (:func:`uncertainty_of`), relative to the identified plant as
:class:`~vfgym.axis.Uncertainty` states them, holds every plant the captures cannot rule
out and every range the user stated:

- each estimated quantity's 95 % interval widened by :data:`MARGIN`, and at least its
  :attr:`~vfgym.identify.fit.Estimate.resolution` each side (the change no single reading
  of the count shows); a quantity the captures leave unknown keeps its nominal value with
  a wide range (:func:`vfgym.identify.problem.wide_range`);
- where the captures fix only the ratios to the drive's gain, the same over the fits along
  the line within the gain's prior (:mod:`vfgym.identify.prior`), and the gain over its
  prior. A box holds plants off the line as well (the inertia high where the gain is
  low), which the captures rule out; over a prior of ±10 % they are at most 1.22x off in
  J/K3, the price of a block that holds the machine whatever its gain;
- a transmission's stiffness and damping, where the captures show the resonance: their
  95 % intervals widened by :data:`MARGIN` (factors on the estimates); else the nominal
  file's own ranges, relative to its transmission, kept;
- the ranges of the nominal file's own ``uncertainty:`` block for the inertia and the
  torques, which state how the axis varies in use (a payload picked up, friction warming
  up): one capture measures one payload, so each is kept, widened where the capture's
  range reaches past it, never narrowed. The gain's stated range is the prior on the
  drive's gain (a setting of the drive, not a variation in use): where the captures
  measure the gain, they replace it.

Each range is then kept to motors the axis can have (friction and load below the peak
torque, viscous friction below the peak torque at the knee speed), and each kept or
clipped range is said in one line (:attr:`Identified.kept`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

from vfgym.axis import FACTOR_RANGE, Axis, Uncertainty
from vfgym.identify.checks import PlanMatch
from vfgym.identify.fit import EXPLAINED, PARAMS, QUANTISATION_FLOOR, Estimate, Fit
from vfgym.identify.lines import Capture
from vfgym.identify.model import Record
from vfgym.identify.notes import capture_notes, likely_cause, not_excited_notes
from vfgym.identify.prior import Profile, spanned
from vfgym.identify.resonance import Resonance
from vfgym.params import Plant

MARGIN = 2.0
"""The uncertainty block's half-widths are this many times the 95 % intervals' (3.9
standard errors: a normal estimate falls outside with odds of 1 in 10 000, so the block
holds all five quantities of an axis whose intervals are right but for a few percent of
its coverage, as measured in docs/results/identify.md)."""

IN_USE = ("inertia", "coulomb_nm", "viscous_nm_s_rad", "load_torque_nm")
"""The quantities whose stated ranges describe how the axis varies in use, kept."""


@dataclass(frozen=True)
class Identified:
    """The identified axis and what to say about it.

    Attributes
    ----------
    axis : Axis
        The nominal axis with the estimates and their uncertainty block.
    fit : Fit
        The fit it comes from, each interval spanning the plants along the gain's prior
        where the captures do not separate the gain.
    notes : tuple of str
        One line for each thing the captures cannot show or did not hold as planned.
    explained : bool
        False when the residual is far above the quantisation floor: no axis to write.
    cause : str or None
        The likely cause of a residual far above the floor.
    kept : tuple of str
        One line for each stated range the block kept, and each range it clipped.
    profile : Profile or None
        The fits along the gain's prior (``None`` where the captures estimate the gain).
    resonance : Resonance or None
        A compliant axis's resonance estimate (``None`` on a rigid axis).
    floor_counts : float
        The residual's floor the fit is judged against (counts RMS): the quantisation's,
        or on a compliant axis the larger of it and a ringing servo's own
        (:func:`vfgym.identify.ringing.ringing_floor`).
    """

    axis: Axis
    fit: Fit
    notes: tuple[str, ...]
    explained: bool
    cause: str | None
    kept: tuple[str, ...] = ()
    profile: Profile | None = None
    resonance: Resonance | None = None
    floor_counts: float = QUANTISATION_FLOOR


def identified_plant(nominal: Plant, fit: Fit, resonance: Resonance | None = None) -> Plant:
    """The nominal plant with the estimates written in (see the module doc).

    Parameters
    ----------
    nominal : Plant
        The nominal axis's plant.
    fit : Fit
        The fit.
    resonance : Resonance or None
        A compliant axis's resonance estimate (its transmission written where shown).

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
    tr = nominal.transmission
    if tr is not None:
        j = fit.estimate("inertia").value
        tr = replace(tr, load_inertia_kgm2=tr.load_inertia_kgm2 * j)
        if resonance is not None and resonance.shown:
            est = resonance.transmission
            tr = replace(
                tr, stiffness_nm_rad=est.stiffness_nm_rad, damping_nm_s_rad=est.damping_nm_s_rad
            )
    return replace(
        nominal, motor=motor, servo=replace(sv, torque_per_count_nm=per), transmission=tr
    )


def _spring_ranges(
    resonance: Resonance | None, nominal_axis: Axis
) -> tuple[dict[str, tuple[float, float]], list[str]]:
    """The stiffness and damping ranges (factors on the identified values), and a line
    for each stated range kept (see the module doc)."""
    stated = nominal_axis.uncertainty
    out: dict[str, tuple[float, float]] = {}
    kept: list[str] = []
    if resonance is None or not resonance.shown:
        for name in ("stiffness", "damping"):
            s = getattr(stated, name)
            if s is not None:
                out[name] = s
                kept.append(f"{name}: the nominal file's {_text(s)} kept with its transmission")
        return out, kept
    tr, nom = resonance.transmission, nominal_axis.plant.transmission
    assert nom is not None
    for name, value, span, was in (
        ("stiffness", tr.stiffness_nm_rad, resonance.stiffness_range_nm_rad,
         nom.stiffness_nm_rad),
        ("damping", tr.damping_nm_s_rad, resonance.damping_range_nm_s_rad,
         nom.damping_nm_s_rad),
    ):  # fmt: skip
        if value <= 0.0:
            continue
        lo, hi = (x / value for x in _widened(value, *span))
        s = getattr(stated, name)
        if s is not None and was > 0.0:
            lo, hi = min(lo, s[0] * was / value), max(hi, s[1] * was / value)
            kept.append(
                f"{name}: the nominal file's {_text(s)} (on its transmission) kept, widened "
                "to hold the capture's"
            )
        out[name] = (max(FACTOR_RANGE[0], lo), min(FACTOR_RANGE[1], hi))
    return out, kept


def _widen(e: Estimate) -> tuple[float, float]:
    """The estimate's interval times :data:`MARGIN`, at least its resolution each side."""
    return _widened(e.value, e.low, e.high, e.resolution)


def _widened(value: float, low: float, high: float, resolution: float = 0.0) -> tuple[float, float]:
    """The interval ``[low, high]`` around ``value`` times :data:`MARGIN` each side, at
    least ``resolution``."""
    lo = value - max(MARGIN * (value - low), resolution)
    return lo, value + max(MARGIN * (high - value), resolution)


def _captured(fit: Fit, profile: Profile | None) -> dict[str, tuple[float, float]]:
    """What the captures warrant, each quantity in the estimates' own units (inertia and
    gain as factors on the nominal total and on K3 as set)."""
    fits = profile.fits if profile is not None else (fit,)
    out: dict[str, tuple[float, float]] = {}
    for name in PARAMS:
        e = fit.estimate(name)
        if name == "torque_per_count":
            if e.excited:
                out[name] = _widen(e)
            elif profile is not None:
                out[name] = profile.prior
            continue  # without a prior the gain is left out (the ratio alone is known)
        spans = []
        for f in fits:
            a = f.estimate(name)
            spans.append(_widen(a) if a.excited else (a.low, a.high))
        out[name] = (min(lo for lo, _ in spans), max(hi for _, hi in spans))
    return out


def _text(r: tuple[float, float]) -> str:
    return f"[{r[0]:.4g}, {r[1]:.4g}]"


def uncertainty_of(
    fit: Fit,
    nominal_axis: Axis,
    profile: Profile | None = None,
    resonance: Resonance | None = None,
) -> tuple[Uncertainty, list[str]]:
    """The uncertainty block of the identified axis (see the module doc).

    Parameters
    ----------
    fit : Fit
        The fit (at the gain as set where the captures do not separate it).
    nominal_axis : Axis
        The nominal axis: its stated ranges, its motor's limits.
    profile : Profile or None
        The fits along the gain's prior.
    resonance : Resonance or None
        A compliant axis's resonance estimate.

    Returns
    -------
    tuple of (Uncertainty, list of str)
        The block (inertia and gain as factors on the identified values, the torques
        absolute), and one line for each stated range kept and each range clipped.
    """
    m = nominal_axis.plant.motor
    stated = nominal_axis.uncertainty
    got = _captured(fit, profile)
    kept: list[str] = []
    ranges = dict(got)
    for name in IN_USE:
        s = getattr(stated, name)
        if s is None:
            continue
        lo, hi = min(got[name][0], s[0]), max(got[name][1], s[1])
        ranges[name] = (lo, hi)
        unit = " x nominal total" if name == "inertia" else ""
        wider = (
            f", widened to hold the capture's {_text(got[name])}"
            if got[name][0] < s[0] or got[name][1] > s[1]
            else f" (the capture's own: {_text(got[name])})"
        )
        kept.append(
            f"{name}: the nominal file's {_text(s)}{unit} kept, a range the axis varies "
            f"over in use that one capture cannot measure: written {_text((lo, hi))}{unit}"
            f"{wider}"
        )
    g = stated.torque_per_count
    if g is not None:
        how = (
            f"the capture measured it, {_text(got['torque_per_count'])}"
            if fit.estimate("torque_per_count").excited
            else "the capture does not separate it from the inertia, so the block spans it"
        )
        kept.append(
            f"torque_per_count: the nominal file's {_text(g)} is the prior on the drive's "
            f"gain (a setting of the drive, not a variation in use): {how}"
        )
    # relative to the identified plant, every plant a motor the axis can have
    j = fit.estimate("inertia").value
    k = fit.estimate("torque_per_count").value
    out: dict[str, tuple[float, float]] = {}
    for name, (lo, hi) in ranges.items():
        if name in ("inertia", "torque_per_count"):
            v = j if name == "inertia" else k
            out[name] = (max(FACTOR_RANGE[0], lo / v), min(FACTOR_RANGE[1], hi / v))
        else:
            out[name] = (lo if name == "load_torque_nm" else max(0.0, lo), hi)
    before = dict(out)
    b_lo, b_hi = out["viscous_nm_s_rad"]
    b_most = 0.99 * m.peak_torque_nm / m.knee_speed_rad_s
    out["viscous_nm_s_rad"] = (min(b_lo, b_most), min(b_hi, b_most))
    c_lo, c_hi = out["coulomb_nm"]
    c_hi = min(c_hi, 0.5 * m.peak_torque_nm)
    out["coulomb_nm"] = (min(c_lo, c_hi), c_hi)
    room = 0.95 * m.peak_torque_nm - c_hi
    l_lo, l_hi = out["load_torque_nm"]
    out["load_torque_nm"] = (max(l_lo, -room), min(l_hi, room))
    for name in ("coulomb_nm", "viscous_nm_s_rad", "load_torque_nm"):
        if out[name] != before[name]:
            kept.append(
                f"{name}: {_text(before[name])} clipped to {_text(out[name])}, the range a "
                f"motor with a peak torque of {m.peak_torque_nm:g} N*m can hold"
            )
    springs, spring_kept = _spring_ranges(resonance, nominal_axis)
    return Uncertainty(**out, **springs), kept + spring_kept


def identify_report(
    nominal_axis: Axis,
    fit: Fit,
    records: Sequence[Record],
    *,
    profile: Profile | None = None,
    prior_source: str = "the default",
    captures: Sequence[Capture] = (),
    matches: Sequence[PlanMatch | None] = (),
    resonance: Resonance | None = None,
    floor_counts: float = QUANTISATION_FLOOR,
) -> Identified:
    """The identified axis and its notes.

    Parameters
    ----------
    nominal_axis : Axis
        The nominal axis.
    fit : Fit
        The fit of the captures (at the gain as set where they do not separate it).
    records : sequence of Record
        The captures on the tick grid.
    profile : Profile or None
        The fits along the gain's prior (:func:`vfgym.identify.prior.along_gain`).
    prior_source : str
        Where the gain's prior comes from, for its note.
    captures : sequence of Capture
        The captures read, for what in them did not belong (empty: not said).
    matches : sequence of PlanMatch or None
        Each capture's pulse train against the axis's plan.
    resonance : Resonance or None
        A compliant axis's resonance estimate (:mod:`vfgym.identify.resonance`).
    floor_counts : float
        The residual's floor the fit is judged against (:attr:`Identified.floor_counts`):
        it explains the captures up to :data:`~vfgym.identify.fit.EXPLAINED` times it.

    Returns
    -------
    Identified
        The axis with the estimates and the uncertainty block, and what cannot be known.
    """
    plant = identified_plant(nominal_axis.plant, fit, resonance)
    unc, kept = uncertainty_of(fit, nominal_axis, profile, resonance)
    axis = replace(
        nominal_axis,
        plant=plant,
        uncertainty=unc,
        description=(nominal_axis.description + " " if nominal_axis.description else "")
        + f"(identified from {', '.join(r.source for r in records)})",
    )
    notes = not_excited_notes(fit, profile, prior_source)
    if resonance is not None and resonance.note is not None:
        notes.append(resonance.note)
    g = fit.estimate("torque_per_count")
    stated = nominal_axis.uncertainty.torque_per_count
    if g.excited and stated is not None and not stated[0] <= g.value <= stated[1]:
        notes.append(
            f"torque_per_count: the drive's gain is {g.value:.4g} x K3 as set, outside the "
            f"nominal file's {_text(stated)}: check the drive's gain setting and the motor's "
            "torque constant"
        )
    matches = list(matches) or [None] * len(records)
    if captures:
        notes += capture_notes(captures, records, matches, nominal_axis.name)
    explained = fit.residual_rms_counts <= EXPLAINED * floor_counts
    cause = None
    if not explained:
        cause = likely_cause(fit, records, nominal_axis.plant, matches)
        notes.append(
            f"the model does not explain the capture: residual {fit.residual_rms_counts:.3g} "
            f"counts RMS against {floor_text(floor_counts)}; likely cause: {cause}"
        )
    shown = spanned(fit, profile) if profile is not None else fit
    return Identified(
        axis=axis,
        fit=shown,
        notes=tuple(notes),
        explained=explained,
        cause=cause,
        kept=tuple(kept),
        profile=profile,
        resonance=resonance,
        floor_counts=floor_counts,
    )


def floor_text(floor_counts: float) -> str:
    """The residual's floor in words, as the notes and the refusal say it.

    Parameters
    ----------
    floor_counts : float
        :attr:`Identified.floor_counts`.

    Returns
    -------
    str
        "a quantisation floor of …", or the ringing servo's floor beside it.
    """
    if floor_counts <= QUANTISATION_FLOOR:
        return f"a quantisation floor of {QUANTISATION_FLOOR:.3g}"
    return (
        f"a floor of {floor_counts:.3g} (the ringing servo's own spread under starts no "
        f"capture tells apart; the quantisation's {QUANTISATION_FLOOR:.3g})"
    )


__all__ = [
    "EXPLAINED",
    "IN_USE",
    "MARGIN",
    "Identified",
    "floor_text",
    "identified_plant",
    "identify_report",
    "uncertainty_of",
]
