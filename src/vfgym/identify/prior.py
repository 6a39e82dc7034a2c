"""What a capture cannot separate: the plants along J/K3, within a prior on the drive's gain.

Below the torque limit every torque the drive makes is K3 times a count, and the motor's
equation divided by K3 is the same for a drive whose gain is g times the one set and an
axis with g times the inertia and torques (docs/model.md §3). A capture whose torque never
reaches its limit (or reaches it for less than
:data:`~vfgym.identify.excite.MIN_SATURATED_S`) so fixes only the ratios: the inertia
and each torque over the gain. The estimates are stated for the gain as set, and the
plants along the line, within a stated prior on the gain (:func:`gain_prior`: the
``uncertainty:`` block's ``torque_per_count`` of the nominal axis, else ±
:data:`GAIN_PRIOR`, or what ``--gain-prior`` says), are what the capture leaves open:
:func:`along_gain` fits them at the prior's two ends, :func:`spanned` widens each
estimate's interval over them, and the identified axis's block spans them too.

At an end where the plant stays below its torque limit the fit is the one at the gain as
set, scaled (exactly: the same response); where it reaches the limit, the captures are
fitted again with the gain held there (:func:`vfgym.identify.fit.fit`), so that a plant
which the saturated stretch of the capture explains differently is fitted as it is.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from vfgym._validate import check_real
from vfgym.axis import Axis, PlantVariant
from vfgym.identify.fit import Estimate, Fit, fit
from vfgym.identify.model import Record, torque_limit
from vfgym.params import Plant, Settings

GAIN_PRIOR = 0.10
"""The drive's gain is within this share of the one set, unless the nominal axis's
``uncertainty:`` block or ``--gain-prior`` says otherwise."""

SCALED = ("inertia", "coulomb_nm", "viscous_nm_s_rad", "load_torque_nm")
"""The quantities that scale with the gain along the line (the gain itself is the line's
coordinate)."""

SCALE_MARGIN = 0.98
"""An end of the prior is a scaled copy where the fit's largest torque share times the
gain stays below this (the plant there never reaches its limit)."""


def gain_prior(axis: Axis, share: float | None = None) -> tuple[float, float]:
    """The prior on the drive's gain, as factors on K3 as set.

    Parameters
    ----------
    axis : Axis
        The nominal axis; its ``uncertainty.torque_per_count`` where stated.
    share : float or None
        ``--gain-prior``: the gain within this share of the one set, in [0, 0.9]; it
        overrides the axis's.

    Returns
    -------
    tuple of float
        (low, high).

    Raises
    ------
    ValueError
        For a share outside [0, 0.9].
    """
    if share is not None:
        s = check_real("--gain-prior", share, 0.0, 0.9)
        return (1.0 - s, 1.0 + s)
    stated = axis.uncertainty.torque_per_count
    if stated is not None:
        return (min(stated[0], 1.0), max(stated[1], 1.0))
    return (1.0 - GAIN_PRIOR, 1.0 + GAIN_PRIOR)


def torque_share(fit_: Fit, plant: Plant) -> float:
    """The largest share of its torque limit a fitted plant asks for over the captures.

    Parameters
    ----------
    fit_ : Fit
        The fit.
    plant : Plant
        The fitted plant (gives the torque–speed curve).

    Returns
    -------
    float
        Largest |torque| over the limit at its speed (1 where the torque saturates).
    """
    most = 0.0
    for r in fit_.responses:
        limit = torque_limit(plant, r.speed_rad_s, r.torque_nm)
        ask = np.abs(r.torque_nm)
        at = limit > 0.0  # (none past the motor's top speed)
        if np.any(at):
            most = max(most, float(np.max(ask[at] / limit[at])))
        if np.any(~at & (ask > 0.0)):
            return 1.0
    return most


@dataclass(frozen=True)
class Profile:
    """The fits along the line a capture leaves open.

    Attributes
    ----------
    prior : tuple of float
        The prior on the gain (factors on K3 as set).
    fits : tuple of Fit
        At the prior's low end, at the gain as set, at its high end.
    refitted : tuple of bool
        Whether each end was fitted anew (the torque reaches its limit there) or is the
        fit at the gain as set, scaled.
    """

    prior: tuple[float, float]
    fits: tuple[Fit, Fit, Fit]
    refitted: tuple[bool, bool]


def scaled(fit_: Fit, nominal: Plant, gain: float) -> Fit:
    """A fit held at the gain as set, moved along the line to ``gain`` (exact where the
    plant stays below its torque limit: the same response).

    Parameters
    ----------
    fit_ : Fit
        The fit at the gain as set.
    nominal : Plant
        The nominal plant.
    gain : float
        The factor on K3 as set.

    Returns
    -------
    Fit
        Its inertia and torques, their intervals and resolutions, times ``gain``.
    """
    g = gain / fit_.estimate("torque_per_count").value
    out = []
    for e in fit_.estimates:
        if e.name in SCALED:
            out.append(replace(e, value=e.value * g, low=e.low * g, high=e.high * g,
                               resolution=e.resolution * g))  # fmt: skip
        else:
            out.append(replace(e, value=gain, low=gain, high=gain))
    m = nominal.motor
    v = {e.name: e.value for e in out}
    variant = PlantVariant(
        inertia=v["inertia"],
        coulomb_offset_nm=v["coulomb_nm"] - m.coulomb_nm,
        viscous_offset_nm_s_rad=v["viscous_nm_s_rad"] - m.viscous_nm_s_rad,
        load_offset_nm=v["load_torque_nm"] - m.load_torque_nm,
        torque_per_count=gain,
    )
    return replace(fit_, estimates=tuple(out), variant=variant, plant=variant.apply(nominal))


def along_gain(
    records: Sequence[Record],
    nominal: Plant,
    settings: Settings,
    fit_: Fit,
    prior: tuple[float, float],
) -> Profile | None:
    """The fits at the prior's ends where the captures do not separate the gain.

    Parameters
    ----------
    records : sequence of Record
        The captures.
    nominal : Plant
        The nominal plant.
    settings : Settings
        The servo's filter ratio in force.
    fit_ : Fit
        The fit with the gain held as set.
    prior : tuple of float
        The prior on the gain.

    Returns
    -------
    Profile or None
        ``None`` where the captures estimate the gain.
    """
    if fit_.estimate("torque_per_count").excited:
        return None
    share = torque_share(fit_, fit_.plant)
    ends: list[Fit] = []
    refit: list[bool] = []
    for g in prior:
        again = fit_.saturated_s > 0.0 or share * g >= SCALE_MARGIN
        refit.append(again)
        if again:
            ends.append(fit(records, nominal, settings, gain=g, near=fit_))
        else:
            ends.append(scaled(fit_, nominal, g))
    return Profile(prior, (ends[0], fit_, ends[1]), (refit[0], refit[1]))


def spanned(fit_: Fit, profile: Profile) -> Fit:
    """The fit at the gain as set with each interval widened over the line's plants.

    Parameters
    ----------
    fit_ : Fit
        The fit at the gain as set.
    profile : Profile
        The fits along the line.

    Returns
    -------
    Fit
        Each estimate's interval the union of its intervals along the line (the gain's
        the prior); the values as at the gain as set.
    """
    out: list[Estimate] = []
    for e in fit_.estimates:
        if e.name == "torque_per_count":
            out.append(replace(e, low=profile.prior[0], high=profile.prior[1]))
            continue
        along = [f.estimate(e.name) for f in profile.fits]
        out.append(
            replace(
                e,
                low=min(a.low for a in along),
                high=max(a.high for a in along),
                resolution=max(a.resolution for a in along),
            )
        )
    return replace(fit_, estimates=tuple(out))


__all__ = [
    "GAIN_PRIOR",
    "SCALED",
    "Profile",
    "along_gain",
    "gain_prior",
    "scaled",
    "spanned",
    "torque_share",
]
