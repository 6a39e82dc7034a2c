"""``vfgym/VFServo-v0``: retune the four settings every control interval during a move."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from vfgym._validate import check_choice, check_int, check_real
from vfgym.moves.features import OBS_BOUND, SCENARIO_FEATURES
from vfgym.moves.scenarios import Scenario
from vfgym.params import PAPER_SETTINGS, Settings
from vfgym.plant import _layout as L
from vfgym.plant import pack
from vfgym.plant._notice import announce_compile
from vfgym.plant.measures import from_acc
from vfgym.scoring import _cost_compiled as CC
from vfgym.scoring import score
from vfgym.space import SPACE, from_action, to_action

from . import _batch as B
from ._common import (
    SERVO_INTERVAL_S,
    SERVO_SETTLE_TIME_S,
    SERVO_TRACKING_WEIGHT,
    SERVO_VIOLATION_PENALTY,
    EnvConfig,
    Episode,
    as_action,
)
from ._common import scored_info as _scored_info
from ._decision import N_SIGNATURE, DecisionCore

_step_one = B.step_one
_BAD_ACTION = B.BAD_ACTION
_ENDED = B.ENDED

SERVO_FEATURES = B.OBS_DYNAMIC + SCENARIO_FEATURES
"""Names of VFServo-v0's observation entries, in order."""
SETTING_FIELDS = B.SETTING_FIELDS
DECISIONS = ("interval", "once")
"""VFServo-v0's ``decision`` modes: an action every control interval, or one a move."""
SERVO_HOLD_S = 0.002
"""With ``decision="once"``: the base is held 2 ms before the decision (the scheduler's
hold, :class:`vfgym.permove.adaptive.AdaptiveOptions`)."""


def servo_spaces(config: ServoConfig | None = None) -> tuple[spaces.Box, spaces.Box]:
    """(observation space, action space) of VFServo-v0 (of its ``config``: with
    ``decision="once"`` the observation is the hold's response, the base as an action and
    the move's features)."""
    n, m = len(SERVO_FEATURES), len(SPACE)
    if config is not None and config.decision == "once":  # the correction and its ramp
        n = config.hold_intervals * N_SIGNATURE + len(SETTING_FIELDS) + len(SCENARIO_FEATURES)
        if config.tell:  # the response's difference, two estimates of each uncertain quantity
            d = len(config.axis.uncertainty.ranges())
            n += config.hold_intervals * N_SIGNATURE + 2 * d
        m += 1
    obs = spaces.Box(-OBS_BOUND, OBS_BOUND, shape=(n,), dtype=np.float32)
    act = spaces.Box(-1.0, 1.0, shape=(m,), dtype=np.float32)
    return obs, act


def raise_bad_action(action: np.ndarray, accel_law: str, index: int | None = None) -> None:
    """Raise the search space's own ``ValueError`` for an action the kernel refused (for
    a one-decision action, its correction's, else one line of its own)."""
    a = np.asarray(action, dtype=np.float64)
    if a.shape == (5,) and np.isfinite(a).all() and B.action_ok(a[:4]):
        where = "action" if index is None else f"actions[{index}]"
        raise ValueError(
            f"{where}={a.tolist()} is not allowed: its ramp entry must be a number in [-1, 1]"
        )
    try:
        from_action(a[:4] if a.shape == (5,) else action, accel_law)  # NaN / out of the box
    except ValueError as e:
        if index is None:
            raise
        raise ValueError(f"actions[{index}]: {e}") from None
    raise ValueError(f"action={np.asarray(action).tolist()} is not allowed")


@dataclass(frozen=True)
class ServoConfig(EnvConfig):
    """VFServo-v0's arguments, every default here: :class:`EnvConfig`'s and the online
    tuning's own; validated on construction.

    Parameters
    ----------
    scenario, split, seed_range, accel_law, axis, weights, bounds
        As :class:`vfgym.envs._common.EnvConfig` (an axis resolved there).
    residual, residual_scale, residual_base
        As :class:`vfgym.envs._common.EnvConfig`: with residual actions the base is also
        in force before the first action; ``residual_base`` None is
        ``initial_settings``.
    interval_s : float
        The control interval (s), a whole number of ticks (:meth:`vfgym.Plant.whole_ticks`).
    settle_time_s : float
        How long the motor must stay in position to end the episode (s), 0 to 1.
    initial_settings : Settings
        The settings in force before the first action (its law is replaced by
        ``accel_law``).
    tracking_weight : float
        Weight of the tracking-error shaping term (0: none), ≥ 0.
    terminate_on_violation : bool
        End the episode on a constraint violation.
    violation_penalty : float
        The extra negative reward of such an end, ≥ 0 (with ``decision="once"``: of a
        move that breaks a limit the base holds on the same plant).
    decision : str
        ``"interval"``: an action every control interval; ``"once"``: the base held for
        ``hold_s``, then one residual correction held for the rest of the move, a one-step
        episode (:mod:`vfgym.envs._decision`; residual actions only).
    hold_s : float
        With ``decision="once"``: how long the base is held before the decision (s), a
        whole number of control intervals, 1 to 100 of them.
    tell : bool
        With ``decision="once"``: the observation also holds what the hold's response
        tells of the plant (its difference from the modelled plant's response, the
        nearest design plant's quantities and a blend of the three nearest).
    shield : bool
        With ``decision="once"``: check the correction on the axis's design plants whose
        hold response is nearest the one seen (on an exactly known axis, its plant), on
        in-range plants told as the same and on the plants the hold cannot tell from it
        (:mod:`vfgym.envs._decision`), and run the base instead where it breaks a limit
        the base holds there.
    shield_gentler : int
        With ``shield``: where the correction breaks, try it halved, then quartered ...
        this many times (0 to 8), each on the same plants, and run
        the first that breaks none of their limits the base holds; the base only where
        none does (the scheduler's gentler candidate, :mod:`vfgym.permove.adaptive`).

    Raises
    ------
    ValueError
        If an argument is of the wrong type or out of its range.
    """

    interval_s: float = SERVO_INTERVAL_S
    settle_time_s: float = SERVO_SETTLE_TIME_S
    initial_settings: Settings = PAPER_SETTINGS
    tracking_weight: float = SERVO_TRACKING_WEIGHT
    terminate_on_violation: bool = False
    violation_penalty: float = SERVO_VIOLATION_PENALTY
    decision: str = "interval"
    hold_s: float = SERVO_HOLD_S
    tell: bool = False
    shield: bool = False
    shield_gentler: int = 0

    def __post_init__(self) -> None:
        super().__post_init__()
        s = object.__setattr__
        if not isinstance(self.initial_settings, Settings):
            raise ValueError(f"initial_settings={self.initial_settings!r} must be a vfgym.Settings")
        s(self, "initial_settings", self.initial_settings.replace(accel_law=self.accel_law))
        self.plant.whole_ticks("interval_s", self.interval_s)
        s(self, "settle_time_s", check_real("settle_time_s", self.settle_time_s, 0.0, 1.0))
        s(self, "tracking_weight", check_real("tracking_weight", self.tracking_weight, 0.0))
        if not isinstance(self.terminate_on_violation, bool):
            raise ValueError(
                f"terminate_on_violation={self.terminate_on_violation!r} must be a bool"
            )
        s(self, "violation_penalty", check_real("violation_penalty", self.violation_penalty, 0.0))
        check_choice("decision", self.decision, DECISIONS)
        s(self, "hold_s", check_real("hold_s", self.hold_s, 0.0, 1.0, lo_open=True))
        for name in ("tell", "shield"):
            if not isinstance(getattr(self, name), bool):
                raise ValueError(f"{name}={getattr(self, name)!r} must be a bool")
        if self.decision == "once":
            if not self.residual:
                raise ValueError(
                    "decision='once' needs residual=True: the decision is a correction of the base"
                )
            h = self.hold_s / self.interval_s
            if abs(h - round(h)) > 1e-9 * max(1.0, h) or not 1 <= round(h) <= 100:
                raise ValueError(
                    f"hold_s={self.hold_s!r} is not allowed: a whole number of control "
                    f"intervals (interval_s={self.interval_s!r}), 1 to 100 of them"
                )
        for name in ("tell", "shield"):
            if getattr(self, name) and self.decision != "once":
                raise ValueError(f"{name}=True is not allowed here: it needs decision='once'")
        s(self, "shield_gentler", g := check_int("shield_gentler", self.shield_gentler, 0, 8))
        if g and not self.shield:
            raise ValueError(f"shield_gentler={g!r} is not allowed here: it needs shield=True")

    def default_base(self) -> Settings:
        """The base of residual actions when ``residual_base`` is None, and the settings
        in force before the first action without residual actions: ``initial_settings``."""
        return self.initial_settings

    @property
    def interval_ticks(self) -> int:
        """Ticks per control interval."""
        return self.plant.whole_ticks("interval_s", self.interval_s)

    @property
    def hold_intervals(self) -> int:
        """Control intervals the base is held before a ``decision="once"``."""
        return round(self.hold_s / self.interval_s)

    @property
    def hold_ticks(self) -> int:
        """Ticks the motor must stay in position to count as settled."""
        return round(self.settle_time_s * self.plant.tick_hz)


MOTOR_STATE = ("motor_angle_rad", "motor_speed_rad_s", "motor_torque_nm")
"""The simulator's continuous state in every step's ``info`` (for evaluation only: a drive
measures encoder counts, its speed counter and the torque it commands, which the
observation holds)."""
_MOTOR_SLOTS = (L.S_THETA, L.S_OMEGA, L.S_TAU)


def motor_state(w: np.ndarray) -> dict[str, float]:
    """The motor's angle, speed and torque applied in workspace row ``w`` (:data:`MOTOR_STATE`)."""
    return {k: float(w[B.W_ST + j]) for k, j in zip(MOTOR_STATE, _MOTOR_SLOTS, strict=True)}


def motor_state_rows(W: np.ndarray) -> np.ndarray:
    """:func:`motor_state` of every row of a batch of workspaces, (rows, 3)."""
    return W[:, [B.W_ST + j for j in _MOTOR_SLOTS]].copy()


class ServoCore:
    """VFServo-v0's configuration and the Python half of its step, shared by the single env
    and the vector env so that both compute the same numbers: filling a workspace row at
    reset, and the end-of-episode scoring."""

    def __init__(self, config: ServoConfig) -> None:
        if not isinstance(config, ServoConfig):
            raise ValueError(f"config={config!r} must be a vfgym.envs.servo.ServoConfig")
        self.config = config
        self.interval_ticks = config.interval_ticks
        self.hold_ticks = config.hold_ticks
        self.source = config.scenario_source()
        self.n_obs = len(SERVO_FEATURES)
        self.width = B.width(self.n_obs)
        prm = pack(PAPER_SETTINGS, config.plant, config.measures, 1.0, 1)
        self.ring_len = B.ring_size(prm)
        self.acc_window = int(prm[L.P_ACC_W])
        self._dims = B.space_table()

    @property
    def accel_law(self) -> str:
        """The acceleration law the actions' settings use."""
        return self.config.accel_law

    def start(self, w: np.ndarray, ring: np.ndarray, cmd: np.ndarray, ep: Episode) -> None:
        """Fill workspace row ``w`` for a new episode on ``ep`` whose command is ``cmd``."""
        n = ep.command.size
        w[:] = 0.0
        c = self.config
        set0 = c.base_settings(ep.scenario)
        w[B.W_PRM : B.W_PRM + L.N_PARAMS] = pack(set0, ep.plant, c.measures, ep.target_rad, n)
        w[B.W_COST : B.W_COST + CC.N_CONST] = CC.constants(ep.yardsticks, n, c.weights, c.bounds)
        cfg = {
            B.C_N: n,
            B.C_I: self.interval_ticks,
            B.C_END: ep.command_end_tick,
            B.C_HOLD: self.hold_ticks,
            B.C_SCALE: ep.scale_rad,
            B.C_VMAX: ep.plant.pulse_top_speed_rad_s,
            B.C_SHAPE: c.tracking_weight,
            B.C_VIOL: 1.0 if c.terminate_on_violation else 0.0,
            B.C_K3: (ep.model or ep.plant).torque_per_count_nm,  # as the drive is set
        }
        for k, v in cfg.items():
            w[k] = v
        w[B.C_DIMS : B.C_DIMS + 20] = self._dims
        w[B.C_RES] = 1.0 if c.residual else 0.0
        w[B.C_RSCALE : B.C_RSCALE + 4] = c.residual_scales()
        w[B.C_BASE : B.C_BASE + 4] = [getattr(set0, f) for f in SETTING_FIELDS]
        w[B.X_SET : B.X_SET + 4] = to_action(set0).astype(np.float64)
        w[B.W_OBS + B.N_DYN : B.W_OBS + self.n_obs] = ep.features
        B.reset_row(w, ring, cmd)

    def finish(self, w: np.ndarray, ep: Episode, flags: int) -> tuple[float, dict[str, Any]]:
        """The last interval's reward and the episode's info: the scoring path's measures
        and cost of the whole move (the settings held after the episode's end)."""
        c = self.config
        acc = w[B.W_ACC : B.W_ACC + L.N_ACC]
        m = from_acc(acc, ep.plant, c.measures, ep.target_rad, ep.command_end_s)
        s = score(m, ep.scenario, ep.plant, c.measures, c.weights, c.bounds)
        violation = bool(flags & B.VIOLATION)
        reward = float(w[B.X_COST_PREV] - s.cost) - float(w[B.X_SHAPE])
        if violation:
            reward -= c.violation_penalty
        info = _scored_info(ep, s.metrics, s.cost, s.constraints)
        info.update(motor_state(w))
        info["ended_settled"] = bool(flags & B.SETTLED)
        info["ended_violation"] = violation
        info["control_ticks"] = int(w[B.X_TICK_END])
        info["steps"] = int(w[B.X_STEPS])
        return reward, info


class VFServoEnv(gym.Env[np.ndarray, np.ndarray]):
    """Tune the V-F controller and the servo's filter online, one control interval a step.

    ## Description

    One episode is one move of the plant of docs/model.md (V-F controller → digital servo →
    motor). Each step is one control interval (default 1 ms = 140 ticks): the action sets
    the four settings for that interval, and the compiled, stateful kernel
    (:func:`vfgym.plant._kernel.run_segment`) advances the plant through it; its state (the V-F
    accumulator, the servo's counters and filter, the motor) carries over from one interval
    to the next. At the episode's end ``info`` holds the scoring path's measures and cost of
    the whole move, so online tuning compares like for like with fixed settings from
    :func:`vfgym.evaluate` (a constant action gives exactly ``evaluate``'s cost).

    With ``decision="once"`` (residual actions) an episode is one decision instead
    (:mod:`vfgym.envs._decision`): the base held for ``hold_s``; the observation, what the
    drive measured over the hold (features 0-13 of each interval), the base as an action,
    the move's features (and with ``tell`` what the response tells of the plant); the
    action, a correction and the length of its ramp (5 entries), held to the move's end;
    the reward, 10 × the share of the base's cost on the same (move, plant) saved; the
    episode ends ``terminated``. ``info`` adds ``base_cost``, ``base_feasible``,
    ``shielded`` and ``ramp``.

    ## Action Space

    ``Box(-1, 1, (4,), float32)``: value, error limit L, k and Ts/Tf for the next
    interval, mapped onto their ranges by the search space (:data:`vfgym.space.SPACE`, log
    scales). With ``residual=True`` the action is instead an offset from a base setting
    (``residual_base``: the paper's by default, fixed tuned settings, or a per-move model's):
    an offset of ``residual_scale`` × the action in :class:`vfgym.space.Relative`'s
    coordinates (value, L/value, k, Ts/Tf on log scales; L keeps the base's L/value as the
    value moves), so the zero action holds the base exactly, and the return of zero
    actions is minus the base's cost bit for bit. The acceleration law is the
    ``accel_law`` argument. NaN or out-of-box actions raise ``ValueError``.

    ## Observation Space

    ``Box(-10, 10, (37,), float32)``, each entry clipped: what a drive measures (its
    encoder count, its speed counter, the pulses it was sent, the torque it commands),
    never the simulator's continuous state, which is in ``info`` for evaluation only. With
    P the command on the last tick simulated (0 before the first), c·q the motor's
    position as the encoder counts it (count c, count angle q), x the speed counter's
    latched output (B counts a count over the sample period of Ns ticks), u the servo's
    error (counts), K3 the drive's gain as set (the modelled plant's), D the move's size
    (its largest move, or amplitude) and W the in-position half-width:

    | index | name | definition |
    |---|---|---|
    | 0 | error | (P − c·q) / D |
    | 1 | error_log | sign(P − c·q) · log10(1 + \\|P − c·q\\| / W) / 4 |
    | 2 | remaining | (target − c·q) / D |
    | 3 | command_remaining | (target − P) / D |
    | 4 | command_ahead | (command at the end of the next interval − P) / D |
    | 5 | speed_counter | (x / B) · q / (Ns·T) / (δ·f): the counter's speed over the top speed |
    | 6 | accel | change of that speed over the last interval / its length / motor limit |
    | 7 | torque_command | K3 · u / peak torque |
    | 8 | torque_saturation | share of the last interval's ticks at the torque limit |
    | 9 | pulse_error | (P − n·δ) / D, the V-F controller's own error |
    | 10 | following_error | servo position counter (counts) × q / D |
    | 11 | overshoot_log | log10(1 + overshoot of c·q so far, seen at the intervals' ends / W) / 4 |
    | 12 | accel_peak | peak pulse-train acceleration so far / motor limit |
    | 13 | progress | ticks simulated / ticks of the move |
    | 14-17 | setting_* | the settings in force, as an action in [-1, 1] |
    | 18-36 | | the move and its plant, as VFTune-v0's observation |

    ## Rewards

    Per interval, ``r = C(before) − C(after) − tracking_weight · ΔISE · T / (D² · t_ideal)``
    where C is the scoring path's cost formula (:func:`vfgym.scoring.score`, compiled in
    :mod:`vfgym.scoring._cost_compiled`) on the measures streamed so far: time out of the
    in-position window / ideal time (or RMS tracking error for a moving reference), + 0.1 ×
    overshoot in windows, + 5 × the acceleration over the limit (so a violation shades the
    reward by its degree), + time at the torque limit / ideal time (weights from
    ``weights``); ΔISE is the interval's sum of squared tracking error (P − θ)². On the last
    step C(after) is the scoring path's cost of the whole move, including its arrival term
    (a move not settled in the in-position window at its end, or a sine not followed, pays
    a penalty growing with the distance left) and, on a compliant axis, its residual term
    (the load's residual vibration), ΔISE runs to the end of the move, and
    ``violation_penalty`` is subtracted on a violation. So the return of an episode is
    minus the cost of its move (to rounding) when ``tracking_weight=0``; C(before) = 0.

    ## Starting State

    As VFTune-v0: the scenario comes from the ``scenario`` argument, the reset options
    (``scenario``, ``scenario_seed``) or a seeded draw from the split. The plant is at rest
    at 0, the settings in force are ``initial_settings`` (the paper's).

    ## Episode End

    Terminated when the motor has settled: the command is at its final value and the motor
    has stayed in the in-position window for ``settle_time_s``; or, with
    ``terminate_on_violation``, as soon as a constraint that can be known while the move
    runs (acceleration, torque, overshoot) is violated; arrival is judged at the move's
    end, in ``info``. Truncated at the end of the scenario's command (its duration). When an
    episode ends early the rest of the move is simulated with the last settings held, so
    that the end-of-episode measures cover the whole command, as ``evaluate``'s do.

    ## Arguments

    ``gymnasium.make("vfgym/VFServo-v0", scenario=None, split="train", seed_range=None,
    accel_law="rise", interval_s=1e-3, settle_time_s=5e-3,
    initial_settings=PAPER_SETTINGS, tracking_weight=0.0, terminate_on_violation=False,
    violation_penalty=5.0, residual=False, residual_scale=0.25, residual_base=None,
    decision="interval", hold_s=0.002, tell=False, shield=False, shield_gentler=0,
    axis=LOADS_AXIS, weights=DEFAULT_WEIGHTS, bounds=DEFAULT_BOUNDS, render_mode=None)``; see
    Parameters.

    ``gymnasium.make_vec("vfgym/VFServo-v0", num_envs=N)`` gives
    :class:`vfgym.envs.vector.VFServoVectorEnv`, which steps all N envs in one compiled
    call, their plants ticking together in SIMD lanes.

    ## Version History

    * v0: Initial version.

    Parameters
    ----------
    scenario : str, Scenario or None
        As :class:`vfgym.envs.tune.VFTuneEnv`.
    render_mode : str or None
        ``"rgb_array"`` draws the episode's move so far (position, speed, acceleration,
        command against motor) as an (480, 640, 3) uint8 array.
    **options
        The other fields of :class:`ServoConfig`, where their defaults live and are
        checked: VFTune-v0's (``split``, ``seed_range``, ``accel_law``, ``axis``,
        ``weights``, ``bounds``), and ``interval_s`` (the control
        interval, a whole number of ticks), ``settle_time_s`` (how long the motor must stay
        in position to end the episode), ``initial_settings`` (the settings in force
        before the first action), ``tracking_weight`` (weight of the tracking-error
        shaping term; 0: none), ``terminate_on_violation`` and ``violation_penalty`` (end
        on a constraint violation, with this extra negative reward), ``decision``,
        ``hold_s``, ``tell``, ``shield`` and ``shield_gentler`` (one decision a move,
        above).

    Raises
    ------
    ValueError
        If an argument is out of its range or of the wrong type.
    TypeError
        If an option is not a field of :class:`ServoConfig`.
    """

    metadata: ClassVar[dict[str, Any]] = {"render_modes": ["rgb_array"], "render_fps": 30}

    def __init__(
        self,
        scenario: str | Scenario | None = None,
        *,
        render_mode: str | None = None,
        **options: Any,
    ) -> None:
        self.core = ServoCore(ServoConfig(scenario, **options))
        if render_mode is not None:
            check_choice("render_mode", render_mode, self.metadata["render_modes"])
            if self.core.config.decision == "once":
                raise ValueError(
                    f"render_mode={render_mode!r} is not allowed with decision='once': "
                    "render the per-interval env"
                )
        self.render_mode = render_mode
        self.observation_space, self.action_space = servo_spaces(self.core.config)
        once = self.core.config.decision == "once"
        self.decision: DecisionCore | None = DecisionCore(self.core) if once else None
        self._once_obs: np.ndarray | None = None
        self._w = np.zeros(self.core.width, dtype=np.float64)
        self._w0 = self._w.copy()
        self._ring = np.zeros(self.core.ring_len, dtype=np.float64)
        self._obs = slice(B.W_OBS, B.W_OBS + self.core.n_obs)
        self._obs32 = np.zeros(self.core.n_obs, dtype=np.float32)
        self._ep: Episode | None = None
        self._cmd: np.ndarray | None = None
        self._ended = False
        self._record: list[tuple[np.ndarray, int]] = []

    @property
    def episode(self) -> Episode | None:
        """The current episode (scenario, plant, command), or None before ``reset``."""
        return self._ep

    @property
    def accel_law(self) -> str:
        """The acceleration law the actions' settings use."""
        return self.core.accel_law

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Start an episode at rest, before the move's first control interval.

        Parameters
        ----------
        seed, options
            As :meth:`vfgym.envs.tune.VFTuneEnv.reset`.

        Returns
        -------
        tuple
            ``(observation, info)``: the interval's observation and ``{"scenario": name}``.
        """
        super().reset(seed=seed)
        ep = self.core.source.draw(self.np_random, options)
        self._ep = ep
        self._cmd = ep.command
        announce_compile("servo env", "VFServo-v0's step", _step_one)
        self._ended = False
        if self.decision is not None:
            self._once_obs = self.decision.reset(ep)
            return self._once_obs.copy(), {"scenario": ep.scenario.name}
        self.core.start(self._w, self._ring, self._cmd, ep)
        if self.render_mode is not None:
            self._w0 = self._w.copy()
            self._record = []
        return self._w[self._obs].astype(np.float32), {"scenario": ep.scenario.name}

    def step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        """Hold the settings the action maps to for one control interval of the move.

        Parameters
        ----------
        action : numpy.ndarray
            A point of ``[-1, 1]⁴``: value, L, k, Ts/Tf on the search space.

        Returns
        -------
        tuple
            ``(observation, reward, terminated, truncated, info)``; ``info`` holds the
            motor's continuous state (:data:`MOTOR_STATE`: angle, speed, torque applied;
            for evaluation, not in the observation) and, at the episode's end, the scored
            move's info.

        Raises
        ------
        gymnasium.error.ResetNeeded
            After the episode has ended (or before ``reset()``).
        ValueError
            If the action is not finite or outside the box.
        """
        if self._ended or self._cmd is None:
            raise gym.error.ResetNeeded(
                "call reset() before step(): "
                + ("the episode has ended" if self._ended else "no episode yet")
            )
        if self.decision is not None:
            a = np.asarray(action, dtype=np.float64)
            if a.shape != (5,):
                raise ValueError(f"action must hold 5 numbers in [-1, 1], got shape {a.shape}")
            if not B.action_ok(a):
                raise_bad_action(a, self.core.accel_law)
            self._ended = True
            reward, info = self.decision.decide(a)
            return np.array(self._once_obs, dtype=np.float32), reward, True, False, info
        a = action
        # the fast path takes a 1-D float64 array as it is (the kernel checks its length
        # and values); anything else goes through as_action, so that one kernel compiles
        # (float32 actions from SB3 convert exactly)
        if type(a) is not np.ndarray or a.ndim != 1 or a.dtype != np.float64:
            a = as_action(action)
        reward, flags = _step_one(a, self._w, self._ring, self._cmd, self._obs32)
        if flags & _BAD_ACTION:
            raise_bad_action(as_action(a), self.core.accel_law)
        if self.render_mode is not None:
            self._record.append((np.array(a, dtype=np.float64), int(self._w[B.X_TICK_END])))
        obs = self._obs32.copy()
        if not flags & _ENDED:
            return obs, reward, False, False, motor_state(self._w)
        self._ended = True
        reward, info = self.core.finish(self._w, self._ep, flags)
        return obs, reward, bool(flags & B.TERMINATED), bool(flags & B.TRUNCATED), info

    def render(self) -> np.ndarray | None:
        """The episode's move so far (the whole move once it has ended) as an RGB array.

        Returns
        -------
        numpy.ndarray or None
            (480, 640, 3) uint8, or ``None`` (with a warning) without a render mode.

        Raises
        ------
        gymnasium.error.ResetNeeded
            Before the first ``reset()``.
        """
        if self.render_mode is None:
            gym.logger.warn(
                "VFServo-v0.render() without a render_mode: make the env with "
                'render_mode="rgb_array"'
            )
            return None
        if self._ep is None:
            raise gym.error.ResetNeeded("call reset() before render()")
        from .render import move_picture

        ep = self._ep
        rec = self._replay()
        title = f"VFServo-v0, {ep.scenario.name}, {len(self._record)} steps"
        if rec.shape[1] == 0:
            return move_picture(
                ep.plant,
                ep.command,
                None,
                None,
                None,
                self.core.config.measures.accel_window_s,
                title,
            )
        return move_picture(
            ep.plant,
            rec[L.R_COMMAND],
            rec[L.R_PULSE],
            rec[L.R_THETA],
            rec[L.R_OMEGA],
            self.core.config.measures.accel_window_s,
            title,
        )

    def _replay(self) -> np.ndarray:
        """Every tick of the episode so far as trace rows (:func:`vfgym.envs.render.replay`)."""
        from .render import replay

        cmd = self._cmd if self._cmd is not None else np.zeros(0)
        ends = [i1 for _, i1 in self._record]
        if self._ended:
            ends[-1] = cmd.size
        return replay(self._w0, len(self._ring), cmd, [a for a, _ in self._record], ends)
