"""Identification of an axis's plant from a logic analyser's capture (``vfgym identify``).

The recorded pulse train drives the axis's servo and motor in the exact simulator; the
plant whose simulated encoder count best matches the recorded one, by least squares, gives
the estimates (inertia, Coulomb and viscous friction, load torque, the drive's gain) and
their 95 % intervals, written back as an axis with an ``uncertainty:`` block.

Modules
-------
capture
    Reading a capture: VCD (a logic analyser's, or ``vfgym export``'s) or CSV.
simulated
    A capture simulated on a plant: pulses run with rest before and after, recorded as an
    analyser does (the VCD is written by :mod:`vfgym.io.vcd`).
model
    A capture on the simulator's tick grid, the state it starts from, and its simulation
    on candidate plants.
excite
    What the moves excite: constant-speed segments, directions, torque saturation.
fit
    The least-squares estimator and its intervals.
covariance
    The covariance of the estimates from the encoder count's quantisation.
plan
    The moves to run for an identification.
written
    The identified axis written: its uncertainty block, and what the captures cannot show.
"""
