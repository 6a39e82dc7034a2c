"""Plain-Python reference of the plant: the same equations as the compiled kernel.

Kept for tests: it is written block by block (pulse source, servo, motor, encoder,
measures), in the style of a plant composed of parts, and shares nothing with the kernel
but the parameter row it reads. Tests check that the two agree bit for bit. It is slow
(a few hundred thousand ticks a second) and is not used by the library.
"""

from __future__ import annotations

import itertools
import math

import numpy as np

from vfgym.plant import _layout as L


def _h(x: float) -> float:
    if x < 1e-3:
        return 1.0 - x * (0.5 - x * (1.0 / 6.0 - x * (1.0 / 24.0 - x * (1.0 / 120.0))))
    return -math.expm1(-x) / x


def _g(x: float) -> float:
    if x < 1e-3:
        return 0.5 - x * (1.0 / 6.0 - x * (1.0 / 24.0 - x * (1.0 / 120.0 - x * (1.0 / 720.0))))
    return (x + math.expm1(-x)) / (x * x)


class VFController:
    """docs/model.md §1: error, error limit, acceleration law, accumulator against value."""

    def __init__(self, prm: np.ndarray) -> None:
        self.delta = float(prm[L.P_DELTA])
        self.value = float(prm[L.P_VALUE])
        self.limit = float(prm[L.P_LIMIT])
        self.step = float(prm[L.P_STEP])
        self.slew = int(prm[L.P_LAW]) == 1
        self.n = 0
        self.sum = 0.0
        self.e_prev = 0.0

    def tick(self, command: float) -> int:
        e = command - self.n * self.delta
        e = min(max(e, -self.limit), self.limit)
        hi = self.e_prev + self.step
        lo = self.e_prev - self.step
        if self.slew:
            e = min(max(e, lo), hi)
        else:
            if self.e_prev >= 0.0:
                e = min(e, hi)
            if self.e_prev <= 0.0:
                e = max(e, lo)
        self.e_prev = e
        self.sum += e
        pulse = 0
        if self.sum >= self.value:
            pulse = 1
            self.sum -= self.value
        elif self.sum <= -self.value:
            pulse = -1
            self.sum += self.value
        self.n += pulse
        return pulse


class DigitalServo:
    """docs/model.md §2: position counter, speed counter, filter, error calculator, amplifier."""

    def __init__(self, prm: np.ndarray) -> None:
        self.gear = int(prm[L.P_GEAR])
        self.ns = int(prm[L.P_NS])
        self.B = float(prm[L.P_B])
        self.A = float(prm[L.P_A])
        self.K3 = float(prm[L.P_K3])
        self.pc = 0
        self.count = 0
        self.ticks_in_sample = 0
        self.x = 0.0
        self.y = 0.0
        self.u = 0.0

    def tick(self, pulse: int, encoder_change: int) -> tuple[float, bool]:
        """Advance one tick; returns the torque command and whether a sample was taken."""
        self.pc += self.gear * pulse - encoder_change
        self.count += encoder_change
        self.ticks_in_sample += 1
        sampled = self.ticks_in_sample == self.ns
        if sampled:
            self.ticks_in_sample = 0
            self.x = self.B * self.count
            self.y = self.y + self.A * (self.x - self.y)
            self.count = 0
        self.u = self.pc - self.y
        return self.K3 * self.u, sampled


class MotorLoad:
    """docs/model.md §3: J·dω/dt = τ − b·ω − τc·sign(ω) − τ_load, exact for τ held over a tick."""

    def __init__(self, prm: np.ndarray) -> None:
        self.T = float(prm[L.P_TICK_S])
        self.inv_j = float(prm[L.P_INV_J])
        self.damp = float(prm[L.P_DAMP])
        self.cww, self.cwf = float(prm[L.P_CWW]), float(prm[L.P_CWF])
        self.ctw, self.ctf = float(prm[L.P_CTW]), float(prm[L.P_CTF])
        self.tc = float(prm[L.P_TC])
        self.tload = float(prm[L.P_TLOAD])
        self.tpeak = float(prm[L.P_TPEAK])
        self.wknee = float(prm[L.P_WKNEE])
        self.wmax = float(prm[L.P_WMAX])
        self.slope = float(prm[L.P_SLOPE])
        self.theta = 0.0
        self.omega = 0.0

    def available(self, tau: float) -> float:
        """Torque available: the torque–speed curve when motoring, the peak when braking."""
        if tau * self.omega <= 0.0:
            return self.tpeak
        w = abs(self.omega)
        if w <= self.wknee:
            return self.tpeak
        if w < self.wmax:
            return self.tpeak + self.slope * (w - self.wknee)
        return 0.0

    def tick(self, tau: float) -> None:
        net = tau - self.tload
        w = self.omega
        if self.tc == 0.0:
            self.theta = self.theta + (self.ctw * w + self.ctf * net)
            self.omega = self.cww * w + self.cwf * net
            return
        if w == 0.0:
            if abs(net) > self.tc:
                f = net - math.copysign(self.tc, net)
                self.theta = self.theta + self.ctf * f
                self.omega = self.cwf * f
            return
        sgn = 1.0 if w > 0.0 else -1.0
        f = net - sgn * self.tc
        w_new = self.cww * w + self.cwf * f
        if w_new * sgn > 0.0:
            self.theta = self.theta + (self.ctw * w + self.ctf * f)
            self.omega = w_new
            return
        # stops within the tick: find when, then restart or stick for the rest
        alpha = f * self.inv_j
        t0 = math.log1p(-self.damp * w / alpha) / self.damp if self.damp > 0.0 else -w / alpha
        t0 = min(t0, self.T)
        x0 = self.damp * t0
        self.theta = self.theta + (w * t0 * _h(x0) + f * self.inv_j * t0 * t0 * _g(x0))
        self.omega = 0.0
        rem = self.T - t0
        if rem > 0.0 and abs(net) > self.tc:
            f2 = net - math.copysign(self.tc, net)
            x1 = self.damp * rem
            self.theta = self.theta + f2 * self.inv_j * rem * rem * _g(x1)
            self.omega = f2 * self.inv_j * rem * _h(x1)


class TwoMassLoad(MotorLoad):
    """docs/model.md §3.1: the motor (J_M, b, τc, τ_load) and the load J_L (its own Coulomb
    friction τc_L) beyond a spring K_S with damping c_S, exact (the parameter row's matrix
    exponentials) for the friction forces held; friction's stops and break-aways at the
    tick's boundaries."""

    def __init__(self, prm: np.ndarray) -> None:
        super().__init__(prm)
        self.ks = float(prm[L.P_KS])
        self.cs = float(prm[L.P_CS])
        self.tcl = float(prm[L.P_TCL])

        def rows(first: int, last: int, width: int) -> list[list[float]]:
            return [[float(v) for v in r] for r in prm[first : last + 1].reshape(-1, width)]

        # both moving: (θ, ω, d, ω_L) per (ω, d, ω_L, F, G)
        self.both = rows(L.P_Z_TW, L.P_Z_LG, 5)
        self.motor_held = rows(L.P_Z_MDD, L.P_Z_MLG, 3)  # (d, ω_L) per (d, ω_L, G)
        self.load_held = rows(L.P_Z_LTW, L.P_Z_LDF, 3)  # (θ, ω, d) per (ω, d, F)
        self.twist = 0.0  # d = θ − θ_L
        self.load_omega = 0.0

    @property
    def load_theta(self) -> float:
        return self.theta - self.twist

    @staticmethod
    def friction(speed: float, pull: float, tc: float) -> tuple[float, bool]:
        """The sign of a mass's Coulomb force (that of its speed, or at rest of the torque
        pulling it, if beyond ``tc``), and whether it stays held."""
        if tc == 0.0:
            return 0.0, False
        if speed != 0.0:
            return (1.0 if speed > 0.0 else -1.0), False
        if abs(pull) <= tc:
            return 0.0, True
        return (1.0 if pull > 0.0 else -1.0), False

    @staticmethod
    def stopped(sign: float, speed: float) -> float:
        """A moving mass that friction would turn back within the tick is at rest at its end."""
        return 0.0 if sign != 0.0 and sign * speed <= 0.0 else speed

    def tick(self, tau: float) -> None:
        net = tau - self.tload
        w, d, wl = self.omega, self.twist, self.load_omega
        spring = self.ks * d + self.cs * (w - wl)  # on the load; against the motor
        s, motor_held = self.friction(w, net - spring, self.tc)
        sl, load_held = self.friction(wl, spring, self.tcl)
        f = net - s * self.tc
        g = 0.0 - sl * self.tcl
        if motor_held and load_held:
            return
        if motor_held:  # the load moves on the spring alone
            (dd, dl, dg), (ld, ll, lg) = self.motor_held
            self.twist = dd * d + dl * wl + dg * g
            self.load_omega = self.stopped(sl, ld * d + ll * wl + lg * g)
            return
        if load_held:  # the motor moves against the spring
            (tw, td, tf), (ww, wd, wf), (dw, dd, df) = self.load_held
            self.theta = self.theta + (tw * w + td * d + tf * f)
            self.omega = self.stopped(s, ww * w + wd * d + wf * f)
            self.twist = dw * w + dd * d + df * f
            return
        rows = self.both
        x = (w, d, wl, f, g)
        t_row, w_row, d_row, l_row = ([c * v for c, v in zip(r, x, strict=True)] for r in rows)
        self.theta = self.theta + (t_row[0] + t_row[1] + t_row[2] + t_row[3] + t_row[4])
        self.omega = self.stopped(s, w_row[0] + w_row[1] + w_row[2] + w_row[3] + w_row[4])
        self.twist = d_row[0] + d_row[1] + d_row[2] + d_row[3] + d_row[4]
        self.load_omega = self.stopped(sl, l_row[0] + l_row[1] + l_row[2] + l_row[3] + l_row[4])


class Encoder:
    """Quadrature encoder decoded ×4: count = floor(θ / q)."""

    def __init__(self, prm: np.ndarray) -> None:
        self.q = float(prm[L.P_COUNT_RAD])
        self.count = 0

    def read(self, theta: float) -> int:
        self.count = math.floor(theta / self.q)
        return self.count


def reference_run(
    cmd: np.ndarray, ext: np.ndarray, prm: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Simulate one move; returns (accumulator row, trace rows at every tick)."""
    vf = VFController(prm)
    servo = DigitalServo(prm)
    two = prm[L.P_TWO] != 0.0
    motor = TwoMassLoad(prm) if two else MotorLoad(prm)
    enc = Encoder(prm)
    use_ext = prm[L.P_USE_EXT] != 0.0
    T = float(prm[L.P_TICK_S])
    delta = float(prm[L.P_DELTA])
    target = float(prm[L.P_TARGET])
    win = float(prm[L.P_WIN_RAD])
    ss_start = int(prm[L.P_SS_START])
    w = int(prm[L.P_ACC_W])
    acc_scale = float(prm[L.P_ACC_SCALE])
    ns = servo.ns
    x_hist = [0.0] * (2 * w)

    rows: list[list[float]] = []
    a = np.zeros(L.N_ACC)
    ov_m = ov_p = 0.0
    last_out_m = last_out_p = -1
    ss_m = ss_p = 0.0
    ss_n = 0
    acc_p = acc_m = 0.0
    sat = 0
    trk = [0.0, 0.0, 0.0, 0.0]
    sample_speeds: list[float] = []
    rip_sq = 0.0
    theta_s0 = 0.0
    pulse_ticks: list[int] = []
    pulse_signs: list[int] = []
    tq_mx = w_mx = 0.0
    pc_mx = 0
    n = 0
    c_seen = 0
    p_prev = 0.0
    last_dir = 0.0
    # the load's (two-mass): overshoot, last tick out, θ_L since the motor was last out,
    # tracking
    ov_l = 0.0
    last_out_l = -1
    since_motor_out: list[float] = [0.0]
    trk_l = [0.0, 0.0]
    for i, P in enumerate(cmd.tolist()):
        p = int(ext[i]) if use_ext else vf.tick(P)
        n += p
        change = enc.count - c_seen
        c_seen = enc.count
        tau_cmd, sampled = servo.tick(p, change)
        if sampled:
            v0 = (motor.theta - theta_s0) / (ns * T)
            theta_s0 = motor.theta
            sample_speeds.append(v0)
            if len(sample_speeds) >= 3:
                d2 = v0 - 2.0 * sample_speeds[-2] + sample_speeds[-3]
                rip_sq += d2 * d2
        lim = motor.available(tau_cmd)
        tau = min(max(tau_cmd, -lim), lim)
        if tau_cmd > lim or tau_cmd < -lim:
            sat += 1
        omega_old = motor.omega
        motor.tick(tau)
        enc.read(motor.theta)
        theta, omega = motor.theta, motor.omega

        pos = n * delta
        if p_prev != P:
            last_dir = 1.0 if p_prev < P else -1.0
        elif last_dir != 0.0:
            ov_m = max(ov_m, last_dir * (theta - P))
            ov_p = max(ov_p, last_dir * (pos - P))
        if isinstance(motor, TwoMassLoad):
            thl = motor.load_theta
            if p_prev == P and last_dir != 0.0:
                ov_l = max(ov_l, last_dir * (thl - P))
            if abs(thl - target) > win:
                last_out_l = i
            if abs(theta - target) > win:
                since_motor_out = []
            since_motor_out.append(thl)
            d_l = P - thl
            trk_l[0] += d_l * d_l
            trk_l[1] = max(trk_l[1], abs(d_l))
            load_row = [thl, motor.load_omega]
        else:
            load_row = [theta, omega]
        p_prev = P
        if abs(theta - target) > win:
            last_out_m = i
        if abs(pos - target) > win:
            last_out_p = i
        if i >= ss_start:
            ss_m += theta - target
            ss_p += pos - target
            ss_n += 1
        # the train's unquantised position (pulses): the V-F's n + its phase sum/value held
        # to ±1, else n
        x = float(n) if use_ext else vf.n + min(max(vf.sum / vf.value, -1.0), 1.0)
        x_hist.append(x)  # x_hist[2w + i] is x after tick i; the plant was at rest before
        acc_p = max(acc_p, abs(x - 2.0 * x_hist[i + w] + x_hist[i]) * acc_scale)
        acc_m = max(acc_m, abs(omega - omega_old) / T)
        for k, ref in ((0, theta), (2, pos)):
            d = P - ref
            trk[k] += d * d
            trk[k + 1] = max(trk[k + 1], abs(d))
        if p != 0:
            pulse_ticks.append(i)
            pulse_signs.append(p)
        tq_mx = max(tq_mx, abs(tau))
        pc_mx = max(pc_mx, abs(servo.pc))
        w_mx = max(w_mx, abs(omega))
        rows.append(
            [P, pos, theta, omega, tau, servo.u, servo.pc, servo.y, servo.x, x * delta, *load_row]
        )

    a[L.A_OV_MOTOR], a[L.A_OV_PULSE] = ov_m, ov_p
    a[L.A_LAST_OUT_MOTOR], a[L.A_LAST_OUT_PULSE] = last_out_m, last_out_p
    a[L.A_SS_SUM_MOTOR], a[L.A_SS_SUM_PULSE], a[L.A_SS_COUNT] = ss_m, ss_p, ss_n
    a[L.A_ACC_PULSE], a[L.A_ACC_MOTOR] = acc_p, acc_m
    a[L.A_SAT_TICKS] = sat
    a[L.A_TRK_SQ_MOTOR], a[L.A_TRK_MAX_MOTOR] = trk[0], trk[1]
    a[L.A_TRK_SQ_PULSE], a[L.A_TRK_MAX_PULSE] = trk[2], trk[3]
    a[L.A_RIPPLE_SQ], a[L.A_RIPPLE_N] = rip_sq, max(0, len(sample_speeds) - 2)
    a[L.A_PULSES] = len(pulse_ticks)
    a[L.A_REVERSALS] = sum(1 for s0, s1 in itertools.pairwise(pulse_signs) if s0 != s1)
    gaps = np.diff(pulse_ticks)
    a[L.A_MIN_INTERVAL] = int(gaps.min()) if gaps.size else 0
    a[L.A_FIRST_PULSE] = pulse_ticks[0] if pulse_ticks else -1
    a[L.A_LAST_PULSE] = pulse_ticks[-1] if pulse_ticks else -1
    a[L.A_TORQUE_MAX], a[L.A_PC_MAX], a[L.A_SPEED_MAX] = tq_mx, pc_mx, w_mx
    a[L.A_THETA], a[L.A_OMEGA], a[L.A_N], a[L.A_PC] = motor.theta, motor.omega, n, servo.pc
    a[L.A_TICKS] = len(cmd)
    a[L.A_ACC_WINDOW] = w
    a[L.A_ACC_QUANTUM] = 2.0 * acc_scale if use_ext else 0.0
    if isinstance(motor, TwoMassLoad):
        a[L.A_OV_LOAD], a[L.A_LAST_OUT_LOAD] = ov_l, last_out_l
        a[L.A_RESIDUAL] = max(since_motor_out) - min(since_motor_out)
        a[L.A_TRK_SQ_LOAD], a[L.A_TRK_MAX_LOAD] = trk_l
        a[L.A_LOAD], a[L.A_LOAD_SPEED] = motor.load_theta, motor.load_omega
    else:  # the kernel's initial values, and the load turning with the motor
        a[L.A_LAST_OUT_LOAD] = -1
        a[L.A_LOAD], a[L.A_LOAD_SPEED] = motor.theta, motor.omega
    return a, np.array(rows, dtype=np.float64).T.reshape(L.N_ROWS, len(cmd))


def reference_vf_pulses(cmd: np.ndarray, prm: np.ndarray) -> np.ndarray:
    """The V-F controller alone, per tick."""
    vf = VFController(prm)
    return np.array([vf.tick(P) for P in cmd.tolist()], dtype=np.int8)
