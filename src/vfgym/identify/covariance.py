"""The covariance of the estimates from the encoder count's quantisation.

The residuals are the error of reading the motor's angle as whole counts: for a count
read at angle θ (in counts), 0.5 − frac(θ + φ), where φ is where the count's edges lie
against the simulated motion, which no capture knows. Over a uniform φ this error has
variance 1/12 and, between two samples of one stretch of motion, the covariance
½·B₂(frac(θₛ − θₜ)) (B₂ the second Bernoulli polynomial): samples a whole number of counts
apart err alike, so a move at a steady speed or a rest, whose samples fall at the same
place within a count again and again, carries an error that does not average out however
long it lasts. Where the motion changes (a move starts or ends, a cruise begins), the
servo settles into another pattern against the counts; each such stretch (a
:func:`pieces` piece) takes its own φ.

The covariance of the least-squares estimates is then the sandwich (JᵀJ)⁻¹ JᵀΣJ (JᵀJ)⁻¹
with that Σ, computed from the Fourier series ½·B₂(x) = Σₖ cos(2πkx) / (2π²k²) without
forming Σ: JᵀΣJ = Σ_pieces Σₖ (cₖcₖᵀ + sₖsₖᵀ) / (2π²k²), cₖ = Σₜ Jₜ cos(2πkθₜ) (and sₖ
with sin), to :data:`HARMONICS` terms, the rest of the series' variance taken as
independent from sample to sample.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from vfgym.identify.model import SAMPLE_TICKS, Record
from vfgym.identify.problem import PARAMS, Problem, wide_range

HARMONICS = 64
"""Terms of the Fourier series of the quantisation error's covariance."""

WINDOW_S = 0.005
"""Pulse rates are counted over windows of this length (s) to find the pieces."""

STEADY_TOL = 0.03
"""A window belongs to a steady stretch when its neighbours' rates are within this share
(and one pulse) of its own."""


def pieces(record: Record, tick_hz: float) -> list[np.ndarray]:
    """The stretches of a record over which the count's error keeps one pattern.

    Parameters
    ----------
    record : Record
        The capture on the tick grid.
    tick_hz : float
        The controller's tick rate (Hz).

    Returns
    -------
    list of numpy.ndarray
        Indices into the residuals the record contributes (its samples from
        :attr:`~vfgym.identify.model.Record.first_sample` on): each rest, each steady
        speed, and each change of speed between them is one piece.
    """
    n = record.measured.size
    w = max(SAMPLE_TICKS, round(WINDOW_S * tick_hz) // SAMPLE_TICKS * SAMPLE_TICKS)
    nw = -(-n * SAMPLE_TICKS // w)
    p = np.zeros(nw * w, dtype=np.int64)
    m = min(record.pulses.size, p.size)
    p[:m] = record.pulses[:m]
    rate = p.reshape(nw, w).sum(axis=1)
    labels: list[tuple[str, int]] = []
    for i in range(nw):
        if rate[i] == 0:
            labels.append(("rest", 0))
            continue
        near = rate[max(0, i - 1) : i + 2]
        steady = bool(np.all(np.abs(near - rate[i]) <= STEADY_TOL * abs(rate[i]) + 1))
        labels.append(("steady", int(rate[i])) if steady else ("change", i))
    per = w // SAMPLE_TICKS
    cuts = [i * per for i in range(1, nw) if labels[i] != labels[i - 1]]
    idx = np.arange(record.first_sample, n) - record.first_sample
    edges = [c - record.first_sample for c in cuts if record.first_sample < c < n]
    return [piece for piece in np.split(idx, edges) if piece.size]


def quantisation_meat(
    jac: np.ndarray, counts: np.ndarray, groups: Sequence[np.ndarray]
) -> np.ndarray:
    """JᵀΣJ for the count's quantisation error (see the module doc).

    Parameters
    ----------
    jac : numpy.ndarray
        The Jacobian of the residuals (rows: samples).
    counts : numpy.ndarray
        The simulated count (motor angle in counts) at each sample.
    groups : sequence of numpy.ndarray
        Row indices of each piece (every row in one piece).

    Returns
    -------
    numpy.ndarray
        The p×p matrix JᵀΣJ.
    """
    k = np.arange(1, HARMONICS + 1)
    weight = 1.0 / (2.0 * np.pi**2 * k**2)
    p = jac.shape[1]
    meat = np.zeros((p, p))
    for rows in groups:
        jp = jac[rows]
        angle = 2.0 * np.pi * np.outer(counts[rows], k)
        c = jp.T @ np.cos(angle)
        s = jp.T @ np.sin(angle)
        meat += (c * weight) @ c.T + (s * weight) @ s.T
    rest = 1.0 / 12.0 - float(weight.sum())
    return meat + rest * (jac.T @ jac)


def resolution(jac: np.ndarray, floor: float) -> np.ndarray:
    """The finest change of each coordinate one reading of the count shows.

    A change that moves no sample's simulated count by more than the quantisation
    ``floor`` (the RMS error of reading a position as whole counts) is below what any
    single sample can show; the fit resolves finer only by averaging many samples.

    Parameters
    ----------
    jac : numpy.ndarray
        The residuals' Jacobian (samples × coordinates, counts per unit coordinate).
    floor : float
        The quantisation floor (counts RMS).

    Returns
    -------
    numpy.ndarray
        Per coordinate, ``floor`` over the largest sensitivity of any sample (inf for a
        coordinate no sample responds to).
    """
    most = np.max(np.abs(jac), axis=0) if jac.size else np.zeros(jac.shape[1])
    with np.errstate(divide="ignore"):
        return floor / most


HELD_TORQUES = ("coulomb_nm", "viscous_nm_s_rad", "load_torque_nm")
"""Quantities held at their nominal value whose range enters the others' covariance (the
gain's does not: without it the inertia is stated relative to K3 as set, and the
uncertainty block widens by the gain's range instead)."""

NUISANCE_PHASE_STEP = 5
"""Step (ticks) of the other servo phases whose effect on the estimate is added to the
covariance."""


def estimate_covariance(problem: Problem, z: np.ndarray, jac: np.ndarray) -> np.ndarray:
    """The covariance of the free coordinates (see the module doc): the sandwich with the
    count's quantisation error, plus the spread over the servo's sample phase."""
    A = jac.T @ jac
    try:
        Ainv = np.linalg.inv(A)
    except np.linalg.LinAlgError:
        Ainv = np.linalg.pinv(A)
    nominal = problem.scale.nominal
    groups, counts, shift = [], [], []
    start = 0
    for r, resp in zip(problem.records, problem.simulated(z), strict=True):
        groups += [piece + start for piece in pieces(r, nominal.tick_hz)]
        counts.append(r.used(resp.counts))
        # the tick grid's phase, known to within the record's phase width: the residuals'
        # change for a shift of the grid by δ is −(ω/q)·δ, δ uniform over that width
        g = np.zeros(jac.shape[0])
        g[start : start + counts[-1].size] = -r.used(resp.speed_rad_s) / nominal.motor.count_rad
        shift.append(jac.T @ g * (r.phase_width_s / math.sqrt(12.0)))
        start += counts[-1].size
    meat = quantisation_meat(jac, np.concatenate(counts), groups)
    meat = meat + sum(np.outer(v, v) for v in shift)
    cov = Ainv @ meat @ Ainv
    # the servo's sample clock against the pulses, which no capture records: the
    # Gauss–Newton step each other phase's residuals would take from the optimum
    steps = []
    keep = list(problem.phases)
    try:
        for ph in range(0, problem.scale.nominal.servo.sample_ticks, NUISANCE_PHASE_STEP):
            problem.phases = [(p0 + ph) % problem.scale.nominal.servo.sample_ticks for p0 in keep]
            if ph:
                steps.append(-Ainv @ (jac.T @ problem.residuals_of([z])[0]))
    finally:
        problem.phases = keep
    if steps:
        cov = cov + sum(np.outer(d, d) for d in steps) / len(steps)
    # a torque held at its nominal value (not excited) may be anywhere in its wide range:
    # the estimates move with it by −A⁻¹Jᵀ∂r/∂p, over its mean square offset in that range
    scale = problem.scale
    for i in np.flatnonzero(~problem.free[: len(PARAMS)]):
        if PARAMS[i] not in HELD_TORQUES:
            continue
        lo, hi = (v / scale.jacobian_diag(z)[i] for v in wide_range(PARAMS[i], nominal))
        zu, zd = z.copy(), z.copy()
        zu[i] += scale.steps[i]
        zd[i] -= scale.steps[i]
        ru, rd = problem.residuals_of([zu, zd])
        d = -Ainv @ (jac.T @ ((ru - rd) / (2.0 * scale.steps[i])))
        mean_square = ((hi - z[i]) ** 3 - (lo - z[i]) ** 3) / (3.0 * (hi - lo))
        cov = cov + np.outer(d, d) * mean_square
    return cov


__all__ = [
    "HARMONICS",
    "HELD_TORQUES",
    "NUISANCE_PHASE_STEP",
    "estimate_covariance",
    "pieces",
    "quantisation_meat",
    "resolution",
]
