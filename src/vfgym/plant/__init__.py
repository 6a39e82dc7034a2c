"""The plant: V-F controller → digital servo → motor, load and encoder, tick by tick.

``params → simulate → trace``. :func:`simulate` packs the frozen parameters
(:mod:`vfgym.params`) into the kernel's parameter row, runs the compiled kernel
(``_kernel``, one move; ``_lanes``, up to 16 moves in SIMD lanes) and returns a
:class:`Trace` whose :attr:`Trace.metrics` are the measures the kernel streamed
(:mod:`vfgym.plant.measures`). :mod:`vfgym.plant.reference` is the plain-Python statement
of the same equations, which the kernel matches bit for bit. The model is described in
``docs/model.md``.

Modules
-------
_jit
    The one numba policy (cache, error model, inlining) of every compiled function.
_layout
    The kernel's plain-array layout: parameter row, state, accumulators, trace rows.
_tick
    The blocks of one tick (V-F controller, servo, torque, motor, encoder, measures),
    inlined into the kernel's loop.
_kernel, _lanes
    The compiled loop, for one move (and a batch over threads) and for SIMD lanes of moves.
_two_mass
    The two-mass plant's one-tick coefficients (a compliant transmission).
_simulate
    The public entry points (:func:`simulate`, :func:`simulate_train`, :func:`vf_pulses`).
measures
    Each measure of a move, decoded from the kernel's streamed accumulators.
reference
    The plain-Python reference of the tick.
"""

from vfgym.plant._simulate import (
    Trace,
    check_pulses,
    motor_coefficients,
    pack,
    run_move,
    simulate,
    simulate_train,
    step_command,
    vf_pulses,
)
from vfgym.plant._two_mass import two_mass_coefficients
from vfgym.plant.measures import command_end_s

__all__ = [
    "Trace",
    "check_pulses",
    "command_end_s",
    "motor_coefficients",
    "pack",
    "run_move",
    "simulate",
    "simulate_train",
    "step_command",
    "two_mass_coefficients",
    "vf_pulses",
]
