"""The ranges in which a physical value of the plant can mean something: every check of
:mod:`vfgym.params` that is not ``> 0`` or ``≥ 0`` takes its bound from here.
"""

from __future__ import annotations

import math

TICK_HZ_RANGE = (1e3, 1e7)
"""Controller tick rates (Hz): 1 kHz to 10 MHz, above every pulse-train input of a servo
drive (the MCX514's 8 Mpps); one tick is one step of the simulation."""
MAX_MOVE_TICKS = 2**24
"""The longest move a simulation holds in memory (ticks, ~16.8 million: 120 s at 140 kHz,
1.7 s at 10 MHz); its per-tick arrays stay within a few hundred MB."""
MAX_SAMPLE_S = 0.01
"""The servo's longest sample period Ts (s): a digital servo samples at 100 Hz or faster."""
MAX_PULSE_RAD = math.pi / 2.0
"""The largest pulse equivalent δ (rad): at least four command pulses a revolution."""
MAX_ROTOR_INERTIA_KGM2 = 1.0
"""The largest rotor inertia (kg·m²), above the largest servomotors' (~0.1 kg·m²)."""
MAX_INERTIA_RATIO = 200.0
"""The largest load inertia ratio, a drive's settable range (Yaskawa Pn103: 0-20000 %)."""
MAX_ACCEL_RAD_S2 = 1e7
"""The largest acceleration limit (rad/s²), above any servomotor's bare-shaft peak."""
MAX_ENCODER_LINES = 2**24
"""The most encoder lines a revolution (2^26 counts after ×4)."""
