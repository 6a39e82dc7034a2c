"""The compiled hot loop: V-F controller → digital servo → motor → encoder, tick by tick.

One kernel (:func:`run_segment`) over plain arrays and scalars, compiled by numba with
``cache=True`` (where it can write one) and no fastmath, so its floating-point operations
are IEEE double in the written order and agree bit for bit with :mod:`vfgym.plant.reference`.
The equations are those of ``docs/model.md`` §1–§3; their order within a tick is:

1. pulse source: V-F controller on the command ``cmd[i]`` (or an external pulse array);
2. servo: encoder count change since the last tick into the position counter (with the
   gear times the pulse) and the speed counter; every Ns ticks the speed counter is
   latched (x = B·count), filtered (y += A·(x − y)) and reset;
3. torque τ = K3·(pc − y), clipped to the torque–speed curve;
4. motor: exact integration over the tick for τ held constant (viscous, Coulomb, load);
5. encoder: count = floor(θ / q).

Measures are streamed into an accumulator row as the loop goes (no trace is needed);
a trace is written only when the caller passes arrays for it.
"""

from __future__ import annotations

import hashlib
import math
import os
from pathlib import Path
from types import ModuleType
from typing import Any

# numba's OpenMP workers spin a while after each parallel call by default. With several
# processes on the cores (sweep workers, a busy machine) spinning workers take the cores
# from working ones (measured ~3x slower: two processes stepping vector envs), so vfgym
# makes them sleep (PASSIVE). Waking them costs ~55 us a call on this VM, though, so a
# user who has the machine to themselves may opt in to spinning: setting OMP_WAIT_POLICY
# or GOMP_SPINCOUNT (libgomp's default is 300000) keeps the user's choice.
if "GOMP_SPINCOUNT" not in os.environ:
    os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

import numba
import numpy as np

from vfgym.plant._layout import (
    A_ACC_MOTOR,
    A_ACC_PULSE,
    A_FIRST_PULSE,
    A_LAST_OUT_MOTOR,
    A_LAST_OUT_PULSE,
    A_LAST_PULSE,
    A_MIN_INTERVAL,
    A_N,
    A_OMEGA,
    A_OV_MOTOR,
    A_OV_PULSE,
    A_PC,
    A_PC_MAX,
    A_PULSES,
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
    A_TRK_MAX_MOTOR,
    A_TRK_MAX_PULSE,
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
    P_TICK_S,
    P_TLOAD,
    P_TPEAK,
    P_USE_EXT,
    P_VALUE,
    P_WIN_RAD,
    P_WKNEE,
    P_WMAX,
    R_COMMAND,
    R_ERROR,
    R_FEEDBACK,
    R_OMEGA,
    R_PC,
    R_PULSE,
    R_SPEED_COUNT,
    R_THETA,
    R_TORQUE,
    S_C,
    S_CPREV,
    S_D2MX,
    S_DWMX,
    S_EPREV,
    S_FIRSTP,
    S_LASTDIR,
    S_LASTP,
    S_LASTSIGN,
    S_LOM,
    S_LOP,
    S_MINIV,
    S_N,
    S_NSAMP,
    S_NSLEFT,
    S_OMEGA,
    S_OVM,
    S_OVP,
    S_PC,
    S_PCMX,
    S_PPREV,
    S_PULSES,
    S_REV,
    S_RIPN,
    S_RIPSQ,
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
    S_TMXM,
    S_TMXP,
    S_TQMX,
    S_TSQM,
    S_TSQP,
    S_U,
    S_V1,
    S_V2,
    S_WMX,
    S_X,
    S_Y,
)


def workers_spin(environ: Any) -> bool:
    """Whether numba's OpenMP workers spin between parallel calls under these environment
    variables (libgomp: they spin unless OMP_WAIT_POLICY is PASSIVE or GOMP_SPINCOUNT 0)."""
    if environ.get("OMP_WAIT_POLICY", "").strip().upper() == "PASSIVE":
        return False
    return environ.get("GOMP_SPINCOUNT", "").strip() not in ("0",)


SPINNING_WORKERS = workers_spin(os.environ)
"""Whether this process's numba workers spin between parallel calls (see above)."""


def _probe() -> None:  # a function of this file, for the cache check below
    return None


def _can_cache() -> bool:
    """Whether numba can cache this module's machine code somewhere writable: next to the
    source, in NUMBA_CACHE_DIR, or in the user's cache directory. On a read-only install
    with nowhere to write, compile every session instead of failing at import."""
    from numba.core.caching import FunctionCache

    try:
        FunctionCache(_probe)
    except RuntimeError:
        return False
    return True


CACHE = _can_cache()


def guard_cache(dispatcher: Any, sources: tuple[ModuleType, ...]) -> None:
    """Drop the numba cache of ``dispatcher``'s module when any of ``sources`` changed.

    numba keys a cached function on its own file only, so a module whose functions
    compile this kernel into themselves would keep stale machine code after an edit of
    the kernel. Call this at the end of such a module, before any of its functions run;
    the sources' hash is kept next to the cache files."""
    try:
        cache_dir = Path(dispatcher._cache._cache_path)
    except AttributeError:  # no cache, or a numba without this layout: nothing to guard
        return
    stem = Path(dispatcher.py_func.__code__.co_filename).stem
    digest = hashlib.sha256()
    for mod in sources:
        digest.update(Path(str(mod.__file__)).read_bytes())
    stamp = cache_dir / f"{stem}.kernel-sha256"
    try:
        if stamp.read_text() == digest.hexdigest():
            return
    except OSError:
        pass
    for f in cache_dir.glob(f"{stem}.*.nb[ic]"):
        f.unlink(missing_ok=True)
    try:
        cache_dir.mkdir(parents=True, exist_ok=True)
        stamp.write_text(digest.hexdigest())
    except OSError:
        pass


_jit = numba.njit(cache=CACHE, fastmath=False, nogil=True)


@_jit
def phi_h(x: float) -> float:
    """h(x) = (1 − e^(−x))/x, h(0) = 1: ω gain of a held torque over a stretch x = (b/J)·t."""
    if x < 1e-3:
        return 1.0 - x * (0.5 - x * (1.0 / 6.0 - x * (1.0 / 24.0 - x * (1.0 / 120.0))))
    return -math.expm1(-x) / x


@_jit
def phi_g(x: float) -> float:
    """g(x) = (x − 1 + e^(−x))/x², g(0) = 1/2: θ gain of a held torque over x = (b/J)·t."""
    if x < 1e-3:
        return 0.5 - x * (1.0 / 6.0 - x * (1.0 / 24.0 - x * (1.0 / 120.0 - x * (1.0 / 720.0))))
    return (x + math.expm1(-x)) / (x * x)


@numba.njit(cache=CACHE, fastmath=False, nogil=True, inline="always")
def stop_within_tick(theta, omega, f, net, tc, damp, inv_j, T):
    """Motor over a tick in which Coulomb friction brings the speed to zero (force ``f``
    on the moving motor, ``net`` once stopped): stop there, then restart or stick.
    Returns (θ, ω) at the tick's end."""
    t0 = math.log1p(-damp * omega / (f * inv_j)) / damp if damp > 0.0 else -omega / (f * inv_j)
    if t0 > T:
        t0 = T
    x0 = damp * t0
    theta = theta + (omega * t0 * phi_h(x0) + f * inv_j * t0 * t0 * phi_g(x0))
    omega = 0.0
    rem = T - t0
    if rem > 0.0 and (net > tc or net < -tc):
        f2 = net - tc if net > 0.0 else net + tc
        x1 = damp * rem
        theta = theta + f2 * inv_j * rem * rem * phi_g(x1)
        omega = f2 * inv_j * rem * phi_h(x1)
    return theta, omega


@numba.njit(cache=CACHE, fastmath=False, nogil=True, inline="always")
def vf_tick(P, n, s, e_prev, delta, value, limit, step, law):
    """One tick of the V-F controller (docs/model.md §1): returns (pulse, sum, limited error).

    Error against the pulse counter, the error limit, the acceleration law (0 = rise:
    only growth away from zero is held to value/k a tick; 1 = slew: both ways), the
    accumulator against value, at most one pulse."""
    e = P - n * delta
    if e > limit:
        e = limit
    elif e < -limit:
        e = -limit
    if law == 0:
        if e_prev >= 0.0 and e > e_prev + step:
            e = e_prev + step
        if e_prev <= 0.0 and e < e_prev - step:
            e = e_prev - step
    else:
        if e > e_prev + step:
            e = e_prev + step
        elif e < e_prev - step:
            e = e_prev - step
    s += e
    if s >= value:
        return 1, s - value, e
    if s <= -value:
        return -1, s + value, e
    return 0, s, e


@_jit
def vf_pulses_kernel(cmd, delta, value, limit, step, law, out):
    """V-F controller alone: one pulse (−1, 0, +1) per tick into ``out``."""
    n = 0
    s = 0.0
    e_prev = 0.0
    for i in range(cmd.shape[0]):
        p, s, e_prev = vf_tick(cmd[i], n, s, e_prev, delta, value, limit, step, law)
        out[i] = p
        n += p


@_jit
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
    st[S_D2MX] = 0
    st[S_DWMX] = 0.0
    st[S_TICK] = 0
    ring[:] = 0


@_jit
def run_segment(cmd, ext, prm, st, ring, i1, rec, dec):
    """Advance the move in ``st`` from tick ``st[S_TICK]`` to tick ``i1`` (exclusive),
    streaming its measures into ``st`` and writing every ``dec``-th tick's state into
    ``rec`` (shape (N_ROWS, m), m = 0 for none). ``cmd`` and ``ext`` are indexed by the
    move's own tick number; ``prm`` may change between segments (online tuning)."""
    T = prm[P_TICK_S]
    delta = prm[P_DELTA]
    value = prm[P_VALUE]
    limit = prm[P_LIMIT]
    step = prm[P_STEP]
    law = int(prm[P_LAW])
    gear = int(prm[P_GEAR])
    ns = int(prm[P_NS])
    B = prm[P_B]
    A = prm[P_A]
    K3 = prm[P_K3]
    q = prm[P_COUNT_RAD]
    inv_q = 1.0 / q
    inv_j = prm[P_INV_J]
    damp = prm[P_DAMP]
    cww = prm[P_CWW]
    cwf = prm[P_CWF]
    ctw = prm[P_CTW]
    ctf = prm[P_CTF]
    tc = prm[P_TC]
    tload = prm[P_TLOAD]
    tpeak = prm[P_TPEAK]
    wknee = prm[P_WKNEE]
    wmax = prm[P_WMAX]
    slope = prm[P_SLOPE]
    target = prm[P_TARGET]
    win = prm[P_WIN_RAD]
    ss_start = int(prm[P_SS_START])
    accw = int(prm[P_ACC_W])
    use_ext = prm[P_USE_EXT] != 0.0
    n_rec = rec.shape[1] if rec.shape[0] >= N_ROWS else 0

    mask = ring.shape[0] - 1
    i0 = int(st[S_TICK])
    rec_left = dec
    rec_j = 0
    n = int(st[S_N])
    s = st[S_SUM]
    e_prev = st[S_EPREV]
    c_prev = int(st[S_CPREV])
    c = int(st[S_C])
    pc = int(st[S_PC])
    sc = int(st[S_SC])
    ns_left = int(st[S_NSLEFT])
    y = st[S_Y]
    x = st[S_X]
    theta = st[S_THETA]
    omega = st[S_OMEGA]
    tau = st[S_TAU]
    u = st[S_U]
    p_prev = st[S_PPREV]
    last_dir = st[S_LASTDIR]
    ov_m = st[S_OVM]
    ov_p = st[S_OVP]
    last_out_m = int(st[S_LOM])
    last_out_p = int(st[S_LOP])
    ss_m = st[S_SSM]
    ss_p = st[S_SSP]
    ss_n = int(st[S_SSN])
    sat = int(st[S_SAT])
    trk_sq_m = st[S_TSQM]
    trk_mx_m = st[S_TMXM]
    trk_sq_p = st[S_TSQP]
    trk_mx_p = st[S_TMXP]
    rip_sq = st[S_RIPSQ]
    rip_n = int(st[S_RIPN])
    theta_s0 = st[S_THS0]
    v1 = st[S_V1]
    v2 = st[S_V2]
    n_samples = int(st[S_NSAMP])
    pulses = int(st[S_PULSES])
    reversals = int(st[S_REV])
    min_iv = int(st[S_MINIV])
    first_p = int(st[S_FIRSTP])
    last_p = int(st[S_LASTP])
    last_sign = int(st[S_LASTSIGN])
    tq_mx = st[S_TQMX]
    pc_mx = int(st[S_PCMX])
    w_mx = st[S_WMX]
    d2_max = int(st[S_D2MX])
    dw_max = st[S_DWMX]
    for i in range(i0, i1):
        P = cmd[i]
        # 1. pulse source
        if use_ext:
            p = int(ext[i])
        else:
            p, s, e_prev = vf_tick(P, n, s, e_prev, delta, value, limit, step, law)
        n += p
        # 2. servo counters and sampled filter
        dc = c - c_prev
        c_prev = c
        pc += gear * p - dc
        sc += dc
        ns_left -= 1
        if ns_left == 0:
            ns_left = ns
            x = B * sc
            y = y + A * (x - y)
            sc = 0
            # measure: speed ripple from the mean speeds of consecutive sample periods
            v0 = (theta - theta_s0) / (ns * T)
            theta_s0 = theta
            n_samples += 1
            if n_samples >= 3:
                d2 = v0 - 2.0 * v1 + v2
                rip_sq += d2 * d2
                rip_n += 1
            v2 = v1
            v1 = v0
        # 3. torque command and the torque–speed limit
        u = pc - y
        tau = K3 * u
        if tau * omega > 0.0:
            aw = abs(omega)
            if aw <= wknee:
                lim = tpeak
            elif aw < wmax:
                lim = tpeak + slope * (aw - wknee)
            else:
                lim = 0.0
        else:
            lim = tpeak
        if tau > lim:
            tau = lim
            sat += 1
        elif tau < -lim:
            tau = -lim
            sat += 1
        # 4. motor over the tick, torque held
        net = tau - tload
        omega_old = omega
        if tc == 0.0:
            theta = theta + (ctw * omega + ctf * net)
            omega = cww * omega + cwf * net
        elif omega == 0.0:
            if net > tc or net < -tc:
                f = net - tc if net > 0.0 else net + tc
                theta = theta + ctf * f
                omega = cwf * f
        else:
            sgn = 1.0 if omega > 0.0 else -1.0
            f = net - sgn * tc
            w_new = cww * omega + cwf * f
            if w_new * sgn > 0.0:
                theta = theta + (ctw * omega + ctf * f)
                omega = w_new
            else:
                theta, omega = stop_within_tick(theta, omega, f, net, tc, damp, inv_j, T)
        # 5. encoder: count = floor(θ/q). The product with 1/q is the fast guess; the
        # exact quotient checks it. The check is a branch the CPU predicts, so the next
        # tick need not wait for the division (~10 % faster); it is taken only when the
        # product rounds across a whole count. Its store keeps LLVM from folding it into
        # a select on the quotient.
        c = math.floor(theta * inv_q)
        c_exact = math.floor(theta / q)
        if c != c_exact:
            c = c_exact
            st[S_C] = c_exact

        # --- streamed measures -------------------------------------------------------------
        pos = n * delta
        if p_prev != P:
            last_dir = 1.0 if p_prev < P else -1.0
        elif last_dir != 0.0:
            o = last_dir * (theta - P)
            if o > ov_m:
                ov_m = o
            o = last_dir * (pos - P)
            if o > ov_p:
                ov_p = o
        p_prev = P
        if abs(theta - target) > win:
            last_out_m = i
        if abs(pos - target) > win:
            last_out_p = i
        if i >= ss_start:
            ss_m += theta - target
            ss_p += pos - target
            ss_n += 1
        ring[i & mask] = n
        d2 = abs(n - 2 * ring[(i - accw) & mask] + ring[(i - 2 * accw) & mask])
        if d2 > d2_max:
            d2_max = d2
        dw = abs(omega - omega_old)
        if dw > dw_max:
            dw_max = dw
        d = P - theta
        trk_sq_m += d * d
        if abs(d) > trk_mx_m:
            trk_mx_m = abs(d)
        d = P - pos
        trk_sq_p += d * d
        if abs(d) > trk_mx_p:
            trk_mx_p = abs(d)
        if p != 0:
            pulses += 1
            if last_p >= 0:
                iv = i - last_p
                if min_iv == 0 or iv < min_iv:
                    min_iv = iv
                if p != last_sign:
                    reversals += 1
            else:
                first_p = i
            last_p = i
            last_sign = p
        if abs(tau) > tq_mx:
            tq_mx = abs(tau)
        if abs(pc) > pc_mx:
            pc_mx = abs(pc)
        if abs(omega) > w_mx:
            w_mx = abs(omega)
        if n_rec > 0:
            rec_left -= 1
            if rec_left == 0:
                rec_left = dec
                if rec_j < n_rec:
                    rec[R_COMMAND, rec_j] = P
                    rec[R_PULSE, rec_j] = pos
                    rec[R_THETA, rec_j] = theta
                    rec[R_OMEGA, rec_j] = omega
                    rec[R_TORQUE, rec_j] = tau
                    rec[R_ERROR, rec_j] = u
                    rec[R_PC, rec_j] = pc
                    rec[R_FEEDBACK, rec_j] = y
                    rec[R_SPEED_COUNT, rec_j] = x
                    rec_j += 1

    st[S_N] = n
    st[S_SUM] = s
    st[S_EPREV] = e_prev
    st[S_CPREV] = c_prev
    st[S_C] = c
    st[S_PC] = pc
    st[S_SC] = sc
    st[S_NSLEFT] = ns_left
    st[S_Y] = y
    st[S_X] = x
    st[S_THETA] = theta
    st[S_OMEGA] = omega
    st[S_TAU] = tau
    st[S_U] = u
    st[S_PPREV] = p_prev
    st[S_LASTDIR] = last_dir
    st[S_OVM] = ov_m
    st[S_OVP] = ov_p
    st[S_LOM] = last_out_m
    st[S_LOP] = last_out_p
    st[S_SSM] = ss_m
    st[S_SSP] = ss_p
    st[S_SSN] = ss_n
    st[S_SAT] = sat
    st[S_TSQM] = trk_sq_m
    st[S_TMXM] = trk_mx_m
    st[S_TSQP] = trk_sq_p
    st[S_TMXP] = trk_mx_p
    st[S_RIPSQ] = rip_sq
    st[S_RIPN] = rip_n
    st[S_THS0] = theta_s0
    st[S_V1] = v1
    st[S_V2] = v2
    st[S_NSAMP] = n_samples
    st[S_PULSES] = pulses
    st[S_REV] = reversals
    st[S_MINIV] = min_iv
    st[S_FIRSTP] = first_p
    st[S_LASTP] = last_p
    st[S_LASTSIGN] = last_sign
    st[S_TQMX] = tq_mx
    st[S_PCMX] = pc_mx
    st[S_WMX] = w_mx
    st[S_D2MX] = d2_max
    st[S_DWMX] = dw_max
    st[S_TICK] = i1


@_jit
def finish(st, acc, n_ticks, T, acc_scale):
    """The accumulator row of a move from its loop state (see :mod:`vfgym.plant._layout`)."""
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


@_jit
def ring_size(prm):
    """Length of the pulse-count history: a power of two above 2w."""
    size = 1
    while size < 2 * int(prm[P_ACC_W]) + 1:
        size *= 2
    return size


@_jit
def run_one(cmd, ext, prm, acc, rec, dec):
    """Simulate one whole move; stream its measures into ``acc``; write every ``dec``-th
    tick's state into ``rec`` (shape (N_ROWS, m), m = 0 for none)."""
    st = np.empty(N_STATE, dtype=np.float64)
    ring = np.empty(ring_size(prm), dtype=np.int64)
    init_state(prm, st, ring)
    run_segment(cmd, ext, prm, st, ring, cmd.shape[0], rec, dec)
    finish(st, acc, cmd.shape[0], prm[P_TICK_S], prm[P_ACC_SCALE])


@numba.njit(cache=CACHE, fastmath=False, nogil=True, parallel=True)
def run_batch(cmd_flat, cmd_off, cmd_idx, ext_flat, ext_off, ext_idx, prm, acc):
    """Run ``prm.shape[0]`` moves in parallel (numba threads over the runs). Run r reads
    command ``cmd_idx[r]``, i.e. ``cmd_flat[cmd_off[j]:cmd_off[j+1]]``, and external pulses
    ``ext_idx[r]`` from ``ext_flat`` likewise (an empty segment when the V-F controller
    makes the pulses); it writes measures only, into ``acc[r]``."""
    rec = np.zeros((N_ROWS, 0), dtype=np.float64)
    for r in numba.prange(prm.shape[0]):
        j = cmd_idx[r]
        e = ext_idx[r]
        cmd = cmd_flat[cmd_off[j] : cmd_off[j + 1]]
        ext = ext_flat[ext_off[e] : ext_off[e + 1]]
        run_one(cmd, ext, prm[r], acc[r], rec, 1)


def new_acc(runs: int = 0) -> np.ndarray:
    """A zeroed accumulator row (or ``runs`` rows)."""
    return np.zeros(N_ACC if runs == 0 else (runs, N_ACC), dtype=np.float64)
