"""Compiled stepping of VFServo-v0: one control interval of one env, or of a batch of envs.

Each env keeps everything it needs in one float64 *workspace* row (layout below): the
kernel's parameter row and loop state (:mod:`vfgym.plant._layout`), the cost's constants
(:mod:`vfgym.scoring._cost_compiled`), the episode's constants, the running cost, the final
accumulators and the observation. :func:`env_step` maps the action
onto the four settings (the search space's own scaling, read from the row), advances the
stateful kernel (:func:`vfgym.plant._kernel.run_segment`) by one interval, and writes the reward
terms, the end-of-episode flags and the observation. :func:`step_one` (one env, no threads)
and :func:`step_batch` (numba ``prange`` over envs) call the same :func:`env_step`, so a
single env and a batched one produce the same numbers bit for bit.

Reward terms (see :class:`vfgym.envs.servo.VFServoEnv`): the running cost C(s) is the
scoring path's cost formula evaluated on the measures streamed so far
(:func:`vfgym.scoring._cost_compiled.running_cost`, the compiled copy that sits beside
:func:`vfgym.scoring.score`), without the arrival and residual terms, known only at the end;
each interval's reward is C before minus C after, minus an optional tracking-error shaping
term. The last interval's reward is finished in Python with the scoring path's own cost of
the whole move.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from vfgym.moves.features import clip_feature
from vfgym.plant import _jit as J
from vfgym.plant import _kernel as K
from vfgym.plant import _lanes as LN
from vfgym.plant import _layout as L
from vfgym.plant import _tick as TK
from vfgym.plant._notice import announced, compiling
from vfgym.plant._threads import keeps_torch_threads
from vfgym.scoring import _cost_compiled as CC

from . import _common

_jit = J.jit

SETTING_FIELDS = _common.SETTING_FIELDS
space_table = _common.space_table


ACTION_TOL = 1e-6
"""Actions may exceed [-1, 1] by this much (float rounding), as :func:`vfgym.space.from_action`."""

# flags returned by env_step
TERMINATED = 1
TRUNCATED = 2
BAD_ACTION = 4
VIOLATION = 8
SETTLED = 16
ENDED = TERMINATED | TRUNCATED

# --- workspace row ----------------------------------------------------------------------
W_PRM = 0
W_ST = W_PRM + L.N_PARAMS
W_COST = W_ST + L.N_STATE  # the cost's constants (vfgym.scoring._cost_compiled.constants)
C_IDEAL = W_COST + CC.K_IDEAL  # ideal move time (s), the cost's yardstick
C_WIN = W_COST + CC.K_WIN  # in-position half-width (rad)
C_LIMIT = W_COST + CC.K_LIMIT  # the acceleration limit: Motor.usable_accel_rad_s2 (rad/s²)
_c = W_COST + CC.N_CONST
# episode constants
C_N = _c + 0  # ticks of the move (the command's length): the time limit
C_I = _c + 1  # ticks per control interval
C_END = _c + 2  # tick from which the command is at its final value
C_HOLD = _c + 3  # ticks the motor must stay in position to count as settled
C_SCALE = _c + 4  # the move's size (rad): observation scale
C_VMAX = _c + 5  # pulse train top speed δ·f (rad/s)
C_SHAPE = _c + 6  # tracking-error shaping weight
C_VIOL = _c + 7  # 1: end the episode on a constraint violation
C_K3 = _c + 8  # the drive's gain K3 as set, the modelled plant's (N·m/count): the torque
# command the drive knows is K3 as set times its error (the true K3 may differ)
C_DIMS = _c + 9  # 4 × (action index, low, high, log, width) for value, error limit, k,
# Ts/Tf (space_table); for a log dimension low and high are stored as log(low), log(high)
C_RES = C_DIMS + 20  # 1: residual actions, 0: absolute
C_RSCALE = C_RES + 1  # residual actions: each offset's scale in unit coordinates (4 slots,
# in SETTING_FIELDS order)
C_BASE = C_RSCALE + 4  # residual actions: the base settings (4 slots, SETTING_FIELDS order)
_x = C_BASE + 4
# per-step results and running values
X_COST = _x + 0  # running cost after the last interval
X_COST_PREV = _x + 1  # running cost before the last interval
X_SHAPE = _x + 2  # shaping term of the last interval (and of the run-out at the end)
X_REWARD = _x + 3  # reward of the last interval (before the end-of-episode correction)
X_STEPS = _x + 4  # intervals stepped
X_TICK_END = _x + 5  # ticks simulated under the agent's control
X_SET = _x + 6  # the action in force, clipped to [-1, 1] (4 slots)
X_SPEED0 = X_SET + 4  # speed counter's speed (rad/s), saturated ticks and Σ tracking
X_SAT0 = X_SET + 5  # error² at the interval's start
X_TSQ0 = X_SET + 6
X_LANE = X_SET + 7  # 1: the last counts are in the lane block's history, not the ring
X_OVC = X_SET + 8  # overshoot so far in encoder counts, seen at the intervals' ends (rad)
W_ACC = X_SET + 9  # accumulator row of the whole move (written at the episode's end)
W_OBS = W_ACC + L.N_ACC

OBS_DYNAMIC = (
    "error",
    "error_log",
    "remaining",
    "command_remaining",
    "command_ahead",
    "speed_counter",
    "accel",
    "torque_command",
    "torque_saturation",
    "pulse_error",
    "following_error",
    "overshoot_log",
    "accel_peak",
    "progress",
    "setting_value",
    "setting_error_limit",
    "setting_k",
    "setting_ts_over_tf",
)
"""The VFServo-v0 features the kernel writes each interval (definitions in servo.py): what
a drive measures (encoder counts, its speed counter, the pulses it was sent, the torque it
commands), never the simulator's continuous angle, speed or torque."""
N_DYN = len(OBS_DYNAMIC)


def width(n_obs: int) -> int:
    """Length of a workspace row with ``n_obs`` observation features."""
    return W_OBS + n_obs


_clip = _jit(clip_feature)  # the observation clip, compiled (tests/envs: equal on random x)


@_jit
def from_unit(u: float, lo: float, hi: float, log: bool) -> float:
    """:meth:`vfgym.space.Dim.from_unit`, the same operations in the same order; for a log
    dimension ``lo`` and ``hi`` are already log(low) and log(high)."""
    t = (min(max(u, -1.0), 1.0) + 1.0) / 2.0
    if log:
        return math.exp(lo + t * (hi - lo))
    return lo + t * (hi - lo)


@_jit
def action_ok(act) -> bool:
    """Every entry finite and within [-1, 1] (to ACTION_TOL)."""
    for j in range(act.shape[0]):
        a = float(act[j])
        if not (a >= -1.0 - ACTION_TOL and a <= 1.0 + ACTION_TOL):
            return False
    return True


@_jit
def map_action(act, dims, residual: bool, scales, base, unit) -> tuple:
    """The four settings (value, L, k, Ts/Tf) an action in [-1, 1]⁴ stands for, and (into
    ``unit``, in action order) their unit coordinates in the search space: the one
    mapping of both envs.

    ``dims`` holds 4 × (action index, low, high, log, width) in that order
    (:func:`space_table`: a log dimension's low and high as their logarithms). Absolute
    actions: each entry is the unit coordinate, as the search space maps it. Residual
    actions: an offset in :class:`vfgym.space.Relative`'s coordinates (logarithms of the
    value, L/value, k and Ts/Tf), entry × its ``scales`` (in the order of ``dims``) × half
    the axis's ``width``, from ``base`` (the four settings, in that order), each setting
    clipped to the search space. Once the value has moved, L is the new value times the
    base's L/value, then offset, so a base with L = value keeps L = value bit for bit
    under any value offset (the V-F controller's cost has a ridge there: docs/model.md
    §1); a setting whose offset is zero is its base exactly (no round trip through the
    logarithm)."""
    v0 = 0.0
    v1 = 0.0
    v2 = 0.0
    v3 = 0.0
    moved = False  # the value is off its base (residual actions)
    zv = 0.0  # the value's new logarithm
    for f in range(4):
        b = 5 * f
        j = int(dims[b])
        lo = dims[b + 1]
        hi = dims[b + 2]
        c = min(max(float(act[j]), -1.0), 1.0)
        if not residual:
            x = from_unit(c, lo, hi, dims[b + 3] != 0.0)
            u = c
        else:
            w = dims[b + 4]
            d = scales[f] * c
            xb = base[f]
            x0 = math.log(xb)
            if f == 1 and moved:
                y = min(max(zv + (x0 - math.log(base[0])) + d * w / 2.0, lo), hi)
                x = math.exp(y)
                u = min(max(2.0 * (y - lo) / (hi - lo) - 1.0, -1.0), 1.0)
            else:
                t0 = (x0 - lo) / (hi - lo)
                x = xb
                if d != 0.0:
                    y = min(max(x0 + d * w / 2.0, lo), hi)
                    x = math.exp(y)
                    if f == 0:
                        zv = y
                        moved = True
                u = min(max(2.0 * t0 - 1.0 + d * (w / (hi - lo)), -1.0), 1.0)
        unit[j] = u
        if f == 0:
            v0 = x
        elif f == 1:
            v1 = x
        elif f == 2:
            v2 = x
        else:
            v3 = x
    return v0, v1, v2, v3


@_jit
def apply_action(act, w) -> bool:
    """Set the settings in force from an action in [-1, 1]⁴; False (nothing set) if bad."""
    if act.shape[0] != 4 or not action_ok(act):
        return False
    x0, x1, x2, x3 = map_action(
        act,
        w[C_DIMS : C_DIMS + 20],
        w[C_RES] != 0.0,
        w[C_RSCALE : C_RSCALE + 4],
        w[C_BASE : C_BASE + 4],
        w[X_SET : X_SET + 4],
    )
    w[W_PRM + L.P_VALUE] = x0
    w[W_PRM + L.P_LIMIT] = x1
    w[W_PRM + L.P_STEP] = x0 / x2
    w[W_PRM + L.P_A] = x3
    return True


@_jit
def counter_speed(w) -> float:
    """The speed the drive's speed counter tells (rad/s): its latched output x = B·count
    over the last sample period of Ns ticks."""
    p = W_PRM
    return (
        w[W_ST + L.S_X] / w[p + L.P_B] * w[p + L.P_COUNT_RAD] / (w[p + L.P_NS] * w[p + L.P_TICK_S])
    )


@_jit
def write_obs(w, cmd, speed0: float, sat0: float, nt: int) -> None:
    """The dynamic features after an interval of ``nt`` ticks that started with the speed
    counter at ``speed0`` (rad/s) and ``sat0`` saturated ticks so far: what the drive
    measures, the motor's position as its encoder count."""
    o = W_OBS
    st = W_ST
    n = int(w[C_N])
    i = int(w[st + L.S_TICK])
    D = w[C_SCALE]
    win = max(w[C_WIN], 1e-12)  # a zero in-position window is allowed by Measures
    target = w[W_PRM + L.P_TARGET]
    T = w[W_PRM + L.P_TICK_S]
    P = cmd[i - 1] if i > 0 else 0.0
    ahead = cmd[min(i + int(w[C_I]), n) - 1]
    pos = w[st + L.S_C] * w[W_PRM + L.P_COUNT_RAD]  # the encoder's count, as an angle
    e = P - pos
    speed = counter_speed(w)
    if i > 0 and cmd[i - 1] == (cmd[i - 2] if i > 1 else 0.0):  # the command at rest
        w[X_OVC] = max(w[X_OVC], w[st + L.S_LASTDIR] * (pos - P))
    w[o + 0] = _clip(e / D)
    w[o + 1] = _clip(math.copysign(math.log10(1.0 + abs(e) / win), e) / 4.0)
    w[o + 2] = _clip((target - pos) / D)
    w[o + 3] = _clip((target - P) / D)
    w[o + 4] = _clip((ahead - P) / D)
    w[o + 5] = _clip(speed / w[C_VMAX])
    w[o + 6] = _clip((speed - speed0) / (nt * T) / w[C_LIMIT]) if nt > 0 else 0.0
    w[o + 7] = _clip(w[C_K3] * w[st + L.S_U] / w[W_PRM + L.P_TPEAK])
    w[o + 8] = (w[st + L.S_SAT] - sat0) / nt if nt > 0 else 0.0
    w[o + 9] = _clip((P - w[st + L.S_N] * w[W_PRM + L.P_DELTA]) / D)
    w[o + 10] = _clip(w[st + L.S_PC] * w[W_PRM + L.P_COUNT_RAD] / D)
    w[o + 11] = _clip(math.log10(1.0 + w[X_OVC] / win) / 4.0)
    w[o + 12] = _clip(w[st + L.S_D2MX] * w[W_PRM + L.P_ACC_SCALE] / w[C_LIMIT])
    w[o + 13] = i / n
    for j in range(4):
        w[o + 14 + j] = w[X_SET + j]


@_jit
def reset_row(w, ring, cmd) -> None:
    """Start the episode in ``w`` (parameters, constants, features already filled in)."""
    K.init_state(w[W_PRM : W_PRM + L.N_PARAMS], w[W_ST : W_ST + L.N_STATE], ring)
    w[X_COST] = 0.0
    w[X_COST_PREV] = 0.0
    w[X_SHAPE] = 0.0
    w[X_REWARD] = 0.0
    w[X_STEPS] = 0.0
    w[X_TICK_END] = 0.0
    w[X_LANE] = 0.0
    w[X_OVC] = 0.0
    w[W_ACC : W_ACC + L.N_ACC] = 0.0
    write_obs(w, cmd, 0.0, 0.0, 0)


@_jit
def begin_step(act, w) -> bool:
    """Set the action's settings and note the interval's starting values; False if the
    action is bad (nothing changed)."""
    if not apply_action(act, w):
        return False
    w[X_SPEED0] = counter_speed(w)
    w[X_SAT0] = w[W_ST + L.S_SAT]
    w[X_TSQ0] = w[W_ST + L.S_TSQM]
    return True


@_jit
def interval_end(w) -> int:
    """The tick the interval that starts now ends at."""
    return min(int(w[W_ST + L.S_TICK]) + int(w[C_I]), int(w[C_N]))


@_jit
def interval_flags(w, cmd, i0: int) -> int:
    """After the interval from tick ``i0``: running cost, observation and the flags."""
    st = w[W_ST : W_ST + L.N_STATE]
    n = int(w[C_N])
    i1 = int(st[L.S_TICK])
    w[X_COST_PREV] = w[X_COST]
    prm = w[W_PRM : W_PRM + L.N_PARAMS]
    cost_k = w[W_COST : W_COST + CC.N_CONST]
    w[X_COST] = CC.running_cost(st, prm, cost_k)
    w[X_STEPS] += 1.0
    w[X_TICK_END] = i1
    write_obs(w, cmd, w[X_SPEED0], w[X_SAT0], i1 - i0)
    flags = 0
    if i1 >= w[C_END] and (i1 - 1) - st[L.S_LOM] >= w[C_HOLD]:
        flags = TERMINATED | SETTLED
    if w[C_VIOL] != 0.0 and CC.violated(st, prm, cost_k):
        flags |= TERMINATED | VIOLATION
    if flags == 0 and i1 >= n:
        flags = TRUNCATED
    return flags


@_jit
def run_out(w, ring, cmd) -> None:
    """At the episode's end: the rest of the move with the settings held, so that the
    end-of-episode measures cover the whole command, as the scoring path's do; then the
    move's accumulators."""
    prm = w[W_PRM : W_PRM + L.N_PARAMS]
    st = w[W_ST : W_ST + L.N_STATE]
    n = int(w[C_N])
    if int(st[L.S_TICK]) < n:
        ext = np.zeros(0, dtype=np.int8)
        rec = np.zeros((L.N_ROWS, 0), dtype=np.float64)
        K.run_segment(cmd, ext, prm, st, ring, n, rec, 1)
    K.finish(st, w[W_ACC : W_ACC + L.N_ACC], n, prm)


@_jit
def set_reward(w) -> None:
    """The interval's reward: running cost before minus after, minus the shaping term
    (over the run-out too, at the episode's end)."""
    shape = 0.0
    if w[C_SHAPE] != 0.0:
        D = w[C_SCALE]
        tsq = w[W_ST + L.S_TSQM] - w[X_TSQ0]
        shape = w[C_SHAPE] * (tsq * w[W_PRM + L.P_TICK_S]) / (D * D * w[C_IDEAL])
    w[X_SHAPE] = shape
    w[X_REWARD] = (w[X_COST_PREV] - w[X_COST]) - shape


@_jit
def env_step(act, w, ring, cmd) -> int:
    """Advance one env by one control interval; returns its flags (see the constants)."""
    if not begin_step(act, w):
        return BAD_ACTION
    i0 = int(w[W_ST + L.S_TICK])
    ext = np.zeros(0, dtype=np.int8)
    rec = np.zeros((L.N_ROWS, 0), dtype=np.float64)
    prm = w[W_PRM : W_PRM + L.N_PARAMS]
    K.run_segment(cmd, ext, prm, w[W_ST : W_ST + L.N_STATE], ring, interval_end(w), rec, 1)
    flags = interval_flags(w, cmd, i0)
    if flags != 0:
        run_out(w, ring, cmd)
    set_reward(w)
    return flags


@_jit
def step_one(act, w, ring, cmd, obs):
    """One env, one interval: (reward before the end-of-episode correction, flags); the
    observation is also written, as float32, into ``obs``."""
    flags = env_step(act, w, ring, cmd)
    for j in range(obs.shape[0]):
        obs[j] = w[W_OBS + j]
    return w[X_REWARD], flags


LANE_MIN = LN.LANES // 2
"""A block runs in SIMD lanes when at least this many of its envs can; else env by env."""
PARALLEL_MIN_ENVS = 32 if J.SPINNING_WORKERS else 512
"""From this many envs a step spreads its blocks over numba's threads; below, it stays on
the calling thread. A step of 64 envs takes ~150 us on one core. Waking numba's sleeping
workers (vfgym's default, OMP_WAIT_POLICY=PASSIVE) costs ~55 us a call, so on the 2-core
VM measured (benchmarks/bench_envs.py) the second thread only paid from ~512 envs; with
spinning workers (opt-in, :data:`vfgym.plant._jit.SPINNING_WORKERS`) it paid from 32."""


@_jit
def _lane_ready(w, m: int, acc_w: int) -> bool:
    """Whether this env's next interval can run in a lane: a whole interval of ``m`` ticks
    left, the V-F controller as pulse source, the block's acceleration window."""
    return (
        int(w[C_I]) == m
        and int(w[W_ST + L.S_TICK]) + m <= int(w[C_N])
        and w[W_PRM + L.P_USE_EXT] == 0.0
        and int(w[W_PRM + L.P_ACC_W]) == acc_w
    )


@_jit
def _leave_lanes(w, ring, H, e: int, g: int, acc_w: int) -> None:
    """If the env in lane ``e`` has its last counts in the block's history ``H`` (block
    tick ``g``), write them back into its ring, where the single-env kernel reads them."""
    if w[X_LANE] != 0.0:
        LN.flush_history(H, e, ring, int(w[W_ST + L.S_TICK]), g, acc_w)
        w[X_LANE] = 0.0


@_jit
def _step_block(b: int, W, RING, CMD, active, Z, CB, H, G, lane_min: int) -> None:
    """Advance the active envs of lane block ``b`` (envs b·LANES …) by one interval: in
    SIMD lanes (:mod:`vfgym.plant._lanes`) when enough of them can, else one by one."""
    N = W.shape[0]
    m = CB.shape[0]
    acc_w = (H.shape[0] - m) // 2
    first = b * LN.LANES
    last = min(first + LN.LANES, N)
    ready = np.zeros(LN.LANES, dtype=np.bool_)
    count = 0
    lead = -1
    for r in range(first, last):
        if active[r] and _lane_ready(W[r], m, acc_w):
            ready[r - first] = True
            count += 1
            if lead < 0:
                lead = r
    lanes = count >= lane_min
    g = G[b]
    for r in range(first, last):
        e = r - first
        # the block's history is about to be overwritten: give the envs that leave it
        # their counts back
        if not (lanes and ready[e]):
            _leave_lanes(W[r], RING[r], H, e, g, acc_w)
    if lanes:
        for e in range(LN.LANES):
            r = first + e if first + e < last and ready[e] else lead
            w = W[r]
            LN.load_lane(Z, CB, e, w[W_PRM : W_PRM + L.N_PARAMS], w[W_ST : W_ST + L.N_STATE],
                         CMD[r], m)  # fmt: skip
            if r == first + e and w[X_LANE] == 0.0:
                LN.load_history(H, e, RING[r], int(w[W_ST + L.S_TICK]), g, acc_w)
        LN.run_block(Z, CB, H, g, m, acc_w)
        G[b] = g + m
        for e in range(last - first):
            if ready[e]:
                r = first + e
                LN.store_lane(Z, e, W[r, W_ST : W_ST + L.N_STATE])
                W[r, X_LANE] = 1.0
    ext = np.zeros(0, dtype=np.int8)
    rec = np.zeros((L.N_ROWS, 0), dtype=np.float64)
    for r in range(first, last):
        if active[r] and not (lanes and ready[r - first]):
            w = W[r]
            K.run_segment(CMD[r, : int(w[C_N])], ext, w[W_PRM : W_PRM + L.N_PARAMS],
                          w[W_ST : W_ST + L.N_STATE], RING[r], interval_end(w), rec, 1)  # fmt: skip


@_jit
def _end_block(b: int, W, RING, CMD, active, flags, I0, H, G, m: int) -> None:
    """Rewards, observations and flags of block ``b``'s active envs after their interval;
    an env whose episode ended runs the rest of its move (its counts back in its ring)."""
    acc_w = (H.shape[0] - m) // 2
    for r in range(b * LN.LANES, min((b + 1) * LN.LANES, W.shape[0])):
        if active[r]:
            w = W[r]
            cmd = CMD[r, : int(w[C_N])]
            f = interval_flags(w, cmd, I0[r])
            if f != 0:
                _leave_lanes(w, RING[r], H, r % LN.LANES, G[b], acc_w)
                run_out(w, RING[r], cmd)
            set_reward(w)
            flags[r] = f


@_jit
def _begin_batch(act, W, active, flags, I0) -> int:
    """Check the active envs' actions and, if all are good, set their settings and note
    each env's tick in ``I0``; returns −1, or the first env whose action is bad (then no
    env has changed)."""
    N = W.shape[0]
    for r in range(N):
        flags[r] = 0
        if active[r] and (act.shape[1] != 4 or not action_ok(act[r])):
            flags[r] = BAD_ACTION
            return r
    for r in range(N):
        I0[r] = int(W[r, W_ST + L.S_TICK])
        if active[r]:
            begin_step(act[r], W[r])
    return -1


@_jit
def _step_serial(act, W, RING, CMD, active, flags, Z, CB, H, G, lane_min) -> int:
    """:func:`step_batch` on the calling thread, block after block."""
    I0 = np.empty(W.shape[0], dtype=np.int64)
    bad = _begin_batch(act, W, active, flags, I0)
    if bad >= 0:
        return bad
    m = CB.shape[1]
    for b in range(G.shape[0]):
        _step_block(b, W, RING, CMD, active, Z[b], CB[b], H[b], G, lane_min)
        _end_block(b, W, RING, CMD, active, flags, I0, H[b], G, m)
    return -1


@J.jit(parallel=True)
def _step_parallel(act, W, RING, CMD, active, flags, Z, CB, H, G, lane_min) -> int:
    """:func:`step_batch` with the blocks on numba's threads. Kept apart from
    :func:`_step_serial`, so that its compile (numba's parallel passes, some seconds)
    is paid only by a batch that uses the threads."""
    I0 = np.empty(W.shape[0], dtype=np.int64)
    bad = _begin_batch(act, W, active, flags, I0)
    if bad >= 0:
        return bad
    m = CB.shape[1]
    for i in numba.prange(G.shape[0]):
        b = np.int64(i)  # prange's index is unsigned: one compile of the blocks serves both
        _step_block(b, W, RING, CMD, active, Z[b], CB[b], H[b], G, lane_min)
        _end_block(b, W, RING, CMD, active, flags, I0, H[b], G, m)
    return -1


def _batch_kernel(num_envs: int, parallel_min: int | None):
    """The compiled step a batch of ``num_envs`` envs runs: on numba's threads from
    ``parallel_min`` envs (None: :data:`PARALLEL_MIN_ENVS`), else on the calling thread."""
    par = PARALLEL_MIN_ENVS if parallel_min is None else parallel_min
    return _step_parallel if num_envs >= par else _step_serial


def step_batch(
    act, W, RING, CMD, active, flags, Z, CB, H, G, lane_min=LANE_MIN, parallel_min=None
) -> int:
    """Step every env ``r`` with ``active[r]`` by one interval; ``flags[r]`` gets its flags
    (0 for inactive envs). Returns −1, or the first env whose action is bad, in which case
    no env has been stepped.

    Envs are simulated in lane blocks of :data:`vfgym.plant._lanes.LANES` (env r in block
    r // LANES, lane r % LANES), numba threads over the blocks from ``parallel_min``
    envs (None: :data:`PARALLEL_MIN_ENVS`); a block with fewer than
    ``lane_min`` envs that can tick in lanes runs them one by one. ``Z``, ``CB``, ``H``:
    one block scratch each per block (:func:`vfgym.plant._lanes.scratch`); ``G``: each block's
    tick counter. While an env's last counts live in its block's history (``X_LANE``),
    its ring is out of date; they are written back whenever it leaves the lanes.

    ``act`` should be float64 (float32 works, at the cost of a second compile of the
    kernels' action path: :func:`step_batch_balanced` converts)."""
    kernel = _batch_kernel(W.shape[0], parallel_min)
    return kernel(act, W, RING, CMD, active, flags, Z, CB, H, G, lane_min)


def lane_scratch(num_envs: int, interval_ticks: int, acc_window: int) -> tuple[np.ndarray, ...]:
    """The (Z, CB, H, G) arrays :func:`step_batch` needs for ``num_envs`` envs."""
    blocks = -(-num_envs // LN.LANES)
    return (*LN.scratch(blocks, interval_ticks, acc_window), np.zeros(blocks, dtype=np.int64))


@keeps_torch_threads
def step_batch_balanced(
    act, W, RING, CMD, active, flags, scratch, lane_min: int = LANE_MIN, parallel_min=None
) -> int:
    """:func:`step_batch` with one block per work chunk, handed out as threads free up (an
    env whose episode ends runs the rest of its move in the same call, so the work is
    uneven). The chunk size is set from Python: set inside the compiled function it would
    stop numba from caching it. The actions are taken as float64 (SB3 hands float32, users
    float64: one compiled kernel serves both, with the same numbers, float32 → float64
    being exact)."""
    kernel = _batch_kernel(W.shape[0], parallel_min)
    act = np.asarray(act, dtype=np.float64)
    args = (act, W, RING, CMD, active, flags, *scratch, lane_min)
    threads = kernel is _step_parallel
    entry = "vector env, threads" if threads else "vector env"
    if not announced(entry):  # the first call: it may compile, for some 30 s
        what = "the vector env's SIMD-lane kernels" + (" on threads" if threads else "")
        with compiling(entry, what, kernel):
            return _run(kernel, args, threads)
    return _run(kernel, args, threads)


def _run(kernel, args: tuple, threads: bool) -> int:
    """``kernel(*args)``, with one block per work chunk when on threads."""
    if not threads:
        return kernel(*args)
    old = numba.set_parallel_chunksize(1)
    try:
        return kernel(*args)
    finally:
        numba.set_parallel_chunksize(old)


def ring_size(prm: np.ndarray) -> int:
    """Length of the kernel's pulse-count history for this parameter row."""
    return int(K.ring_size(prm))


# The functions here compile the kernel, its tick, the lane kernel, the compiled cost and
# the observation clip (vfgym.moves.features.clip_feature) into themselves.
J.guard_cache(step_one, (K, TK, LN, L, CC, _common))
