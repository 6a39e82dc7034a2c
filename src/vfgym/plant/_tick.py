"""One tick of the plant, block by block, for the compiled loop of :mod:`vfgym.plant._kernel`.

Each block is a small function on scalars that returns the block's new state; all are
compiled with ``inline=True`` (:mod:`vfgym.plant._jit`), so numba puts them into the
loop of :func:`vfgym.plant._kernel.run_segment`, which keeps the whole loop state in
registers. No fastmath: every floating-point operation is IEEE double in the written
order, the order of :mod:`vfgym.plant.reference`. The blocks, in the tick's order:

1. :func:`vf_tick`: the V-F controller makes at most one pulse from the command;
2. :func:`servo_count`, :func:`servo_sample`: the servo's position and speed counters,
   and every Ns ticks the latch and filter of the speed counter;
3. :func:`torque`: the torque command, clipped to the torque–speed curve;
4. :func:`motor` (with :func:`stop_within_tick`): exact integration over the tick with
   the torque held; on a two-mass plant :func:`motor_two` (docs/model.md §3.1), with the
   load beyond a spring, its coefficients :func:`two_mass` read from the parameter row;
5. :func:`encoder`: the encoder count of the new angle;

then the measures streamed from the tick (:func:`ripple_sample` at each servo sample,
:func:`overshoot`, :func:`in_position`, :func:`steady_state`, :func:`pulse_accel`,
:func:`tracking`, :func:`pulse_stats`, :func:`peak`, and on a two-mass plant
:func:`load_tick`) and the trace row (:func:`record`). Whole numbers (counts, ticks) are
int64 here.
"""

from __future__ import annotations

import math

from vfgym.plant import _layout as L
from vfgym.plant._jit import jit
from vfgym.plant._layout import (
    R_COMMAND,
    R_ERROR,
    R_FEEDBACK,
    R_LOAD,
    R_LOAD_SPEED,
    R_OMEGA,
    R_PC,
    R_PULSE,
    R_SPEED_COUNT,
    R_THETA,
    R_TORQUE,
    R_TRAIN,
    S_C,
)

# --- motor integrals -----------------------------------------------------------------------


@jit
def phi_h(x: float) -> float:
    """h(x) = (1 − e^(−x))/x, h(0) = 1: ω gain of a held torque over a stretch x = (b/J)·t."""
    if x < 1e-3:
        return 1.0 - x * (0.5 - x * (1.0 / 6.0 - x * (1.0 / 24.0 - x * (1.0 / 120.0))))
    return -math.expm1(-x) / x


@jit
def phi_g(x: float) -> float:
    """g(x) = (x − 1 + e^(−x))/x², g(0) = 1/2: θ gain of a held torque over x = (b/J)·t."""
    if x < 1e-3:
        return 0.5 - x * (1.0 / 6.0 - x * (1.0 / 24.0 - x * (1.0 / 120.0 - x * (1.0 / 720.0))))
    return (x + math.expm1(-x)) / (x * x)


# --- 1. V-F controller -------------------------------------------------------------------


@jit(inline=True)
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


# --- 2. servo ------------------------------------------------------------------------------


@jit(inline=True)
def servo_count(p, c, c_prev, pc, sc, gear):
    """The counters on this tick's pulse ``p`` and the encoder's change since the last
    tick (count ``c`` now, ``c_prev`` then): returns (position counter, speed counter)."""
    dc = c - c_prev
    return pc + (gear * p - dc), sc + dc


@jit(inline=True)
def servo_sample(sc, y, B, A):
    """The sample at the end of a period: the speed counter latched (x = B·count) and
    filtered (y += A·(x − y)). Returns (x, y); the caller resets the counter."""
    x = B * sc
    return x, y + A * (x - y)


# --- 3. torque -----------------------------------------------------------------------------


@jit(inline=True)
def torque(u, omega, sat, K3, tpeak, wknee, wmax, slope):
    """τ = K3·u for the servo error ``u`` (counts), clipped to the torque–speed curve at
    speed ``omega`` (the curve bounds only a torque that drives the motor on; braking
    has the peak). Returns (τ, ``sat`` + 1 if clipped else ``sat``).

    The count of clipped ticks is kept here, in the clipping branches: returned as a
    0/1 flag instead, it let LLVM turn the lower clip into a branchless max on the
    tick's dependency chain (τ → ω → θ → count → τ), ~4 % slower on the paper step."""
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
    return tau, sat


# --- 4. motor ------------------------------------------------------------------------------


@jit(inline=True)
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


@jit(inline=True)
def motor(theta, omega, net, tc, cww, cwf, ctw, ctf, damp, inv_j, T):
    """The motor over the tick under the net torque ``net`` (drive minus load) held:
    θ(T) = θ + CTW·ω + CTF·F, ω(T) = CWW·ω + CWF·F with F the net force after Coulomb
    friction ``tc``; a motor at rest sticks while |net| ≤ tc; one that friction stops
    within the tick goes through :func:`stop_within_tick`. Returns (θ, ω)."""
    if tc == 0.0:
        return theta + (ctw * omega + ctf * net), cww * omega + cwf * net
    if omega == 0.0:
        if net > tc or net < -tc:
            f = net - tc if net > 0.0 else net + tc
            return theta + ctf * f, cwf * f
        return theta, omega
    sgn = 1.0 if omega > 0.0 else -1.0
    f = net - sgn * tc
    w_new = cww * omega + cwf * f
    if w_new * sgn > 0.0:
        return theta + (ctw * omega + ctf * f), w_new
    return stop_within_tick(theta, omega, f, net, tc, damp, inv_j, T)


@jit(inline=True)
def two_mass(prm):
    """The two-mass plant's constants from the parameter row, in the order
    :func:`motor_two` reads them (read once, before a loop): K_S, c_S, then the 35
    coefficients ``P_Z_TW`` … ``P_Z_LDF`` (indices 2 … 36)."""
    return (
        prm[L.P_KS], prm[L.P_CS],
        prm[L.P_Z_TW], prm[L.P_Z_TD], prm[L.P_Z_TL], prm[L.P_Z_TF], prm[L.P_Z_TG],
        prm[L.P_Z_WW], prm[L.P_Z_WD], prm[L.P_Z_WL], prm[L.P_Z_WF], prm[L.P_Z_WG],
        prm[L.P_Z_DW], prm[L.P_Z_DD], prm[L.P_Z_DL], prm[L.P_Z_DF], prm[L.P_Z_DG],
        prm[L.P_Z_LW], prm[L.P_Z_LD], prm[L.P_Z_LL], prm[L.P_Z_LF], prm[L.P_Z_LG],
        prm[L.P_Z_MDD], prm[L.P_Z_MDL], prm[L.P_Z_MDG], prm[L.P_Z_MLD], prm[L.P_Z_MLL],
        prm[L.P_Z_MLG], prm[L.P_Z_LTW], prm[L.P_Z_LTD], prm[L.P_Z_LTF], prm[L.P_Z_LWW],
        prm[L.P_Z_LWD], prm[L.P_Z_LWF], prm[L.P_Z_LDW], prm[L.P_Z_LDD], prm[L.P_Z_LDF],
    )  # fmt: skip


@jit(inline=True)
def motor_two(theta, omega, d, wl, net, tc, tcl, z):
    """The two-mass plant over the tick under the net torque ``net`` on the motor held
    (docs/model.md §3.1): motor angle and speed θ, ω, the spring's twist d = θ − θ_L, the
    load's speed ω_L; Coulomb friction ``tc`` on the motor, ``tcl`` on the load. Returns
    (θ, ω, d, ω_L).

    Exact (the zero-order-hold matrix exponentials of :func:`vfgym.plant.two_mass_coefficients`)
    for the friction forces held over the tick, F = net − s·τc on the motor and
    G = −s_L·τc_L on the load, each sign that of its mass's speed at the tick's start. A
    mass at rest breaks away (the sign of the torque on it) when that torque exceeds its
    friction: net − S on the motor, S on the load, S = K_S·d + c_S·(ω − ω_L) the spring's;
    else it stays held while the other moves (the held systems' exponentials). A moving
    mass that friction would turn back within the tick is at rest at the tick's end."""
    spring = z[0] * d + z[1] * (omega - wl)
    s = 0.0
    m_held = False
    if tc != 0.0:
        if omega > 0.0:
            s = 1.0
        elif omega < 0.0:
            s = -1.0
        else:
            pull = net - spring
            if pull > tc:
                s = 1.0
            elif pull < -tc:
                s = -1.0
            else:
                m_held = True
    sl = 0.0
    l_held = False
    if tcl != 0.0:
        if wl > 0.0:
            sl = 1.0
        elif wl < 0.0:
            sl = -1.0
        elif spring > tcl:
            sl = 1.0
        elif spring < -tcl:
            sl = -1.0
        else:
            l_held = True
    f = net - s * tc
    g = 0.0 - sl * tcl
    if m_held and l_held:
        return theta, omega, d, wl
    if m_held:
        d1 = z[22] * d + z[23] * wl + z[24] * g
        wl1 = z[25] * d + z[26] * wl + z[27] * g
        if sl != 0.0 and sl * wl1 <= 0.0:
            wl1 = 0.0
        return theta, omega, d1, wl1
    if l_held:
        th = theta + (z[28] * omega + z[29] * d + z[30] * f)
        w = z[31] * omega + z[32] * d + z[33] * f
        d1 = z[34] * omega + z[35] * d + z[36] * f
        if s != 0.0 and s * w <= 0.0:
            w = 0.0
        return th, w, d1, wl
    th = theta + (z[2] * omega + z[3] * d + z[4] * wl + z[5] * f + z[6] * g)
    w = z[7] * omega + z[8] * d + z[9] * wl + z[10] * f + z[11] * g
    d1 = z[12] * omega + z[13] * d + z[14] * wl + z[15] * f + z[16] * g
    wl1 = z[17] * omega + z[18] * d + z[19] * wl + z[20] * f + z[21] * g
    if s != 0.0 and s * w <= 0.0:
        w = 0.0
    if sl != 0.0 and sl * wl1 <= 0.0:
        wl1 = 0.0
    return th, w, d1, wl1


# --- 5. encoder ----------------------------------------------------------------------------


@jit(inline=True)
def encoder(theta, q, inv_q, st):
    """The encoder count floor(θ/q) (``inv_q`` = 1/q).

    The product with 1/q is the fast guess; the exact quotient checks it. The check is a
    branch the CPU predicts, so the next tick need not wait for the division (~10 %
    faster); it is taken only when the product rounds across a whole count. Its store of
    the count into the state row ``st`` keeps LLVM from folding it into a select on the
    quotient."""
    c = math.floor(theta * inv_q)
    c_exact = math.floor(theta / q)
    if c != c_exact:
        st[S_C] = c_exact
        return c_exact
    return c


# --- streamed measures (see vfgym.plant.measures) ------------------------------------------


@jit(inline=True)
def ripple_sample(theta, theta_s0, v1, v2, n_samples, rip_sq, rip_n, ns, T):
    """At a servo sample: the mean speed over the period now ended, and the square of the
    second difference of consecutive ones. Returns (θ at this sample, v1, v2, samples,
    Σ squares, their count)."""
    v0 = (theta - theta_s0) / (ns * T)
    n_samples += 1
    if n_samples >= 3:
        d2 = v0 - 2.0 * v1 + v2
        rip_sq += d2 * d2
        rip_n += 1
    return theta, v0, v1, n_samples, rip_sq, rip_n


@jit(inline=True)
def overshoot(P, p_prev, last_dir, theta, pos, ov_m, ov_p):
    """Overshoot past the command ``P`` while it rests, in the direction of its last
    change, of the motor (θ) and of the pulse position (n·δ). Returns (direction of the
    last change, motor peak, pulse peak)."""
    if p_prev != P:
        return (1.0 if p_prev < P else -1.0), ov_m, ov_p
    if last_dir != 0.0:
        o = last_dir * (theta - P)
        if o > ov_m:
            ov_m = o
        o = last_dir * (pos - P)
        if o > ov_p:
            ov_p = o
    return last_dir, ov_m, ov_p


@jit(inline=True)
def in_position(i, theta, pos, target, win, last_out_m, last_out_p):
    """The last tick at which the motor, and the pulse position, were outside the window
    ``win`` around ``target``. Returns (motor's, pulses')."""
    if abs(theta - target) > win:
        last_out_m = i
    if abs(pos - target) > win:
        last_out_p = i
    return last_out_m, last_out_p


@jit(inline=True)
def steady_state(i, ss_start, theta, pos, target, ss_m, ss_p, ss_n):
    """Sums of the errors to ``target`` from tick ``ss_start`` on. Returns (motor's sum,
    pulses' sum, ticks summed)."""
    if i >= ss_start:
        return ss_m + (theta - target), ss_p + (pos - target), ss_n + 1
    return ss_m, ss_p, ss_n


@jit(inline=True)
def train_position(n, s, value, use_ext):
    """The pulse train's position in pulses, unquantised (docs/model.md §5.1): the V-F
    controller's count n plus its accumulator's phase sum/value, the phase held to ±1 (a
    controller whose error exceeds value is saturated: a pulse every tick, its sum
    growing); an external train's count n."""
    if use_ext:
        return float(n)
    ph = s / value
    if ph > 1.0:
        ph = 1.0
    elif ph < -1.0:
        ph = -1.0
    return n + ph


@jit(inline=True)
def pulse_accel(ring, i, x, accw, d2_max):
    """The train position ``x`` of tick ``i`` (:func:`train_position`) into the history
    ``ring`` (length a power of two), and the peak |second difference of x over ``accw``
    ticks|."""
    mask = ring.shape[0] - 1
    ring[i & mask] = x
    d2 = abs(x - 2.0 * ring[(i - accw) & mask] + ring[(i - 2 * accw) & mask])
    if d2 > d2_max:
        return d2
    return d2_max


@jit(inline=True)
def peak(a, mx):
    """The running peak ``mx`` after the value ``a``."""
    if a > mx:
        return a
    return mx


@jit(inline=True)
def tracking(d, sq, mx):
    """The tracking error ``d`` into its sum of squares and its peak |d|."""
    return sq + d * d, peak(abs(d), mx)


@jit(inline=True)
def pulse_stats(p, i, pulses, min_iv, reversals, first_p, last_p, last_sign):
    """The pulse ``p`` (−1, 0, +1) of tick ``i`` into the pulse statistics. Returns
    (pulses, shortest interval, reversals, first pulse's tick, last pulse's tick, last
    pulse's sign)."""
    if p == 0:
        return pulses, min_iv, reversals, first_p, last_p, last_sign
    if last_p >= 0:
        iv = i - last_p
        if min_iv == 0 or iv < min_iv:
            min_iv = iv
        if p != last_sign:
            reversals += 1
    else:
        first_p = i
    return pulses + 1, min_iv, reversals, first_p, i, p


@jit(inline=True)
def load_tick(i, P, p_prev, last_dir, theta, thl, target, win, ov_l, lo_l, rv_hi, rv_lo):
    """The load's measures on a two-mass plant at tick ``i``, its angle ``thl``: overshoot
    while the command rests (as :func:`overshoot`), its last tick out of the window, and
    the highest and lowest θ_L since the motor (θ) was last out of it. Returns (overshoot,
    last tick out, highest, lowest)."""
    if p_prev == P and last_dir != 0.0:
        o = last_dir * (thl - P)
        if o > ov_l:
            ov_l = o
    if abs(thl - target) > win:
        lo_l = i
    if abs(theta - target) > win:
        return ov_l, lo_l, thl, thl
    if thl > rv_hi:
        rv_hi = thl
    if thl < rv_lo:
        rv_lo = thl
    return ov_l, lo_l, rv_hi, rv_lo


@jit(inline=True)
def record(rec, j, P, pos, theta, omega, tau, u, pc, y, x, train, thl, wl):
    """The tick's state into column ``j`` of the trace ``rec`` (``thl``, ``wl``: the
    load's angle and speed, the motor's on a rigid plant)."""
    rec[R_COMMAND, j] = P
    rec[R_PULSE, j] = pos
    rec[R_THETA, j] = theta
    rec[R_OMEGA, j] = omega
    rec[R_TORQUE, j] = tau
    rec[R_ERROR, j] = u
    rec[R_PC, j] = pc
    rec[R_FEEDBACK, j] = y
    rec[R_SPEED_COUNT, j] = x
    rec[R_TRAIN, j] = train
    rec[R_LOAD, j] = thl
    rec[R_LOAD_SPEED, j] = wl
