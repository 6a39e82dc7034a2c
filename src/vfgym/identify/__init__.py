"""Identification of an axis's plant from a logic analyser's capture (``vfgym identify``).

The recorded pulse train drives the axis's servo and motor in the exact simulator; the
plant whose simulated encoder count best matches the recorded one, by least squares, gives
the estimates (inertia, Coulomb and viscous friction, load torque, the drive's gain) and
their 95 % intervals (and, on a compliant axis, the transmission's stiffness and damping),
written back as an axis with an ``uncertainty:`` block.

Modules
-------
capture
    Reading a capture: VCD (a logic analyser's, or ``vfgym export``'s), or CSV.
capture_csv
    sigrok-cli's CSV (with or without its time column) and vfgym's trace CSV.
lines
    A capture's lines decoded into pulses and the encoder's count; glitches taken out.
checks
    What a capture must be before it is fitted: no lost encoder edge, A and B the right
    way round; its pulse train against the axis's plan.
model
    A capture on the simulator's tick grid, the state it starts from, and its simulation
    on candidate plants.
excite
    What the moves excite: constant-speed segments, directions, torque saturation.
problem
    The least squares' scaled coordinates and residuals.
fit
    The least-squares estimator and its intervals.
resonance
    A compliant transmission's resonance and damping ratio, through the simulator.
resonance_problem
    The resonance moves' residuals over the resonance, damping ratio and a gain factor.
ringing
    The floor a servo that rings sets under a compliant axis's residual.
covariance
    The covariance of the estimates from the encoder count's quantisation.
prior
    The plants along J/K3 a capture cannot tell apart, within a prior on the drive's gain.
plan
    The moves to run for an identification.
simulated
    A capture simulated on a plant (the VCD written by :mod:`vfgym.io.vcd`), and with the
    faults a recording may hold.
notes
    What the captures cannot show, what in them did not belong, the likely cause of a
    misfit.
written
    The identified axis written: its uncertainty block (the stated ranges kept).
pipeline
    ``vfgym identify``'s steps from the captures read to the identified axis.
"""
