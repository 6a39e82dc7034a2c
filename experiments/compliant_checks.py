"""The two-mass plant's closed-form checks, as figures (the tests assert them; this prints
how far within their bounds they are): the free oscillation's frequency against the
formula, energy kept without damping or friction over a second, the held masses' ringing
against their own formulas, the tick's coefficients against a 50-digit matrix exponential,
and the load's distance from the rigid plant's motor as the spring stiffens.

    PYTHONPATH=src python experiments/compliant_checks.py
"""

from __future__ import annotations

import math

import mpmath
import numpy as np

from vfgym import PAPER_PLANT, PAPER_SETTINGS, Measures, Transmission, simulate, step_command
from vfgym.plant import _tick as TK
from vfgym.plant import pack, two_mass_coefficients

T = PAPER_PLANT.tick_s
ROTOR = PAPER_PLANT.motor.rotor_inertia_kgm2


def plant(ratio=0.5, jl=3e-5, ks=1.0, cs=0.0, coulomb=0.0, load_coulomb=0.0, viscous=0.0):
    base = PAPER_PLANT.with_motor(inertia_ratio=ratio, coulomb_nm=coulomb, viscous_nm_s_rad=viscous)
    return base.replace(transmission=Transmission(jl, ks, cs, load_coulomb_nm=load_coulomb))


def run(p, x0, seconds, tc=0.0, tcl=0.0):
    z = TK.two_mass.py_func(pack(PAPER_SETTINGS, p, Measures(), 1.0, 10))
    n = round(seconds / T)
    out = np.empty((n + 1, 4))
    out[0] = x = tuple(x0)
    for i in range(n):
        x = TK.motor_two.py_func(*x, 0.0, tc, tcl, z)
        out[i + 1] = x
    return out


def frequency(x):
    t = np.arange(x.size) * T
    i = np.flatnonzero((x[:-1] < 0.0) & (x[1:] >= 0.0))
    c = t[i] - x[i] * T / (x[i + 1] - x[i])
    return (c.size - 1) / (c[-1] - c[0])


def exact_coefficients(p):
    """The moving system's 4×5 block by mpmath's expm at 50 digits."""
    mpmath.mp.dps = 50
    jm, b = p.motor.inertia_kgm2, p.motor.viscous_nm_s_rad
    tr = p.transmission
    jl, ks, cs = tr.load_inertia_kgm2, tr.stiffness_nm_rad, tr.damping_nm_s_rad
    a = np.zeros((6, 6))
    a[0, 1] = 1.0
    a[1, 1:5] = (-(b + cs) / jm, -ks / jm, cs / jm, 1.0 / jm)
    a[2, 1], a[2, 3] = 1.0, -1.0
    a[3, 1:4] = (cs / jl, ks / jl, -cs / jl)
    a[3, 5] = 1.0 / jl
    e = mpmath.expm(mpmath.matrix(a.tolist()) * mpmath.mpf(T))
    return np.array([[float(e[i, j]) for j in range(1, 6)] for i in range(4)])


def main() -> None:
    print("free oscillation (no torque, damping or friction): frequency against the formula")
    for ratio, jl, ks in ((0.5, 3e-5, 1.0), (0.36, 8.2e-5, 5.41), (0.0, 1e-5, 2000.0)):
        p = plant(ratio, jl, ks)
        f = frequency(run(p, (0, 0, 1e-3, 0), 0.25)[:, 2])
        print(f"  J_M/J_L {p.motor.inertia_kgm2 / jl:5.3f}, K_S {ks:7g}: {f:9.4f} Hz against "
              f"{p.resonance_hz:9.4f} Hz, relative {f / p.resonance_hz - 1:+.1e}")  # fmt: skip
    p = plant()
    x = run(p, (0.0, 20.0, 2e-3, -5.0), 1.0)
    jm = p.motor.inertia_kgm2
    energy = 0.5 * jm * x[:, 1] ** 2 + 0.5 * 3e-5 * x[:, 3] ** 2 + 0.5 * x[:, 2] ** 2
    drift = np.abs(energy / energy[0] - 1).max()
    print(f"energy over 1 s (140,000 ticks): largest relative drift {drift:.2e}")
    held = run(plant(coulomb=0.05), (0.1, 0.0, 1e-2, 0.0), 0.2, tc=0.05)
    fa = plant().transmission.antiresonance_hz
    print(f"motor held by friction: the load rings at {frequency(held[:, 2]):.4f} Hz, "
          f"(1/2π)√(K_S/J_L) = {fa:.4f} Hz")  # fmt: skip
    held = run(plant(load_coulomb=0.05), (0.0, 0.0, 1e-2, 0.0), 0.2, tcl=0.05)
    fm = math.sqrt(1.0 / jm) / (2 * math.pi)
    print(f"load held by friction: the motor rings at {frequency(held[:, 2]):.4f} Hz, "
          f"(1/2π)√(K_S/J_M) = {fm:.4f} Hz")  # fmt: skip
    print("the tick's coefficients (both moving) against mpmath's expm at 50 digits:")
    for p in (plant(cs=0.002), plant(0.36, 8.2e-5, 5.41, 4.9e-4, viscous=1e-4),
              plant(0.0, 1e-5, 2000.0, 0.05)):  # fmt: skip
        z = two_mass_coefficients(p)[:20].reshape(4, 5)
        ex = exact_coefficients(p)
        rel = np.abs(z - ex) / np.abs(ex)
        print(f"  resonance {p.resonance_hz:7.1f} Hz: largest relative error {rel.max():.1e}")
    print("the load against the rigid plant's motor (same whole inertia), a 2 rad step:")
    jm, jl = ROTOR * 1.5, 3e-5
    rigid = PAPER_PLANT.with_motor(inertia_ratio=(jm + jl) / ROTOR - 1.0)
    cmd = step_command(2.0, 14000)
    ref = simulate(cmd, PAPER_SETTINGS, rigid).motor_rad
    q = PAPER_PLANT.motor.count_rad
    for hz in (100.0, 300.0, 1000.0, 3000.0, 10000.0):
        p = PAPER_PLANT.with_motor(inertia_ratio=0.5).replace(
            transmission=Transmission.from_resonance(jl, jm, hz, 0.1)
        )
        gap = np.abs(simulate(cmd, PAPER_SETTINGS, p).load_rad - ref).max() / q
        print(f"  resonance {hz:7.0f} Hz (K_S {p.transmission.stiffness_nm_rad:10.4g}): "
              f"largest distance {gap:9.3f} counts")  # fmt: skip


if __name__ == "__main__":
    main()
