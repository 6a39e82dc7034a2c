"""The SIMD lane kernel (vfgym.plant._lanes) against the kernel it restates (run_segment): the same
loop state and pulse-count history, bit for bit, for random plants (friction, loads, two-mass
plants alone or mixed with rigid ones), random settings of both laws, envs at different ticks,
and lanes left unused."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from vfgym import DEFAULT_MEASURES, Transmission
from vfgym.moves.distribution import get_scenario, random_scenario
from vfgym.params import Settings
from vfgym.plant import _kernel as K
from vfgym.plant import _lanes, pack, simulate
from vfgym.plant import _layout as L

NAMED = ("paper-step", "friction", "heavy-load", "reversal", "short-move", "paper-sine")


def _moves(seed: int, count: int, compliant: float = 0.0):
    """``count`` moves; each on a two-mass plant (a transmission, resonance 20-500 Hz)
    with probability ``compliant``."""
    rng = np.random.default_rng(seed)
    prms, cmds = [], []
    for j in range(count):
        sc = random_scenario(seed * 100 + j, "train") if j % 2 else get_scenario(NAMED[j // 2 % 6])
        plant = sc.plant()
        if compliant and rng.random() < compliant:
            jm = plant.motor.inertia_kgm2
            plant = plant.replace(
                transmission=Transmission.from_resonance(
                    jm * rng.uniform(0.2, 5.0),
                    jm,
                    rng.uniform(20.0, 500.0),
                    rng.uniform(0.0, 0.3),
                    load_coulomb_nm=float(rng.choice([0.0, 0.005, 0.02])),
                )
            )
        cmd = sc.command(plant)
        s = Settings(
            value_rad=float(rng.uniform(0.05, 3.0)),
            error_limit_rad=float(rng.uniform(0.05, 3.0)),
            k=float(np.exp(rng.uniform(np.log(20.0), np.log(20000.0)))),
            ts_over_tf=float(rng.uniform(0.02, 1.0)),
            accel_law=("rise", "slew")[int(rng.integers(2))],
        )
        prms.append(pack(s, plant, DEFAULT_MEASURES, float(cmd[-1]), cmd.size))
        cmds.append(cmd)
    return prms, cmds


@settings(max_examples=25, deadline=None)
@given(
    seed=st.integers(0, 10_000),
    count=st.integers(1, _lanes.LANES),
    m=st.integers(1, 300),
    steps=st.integers(1, 6),
    aligned=st.booleans(),
    frictionless=st.booleans(),
    compliant=st.sampled_from([0.0, 0.5, 1.0]),
)
def test_lanes_end_where_the_kernel_ends(seed, count, m, steps, aligned, frictionless, compliant):
    """aligned: every move starts at the same tick, so the lanes' sample periods are in
    step (one latch for all); frictionless: no Coulomb friction (one fused pass a tick);
    compliant: the share of two-mass plants (a block mixes them with rigid ones)."""
    prms, cmds = _moves(seed, count, compliant)
    if frictionless:
        for p in prms:
            p[L.P_TC] = 0.0
    size = max(int(K.ring_size(p)) for p in prms)
    w = int(prms[0][L.P_ACC_W])
    PRM = np.stack(prms)
    CMD = np.zeros((count, max(c.size for c in cmds)))
    for j, c in enumerate(cmds):
        CMD[j, : c.size] = c
    ST = np.zeros((count, L.N_STATE))
    RING = np.zeros((count, size))
    ext = np.zeros(0, dtype=np.int8)
    rec = np.zeros((L.N_ROWS, 0))
    rng = np.random.default_rng(seed)
    shortest = min(c.size for c in cmds)
    common = int(rng.integers(0, max(1, shortest - m * steps)))
    for j in range(count):  # start each move somewhere else (or all at one tick), by the kernel
        K.init_state(PRM[j], ST[j], RING[j])
        start = common if aligned else int(rng.integers(0, max(1, cmds[j].size - m * steps)))
        K.run_segment(CMD[j, : cmds[j].size], ext, PRM[j], ST[j], RING[j], start, rec, 1)
    ST2, RING2 = ST.copy(), RING.copy()
    Z, CB, H = (a[0] for a in _lanes.scratch(1, m, w))
    ids = np.zeros(_lanes.LANES, dtype=np.int64)
    ids[:count] = np.arange(count)
    for _ in range(steps):
        if any(ST[j, L.S_TICK] + m > cmds[j].size for j in range(count)):
            break
        _lanes.advance(ids, count, PRM, ST, RING, CMD, m, Z, CB, H)
        for j in range(count):
            i1 = int(ST2[j, L.S_TICK]) + m
            K.run_segment(CMD[j, : cmds[j].size], ext, PRM[j], ST2[j], RING2[j], i1, rec, 1)
    np.testing.assert_array_equal(ST, ST2)
    for j in range(count):  # the counts run_segment reads back from the ring
        i = int(ST[j, L.S_TICK])
        slots = (i - 1 - np.arange(2 * w)) & (size - 1)
        np.testing.assert_array_equal(RING[j, slots], RING2[j, slots])


def test_a_tick_in_which_friction_stops_the_motor_takes_the_scalar_step():
    """The friction scenario stops and restarts the motor inside ticks; the lanes flag
    those ticks and take the kernel's own stop_within_tick for them."""
    sc = get_scenario("friction")
    plant = sc.plant()
    cmd = sc.command(plant)
    prm = pack(Settings(), plant, DEFAULT_MEASURES, float(cmd[-1]), cmd.size)
    w = int(prm[L.P_ACC_W])
    PRM, CMD = prm[None, :].copy(), cmd[None, :].copy()
    ST = np.zeros((1, L.N_STATE))
    RING = np.zeros((1, int(K.ring_size(prm))))
    K.init_state(prm, ST[0], RING[0])
    ST2, RING2 = ST.copy(), RING.copy()
    m = 500
    Z, CB, H = (a[0] for a in _lanes.scratch(1, m, w))
    ids = np.zeros(_lanes.LANES, dtype=np.int64)
    rec = np.zeros((L.N_ROWS, 0))
    while ST[0, L.S_TICK] + m <= cmd.size:
        _lanes.advance(ids, 1, PRM, ST, RING, CMD, m, Z, CB, H)
        K.run_segment(cmd, np.zeros(0, np.int8), prm, ST2[0], RING2[0], int(ST[0, L.S_TICK]),
                      rec, 1)  # fmt: skip
        np.testing.assert_array_equal(ST, ST2)
    # ticks in which the moving motor stopped (speed to zero, or through it) were covered
    speed = simulate(cmd[: int(ST[0, L.S_TICK])], Settings(), plant).speed_rad_s
    stops = (speed[:-1] != 0.0) & ((speed[1:] == 0.0) | (np.sign(speed[1:]) != np.sign(speed[:-1])))
    assert stops.sum() >= 3


def test_a_two_mass_lane_held_by_friction_ends_where_the_kernel_ends():
    """The friction scenario on a two-mass plant, in a block beside rigid lanes: its motor
    is held by friction while its load rings, breaks away and stops, all in the lanes' one
    pass (no scalar step), bit for bit; and a lane whose load is held by its own friction."""
    sc = get_scenario("friction")
    rigid = sc.plant()
    jm = rigid.motor.inertia_kgm2
    two = rigid.replace(transmission=Transmission.from_resonance(2 * jm, jm, 200.0, 0.02))
    tr = Transmission.from_resonance(2 * jm, jm, 200.0, 0.02, load_coulomb_nm=0.01)
    both = rigid.replace(transmission=tr)
    prms, cmds = [], []
    for plant in (two, rigid, both):
        cmd = sc.command(plant)
        prms.append(pack(Settings(), plant, DEFAULT_MEASURES, float(cmd[-1]), cmd.size))
        cmds.append(cmd)
    PRM, CMD = np.stack(prms), np.stack(cmds)
    w = int(PRM[0, L.P_ACC_W])
    size = int(K.ring_size(PRM[0]))
    ST, RING = np.zeros((3, L.N_STATE)), np.zeros((3, size))
    for j in range(3):
        K.init_state(PRM[j], ST[j], RING[j])
    ST2, RING2 = ST.copy(), RING.copy()
    m = 700
    Z, CB, H = (a[0] for a in _lanes.scratch(1, m, w))
    ids = np.zeros(_lanes.LANES, dtype=np.int64)
    ids[:3] = np.arange(3)
    rec = np.zeros((L.N_ROWS, 0))
    while ST[0, L.S_TICK] + m <= CMD.shape[1]:
        _lanes.advance(ids, 3, PRM, ST, RING, CMD, m, Z, CB, H)
        for j in range(3):
            i1 = int(ST[j, L.S_TICK])
            K.run_segment(CMD[j], np.zeros(0, np.int8), PRM[j], ST2[j], RING2[j], i1, rec, 1)
        np.testing.assert_array_equal(ST, ST2)
    # the ticks covered held the motor while its load moved, and broke it away
    tr = simulate(CMD[0, : int(ST[0, L.S_TICK])], Settings(), two)
    w, twist = tr.speed_rad_s, tr.motor_rad - tr.load_rad
    held = (w[1:] == 0.0) & (w[:-1] == 0.0) & (twist[1:] != twist[:-1])
    breaks = (w[:-1] == 0.0) & (w[1:] != 0.0)
    assert held.sum() > 100 and breaks.sum() >= 2
    wl = simulate(CMD[2, : int(ST[2, L.S_TICK])], Settings(), both).load_speed_rad_s
    assert ((wl[1:] == 0.0) & (wl[:-1] == 0.0)).sum() > 100
