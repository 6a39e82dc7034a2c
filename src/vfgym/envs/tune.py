"""``vfgym/VFTune-v0``: choose the four settings for a whole move, in one step."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, ClassVar

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from vfgym._validate import check_choice, check_real
from vfgym.moves.features import OBS_BOUND, SCENARIO_FEATURES
from vfgym.moves.scenarios import Scenario
from vfgym.params import Measures, Settings
from vfgym.plant import simulate
from vfgym.scoring import (
    Bounds,
    CostWeights,
    Score,
    score_pairs,
)
from vfgym.space import SPACE, from_action, settings_to_dict, to_action

from . import _batch as B
from ._common import EnvConfig, Episode, as_action, scored_info


@dataclass(frozen=True)
class TuneConfig(EnvConfig):
    """VFTune-v0's arguments, every default here: :class:`EnvConfig`'s and its own;
    validated on construction.

    Parameters
    ----------
    scenario, split, seed_range, accel_law, axis, weights, bounds
        As :class:`vfgym.envs._common.EnvConfig`.
    residual, residual_scale, residual_base
        As :class:`vfgym.envs._common.EnvConfig` (``residual_base`` None: the paper's).
    violation_penalty : float
        Subtracted from the reward of a move that breaks a constraint (0: the reward is
        minus the cost alone), ≥ 0. The cost already grows with the acceleration over the
        limit, so an agent may find a move a little over it cheaper; a penalty makes
        feasibility worth more than that.

    Raises
    ------
    ValueError
        If an argument is of the wrong type or out of its range.
    """

    violation_penalty: float = 0.0

    def __post_init__(self) -> None:
        super().__post_init__()
        penalty = check_real("violation_penalty", self.violation_penalty, 0.0)
        object.__setattr__(self, "violation_penalty", penalty)

    def reward(self, cost: float, feasible: bool) -> float:
        """The reward of a scored move: minus its cost, minus ``violation_penalty`` if it
        broke a constraint."""
        return -cost - (0.0 if feasible else self.violation_penalty)


RESIDUAL_FEATURES = tuple(f"base_{d.name}" for d in SPACE)
"""The entries VFTune-v0's observation ends with under residual actions: the base setting
as an action in [-1, 1] (:func:`vfgym.space.to_action`)."""


def tune_spaces(residual: bool = False) -> tuple[spaces.Box, spaces.Box]:
    """(observation space, action space) of VFTune-v0 (``residual``: with residual
    actions, the observation ends with :data:`RESIDUAL_FEATURES`)."""
    n = len(SCENARIO_FEATURES) + (len(RESIDUAL_FEATURES) if residual else 0)
    obs = spaces.Box(-OBS_BOUND, OBS_BOUND, shape=(n,), dtype=np.float32)
    act = spaces.Box(-1.0, 1.0, shape=(len(SPACE),), dtype=np.float32)
    return obs, act


def action_settings(action: Any, accel_law: str) -> Settings:
    """The settings an action in [-1, 1]⁴ stands for (:func:`vfgym.space.from_action`);
    NaN, out-of-box or misshapen actions raise ``ValueError``."""
    return from_action(as_action(action), accel_law)


class ActionMap:
    """VFTune-v0's action → settings on one env's config: the search space's mapping, or
    with residual actions the offset from each move's base through the compiled mapping
    VFServo-v0 steps with (:func:`vfgym.envs._batch.map_action`, one core for both envs).

    Parameters
    ----------
    config : TuneConfig
        The env's arguments (``accel_law``, ``residual*``).
    """

    def __init__(self, config: TuneConfig) -> None:
        self.config = config
        self.residual = config.residual
        self._dims = B.space_table()
        self._scales = config.residual_scales()
        self._unit = np.zeros(len(SPACE))

    def base(self, ep: Episode) -> Settings | None:
        """The move's base setting under residual actions (None without)."""
        return self.config.base_settings(ep.scenario) if self.residual else None

    def features(self, ep: Episode, base: Settings | None) -> np.ndarray:
        """The observation of a move: its features, then (residual) the base as an action."""
        if base is None:
            return ep.features.astype(np.float32)
        return np.concatenate([ep.features, to_action(base)]).astype(np.float32)

    def settings(self, action: Any, base: Settings | None) -> Settings:
        """The settings an action stands for (on the move whose base is ``base``); NaN,
        out-of-box or misshapen actions raise ``ValueError``."""
        law = self.config.accel_law
        s = action_settings(action, law)  # checks the action
        if base is None:
            return s
        a = as_action(action)
        base_row = np.array([getattr(base, f) for f in B.SETTING_FIELDS])
        row = (a, self._dims, True, self._scales, base_row, self._unit)
        value, limit, k, ts = B.map_action(*row)
        return Settings(value_rad=value, error_limit_rad=limit, k=k, ts_over_tf=ts, accel_law=law)


class VFTuneEnv(gym.Env[np.ndarray, np.ndarray]):
    """Tune the V-F controller and the servo's filter for one move, in one step.

    ## Description

    Each episode is one move of the plant of docs/model.md (V-F controller → digital servo →
    motor): ``reset`` picks a scenario (a command profile and the load on the motor), the
    agent answers with the four settings, and ``step`` simulates the whole move tick by tick
    and scores it through :func:`vfgym.evaluate`, the one scoring path, so the reward is
    exactly minus the cost that the Optuna sweeps and the evaluation reports see.

    ## Action Space

    ``Box(-1, 1, (4,), float32)``: value, error limit L, k and Ts/Tf, each mapped onto its
    range by the search space (:data:`vfgym.space.SPACE`, log scales for ranges spanning
    decades): value and L in [0.05, 10] rad, k in [1, 10⁴], Ts/Tf in [0.02, 1]. The
    acceleration law is the ``accel_law`` argument. NaN or out-of-box actions raise
    ``ValueError``. With ``residual=True`` the action is instead an offset from a base
    setting (``residual_base``: the paper's by default, fixed settings, or a per-move
    model's), as VFServo-v0's residual actions and through the same compiled mapping: an
    offset of ``residual_scale`` × the action in :class:`vfgym.space.Relative`'s
    coordinates (value, L/value, k, Ts/Tf on log scales), so the zero action gives the base
    exactly.

    ## Observation Space

    ``Box(-10, 10, (19,), float32)``, the move and its plant, normalised (each clipped);
    with residual actions ``(23,)``, entries 19-22 the base setting as an action
    (:data:`RESIDUAL_FEATURES`):

    | index | name | definition |
    |---|---|---|
    | 0 | direction | sign of the (largest) move |
    | 1 | log_distance | log10(\\|move\\| / 1 rad) / 2 |
    | 2 | log_ideal_time | log10(ideal move time / 1 ms) / 2 |
    | 3 | time_budget | simulated duration / ideal time / 10 |
    | 4-9 | profile_* | one-hot: step, sine, ramp, trapezoid, scurve, multi |
    | 10 | moves | point-to-point moves / 5 |
    | 11 | profile_speed | profile cruise speed / δ·f |
    | 12 | profile_accel | profile acceleration / motor limit |
    | 13 | sine_freq | sine frequency / 100 Hz (0 otherwise) |
    | 14 | inertia_ratio | load / rotor inertia, / 5 |
    | 15 | coulomb | Coulomb friction / 4 mN·m |
    | 16 | viscous | viscous friction / 0.3 mN·m·s/rad |
    | 17 | load_torque | load torque / 4 mN·m |
    | 18 | torque_accel | peak torque / (J · acceleration limit) |

    ## Rewards

    ``-cost`` of the move from :func:`vfgym.evaluate` (lower cost is better; a perfect
    point-to-point move costs about 1): move time / ideal time (or RMS tracking error for a
    moving reference) plus weighted overshoot, acceleration over the limit, time at the
    torque limit and, for a move that does not arrive (not settled in the in-position
    window at its end, or a sine not followed), a penalty growing with the distance left
    (:class:`vfgym.CostWeights`, :mod:`vfgym.scoring`). ``info`` carries every measure of
    :mod:`vfgym.plant.measures`, ``ideal_time_s``, ``time_ratio``, ``window_rad``,
    ``arrived``, ``cost``, the constraint values ``constraint_accel``,
    ``constraint_torque``, ``constraint_overshoot``, ``constraint_arrival`` (feasible when
    ≤ 0), ``feasible``, ``scenario`` and the settings used. With ``violation_penalty`` > 0
    a move that breaks a constraint is rewarded ``-cost - violation_penalty``; ``info``'s
    cost is the cost alone.

    ## Starting State

    A scenario: the ``scenario`` argument or ``options={"scenario": name}`` if given,
    ``options={"scenario_seed": s}`` for a seed of the split, else a seed drawn from the
    env's ``np_random`` in ``seed_range`` and that seed's move of the axis's move set for
    the split (by default :data:`vfgym.axis.LOADS_AXIS`'s: ``random_scenario(seed, split)``).
    Train and test scenarios never coincide. The plant starts at rest at 0.

    ## Episode End

    Always after one step (``terminated=True``); stepping again needs ``reset()``.

    ## Arguments

    ``gymnasium.make("vfgym/VFTune-v0", scenario=None, split="train", seed_range=None,
    accel_law="rise", axis=LOADS_AXIS, weights=DEFAULT_WEIGHTS, bounds=DEFAULT_BOUNDS,
    render_mode=None)``; see
    Parameters.

    ``gymnasium.make_vec("vfgym/VFTune-v0", num_envs=N)`` gives
    :class:`vfgym.envs.vector.VFTuneVectorEnv`, which scores all N moves in one compiled
    call.

    ## Version History

    * v0: Initial version.

    Parameters
    ----------
    scenario : str, Scenario or None
        A fixed scenario (name such as ``"paper-step"`` or ``"test-7"``, or a
        :class:`vfgym.Scenario`); ``None`` draws one per episode.
    render_mode : str or None
        ``"rgb_array"`` draws the last move (position, speed, acceleration, command
        against motor) as an (480, 640, 3) uint8 array.
    **options
        The other fields of :class:`TuneConfig`, where their defaults live and are
        checked: ``split`` (``"train"`` or ``"test"``), ``seed_range``
        ((low, high) of the scenario seeds), ``accel_law`` (``"rise"`` or ``"slew"``),
        ``axis`` (the problem, a :class:`vfgym.axis.Axis` or an axis file's path: its
        plant, measures and move sets), the scoring path's inputs ``weights``,
        ``bounds`` (:func:`vfgym.evaluate`), and ``residual``,
        ``residual_scale``, ``residual_base`` (residual actions),
        ``violation_penalty``.

    Raises
    ------
    ValueError
        If an argument is out of its range or of the wrong type.
    TypeError
        If an option is not a field of :class:`TuneConfig`.
    """

    metadata: ClassVar[dict[str, Any]] = {"render_modes": ["rgb_array"], "render_fps": 4}

    def __init__(
        self,
        scenario: str | Scenario | None = None,
        *,
        render_mode: str | None = None,
        **options: Any,
    ) -> None:
        self.config = TuneConfig(scenario, **options)
        self.accel_law = self.config.accel_law
        if render_mode is not None:
            check_choice("render_mode", render_mode, self.metadata["render_modes"])
        self.render_mode = render_mode
        self.source = self.config.scenario_source()
        self.observation_space, self.action_space = tune_spaces(self.config.residual)
        self.action_map = ActionMap(self.config)
        self._base: Settings | None = None
        self._ep: Episode | None = None
        self._settings: Settings | None = None
        self._done = False

    @property
    def episode(self) -> Episode | None:
        """The current episode (scenario, plant, command), or None before ``reset``."""
        return self._ep

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Start an episode: draw (or take) the scenario of the move.

        Parameters
        ----------
        seed : int or None
            Seeds the env's ``np_random`` (the scenario draws), as Gymnasium does.
        options : dict or None
            ``{"scenario": name or Scenario}`` for a given scenario, or
            ``{"scenario_seed": s}`` for a seed of the env's split.

        Returns
        -------
        tuple
            ``(observation, info)``: the move's features (float32) and
            ``{"scenario": name}``.
        """
        super().reset(seed=seed)
        self._ep = self.source.draw(self.np_random, options)
        self._base = self.action_map.base(self._ep)
        self._settings = None
        self._done = False
        obs = self.action_map.features(self._ep, self._base)
        return obs, {"scenario": self._ep.scenario.name}

    def settings_of(self, action: Any) -> Settings:
        """The settings an action stands for on the current move (with residual actions,
        the offset from its base).

        Parameters
        ----------
        action : array-like
            A point of ``[-1, 1]⁴``.

        Returns
        -------
        Settings
            The settings ``step`` would simulate.

        Raises
        ------
        gymnasium.error.ResetNeeded
            Before ``reset()``.
        ValueError
            If the action is not finite or outside the box.
        """
        if self._ep is None:
            raise gym.error.ResetNeeded("call reset() before settings_of()")
        return self.action_map.settings(action, self._base)

    def step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        """Simulate the whole move with the settings the action maps to, and score it.

        Parameters
        ----------
        action : numpy.ndarray
            A point of ``[-1, 1]⁴``: value, L, k, Ts/Tf on the search space.

        Returns
        -------
        tuple
            ``(observation, reward, terminated, truncated, info)``: the same features,
            minus the move's cost, ``True``, ``False``, and the scored move's info.

        Raises
        ------
        gymnasium.error.ResetNeeded
            When the episode's one step has been taken (or before ``reset()``).
        ValueError
            If the action is not finite or outside the box.
        """
        if self._ep is None or self._done:
            raise gym.error.ResetNeeded(
                "VFTune-v0 episodes are one step long: call reset() before step()"
            )
        ep = self._ep
        settings = self.action_map.settings(action, self._base)
        c = self.config
        # the episode as the vector env scores it: on its true plant where it has one
        (res,) = evaluate_pairs(
            [settings], [ep], measures=c.measures, weights=c.weights, bounds=c.bounds
        )
        cost = float(res.cost)
        info = scored_info(ep, res.metrics, cost, res.constraints)
        info.update(settings_to_dict(settings))
        self._settings = settings
        self._done = True
        reward = c.reward(cost, info["feasible"])
        return self.action_map.features(ep, self._base), reward, True, False, info

    def render(self) -> np.ndarray | None:
        """The last move (or, before a step, the command) as an RGB array.

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
                "VFTune-v0.render() without a render_mode: make the env with "
                'render_mode="rgb_array"'
            )
            return None
        if self._ep is None:
            raise gym.error.ResetNeeded("call reset() before render()")
        from .render import move_picture

        ep = self._ep
        title = f"VFTune-v0, {ep.scenario.name}"
        if self._settings is None:
            return move_picture(
                ep.plant, ep.command, None, None, None, self.config.measures.accel_window_s, title
            )
        tr = simulate(ep.command, self._settings, ep.plant, measures=self.config.measures)
        s = self._settings
        title += f": value {s.value_rad:.3g}, L {s.error_limit_rad:.3g}, k {s.k:.3g}, "
        title += f"Ts/Tf {s.ts_over_tf:.3g}"
        return move_picture(
            ep.plant,
            tr.command_rad,
            tr.pulse_rad,
            tr.motor_rad,
            tr.speed_rad_s,
            self.config.measures.accel_window_s,
            title,
        )


def evaluate_pairs(
    settings: Sequence[Settings],
    episodes: Sequence[Episode],
    *,
    measures: Measures,
    weights: CostWeights,
    bounds: Bounds,
    while_running: Callable[[], None] | None = None,
) -> list[Score]:
    """Score ``settings[i]`` on ``episodes[i]`` for every i in one compiled, multi-threaded
    call: :func:`vfgym.scoring.score_pairs`, the pairwise core of :func:`vfgym.evaluate`;
    ``while_running`` runs beside the compiled call (see there).

    Returns
    -------
    list of Score
        One per pair (V-F settings run every move).
    """
    results = score_pairs(
        list(settings),
        list(episodes),
        measures=measures,
        weights=weights,
        bounds=bounds,
        while_running=while_running,
    )
    return [r for r in results if r is not None]
