"""Shared test set-ups."""

from __future__ import annotations

import math

from vfgym import PAPER_PLANT, Plant


def linear_plant(gear: int, sample_ticks: int, b: float, wn: float) -> Plant:
    """No torque limit and a fine encoder: the regime where patent Fig. 7's G(s) holds.
    K3 gives the continuous loop the natural frequency ``wn`` (rad/s); a command pulse is
    ``gear`` encoder counts."""
    pl = PAPER_PLANT.with_motor(
        encoder_lines=2**18,
        peak_torque_nm=1e9,
        torque_at_max_speed_nm=1e9,
        knee_speed_rad_s=1e9,
        max_speed_rad_s=2e9,
    ).with_servo(gear=gear, sample_ticks=sample_ticks, speed_gain_b=b)
    k4 = pl.motor.counts_per_rev / (2 * math.pi) / pl.motor.inertia_kgm2
    return pl.with_servo(torque_per_count_nm=wn**2 / k4)
