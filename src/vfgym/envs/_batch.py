"""Compiled stepping of VFServo-v0: one control interval of one env, or of a batch of envs.

Each env keeps everything it needs in one float64 *workspace* row (layout below): the
kernel's parameter row and loop state (:mod:`vfgym._layout`), the episode's constants, the
running cost, the final accumulators and the observation. :func:`env_step` maps the action
onto the four settings (the search space's own scaling, read from the row), advances the
stateful kernel (:func:`vfgym._kernel.run_segment`) by one interval, and writes the reward
terms, the end-of-episode flags and the observation. :func:`step_one` (one env, no threads)
and :func:`step_batch` (numba ``prange`` over envs) call the same :func:`env_step`, so a
single env and a batched one produce the same numbers bit for bit.

Reward terms (see :class:`vfgym.envs.servo.VFServoEnv`): the running cost C(s) is the
scoring path's cost formula (:func:`vfgym.scoring.score`) evaluated on the measures
streamed so far, without the "unsettled" term, which is known only at the end; each
interval's reward is C before minus C after, minus an optional tracking-error shaping
term. The last interval's reward is finished in Python with the scoring path's own cost of
the whole move.
"""

from __future__ import annotations

import hashlib
import math
from pathlib import Path

import numba
import numpy as np

from vfgym import _kernel as K
from vfgym import _layout as L

_jit = numba.njit(cache=True, fastmath=False, nogil=True)

ACTION_TOL = 1e-6
"""Actions may exceed [-1, 1] by this much (float rounding), as :func:`vfgym.space.from_action`."""
OBS_BOUND = 10.0
"""Every observation feature is clipped to [-OBS_BOUND, OBS_BOUND]."""

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
_c = W_ST + L.N_STATE
# episode constants
C_N = _c + 0  # ticks of the move (the command's length): the time limit
C_I = _c + 1  # ticks per control interval
C_END = _c + 2  # tick from which the command is at its final value
C_HOLD = _c + 3  # ticks the motor must stay in position to count as settled
C_IDEAL = _c + 4  # ideal move time (s), the cost's yardstick
C_WIN = _c + 5  # in-position half-width (rad)
C_SCALE = _c + 6  # the move's size (rad): observation scale
C_LIMIT = _c + 7  # motor acceleration limit (rad/s²)
C_VMAX = _c + 8  # pulse train top speed δ·f (rad/s)
C_TRACKING = _c + 9  # 1: moving reference (scored by tracking error)
C_TRK_SCALE = _c + 10  # 10 % of the amplitude (rad): the tracking term's yardstick
C_W_TIME = _c + 11  # CostWeights
C_W_TRACK = _c + 12
C_W_OV = _c + 13
C_W_ACC = _c + 14
C_W_TQ = _c + 15
C_W_UNS = _c + 16
C_B_OV = _c + 17  # Bounds.overshoot_windows
C_B_TQ = _c + 18  # Bounds.torque_limit_time_s
C_SHAPE = _c + 19  # tracking-error shaping weight
C_VIOL = _c + 20  # 1: end the episode on a constraint violation
C_DIMS = _c + 21  # 4 × (action index, low, high, log) for value, error limit, k, Ts/Tf;
# for a log dimension low and high are stored as log(low), log(high)
_x = C_DIMS + 16
# per-step results and running values
X_COST = _x + 0  # running cost after the last interval
X_COST_PREV = _x + 1  # running cost before the last interval
X_SHAPE = _x + 2  # shaping term of the last interval (and of the run-out at the end)
X_REWARD = _x + 3  # reward of the last interval (before the end-of-episode correction)
X_STEPS = _x + 4  # intervals stepped
X_TICK_END = _x + 5  # ticks simulated under the agent's control
X_SET = _x + 6  # the action in force, clipped to [-1, 1] (4 slots)
W_ACC = X_SET + 4  # accumulator row of the whole move (written at the episode's end)
W_OBS = W_ACC + L.N_ACC

OBS_DYNAMIC = (
    "error",
    "error_log",
    "remaining",
    "command_remaining",
    "command_ahead",
    "speed",
    "accel",
    "torque",
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
"""The VFServo-v0 features the kernel writes each interval (definitions in servo.py)."""
N_DYN = len(OBS_DYNAMIC)


def width(n_obs: int) -> int:
    """Length of a workspace row with ``n_obs`` observation features."""
    return W_OBS + n_obs


@_jit
def _clip(x: float) -> float:
    if x > OBS_BOUND:
        return OBS_BOUND
    if x < -OBS_BOUND:
        return -OBS_BOUND
    return x


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
def apply_action(act, w) -> bool:
    """Set the settings in force from an action in [-1, 1]⁴; False (nothing set) if bad."""
    if act.shape[0] != 4 or not action_ok(act):
        return False
    x0 = 0.0
    x1 = 0.0
    x2 = 0.0
    x3 = 0.0
    for f in range(4):
        b = C_DIMS + 4 * f
        j = int(w[b])
        u = float(act[j])
        x = from_unit(u, w[b + 1], w[b + 2], w[b + 3] != 0.0)
        w[X_SET + j] = min(max(u, -1.0), 1.0)
        if f == 0:
            x0 = x
        elif f == 1:
            x1 = x
        elif f == 2:
            x2 = x
        else:
            x3 = x
    w[W_PRM + L.P_VALUE] = x0
    w[W_PRM + L.P_LIMIT] = x1
    w[W_PRM + L.P_STEP] = x0 / x2
    w[W_PRM + L.P_A] = x3
    return True


@_jit
def accel_excess(w) -> float:
    """The scoring path's accel constraint on the peak so far: ratio − 1 − quantum/limit."""
    scale = w[W_PRM + L.P_ACC_SCALE]
    limit = w[C_LIMIT]
    return w[W_ST + L.S_D2MX] * scale / limit - 1.0 - 2.0 * scale / limit


@_jit
def running_cost(w) -> float:
    """:func:`vfgym.scoring.score`'s cost on the measures streamed so far, without the
    unsettled term (see the module docstring)."""
    T = w[W_PRM + L.P_TICK_S]
    ideal = w[C_IDEAL]
    if w[C_TRACKING] != 0.0:
        main = 0.0
        if w[C_TRK_SCALE] > 0.0:
            main = w[C_W_TRACK] * (math.sqrt(w[W_ST + L.S_TSQM] / w[C_N]) / w[C_TRK_SCALE])
    else:
        main = w[C_W_TIME] * (((w[W_ST + L.S_LOM] + 1.0) * T) / ideal)
    win = w[C_WIN]
    ov_w = w[W_ST + L.S_OVM] / win if win > 0.0 else 0.0
    return (
        main
        + w[C_W_OV] * ov_w
        + w[C_W_ACC] * max(0.0, accel_excess(w))
        + w[C_W_TQ] * (w[W_ST + L.S_SAT] * T) / ideal
    )


@_jit
def violated(w) -> bool:
    """A constraint of the scoring path (accel, torque, overshoot) is already violated."""
    if accel_excess(w) > 0.0:
        return True
    if w[W_ST + L.S_SAT] * w[W_PRM + L.P_TICK_S] - w[C_B_TQ] > 0.0:
        return True
    win = w[C_WIN]
    ov_w = w[W_ST + L.S_OVM] / win if win > 0.0 else 0.0
    return ov_w - w[C_B_OV] > 0.0


@_jit
def write_obs(w, cmd, omega0: float, sat0: float, nt: int) -> None:
    """The dynamic features after an interval of ``nt`` ticks that started at speed
    ``omega0`` with ``sat0`` saturated ticks so far."""
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
    theta = w[st + L.S_THETA]
    e = P - theta
    w[o + 0] = _clip(e / D)
    w[o + 1] = _clip(math.copysign(math.log10(1.0 + abs(e) / win), e) / 4.0)
    w[o + 2] = _clip((target - theta) / D)
    w[o + 3] = _clip((target - P) / D)
    w[o + 4] = _clip((ahead - P) / D)
    w[o + 5] = _clip(w[st + L.S_OMEGA] / w[C_VMAX])
    w[o + 6] = _clip((w[st + L.S_OMEGA] - omega0) / (nt * T) / w[C_LIMIT]) if nt > 0 else 0.0
    w[o + 7] = _clip(w[st + L.S_TAU] / w[W_PRM + L.P_TPEAK])
    w[o + 8] = (w[st + L.S_SAT] - sat0) / nt if nt > 0 else 0.0
    w[o + 9] = _clip((P - w[st + L.S_N] * w[W_PRM + L.P_DELTA]) / D)
    w[o + 10] = _clip(w[st + L.S_PC] * w[W_PRM + L.P_COUNT_RAD] / D)
    w[o + 11] = _clip(math.log10(1.0 + w[st + L.S_OVM] / win) / 4.0)
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
    w[W_ACC : W_ACC + L.N_ACC] = 0.0
    write_obs(w, cmd, 0.0, 0.0, 0)


@_jit
def env_step(act, w, ring, cmd) -> int:
    """Advance one env by one control interval; returns its flags (see the constants)."""
    if not apply_action(act, w):
        return BAD_ACTION
    prm = w[W_PRM : W_PRM + L.N_PARAMS]
    st = w[W_ST : W_ST + L.N_STATE]
    ext = np.zeros(0, dtype=np.int8)
    rec = np.zeros((L.N_ROWS, 0), dtype=np.float64)
    n = int(w[C_N])
    i0 = int(st[L.S_TICK])
    i1 = min(i0 + int(w[C_I]), n)
    omega0 = st[L.S_OMEGA]
    sat0 = st[L.S_SAT]
    tsq0 = st[L.S_TSQM]
    K.run_segment(cmd, ext, prm, st, ring, i1, rec, 1)
    c_prev = w[X_COST]
    c_now = running_cost(w)
    w[X_COST_PREV] = c_prev
    w[X_COST] = c_now
    w[X_STEPS] += 1.0
    w[X_TICK_END] = i1
    write_obs(w, cmd, omega0, sat0, i1 - i0)
    flags = 0
    if i1 >= w[C_END] and (i1 - 1) - st[L.S_LOM] >= w[C_HOLD]:
        flags = TERMINATED | SETTLED
    if w[C_VIOL] != 0.0 and violated(w):
        flags |= TERMINATED | VIOLATION
    if flags == 0 and i1 >= n:
        flags = TRUNCATED
    if flags != 0:
        # the rest of the move with the settings held, so that the end-of-episode measures
        # cover the whole command, as the scoring path's do
        if i1 < n:
            K.run_segment(cmd, ext, prm, st, ring, n, rec, 1)
        K.finish(st, w[W_ACC : W_ACC + L.N_ACC], n, prm[L.P_TICK_S], prm[L.P_ACC_SCALE])
    shape = 0.0
    if w[C_SHAPE] != 0.0:
        D = w[C_SCALE]
        shape = w[C_SHAPE] * ((st[L.S_TSQM] - tsq0) * prm[L.P_TICK_S]) / (D * D * w[C_IDEAL])
    w[X_SHAPE] = shape
    w[X_REWARD] = (c_prev - c_now) - shape
    return flags


@_jit
def step_one(act, w, ring, cmd, obs):
    """One env, one interval: (reward before the end-of-episode correction, flags); the
    observation is also written, as float32, into ``obs``."""
    flags = env_step(act, w, ring, cmd)
    for j in range(obs.shape[0]):
        obs[j] = w[W_OBS + j]
    return w[X_REWARD], flags


@numba.njit(cache=True, fastmath=False, nogil=True, parallel=True)
def step_batch(act, W, RING, CMD, active, flags) -> int:
    """Step every env ``r`` with ``active[r]`` by one interval, in parallel; ``flags[r]``
    gets its flags (0 for inactive envs). Returns −1, or the first env whose action is
    bad, in which case no env has been stepped."""
    N = W.shape[0]
    for r in range(N):
        flags[r] = 0
        if active[r] and (act.shape[1] != 4 or not action_ok(act[r])):
            flags[r] = BAD_ACTION
            return r
    for r in numba.prange(N):
        if active[r]:
            flags[r] = env_step(act[r], W[r], RING[r], CMD[r, : int(W[r, C_N])])
    return -1


def step_batch_balanced(act, W, RING, CMD, active, flags) -> int:
    """:func:`step_batch` with one env per work chunk, handed out as threads free up (an
    env whose episode ends runs the rest of its move in the same call, so the envs' work
    is uneven). The chunk size is set from Python: set inside the compiled function it
    would stop numba from caching it."""
    old = numba.set_parallel_chunksize(1)
    try:
        return step_batch(act, W, RING, CMD, active, flags)
    finally:
        numba.set_parallel_chunksize(old)


def ring_size(prm: np.ndarray) -> int:
    """Length of the kernel's pulse-count history for this parameter row."""
    return int(K.ring_size(prm))


def _guard_cache() -> None:
    """Drop this module's numba cache when the kernel's source has changed.

    numba keys a cached function on its own file only, yet the functions here compile
    :mod:`vfgym._kernel` into themselves; without this guard an edit of the kernel would
    leave stale machine code here. The kernel's hash is kept next to the cache files."""
    try:
        cache_dir = Path(step_one._cache._cache_path)
    except AttributeError:  # a numba without this layout: nothing to guard
        return
    digest = hashlib.sha256()
    for mod in (K, L):
        digest.update(Path(mod.__file__).read_bytes())
    stamp = cache_dir / "_batch.kernel-sha256"
    try:
        if stamp.read_text() == digest.hexdigest():
            return
    except OSError:
        pass
    for f in cache_dir.glob("_batch.*.nb[ic]"):
        f.unlink(missing_ok=True)
    try:
        cache_dir.mkdir(parents=True, exist_ok=True)
        stamp.write_text(digest.hexdigest())
    except OSError:
        pass


_guard_cache()
