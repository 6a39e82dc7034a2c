"""The two-mass plant's one-tick coefficients (docs/model.md §3.1): the zero-order-hold
matrix exponentials of a compliant transmission, once per plant, for the parameter row.

The kernel's tick (:func:`vfgym.plant._tick.motor_two`) then does multiply-adds only.
"""

from __future__ import annotations

import functools

import numpy as np
import scipy.linalg

from vfgym.params import Plant


def two_mass_coefficients(plant: Plant) -> np.ndarray:
    """Exact one-tick zero-order-hold coefficients of the two-mass plant (docs/model.md §3.1).

    With the state (θ, ω, d, ω_L), d = θ − θ_L the spring's twist, and the forces F on the
    motor (net torque less its Coulomb friction) and G on the load (its Coulomb friction)
    held over the tick,

        J_M·dω/dt = F − b·ω − K_S·d − c_S·(ω − ω_L),   J_L·dω_L/dt = G + K_S·d + c_S·(ω − ω_L),

    the tick's transition is the matrix exponential of the system augmented with its inputs
    (Van Loan's), computed by :func:`scipy.linalg.expm` once per plant; and the same for
    the motor held at rest by friction (the load moving on the spring) and for the load
    held (the motor moving against the spring). Each system is balanced first (speeds in
    rad per tick, forces in rad per tick² of their mass), so that every coefficient, not
    only the largest, comes out to a few units in its last place.

    Parameters
    ----------
    plant : Plant
        A plant with a transmission: the tick T, J_M (:attr:`Motor.inertia_kgm2`), b,
        J_L, K_S, c_S.

    Returns
    -------
    numpy.ndarray
        float64, 35 entries in the parameter row's order ``P_Z_TW`` … ``P_Z_LDF``
        (:mod:`vfgym.plant._layout`): both moving, θ(T) − θ, ω(T), d(T), ω_L(T) per
        (ω, d, ω_L, F, G); the motor held, d(T), ω_L(T) per (d, ω_L, G); the load held,
        θ(T) − θ, ω(T), d(T) per (ω, d, F).

    Raises
    ------
    ValueError
        If the plant has no transmission.
    """
    tr = plant.transmission
    if tr is None:
        raise ValueError("plant.transmission=None: a two-mass plant needs a transmission")
    m = plant.motor
    return _two_mass(
        plant.tick_s, m.inertia_kgm2, m.viscous_nm_s_rad, tr.load_inertia_kgm2,
        tr.stiffness_nm_rad, tr.damping_nm_s_rad,
    ).copy()  # fmt: skip


def _zoh(a: np.ndarray, scale: np.ndarray) -> np.ndarray:
    """e^(a) of an augmented system, balanced by x ↦ S·x: S⁻¹·e^(S·a·S⁻¹)·S."""
    return scipy.linalg.expm(a * scale[:, None] / scale[None, :]) / scale[:, None] * scale[None, :]


@functools.lru_cache(maxsize=256)
def _two_mass(T: float, jm: float, b: float, jl: float, ks: float, cs: float) -> np.ndarray:
    # both moving: (θ, ω, d, ω_L | F, G)
    a = np.zeros((6, 6))
    a[0, 1] = 1.0  # θ' = ω
    a[1, 1:5] = (-(b + cs) / jm, -ks / jm, cs / jm, 1.0 / jm)  # ω' … + F/J_M
    a[2, 1], a[2, 3] = 1.0, -1.0  # d' = ω − ω_L
    a[3, 1:4] = (cs / jl, ks / jl, -cs / jl)  # ω_L'
    a[3, 5] = 1.0 / jl  # … + G/J_L
    both = _zoh(a * T, np.array([1.0, T, 1.0, T, T * T / jm, T * T / jl]))[0:4, 1:6]
    # the motor held: (d, ω_L | G)
    a = np.array([[0.0, -1.0, 0.0], [ks / jl, -cs / jl, 1.0 / jl], [0.0, 0.0, 0.0]])
    motor_held = _zoh(a * T, np.array([1.0, T, T * T / jl]))[0:2, :]
    # the load held: (θ, ω, d | F)
    a = np.zeros((4, 4))
    a[0, 1] = 1.0
    a[1, 1:4] = (-(b + cs) / jm, -ks / jm, 1.0 / jm)
    a[2, 1] = 1.0
    load_held = _zoh(a * T, np.array([1.0, T, 1.0, T * T / jm]))[0:3, 1:4]
    out = np.concatenate([both.ravel(), motor_held.ravel(), load_held.ravel()])
    out.flags.writeable = False
    return out
