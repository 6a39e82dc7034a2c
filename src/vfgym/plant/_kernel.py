"""The compiled hot loop: V-F controller → digital servo → motor → encoder, tick by tick.

One kernel (:func:`run_segment`) over plain arrays and scalars advances a move; its tick
is written block by block in :mod:`vfgym.plant._tick` and compiled into the loop. The
compile options (cache where one can be written, no fastmath, so its floating-point
operations are IEEE double in the written order and agree bit for bit with
:mod:`vfgym.plant.reference`) are the package's one policy, :mod:`vfgym.plant._jit`.
The equations are those of ``docs/model.md`` §1–§3; their order within a tick is:

1. pulse source: V-F controller on the command ``cmd[i]`` (or an external pulse array);
2. servo: encoder count change since the last tick into the position counter (with the
   gear times the pulse) and the speed counter; every Ns ticks the speed counter is
   latched (x = B·count), filtered (y += A·(x − y)) and reset;
3. torque τ = K3·(pc − y), clipped to the torque–speed curve;
4. motor: exact integration over the tick for τ held constant (viscous, Coulomb, load);
   on a two-mass plant (``P_TWO``), the motor and the load beyond its spring (§3.1);
5. encoder: count = floor(θ / q).

Measures are streamed into the state row as the loop goes (no trace is needed) and
copied into an accumulator row at the end (:func:`finish`); a trace is written only when
the caller passes arrays for it. :func:`run_one` runs a whole move, :func:`run_batch`
many moves over numba's threads.
"""

from __future__ import annotations

import numba
import numpy as np

from vfgym.plant import _layout, _tick
from vfgym.plant._jit import guard_cache, jit
from vfgym.plant._layout import (
    A_ACC_MOTOR,
    A_ACC_PULSE,
    A_ACC_QUANTUM,
    A_ACC_WINDOW,
    A_FIRST_PULSE,
    A_LAST_OUT_LOAD,
    A_LAST_OUT_MOTOR,
    A_LAST_OUT_PULSE,
    A_LAST_PULSE,
    A_LOAD,
    A_LOAD_SPEED,
    A_MIN_INTERVAL,
    A_N,
    A_OMEGA,
    A_OV_LOAD,
    A_OV_MOTOR,
    A_OV_PULSE,
    A_PC,
    A_PC_MAX,
    A_PULSES,
    A_RESIDUAL,
    A_REVERSALS,
    A_RIPPLE_N,
    A_RIPPLE_SQ,
    A_SAT_TICKS,
    A_SPEED_MAX,
    A_SS_COUNT,
    A_SS_SUM_MOTOR,
    A_SS_SUM_PULSE,
    A_THETA,
    A_TICKS,
    A_TORQUE_MAX,
    A_TRK_MAX_LOAD,
    A_TRK_MAX_MOTOR,
    A_TRK_MAX_PULSE,
    A_TRK_SQ_LOAD,
    A_TRK_SQ_MOTOR,
    A_TRK_SQ_PULSE,
    N_ACC,
    N_ROWS,
    N_STATE,
    P_A,
    P_ACC_SCALE,
    P_ACC_W,
    P_B,
    P_COUNT_RAD,
    P_CTF,
    P_CTW,
    P_CWF,
    P_CWW,
    P_DAMP,
    P_DELTA,
    P_GEAR,
    P_INV_J,
    P_K3,
    P_LAW,
    P_LIMIT,
    P_NS,
    P_SLOPE,
    P_SS_START,
    P_STEP,
    P_TARGET,
    P_TC,
    P_TCL,
    P_TICK_S,
    P_TLOAD,
    P_TPEAK,
    P_TWO,
    P_USE_EXT,
    P_VALUE,
    P_WIN_RAD,
    P_WKNEE,
    P_WMAX,
    S_C,
    S_CPREV,
    S_D2MX,
    S_DWMX,
    S_EPREV,
    S_FIRSTP,
    S_LASTDIR,
    S_LASTP,
    S_LASTSIGN,
    S_LOL,
    S_LOM,
    S_LOP,
    S_MINIV,
    S_N,
    S_NSAMP,
    S_NSLEFT,
    S_OMEGA,
    S_OVL,
    S_OVM,
    S_OVP,
    S_PC,
    S_PCMX,
    S_PPREV,
    S_PULSES,
    S_REV,
    S_RIPN,
    S_RIPSQ,
    S_RVHI,
    S_RVLO,
    S_SAT,
    S_SC,
    S_SSM,
    S_SSN,
    S_SSP,
    S_SUM,
    S_TAU,
    S_THETA,
    S_THS0,
    S_TICK,
    S_TMXL,
    S_TMXM,
    S_TMXP,
    S_TQMX,
    S_TSQL,
    S_TSQM,
    S_TSQP,
    S_TWIST,
    S_U,
    S_V1,
    S_V2,
    S_WLOAD,
    S_WMX,
    S_X,
    S_Y,
)
from vfgym.plant._tick import (
    encoder,
    in_position,
    load_tick,
    motor,
    motor_two,
    overshoot,
    peak,
    pulse_accel,
    pulse_stats,
    record,
    ripple_sample,
    servo_count,
    servo_sample,
    steady_state,
    torque,
    tracking,
    train_position,
    two_mass,
    vf_tick,
)


@jit
def vf_pulses_kernel(cmd, delta, value, limit, step, law, out):
    """V-F controller alone: one pulse (−1, 0, +1) per tick into ``out``."""
    n = 0
    s = 0.0
    e_prev = 0.0
    for i in range(cmd.shape[0]):
        p, s, e_prev = vf_tick(cmd[i], n, s, e_prev, delta, value, limit, step, law)
        out[i] = p
        n += p


@jit
def init_state(prm, st, ring):
    """Start a move: the plant at rest at 0, every measure at its initial value."""
    st[S_N] = 0
    st[S_SUM] = 0.0
    st[S_EPREV] = 0.0
    st[S_CPREV] = 0
    st[S_C] = 0
    st[S_PC] = 0
    st[S_SC] = 0
    st[S_NSLEFT] = prm[P_NS]
    st[S_Y] = 0.0
    st[S_X] = 0.0
    st[S_THETA] = 0.0
    st[S_OMEGA] = 0.0
    st[S_TAU] = 0.0
    st[S_U] = 0.0
    st[S_PPREV] = 0.0
    st[S_LASTDIR] = 0.0
    st[S_OVM] = 0.0
    st[S_OVP] = 0.0
    st[S_LOM] = -1
    st[S_LOP] = -1
    st[S_SSM] = 0.0
    st[S_SSP] = 0.0
    st[S_SSN] = 0
    st[S_SAT] = 0
    st[S_TSQM] = 0.0
    st[S_TMXM] = 0.0
    st[S_TSQP] = 0.0
    st[S_TMXP] = 0.0
    st[S_RIPSQ] = 0.0
    st[S_RIPN] = 0
    st[S_THS0] = 0.0
    st[S_V1] = 0.0
    st[S_V2] = 0.0
    st[S_NSAMP] = 0
    st[S_PULSES] = 0
    st[S_REV] = 0
    st[S_MINIV] = 0
    st[S_FIRSTP] = -1
    st[S_LASTP] = -1
    st[S_LASTSIGN] = 0
    st[S_TQMX] = 0.0
    st[S_PCMX] = 0
    st[S_WMX] = 0.0
    st[S_D2MX] = 0.0
    st[S_DWMX] = 0.0
    st[S_TICK] = 0
    st[S_TWIST] = 0.0
    st[S_WLOAD] = 0.0
    st[S_OVL] = 0.0
    st[S_LOL] = -1
    st[S_RVHI] = 0.0
    st[S_RVLO] = 0.0
    st[S_TSQL] = 0.0
    st[S_TMXL] = 0.0
    ring[:] = 0


@jit
def run_segment(cmd, ext, prm, st, ring, i1, rec, dec):
    """Advance the move in ``st`` from tick ``st[S_TICK]`` to tick ``i1`` (exclusive),
    streaming its measures into ``st`` and writing every ``dec``-th tick's state into
    ``rec`` (shape (N_ROWS, m), m = 0 for none). ``cmd`` and ``ext`` are indexed by the
    move's own tick number; ``prm`` may change between segments (online tuning).

    A rigid and a two-mass plant (``P_TWO``) each run their own compiled loop
    (:func:`segment`, specialised on its literal ``two``): the rigid loop's tick does
    nothing of the two-mass plant's."""
    if prm[P_TWO] != 0.0:
        segment(cmd, ext, prm, st, ring, i1, rec, dec, True)
    else:
        segment(cmd, ext, prm, st, ring, i1, rec, dec, False)


@jit
def run_segment_rigid(cmd, ext, prm, st, ring, i1, rec, dec):
    """:func:`run_segment` of a rigid plant: what a caller in Python that knows its plant
    calls, so that a first use compiles only its own loop."""
    segment(cmd, ext, prm, st, ring, i1, rec, dec, False)


@jit
def run_segment_two(cmd, ext, prm, st, ring, i1, rec, dec):
    """:func:`run_segment` of a two-mass plant (``P_TWO``), as :func:`run_segment_rigid`."""
    segment(cmd, ext, prm, st, ring, i1, rec, dec, True)


@jit
def segment(cmd, ext, prm, st, ring, i1, rec, dec, two):
    """:func:`run_segment`'s loop; ``two`` (a literal at each call, so numba compiles one
    loop for each value, the other's branches dropped): the two-mass plant.

    The loop state is held in locals (registers) between the state row's loads and
    stores, one line per block; each tick runs the blocks of :mod:`vfgym.plant._tick`."""
    # the parameter row, read once before the loop: the loop stores into ``st``, ``ring``
    # and ``rec``, which LLVM cannot prove distinct from ``prm``, so a read inside the
    # loop would be repeated every tick
    T, q, inv_j, damp = prm[P_TICK_S], prm[P_COUNT_RAD], prm[P_INV_J], prm[P_DAMP]
    delta, value, limit, step = prm[P_DELTA], prm[P_VALUE], prm[P_LIMIT], prm[P_STEP]
    law, use_ext = int(prm[P_LAW]), prm[P_USE_EXT] != 0.0
    gear, ns, B, A = int(prm[P_GEAR]), int(prm[P_NS]), prm[P_B], prm[P_A]
    K3, tpeak, wknee, wmax, slope = prm[P_K3], prm[P_TPEAK], prm[P_WKNEE], prm[P_WMAX], prm[P_SLOPE]
    cww, cwf, ctw, ctf = prm[P_CWW], prm[P_CWF], prm[P_CTW], prm[P_CTF]
    tc, tload = prm[P_TC], prm[P_TLOAD]
    target, win, ss_start = prm[P_TARGET], prm[P_WIN_RAD], int(prm[P_SS_START])
    accw = int(prm[P_ACC_W])
    z, tcl = two_mass(prm), prm[P_TCL]
    inv_q = 1.0 / q
    n_rec = rec.shape[1] if rec.shape[0] >= N_ROWS else 0
    i0 = int(st[S_TICK])
    rec_left = dec
    rec_j = 0

    # the loop state, by block
    n, s, e_prev = int(st[S_N]), st[S_SUM], st[S_EPREV]
    c_prev, c, pc, sc = int(st[S_CPREV]), int(st[S_C]), int(st[S_PC]), int(st[S_SC])
    ns_left, y, x, u = int(st[S_NSLEFT]), st[S_Y], st[S_X], st[S_U]
    theta, omega, tau, sat = st[S_THETA], st[S_OMEGA], st[S_TAU], int(st[S_SAT])
    p_prev, last_dir, ov_m, ov_p = st[S_PPREV], st[S_LASTDIR], st[S_OVM], st[S_OVP]
    last_out_m, last_out_p = int(st[S_LOM]), int(st[S_LOP])
    ss_m, ss_p, ss_n = st[S_SSM], st[S_SSP], int(st[S_SSN])
    trk_sq_m, trk_mx_m, trk_sq_p, trk_mx_p = st[S_TSQM], st[S_TMXM], st[S_TSQP], st[S_TMXP]
    rip_sq, rip_n, theta_s0 = st[S_RIPSQ], int(st[S_RIPN]), st[S_THS0]
    v1, v2, n_samples = st[S_V1], st[S_V2], int(st[S_NSAMP])
    pulses, reversals, min_iv = int(st[S_PULSES]), int(st[S_REV]), int(st[S_MINIV])
    first_p, last_p, last_sign = int(st[S_FIRSTP]), int(st[S_LASTP]), int(st[S_LASTSIGN])
    tq_mx, pc_mx, w_mx = st[S_TQMX], int(st[S_PCMX]), st[S_WMX]
    d2_max, dw_max = st[S_D2MX], st[S_DWMX]
    d, wl, ov_l, lo_l = st[S_TWIST], st[S_WLOAD], st[S_OVL], int(st[S_LOL])
    rv_hi, rv_lo, trk_sq_l, trk_mx_l = st[S_RVHI], st[S_RVLO], st[S_TSQL], st[S_TMXL]

    for i in range(i0, i1):
        P = cmd[i]
        # 1. pulse source
        if use_ext:
            p = int(ext[i])
        else:
            p, s, e_prev = vf_tick(P, n, s, e_prev, delta, value, limit, step, law)
        n += p
        # 2. servo counters, and every ns ticks the speed sample (and its ripple measure)
        pc, sc = servo_count(p, c, c_prev, pc, sc, gear)
        c_prev = c
        ns_left -= 1
        if ns_left == 0:
            ns_left = ns
            x, y = servo_sample(sc, y, B, A)
            sc = 0
            theta_s0, v1, v2, n_samples, rip_sq, rip_n = ripple_sample(
                theta, theta_s0, v1, v2, n_samples, rip_sq, rip_n, ns, T
            )
        # 3. torque
        u = pc - y
        tau, sat = torque(u, omega, sat, K3, tpeak, wknee, wmax, slope)
        # 4. motor over the tick, torque held
        omega_old = omega
        if two:
            theta, omega, d, wl = motor_two(theta, omega, d, wl, tau - tload, tc, tcl, z)
        else:
            theta, omega = motor(theta, omega, tau - tload, tc, cww, cwf, ctw, ctf, damp, inv_j, T)
        # 5. encoder
        c = encoder(theta, q, inv_q, st)
        # streamed measures
        pos = n * delta
        last_dir, ov_m, ov_p = overshoot(P, p_prev, last_dir, theta, pos, ov_m, ov_p)
        if two:
            thl = theta - d
            ov_l, lo_l, rv_hi, rv_lo = load_tick(
                i, P, p_prev, last_dir, theta, thl, target, win, ov_l, lo_l, rv_hi, rv_lo
            )
            trk_sq_l, trk_mx_l = tracking(P - thl, trk_sq_l, trk_mx_l)
        p_prev = P
        last_out_m, last_out_p = in_position(i, theta, pos, target, win, last_out_m, last_out_p)
        ss_m, ss_p, ss_n = steady_state(i, ss_start, theta, pos, target, ss_m, ss_p, ss_n)
        xt = train_position(n, s, value, use_ext)
        d2_max = pulse_accel(ring, i, xt, accw, d2_max)
        dw_max = peak(abs(omega - omega_old), dw_max)
        trk_sq_m, trk_mx_m = tracking(P - theta, trk_sq_m, trk_mx_m)
        trk_sq_p, trk_mx_p = tracking(P - pos, trk_sq_p, trk_mx_p)
        pulses, min_iv, reversals, first_p, last_p, last_sign = pulse_stats(
            p, i, pulses, min_iv, reversals, first_p, last_p, last_sign
        )
        tq_mx = peak(abs(tau), tq_mx)
        pc_mx = peak(abs(pc), pc_mx)
        w_mx = peak(abs(omega), w_mx)
        # the trace, every dec-th tick
        if n_rec > 0:
            rec_left -= 1
            if rec_left == 0:
                rec_left = dec
                if rec_j < n_rec:
                    if two:
                        record(rec, rec_j, P, pos, theta, omega, tau, u, pc, y, x, xt * delta,
                               theta - d, wl)  # fmt: skip
                    else:
                        record(rec, rec_j, P, pos, theta, omega, tau, u, pc, y, x, xt * delta,
                               theta, omega)  # fmt: skip
                    rec_j += 1

    st[S_N], st[S_SUM], st[S_EPREV] = n, s, e_prev
    st[S_CPREV], st[S_C], st[S_PC], st[S_SC] = c_prev, c, pc, sc
    st[S_NSLEFT], st[S_Y], st[S_X], st[S_U] = ns_left, y, x, u
    st[S_THETA], st[S_OMEGA], st[S_TAU], st[S_SAT] = theta, omega, tau, sat
    st[S_PPREV], st[S_LASTDIR], st[S_OVM], st[S_OVP] = p_prev, last_dir, ov_m, ov_p
    st[S_LOM], st[S_LOP] = last_out_m, last_out_p
    st[S_SSM], st[S_SSP], st[S_SSN] = ss_m, ss_p, ss_n
    st[S_TSQM], st[S_TMXM], st[S_TSQP], st[S_TMXP] = trk_sq_m, trk_mx_m, trk_sq_p, trk_mx_p
    st[S_RIPSQ], st[S_RIPN], st[S_THS0] = rip_sq, rip_n, theta_s0
    st[S_V1], st[S_V2], st[S_NSAMP] = v1, v2, n_samples
    st[S_PULSES], st[S_REV], st[S_MINIV] = pulses, reversals, min_iv
    st[S_FIRSTP], st[S_LASTP], st[S_LASTSIGN] = first_p, last_p, last_sign
    st[S_TQMX], st[S_PCMX], st[S_WMX] = tq_mx, pc_mx, w_mx
    st[S_D2MX], st[S_DWMX] = d2_max, dw_max
    st[S_TWIST], st[S_WLOAD], st[S_OVL], st[S_LOL] = d, wl, ov_l, lo_l
    st[S_RVHI], st[S_RVLO], st[S_TSQL], st[S_TMXL] = rv_hi, rv_lo, trk_sq_l, trk_mx_l
    st[S_TICK] = i1


@jit
def finish(st, acc, n_ticks, prm):
    """The accumulator row of a move from its loop state and parameter row (see
    :mod:`vfgym.plant._layout`)."""
    T, acc_scale = prm[P_TICK_S], prm[P_ACC_SCALE]
    acc[A_OV_MOTOR] = st[S_OVM]
    acc[A_OV_PULSE] = st[S_OVP]
    acc[A_LAST_OUT_MOTOR] = st[S_LOM]
    acc[A_LAST_OUT_PULSE] = st[S_LOP]
    acc[A_SS_SUM_MOTOR] = st[S_SSM]
    acc[A_SS_SUM_PULSE] = st[S_SSP]
    acc[A_SS_COUNT] = st[S_SSN]
    acc[A_ACC_PULSE] = st[S_D2MX] * acc_scale
    acc[A_ACC_MOTOR] = st[S_DWMX] / T
    acc[A_SAT_TICKS] = st[S_SAT]
    acc[A_TRK_SQ_MOTOR] = st[S_TSQM]
    acc[A_TRK_MAX_MOTOR] = st[S_TMXM]
    acc[A_TRK_SQ_PULSE] = st[S_TSQP]
    acc[A_TRK_MAX_PULSE] = st[S_TMXP]
    acc[A_RIPPLE_SQ] = st[S_RIPSQ]
    acc[A_RIPPLE_N] = st[S_RIPN]
    acc[A_PULSES] = st[S_PULSES]
    acc[A_REVERSALS] = st[S_REV]
    acc[A_MIN_INTERVAL] = st[S_MINIV]
    acc[A_FIRST_PULSE] = st[S_FIRSTP]
    acc[A_LAST_PULSE] = st[S_LASTP]
    acc[A_TORQUE_MAX] = st[S_TQMX]
    acc[A_PC_MAX] = st[S_PCMX]
    acc[A_THETA] = st[S_THETA]
    acc[A_OMEGA] = st[S_OMEGA]
    acc[A_N] = st[S_N]
    acc[A_PC] = st[S_PC]
    acc[A_SPEED_MAX] = st[S_WMX]
    acc[A_TICKS] = n_ticks
    acc[A_ACC_WINDOW] = prm[P_ACC_W]
    acc[A_ACC_QUANTUM] = 2.0 * acc_scale if prm[P_USE_EXT] != 0.0 else 0.0
    acc[A_OV_LOAD] = st[S_OVL]
    acc[A_LAST_OUT_LOAD] = st[S_LOL]
    acc[A_RESIDUAL] = st[S_RVHI] - st[S_RVLO]
    acc[A_TRK_SQ_LOAD] = st[S_TSQL]
    acc[A_TRK_MAX_LOAD] = st[S_TMXL]
    acc[A_LOAD] = st[S_THETA] - st[S_TWIST]
    acc[A_LOAD_SPEED] = st[S_WLOAD] if prm[P_TWO] != 0.0 else st[S_OMEGA]


@jit
def ring_size(prm):
    """Length of the pulse-count history: a power of two above 2w."""
    size = 1
    while size < 2 * int(prm[P_ACC_W]) + 1:
        size *= 2
    return size


@jit
def one_move(cmd, ext, prm, acc, rec, dec, two):
    """Simulate one whole move; stream its measures into ``acc``; write every ``dec``-th
    tick's state into ``rec`` (shape (N_ROWS, m), m = 0 for none). ``two``, a literal at
    each call as :func:`segment`'s: the plant is a two-mass plant (``P_TWO``)."""
    st = np.empty(N_STATE, dtype=np.float64)
    ring = np.empty(ring_size(prm), dtype=np.float64)
    init_state(prm, st, ring)
    segment(cmd, ext, prm, st, ring, cmd.shape[0], rec, dec, two)
    finish(st, acc, cmd.shape[0], prm)


@jit
def run_one(cmd, ext, prm, acc, rec, dec):
    """:func:`one_move` of a rigid or a two-mass plant, as ``prm`` says."""
    if prm[P_TWO] != 0.0:
        one_move(cmd, ext, prm, acc, rec, dec, True)
    else:
        one_move(cmd, ext, prm, acc, rec, dec, False)


@jit(parallel=True)
def run_batch(cmd_flat, cmd_off, cmd_idx, ext_flat, ext_off, ext_idx, prm, acc):
    """Run ``prm.shape[0]`` moves in parallel (numba threads over the runs). Run r reads
    command ``cmd_idx[r]``, i.e. ``cmd_flat[cmd_off[j]:cmd_off[j+1]]``, and external pulses
    ``ext_idx[r]`` from ``ext_flat`` likewise (an empty segment when the V-F controller
    makes the pulses); it writes measures only, into ``acc[r]``. Rigid and two-mass plants
    may be mixed (:func:`run_batch_rigid` compiles the rigid loop alone)."""
    rec = np.zeros((N_ROWS, 0), dtype=np.float64)
    for r in numba.prange(prm.shape[0]):
        j = cmd_idx[r]
        e = ext_idx[r]
        cmd = cmd_flat[cmd_off[j] : cmd_off[j + 1]]
        ext = ext_flat[ext_off[e] : ext_off[e + 1]]
        run_one(cmd, ext, prm[r], acc[r], rec, 1)


@jit(parallel=True)
def run_batch_rigid(cmd_flat, cmd_off, cmd_idx, ext_flat, ext_off, ext_idx, prm, acc):
    """:func:`run_batch` of rigid plants only (no row's ``P_TWO`` set): what a caller that
    knows its batch calls, so that a first use compiles the rigid loop alone (the two-mass
    loop nearly doubles the batch's compile time)."""
    rec = np.zeros((N_ROWS, 0), dtype=np.float64)
    for r in numba.prange(prm.shape[0]):
        j = cmd_idx[r]
        e = ext_idx[r]
        cmd = cmd_flat[cmd_off[j] : cmd_off[j + 1]]
        ext = ext_flat[ext_off[e] : ext_off[e + 1]]
        one_move(cmd, ext, prm[r], acc[r], rec, 1, False)


def new_acc(runs: int = 0) -> np.ndarray:
    """A zeroed accumulator row (or ``runs`` rows)."""
    return np.zeros(N_ACC if runs == 0 else (runs, N_ACC), dtype=np.float64)


# The loop compiles the blocks of _tick and the slot numbers of _layout into itself.
guard_cache(run_segment, (_tick, _layout))
