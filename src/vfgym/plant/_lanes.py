"""The kernel's tick over a block of envs in SIMD lanes: the vector envs' fast path.

:func:`vfgym.plant._kernel.run_segment` advances one move; it is bound by the latency of one
tick's chain (encoder → servo → torque → motor → encoder), so one core does far less than
it could. Here :data:`LANES` moves advance together, tick by tick: every quantity of the
loop state is a row of ``LANES`` numbers (structure of arrays), and each step of the tick
is a loop over the lanes that LLVM turns into AVX/AVX-512 vector code. The equations and
the order of every floating-point operation are those of ``run_segment``; the branches
become selects (both sides computed, one kept), which changes no result. So a lane ends
bit for bit where ``run_segment`` would (tested on random plants, settings and starting
ticks against the kernel).

What makes the loops vectorise, and must stay so:

* one flat block array ``Z`` of rows of ``LANES`` numbers, indexed with unsigned
  (:func:`_at`) constant-row offsets, so that LLVM sees fixed distances between rows (no
  negative-index wrap-around, no symbolic row);
* ``error_model="numpy"`` (``simd=True`` in the package's policy, :mod:`vfgym.plant._jit`:
  no zero-division branch; every divisor is validated > 0);
* no calls and no reductions across lanes in the vectorised loops; the rare tick in which
  Coulomb friction stops the motor (:func:`vfgym.plant._tick.stop_within_tick`, which calls
  ``log1p``/``expm1``) is flagged and done per lane in a scalar pass between them;
* the train-position history for the acceleration measure is kept per block (``H``) and
  its maximum taken after the ticks (a maximum does not depend on the order).

A two-mass plant (a transmission, docs/model.md §3.1) needs no scalar pass: its tick
(:func:`vfgym.plant._tick.motor_two`) is multiply-adds and selects. A block with any
two-mass lane runs a loop (literal ``two``) that computes both plants' steps and keeps
each lane's own, and streams the load's measures of its two-mass lanes.

Whole numbers of the state (counts, ticks) are held as float64, exactly (< 2**53), as
the kernel's state row holds them.
"""

from __future__ import annotations

import math

import numpy as np
from numba.core import types as nbt
from numba.extending import intrinsic

from vfgym.plant import _layout as L
from vfgym.plant import _tick as TK
from vfgym.plant._jit import guard_cache, jit

LANES = 16
"""Moves per block: two AVX-512 vectors (four AVX2 ones) of float64."""

_jit = jit(simd=True)
"""The lanes' compile policy: ``error_model="numpy"``, so that the loops over lanes vectorise."""

# --- block rows (each LANES numbers) -----------------------------------------------------
Z_PRM = 0  # the kernel's parameter row, transposed
Z_ST = Z_PRM + L.N_PARAMS  # its loop state, transposed
Z_P = Z_ST + L.N_STATE  # pulse of this tick
Z_SLOW = Z_P + 1  # 1: friction stops the motor within this tick (scalar pass)
Z_WOLD = Z_P + 2  # speed before this tick
Z_NET = Z_P + 3  # net torque of this tick
Z_CMD = Z_P + 4  # command of this tick
Z_NOUT = Z_P + 5  # pulse count after this tick
N_ROWS = Z_P + 6


@intrinsic
def _at(typingctx, row, lane):
    """The index of lane ``lane`` of block row ``row`` in ``Z``, row·LANES + lane, as an
    unsigned integer: so LLVM sees fixed distances between rows and no negative-index
    wrap-around. An intrinsic, emitted in place as two integer operations: as a numba
    function inlined at its ~250 uses (``inline=True``) it took minutes to compile, numba
    copying the caller's whole scope at every inlined call."""
    if not (isinstance(row, nbt.Integer) and isinstance(lane, nbt.Integer)):
        return None

    def codegen(context, builder, sig, args):
        r = context.cast(builder, args[0], sig.args[0], nbt.uint64)
        e = context.cast(builder, args[1], sig.args[1], nbt.uint64)
        return builder.add(builder.mul(r, context.get_constant(nbt.uint64, LANES)), e)

    return nbt.uint64(row, lane), codegen


@_jit
def _tick_source_servo_motor(Z, sampling, friction, two) -> int:
    """Steps 1-4 of the tick (pulse source, servo, torque, motor) in every lane; returns
    how many lanes need the friction stop (left unmoved, flagged in ``Z_SLOW``).

    ``sampling``, ``friction`` and ``two`` are constants at each call (literal arguments:
    numba compiles one loop for each, with what cannot happen dropped): sampling 0 / 1: no
    lane / every lane latches its speed counter this tick (the lanes' sample periods are
    in step), 2: each lane as its counter says; friction False: no lane has Coulomb
    friction; two False: no lane is a two-mass plant."""
    nslow = 0
    for e in range(LANES):
        P = Z[_at(Z_CMD, e)]
        # 1. V-F controller (vfgym.plant._tick.vf_tick as selects)
        delta = Z[_at(Z_PRM + L.P_DELTA, e)]
        limit = Z[_at(Z_PRM + L.P_LIMIT, e)]
        step = Z[_at(Z_PRM + L.P_STEP, e)]
        value = Z[_at(Z_PRM + L.P_VALUE, e)]
        slew = Z[_at(Z_PRM + L.P_LAW, e)] != 0.0
        n = Z[_at(Z_ST + L.S_N, e)]
        e_prev = Z[_at(Z_ST + L.S_EPREV, e)]
        err = P - n * delta
        err = limit if err > limit else err
        err = -limit if err < -limit else err
        up = e_prev + step
        dn = e_prev - step
        c_up = err > up and (slew or e_prev >= 0.0)
        err = up if c_up else err
        c_dn = err < dn and ((slew and not c_up) or (not slew and e_prev <= 0.0))
        err = dn if c_dn else err
        s = Z[_at(Z_ST + L.S_SUM, e)] + err
        plus = s >= value
        minus = (not plus) and s <= -value
        p = 1.0 if plus else (-1.0 if minus else 0.0)
        s = s - value if plus else (s + value if minus else s)
        Z[_at(Z_ST + L.S_SUM, e)] = s
        Z[_at(Z_ST + L.S_EPREV, e)] = err
        n = n + p
        Z[_at(Z_ST + L.S_N, e)] = n
        Z[_at(Z_P, e)] = p
        Z[_at(Z_NOUT, e)] = n
        # 2. servo counters and sampled filter
        c = Z[_at(Z_ST + L.S_C, e)]
        dc = c - Z[_at(Z_ST + L.S_CPREV, e)]
        Z[_at(Z_ST + L.S_CPREV, e)] = c
        pc = Z[_at(Z_ST + L.S_PC, e)] + (Z[_at(Z_PRM + L.P_GEAR, e)] * p - dc)
        Z[_at(Z_ST + L.S_PC, e)] = pc
        sc = Z[_at(Z_ST + L.S_SC, e)] + dc
        ns_left = Z[_at(Z_ST + L.S_NSLEFT, e)] - 1.0
        latch = (ns_left == 0.0) if sampling == 2 else (sampling == 1)
        ns = Z[_at(Z_PRM + L.P_NS, e)]
        y = Z[_at(Z_ST + L.S_Y, e)]
        x_new = Z[_at(Z_PRM + L.P_B, e)] * sc
        y_new = y + Z[_at(Z_PRM + L.P_A, e)] * (x_new - y)
        theta = Z[_at(Z_ST + L.S_THETA, e)]
        ths0 = Z[_at(Z_ST + L.S_THS0, e)]
        v0 = (theta - ths0) / (ns * Z[_at(Z_PRM + L.P_TICK_S, e)])
        nsamp = Z[_at(Z_ST + L.S_NSAMP, e)] + 1.0
        v1 = Z[_at(Z_ST + L.S_V1, e)]
        v2 = Z[_at(Z_ST + L.S_V2, e)]
        d2 = v0 - 2.0 * v1 + v2
        ripple = latch and nsamp >= 3.0
        rip_sq = Z[_at(Z_ST + L.S_RIPSQ, e)]
        rip_n = Z[_at(Z_ST + L.S_RIPN, e)]
        Z[_at(Z_ST + L.S_RIPSQ, e)] = rip_sq + d2 * d2 if ripple else rip_sq
        Z[_at(Z_ST + L.S_RIPN, e)] = rip_n + 1.0 if ripple else rip_n
        Z[_at(Z_ST + L.S_V2, e)] = v1 if latch else v2
        Z[_at(Z_ST + L.S_V1, e)] = v0 if latch else v1
        Z[_at(Z_ST + L.S_NSAMP, e)] = nsamp if latch else nsamp - 1.0
        Z[_at(Z_ST + L.S_THS0, e)] = theta if latch else ths0
        x = Z[_at(Z_ST + L.S_X, e)]
        Z[_at(Z_ST + L.S_X, e)] = x_new if latch else x
        y = y_new if latch else y
        Z[_at(Z_ST + L.S_Y, e)] = y
        Z[_at(Z_ST + L.S_SC, e)] = 0.0 if latch else sc
        Z[_at(Z_ST + L.S_NSLEFT, e)] = ns if latch else ns_left
        # 3. torque command and the torque–speed limit
        u = pc - y
        Z[_at(Z_ST + L.S_U, e)] = u
        tau = Z[_at(Z_PRM + L.P_K3, e)] * u
        omega = Z[_at(Z_ST + L.S_OMEGA, e)]
        tpeak = Z[_at(Z_PRM + L.P_TPEAK, e)]
        wknee = Z[_at(Z_PRM + L.P_WKNEE, e)]
        aw = abs(omega)
        sloped = tpeak + Z[_at(Z_PRM + L.P_SLOPE, e)] * (aw - wknee)
        curve = tpeak if aw <= wknee else (sloped if aw < Z[_at(Z_PRM + L.P_WMAX, e)] else 0.0)
        lim = curve if tau * omega > 0.0 else tpeak
        hi = tau > lim
        lo = (not hi) and tau < -lim
        sat = Z[_at(Z_ST + L.S_SAT, e)]
        Z[_at(Z_ST + L.S_SAT, e)] = sat + 1.0 if (hi or lo) else sat
        tau = lim if hi else (-lim if lo else tau)
        Z[_at(Z_ST + L.S_TAU, e)] = tau
        # 4. motor over the tick, torque held
        net = tau - Z[_at(Z_PRM + L.P_TLOAD, e)]
        Z[_at(Z_NET, e)] = net
        Z[_at(Z_WOLD, e)] = omega
        tc = Z[_at(Z_PRM + L.P_TC, e)]
        cww = Z[_at(Z_PRM + L.P_CWW, e)]
        cwf = Z[_at(Z_PRM + L.P_CWF, e)]
        ctw = Z[_at(Z_PRM + L.P_CTW, e)]
        ctf = Z[_at(Z_PRM + L.P_CTF, e)]
        free = (tc == 0.0) if friction else True
        stuck = (not free) and omega == 0.0
        th_free = theta + (ctw * omega + ctf * net)
        w_free = cww * omega + cwf * net
        breaks = net > tc or net < -tc
        f1 = net - tc if net > 0.0 else net + tc
        th_stuck = theta + ctf * f1 if breaks else theta
        w_stuck = cwf * f1 if breaks else omega
        sgn = 1.0 if omega > 0.0 else -1.0
        f2 = net - sgn * tc
        w_move = cww * omega + cwf * f2
        keeps = w_move * sgn > 0.0
        th_move = theta + (ctw * omega + ctf * f2)
        slow = (not free) and (not stuck) and (not keeps)
        th_rigid = th_free if free else (th_stuck if stuck else (th_move if keeps else theta))
        w_rigid = w_free if free else (w_stuck if stuck else (w_move if keeps else omega))
        if two:  # the two-mass tick (vfgym.plant._tick.motor_two as selects)
            lane_two = Z[_at(Z_PRM + L.P_TWO, e)] != 0.0
            slow = slow and not lane_two
            tcl = Z[_at(Z_PRM + L.P_TCL, e)]
            d = Z[_at(Z_ST + L.S_TWIST, e)]
            wl = Z[_at(Z_ST + L.S_WLOAD, e)]
            spring = Z[_at(Z_PRM + L.P_KS, e)] * d + Z[_at(Z_PRM + L.P_CS, e)] * (omega - wl)
            pull = net - spring
            s_pull = 1.0 if pull > tc else (-1.0 if pull < -tc else 0.0)
            s_move = 1.0 if omega > 0.0 else -1.0
            s = (s_pull if omega == 0.0 else s_move) if tc != 0.0 else 0.0
            m_held = tc != 0.0 and omega == 0.0 and s_pull == 0.0
            sl_pull = 1.0 if spring > tcl else (-1.0 if spring < -tcl else 0.0)
            sl_move = 1.0 if wl > 0.0 else -1.0
            sl = (sl_pull if wl == 0.0 else sl_move) if tcl != 0.0 else 0.0
            l_held = tcl != 0.0 and wl == 0.0 and sl_pull == 0.0
            f = net - s * tc
            g = 0.0 - sl * tcl
            # both moving
            th_b = theta + (
                Z[_at(Z_PRM + L.P_Z_TW, e)] * omega
                + Z[_at(Z_PRM + L.P_Z_TD, e)] * d
                + Z[_at(Z_PRM + L.P_Z_TL, e)] * wl
                + Z[_at(Z_PRM + L.P_Z_TF, e)] * f
                + Z[_at(Z_PRM + L.P_Z_TG, e)] * g
            )
            w_b = (
                Z[_at(Z_PRM + L.P_Z_WW, e)] * omega
                + Z[_at(Z_PRM + L.P_Z_WD, e)] * d
                + Z[_at(Z_PRM + L.P_Z_WL, e)] * wl
                + Z[_at(Z_PRM + L.P_Z_WF, e)] * f
                + Z[_at(Z_PRM + L.P_Z_WG, e)] * g
            )
            d_b = (
                Z[_at(Z_PRM + L.P_Z_DW, e)] * omega
                + Z[_at(Z_PRM + L.P_Z_DD, e)] * d
                + Z[_at(Z_PRM + L.P_Z_DL, e)] * wl
                + Z[_at(Z_PRM + L.P_Z_DF, e)] * f
                + Z[_at(Z_PRM + L.P_Z_DG, e)] * g
            )
            wl_b = (
                Z[_at(Z_PRM + L.P_Z_LW, e)] * omega
                + Z[_at(Z_PRM + L.P_Z_LD, e)] * d
                + Z[_at(Z_PRM + L.P_Z_LL, e)] * wl
                + Z[_at(Z_PRM + L.P_Z_LF, e)] * f
                + Z[_at(Z_PRM + L.P_Z_LG, e)] * g
            )
            # the motor held: the load moves on the spring alone
            d_m = (
                Z[_at(Z_PRM + L.P_Z_MDD, e)] * d
                + Z[_at(Z_PRM + L.P_Z_MDL, e)] * wl
                + Z[_at(Z_PRM + L.P_Z_MDG, e)] * g
            )
            wl_m = (
                Z[_at(Z_PRM + L.P_Z_MLD, e)] * d
                + Z[_at(Z_PRM + L.P_Z_MLL, e)] * wl
                + Z[_at(Z_PRM + L.P_Z_MLG, e)] * g
            )
            # the load held: the motor moves against the spring
            th_l = theta + (
                Z[_at(Z_PRM + L.P_Z_LTW, e)] * omega
                + Z[_at(Z_PRM + L.P_Z_LTD, e)] * d
                + Z[_at(Z_PRM + L.P_Z_LTF, e)] * f
            )
            w_l = (
                Z[_at(Z_PRM + L.P_Z_LWW, e)] * omega
                + Z[_at(Z_PRM + L.P_Z_LWD, e)] * d
                + Z[_at(Z_PRM + L.P_Z_LWF, e)] * f
            )
            d_l = (
                Z[_at(Z_PRM + L.P_Z_LDW, e)] * omega
                + Z[_at(Z_PRM + L.P_Z_LDD, e)] * d
                + Z[_at(Z_PRM + L.P_Z_LDF, e)] * f
            )
            # each mode's step, the stops of its moving masses, then the lane's mode
            w_b = 0.0 if (s != 0.0 and s * w_b <= 0.0) else w_b
            wl_b = 0.0 if (sl != 0.0 and sl * wl_b <= 0.0) else wl_b
            wl_m = 0.0 if (sl != 0.0 and sl * wl_m <= 0.0) else wl_m
            w_l = 0.0 if (s != 0.0 and s * w_l <= 0.0) else w_l
            both_held = m_held and l_held
            th2 = theta if m_held else (th_l if l_held else th_b)
            w2 = omega if m_held else (w_l if l_held else w_b)
            d2 = d if both_held else (d_m if m_held else (d_l if l_held else d_b))
            wl2 = wl if l_held else (wl_m if m_held else wl_b)
            Z[_at(Z_ST + L.S_TWIST, e)] = d2 if lane_two else d
            Z[_at(Z_ST + L.S_WLOAD, e)] = wl2 if lane_two else wl
            th_rigid = th2 if lane_two else th_rigid
            w_rigid = w2 if lane_two else w_rigid
        Z[_at(Z_SLOW, e)] = 1.0 if slow else 0.0
        Z[_at(Z_ST + L.S_THETA, e)] = th_rigid
        Z[_at(Z_ST + L.S_OMEGA, e)] = w_rigid
        nslow += 1 if slow else 0
    return nslow


@_jit
def _friction_stops(Z) -> None:
    """The flagged lanes' motor step: Coulomb friction stops the motor within the tick."""
    for e in range(LANES):
        if Z[_at(Z_SLOW, e)] != 0.0:
            omega = Z[_at(Z_ST + L.S_OMEGA, e)]
            net = Z[_at(Z_NET, e)]
            tc = Z[_at(Z_PRM + L.P_TC, e)]
            sgn = 1.0 if omega > 0.0 else -1.0
            theta, omega = TK.stop_within_tick(
                Z[_at(Z_ST + L.S_THETA, e)],
                omega,
                net - sgn * tc,
                net,
                tc,
                Z[_at(Z_PRM + L.P_DAMP, e)],
                Z[_at(Z_PRM + L.P_INV_J, e)],
                Z[_at(Z_PRM + L.P_TICK_S, e)],
            )
            Z[_at(Z_ST + L.S_THETA, e)] = theta
            Z[_at(Z_ST + L.S_OMEGA, e)] = omega


@_jit
def _tick_encoder_measures(Z, k: int, two) -> None:
    """Step 5 of tick ``k`` of the block (encoder) and the streamed measures, in every lane
    (``two``, a literal: the load's measures of the two-mass lanes too)."""
    for e in range(LANES):
        i = Z[_at(Z_ST + L.S_TICK, e)] + k
        P = Z[_at(Z_CMD, e)]
        theta = Z[_at(Z_ST + L.S_THETA, e)]
        omega = Z[_at(Z_ST + L.S_OMEGA, e)]
        Z[_at(Z_ST + L.S_C, e)] = math.floor(theta / Z[_at(Z_PRM + L.P_COUNT_RAD, e)])
        n = Z[_at(Z_ST + L.S_N, e)]
        pos = n * Z[_at(Z_PRM + L.P_DELTA, e)]
        # overshoot while the command is at rest, after its last change
        p_prev = Z[_at(Z_ST + L.S_PPREV, e)]
        last_dir = Z[_at(Z_ST + L.S_LASTDIR, e)]
        changed = p_prev != P
        at_rest = (not changed) and last_dir != 0.0
        o_m = last_dir * (theta - P)
        o_p = last_dir * (pos - P)
        ov_m = Z[_at(Z_ST + L.S_OVM, e)]
        ov_p = Z[_at(Z_ST + L.S_OVP, e)]
        Z[_at(Z_ST + L.S_OVM, e)] = o_m if (at_rest and o_m > ov_m) else ov_m
        Z[_at(Z_ST + L.S_OVP, e)] = o_p if (at_rest and o_p > ov_p) else ov_p
        if two:  # the load's measures (vfgym.plant._tick.load_tick and tracking as selects)
            lane_two = Z[_at(Z_PRM + L.P_TWO, e)] != 0.0
            target = Z[_at(Z_PRM + L.P_TARGET, e)]
            win = Z[_at(Z_PRM + L.P_WIN_RAD, e)]
            thl = theta - Z[_at(Z_ST + L.S_TWIST, e)]
            o_l = last_dir * (thl - P)
            ov_l = Z[_at(Z_ST + L.S_OVL, e)]
            ov_l = o_l if (at_rest and o_l > ov_l) else ov_l
            lol = Z[_at(Z_ST + L.S_LOL, e)]
            lol = i if abs(thl - target) > win else lol
            hi = Z[_at(Z_ST + L.S_RVHI, e)]
            lo = Z[_at(Z_ST + L.S_RVLO, e)]
            out = abs(theta - target) > win
            hi = thl if (out or thl > hi) else hi
            lo = thl if (out or thl < lo) else lo
            dl = P - thl
            sq = Z[_at(Z_ST + L.S_TSQL, e)]
            mx = Z[_at(Z_ST + L.S_TMXL, e)]
            Z[_at(Z_ST + L.S_OVL, e)] = ov_l if lane_two else Z[_at(Z_ST + L.S_OVL, e)]
            Z[_at(Z_ST + L.S_LOL, e)] = lol if lane_two else Z[_at(Z_ST + L.S_LOL, e)]
            Z[_at(Z_ST + L.S_RVHI, e)] = hi if lane_two else Z[_at(Z_ST + L.S_RVHI, e)]
            Z[_at(Z_ST + L.S_RVLO, e)] = lo if lane_two else Z[_at(Z_ST + L.S_RVLO, e)]
            Z[_at(Z_ST + L.S_TSQL, e)] = sq + dl * dl if lane_two else sq
            Z[_at(Z_ST + L.S_TMXL, e)] = (abs(dl) if abs(dl) > mx else mx) if lane_two else mx
        new_dir = 1.0 if p_prev < P else -1.0
        Z[_at(Z_ST + L.S_LASTDIR, e)] = new_dir if changed else last_dir
        Z[_at(Z_ST + L.S_PPREV, e)] = P
        # in-position window and steady state
        target = Z[_at(Z_PRM + L.P_TARGET, e)]
        win = Z[_at(Z_PRM + L.P_WIN_RAD, e)]
        lom = Z[_at(Z_ST + L.S_LOM, e)]
        lop = Z[_at(Z_ST + L.S_LOP, e)]
        Z[_at(Z_ST + L.S_LOM, e)] = i if abs(theta - target) > win else lom
        Z[_at(Z_ST + L.S_LOP, e)] = i if abs(pos - target) > win else lop
        steady = i >= Z[_at(Z_PRM + L.P_SS_START, e)]
        ss_m = Z[_at(Z_ST + L.S_SSM, e)]
        ss_p = Z[_at(Z_ST + L.S_SSP, e)]
        ss_n = Z[_at(Z_ST + L.S_SSN, e)]
        Z[_at(Z_ST + L.S_SSM, e)] = ss_m + (theta - target) if steady else ss_m
        Z[_at(Z_ST + L.S_SSP, e)] = ss_p + (pos - target) if steady else ss_p
        Z[_at(Z_ST + L.S_SSN, e)] = ss_n + 1.0 if steady else ss_n
        # motor acceleration, tracking errors
        dw = abs(omega - Z[_at(Z_WOLD, e)])
        dw_max = Z[_at(Z_ST + L.S_DWMX, e)]
        Z[_at(Z_ST + L.S_DWMX, e)] = dw if dw > dw_max else dw_max
        d = P - theta
        Z[_at(Z_ST + L.S_TSQM, e)] = Z[_at(Z_ST + L.S_TSQM, e)] + d * d
        mx = Z[_at(Z_ST + L.S_TMXM, e)]
        Z[_at(Z_ST + L.S_TMXM, e)] = abs(d) if abs(d) > mx else mx
        d = P - pos
        Z[_at(Z_ST + L.S_TSQP, e)] = Z[_at(Z_ST + L.S_TSQP, e)] + d * d
        mx = Z[_at(Z_ST + L.S_TMXP, e)]
        Z[_at(Z_ST + L.S_TMXP, e)] = abs(d) if abs(d) > mx else mx
        # pulse statistics
        p = Z[_at(Z_P, e)]
        has = p != 0.0
        last_p = Z[_at(Z_ST + L.S_LASTP, e)]
        seen = has and last_p >= 0.0
        iv = i - last_p
        min_iv = Z[_at(Z_ST + L.S_MINIV, e)]
        shorter = seen and (min_iv == 0.0 or iv < min_iv)
        Z[_at(Z_ST + L.S_MINIV, e)] = iv if shorter else min_iv
        last_sign = Z[_at(Z_ST + L.S_LASTSIGN, e)]
        rev = Z[_at(Z_ST + L.S_REV, e)]
        Z[_at(Z_ST + L.S_REV, e)] = rev + 1.0 if (seen and p != last_sign) else rev
        first_p = Z[_at(Z_ST + L.S_FIRSTP, e)]
        Z[_at(Z_ST + L.S_FIRSTP, e)] = i if (has and not seen) else first_p
        Z[_at(Z_ST + L.S_LASTP, e)] = i if has else last_p
        Z[_at(Z_ST + L.S_LASTSIGN, e)] = p if has else last_sign
        pulses = Z[_at(Z_ST + L.S_PULSES, e)]
        Z[_at(Z_ST + L.S_PULSES, e)] = pulses + 1.0 if has else pulses
        # peaks
        tau = Z[_at(Z_ST + L.S_TAU, e)]
        pc = Z[_at(Z_ST + L.S_PC, e)]
        mx = Z[_at(Z_ST + L.S_TQMX, e)]
        Z[_at(Z_ST + L.S_TQMX, e)] = abs(tau) if abs(tau) > mx else mx
        mx = Z[_at(Z_ST + L.S_PCMX, e)]
        Z[_at(Z_ST + L.S_PCMX, e)] = abs(pc) if abs(pc) > mx else mx
        mx = Z[_at(Z_ST + L.S_WMX, e)]
        Z[_at(Z_ST + L.S_WMX, e)] = abs(omega) if abs(omega) > mx else mx


@_jit
def _pulse_accel_peak(Z, H, g: int, m: int, w: int) -> None:
    """The peak |x_t − 2 x_{t−w} + x_{t−2w}| over block ticks g … g+m−1, per lane, into
    the state's running peak (``H`` row t mod len(H) holds the train position x of block
    tick t, :func:`vfgym.plant._tick.train_position`)."""
    R = H.shape[0]
    for k in range(m):
        t = g + k
        r0 = t % R
        r1 = (t - w) % R
        r2 = (t - 2 * w) % R
        for e in range(LANES):
            d2 = abs(H[r0, e] - 2.0 * H[r1, e] + H[r2, e])
            mx = Z[_at(Z_ST + L.S_D2MX, e)]
            Z[_at(Z_ST + L.S_D2MX, e)] = d2 if d2 > mx else mx


@_jit
def run_block(Z, CB, H, g: int, m: int, w: int) -> None:
    """Advance every lane of the block ``Z`` by ``m`` ticks, block ticks g … g+m−1:
    ``CB[k]`` holds the lanes' commands of tick g+k; ``H`` (≥ 2w + m rows) is their
    train-position history, row t mod len(H) for block tick t (w: the acceleration window)."""
    R = H.shape[0]
    friction = False
    two = False
    # the lanes' sample periods in step (same length, same phase): one latch for all
    ns = Z[_at(Z_PRM + L.P_NS, 0)]
    ns_left = Z[_at(Z_ST + L.S_NSLEFT, 0)]
    in_step = True
    for e in range(LANES):
        friction = friction or Z[_at(Z_PRM + L.P_TC, e)] != 0.0
        two = two or Z[_at(Z_PRM + L.P_TWO, e)] != 0.0
        in_step = in_step and Z[_at(Z_PRM + L.P_NS, e)] == ns
        in_step = in_step and Z[_at(Z_ST + L.S_NSLEFT, e)] == ns_left
    for k in range(m):
        for e in range(LANES):
            Z[_at(Z_CMD, e)] = CB[k, e]
        if two:
            if _tick_source_servo_motor(Z, 2, True, True) > 0:
                _friction_stops(Z)
            _tick_encoder_measures(Z, k, True)
        else:
            if friction:
                if _tick_source_servo_motor(Z, 2, True, False) > 0:
                    _friction_stops(Z)
            elif in_step:
                ns_left -= 1.0
                if ns_left == 0.0:
                    ns_left = ns
                    _tick_source_servo_motor(Z, 1, False, False)
                else:
                    _tick_source_servo_motor(Z, 0, False, False)
            else:
                _tick_source_servo_motor(Z, 2, False, False)
            _tick_encoder_measures(Z, k, False)
        row = (g + k) % R
        for e in range(LANES):  # the V-F's train position (TK.train_position, as selects)
            ph = Z[_at(Z_ST + L.S_SUM, e)] / Z[_at(Z_PRM + L.P_VALUE, e)]
            ph = 1.0 if ph > 1.0 else ph
            ph = -1.0 if ph < -1.0 else ph
            H[row, e] = Z[_at(Z_NOUT, e)] + ph
    _pulse_accel_peak(Z, H, g, m, w)
    for e in range(LANES):
        Z[_at(Z_ST + L.S_TICK, e)] += m


@_jit
def load_lane(Z, CB, e: int, prm, st, cmd, m: int) -> None:
    """Lane ``e`` takes a move's parameter row, loop state and next ``m`` commands."""
    for j in range(L.N_PARAMS):
        Z[_at(Z_PRM + j, e)] = prm[j]
    for j in range(L.N_STATE):
        Z[_at(Z_ST + j, e)] = st[j]
    i0 = int(st[L.S_TICK])
    for k in range(m):
        CB[k, e] = cmd[i0 + k]


@_jit
def store_lane(Z, e: int, st) -> None:
    """Lane ``e``'s loop state back into a move's state row."""
    for j in range(L.N_STATE):
        st[j] = Z[_at(Z_ST + j, e)]


@_jit
def load_history(H, e: int, ring, i: int, g: int, w: int) -> None:
    """Lane ``e``'s history before block tick ``g`` from a move's ring at its tick ``i``
    (the 2w counts the acceleration measure reads back)."""
    R = H.shape[0]
    mask = ring.shape[0] - 1
    for j in range(2 * w):
        H[(g - 2 * w + j) % R, e] = ring[(i - 2 * w + j) & mask]


@_jit
def flush_history(H, e: int, ring, i: int, g: int, w: int) -> None:
    """The inverse of :func:`load_history`: the 2w positions before block tick ``g`` into the
    move's ring, where :func:`vfgym.plant._kernel.run_segment` from tick ``i`` reads them."""
    R = H.shape[0]
    mask = ring.shape[0] - 1
    for j in range(1, 2 * w + 1):
        ring[(i - j) & mask] = H[(g - j) % R, e]


@_jit
def advance(ids, count: int, PRM, ST, RING, CMD, m: int, Z, CB, H) -> None:
    """Advance moves ``ids[:count]`` (at most LANES; rows of ``PRM``, ``ST``, ``RING``,
    ``CMD``) by ``m`` ticks each through one block, as :func:`vfgym.plant._kernel.run_segment`
    would: the moves must share the acceleration window w, use the V-F controller and
    have ``m`` ticks of command left. Unused lanes repeat the first move (discarded).
    ``Z``, ``CB``, ``H``: the block's scratch (:func:`scratch`)."""
    w = int(PRM[ids[0], L.P_ACC_W])
    g = 2 * w
    for e in range(LANES):
        r = ids[e] if e < count else ids[0]
        load_lane(Z, CB, e, PRM[r], ST[r], CMD[r], m)
        load_history(H, e, RING[r], int(ST[r, L.S_TICK]), g, w)
    run_block(Z, CB, H, g, m, w)
    for e in range(count):
        r = ids[e]
        store_lane(Z, e, ST[r])
        flush_history(H, e, RING[r], int(ST[r, L.S_TICK]), g + m, w)


def scratch(blocks: int, m: int, w: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Scratch arrays (Z, CB, H) for ``blocks`` blocks of ``m`` ticks, window ``w``."""
    return (
        np.zeros((blocks, N_ROWS * LANES)),
        np.zeros((blocks, max(m, 1), LANES)),
        np.zeros((blocks, 2 * w + max(m, 1), LANES)),
    )


# The functions here compile the tick's stop_within_tick and the slot numbers into themselves.
guard_cache(run_block, (TK, L))
