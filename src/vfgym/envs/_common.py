"""What both environments share: where an episode's scenario comes from, the features that
describe a move and its plant, reset options, and the info of a scored move."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from vfgym._validate import check_choice, check_int, check_real
from vfgym.axis import LOADS_AXIS, NOMINAL, Axis, PlantVariant, as_axis, draw_plant
from vfgym.moves.features import main_move, scenario_features
from vfgym.moves.scenarios import SPLITS, Scenario
from vfgym.params import (
    ACCEL_LAWS,
    PAPER_SETTINGS,
    Measures,
    Plant,
    Settings,
)
from vfgym.scoring import (
    CONSTRAINTS,
    DEFAULT_BOUNDS,
    DEFAULT_WEIGHTS,
    Bounds,
    CostWeights,
    Yardsticks,
    yardsticks,
)

SEED_LIMIT = 2**63 - 1
"""Scenario seeds are whole numbers in [0, SEED_LIMIT) (as :func:`vfgym.random_scenario`)."""
DEFAULT_SEED_RANGE = (0, 2**31)

# VFServo-v0's own defaults, shared by the single and the vector env
SERVO_INTERVAL_S = 1e-3
"""Control interval: the settings may change every 1 ms (140 ticks at 140 kHz)."""
SERVO_SETTLE_TIME_S = 5e-3
"""The episode ends once the motor has stayed in position this long after the command."""
SERVO_TRACKING_WEIGHT = 0.0
"""Weight of the per-interval tracking-error shaping term (0: the return is −cost)."""
SERVO_VIOLATION_PENALTY = 5.0
"""Subtracted at a constraint violation when ``terminate_on_violation`` is on."""
RESIDUAL_SCALE = 0.25
"""With residual actions, an action of ±1 moves each coordinate of
:class:`vfgym.space.Relative` this many half ranges from its base: an eighth of its (log)
range either way (both envs)."""
RESET_OPTIONS = ("scenario", "scenario_seed", "plant")

SETTING_FIELDS = ("value_rad", "error_limit_rad", "k", "ts_over_tf")
"""The order in which the compiled step reads the search space's dimensions."""


def space_table() -> np.ndarray:
    """(action index, low, high, log, width) of each setting in :data:`SETTING_FIELDS`
    order: the range read from :data:`vfgym.space.SPACE`, a log dimension's low and high
    as their logarithms (the very numbers ``from_unit`` computes, so the compiled mapping
    stays bit for bit the search space's), and the width of its axis in
    :class:`vfgym.space.Relative`, in which residual actions are offsets (L's axis is
    L/value: :func:`vfgym.envs._batch.map_action`)."""
    from vfgym.space import SPACE, Relative

    names = [d.name for d in SPACE]
    if sorted(names) != sorted(SETTING_FIELDS):
        raise RuntimeError(f"the search space {names} is not the four settings {SETTING_FIELDS}")
    if not all(d.log for d in SPACE):  # Relative's coordinates are logarithms
        raise RuntimeError("residual actions need every setting on a log scale in SPACE")
    widths = dict(zip(names, Relative.widths(), strict=True))
    rows = []
    for f in SETTING_FIELDS:
        d = SPACE[names.index(f)]
        rows.append((float(names.index(f)), math.log(d.low), math.log(d.high), 1.0, widths[f]))
    return np.array(rows, dtype=np.float64).reshape(-1)


@dataclass(frozen=True)
class Episode:
    """A scenario made ready to simulate: its (true) plant, command and yardsticks.

    On an axis with uncertainty ``plant`` is the episode's true plant (``variant`` of the
    modelled one, ``model``): the move is simulated and scored on it, while its command,
    its features (the observation) and the controllers' settings are the modelled plant's,
    as a controller knows it.
    """

    scenario: Scenario
    plant: Plant
    command: np.ndarray
    target_rad: float
    command_end_s: float
    command_end_tick: int
    """Ticks after which the command is at its final value (0 if it never changes)."""
    ideal_time_s: float
    window_rad: float
    scale_rad: float
    features: np.ndarray
    yardsticks: Yardsticks
    """What the scoring path judges the move against (ideal time, window, ...)."""
    variant: PlantVariant = NOMINAL
    model: Plant | None = None
    """The modelled plant where ``plant`` is a true plant that differs from it."""

    @classmethod
    def make(
        cls, sc: Scenario, base: Plant, measures: Measures, variant: PlantVariant = NOMINAL
    ) -> Episode:
        model = sc.plant(base)
        plant = variant.apply(model)
        if sc.ideal_time_s(plant) <= 0.0:
            raise ValueError(
                f"scenario={sc.name!r} has no move (distance 0): nothing to tune or score"
            )
        cmd = sc.command(model)
        target = float(cmd[-1])
        y = yardsticks(sc, plant, measures, cmd)
        window = y.window_rad
        scale = max(abs(main_move(sc, plant)), abs(target), window, 1e-9)
        # the last change of the command: the first tick of its final run of equal values
        # (the plant is at 0 before tick 0); as vfgym.simulate.command_end_s finds it
        off = np.flatnonzero(cmd != target)
        last = int(off[-1]) + 1 if off.size else (0 if target != 0.0 else -1)
        return cls(
            scenario=sc,
            plant=plant,
            command=cmd,
            target_rad=target,
            command_end_s=float(last) / plant.tick_hz if last >= 0 else 0.0,
            command_end_tick=last + 1,
            ideal_time_s=y.ideal_time_s,
            window_rad=window,
            scale_rad=scale,
            features=scenario_features(sc, base, model),
            yardsticks=y,
            variant=variant,
            model=None if variant.nominal else model,
        )


class ScenarioSource:
    """Where each episode's scenario comes from: a fixed one, or seeded draws from one
    split (train or test) of the axis's move sets (:meth:`vfgym.axis.MoveSet.pick`),
    seeds in ``seed_range`` = [lo, hi); names resolved by :meth:`vfgym.axis.Axis.scenario`.
    On an axis with uncertainty, each episode's true plant is drawn within it."""

    def __init__(
        self,
        scenario: str | Scenario | None,
        split: str,
        seed_range: tuple[int, int] | None,
        axis: Axis,
    ) -> None:
        check_choice("split", split, SPLITS)
        lo, hi = DEFAULT_SEED_RANGE if seed_range is None else _check_range(seed_range)
        self.split = split
        self.seed_range = (lo, hi)
        self.axis = axis
        self.base = axis.plant
        self.measures = axis.measures
        self.uncertainty = axis.uncertainty
        self.fixed = None if scenario is None else self._named(scenario)
        self._cache: dict[tuple[Scenario, PlantVariant], Episode] = {}
        if self.fixed is not None:
            self.episode(self.fixed)  # a bad scenario fails here, not at reset

    def episode(self, sc: Scenario, variant: PlantVariant = NOMINAL) -> Episode:
        """The (cached) episode data of a scenario on a true plant (default: as modelled)."""
        key = (sc, variant)
        ep = self._cache.get(key)
        if ep is None:
            if len(self._cache) >= 64:
                self._cache.clear()
            ep = self._cache[key] = Episode.make(sc, self.base, self.measures, variant)
        return ep

    def draw(self, rng: np.random.Generator, options: dict[str, Any] | None) -> Episode:
        """The next episode: from ``options`` if they name one, else fixed, else drawn; on
        an axis with uncertainty its true plant drawn within it after the move (or
        ``options["plant"]``, a :class:`~vfgym.axis.PlantVariant`)."""
        opts = check_options(options)
        if "scenario" in opts:
            sc = self._named(opts["scenario"])
        elif "scenario_seed" in opts:
            seed = check_int("scenario_seed", opts["scenario_seed"], 0, SEED_LIMIT - 1)
            sc = self.seeded(seed)
        elif self.fixed is not None:
            sc = self.fixed
        else:
            sc = self.seeded(int(rng.integers(self.seed_range[0], self.seed_range[1])))
        if "plant" in opts:
            return self.episode(sc, opts["plant"])
        return self.episode(sc, draw_plant(self.uncertainty, self.base, rng))

    def _named(self, scenario: Any) -> Scenario:
        return self.axis.scenario(_check_scenario(scenario))

    def seeded(self, seed: int) -> Scenario:
        """The scenario a draw of ``seed`` gives (on the source's split and axis)."""
        return self.axis.moves.of(self.split).pick(seed, self.split, self.base)


@dataclass(frozen=True)
class EnvConfig:
    """The arguments both envs take (VFTune-v0's all of them), every default here.

    Validated on construction, except the scenario and its draws, which
    :meth:`scenario_source` checks. The ``axis`` is resolved here, once: an axis file's
    path is loaded, and afterwards ``axis`` is the :class:`~vfgym.axis.Axis`, whose plant
    and measures (:attr:`plant`, :attr:`measures`) the env scores with.

    Parameters
    ----------
    scenario : str, Scenario or None
        A fixed scenario (a name such as ``"paper-step"`` or ``"test-7"``, or a
        :class:`vfgym.Scenario`); ``None`` draws one per episode.
    split : str
        ``"train"`` or ``"test"``, the random distribution's split (on an axis, its move
        set) to draw from.
    seed_range : tuple of (int, int) or None
        (low, high): scenario seeds drawn in [low, high) (default [0, 2³¹)).
    accel_law : str
        ``"rise"`` (the paper's reading) or ``"slew"``.
    axis : Axis, str or os.PathLike
        The problem (:class:`vfgym.axis.Axis`, or an axis file's path, loaded here): its
        plant and measures, and the moves of each split from its move sets (a random
        set's draws, or a listed set's move ``seed mod len``); names resolve on the axis.
        Default: :data:`vfgym.axis.LOADS_AXIS`, the paper's plant under a random load per
        move (``experiments/axes/loads.yaml``, the distribution the agents learn across).
    weights : CostWeights
        Weights of the cost.
    bounds : Bounds
        Bounds of the constraints.
    residual : bool
        Residual actions: the action times ``residual_scale`` is an offset from the base
        setting in :class:`vfgym.space.Relative`'s coordinates (the logarithms of the
        value, L/value, k and Ts/Tf; ±1 moves one by ``residual_scale`` times half its
        range): L keeps the base's L/value as the value moves, so a base with L = value
        (the cost's ridge, docs/model.md §1) keeps it bit for bit. The zero action gives
        the base setting exactly (VFServo-v0: the base is also in force before the first
        action; VFTune-v0: the observation ends with the base as an action, 4 more
        entries).
    residual_scale : float or tuple of 4 floats
        The largest offset of a residual action, in half ranges: one for every setting,
        in (0, 2], or one per setting in the action's order (value, L/value, k, Ts/Tf),
        each in [0, 2] (0 holds that coordinate at its base).
    residual_base : Settings, callable or None
        The base of residual actions: fixed settings, a callable ``(scenario, plant) ->
        Settings`` giving each move's (a per-move settings model; asked with ``plant``,
        before the move's load), or None for the env's default (:meth:`default_base`).
        Its law is replaced by ``accel_law``.

    Raises
    ------
    ValueError
        If an argument is of the wrong type or out of its range, or the axis file is bad.
    """

    scenario: str | Scenario | None = None
    split: str = "train"
    seed_range: tuple[int, int] | None = None
    accel_law: str = "rise"
    axis: Axis = LOADS_AXIS  # (an axis file's path is loaded on construction)
    weights: CostWeights = DEFAULT_WEIGHTS
    bounds: Bounds = DEFAULT_BOUNDS
    residual: bool = False
    residual_scale: float | tuple[float, ...] = RESIDUAL_SCALE
    residual_base: Settings | Callable[[Scenario, Plant], Settings] | None = None

    def __post_init__(self) -> None:
        s = object.__setattr__
        s(self, "axis", as_axis(self.axis))
        check_scoring(self.weights, self.bounds)
        s(self, "accel_law", check_choice("accel_law", self.accel_law, ACCEL_LAWS))
        if not isinstance(self.residual, bool):
            raise ValueError(f"residual={self.residual!r} must be a bool")
        scale = self.residual_scale
        if isinstance(scale, (list, tuple)):
            if len(scale) != 4:
                raise ValueError(
                    f"residual_scale={scale!r} is not allowed: one number, or 4 (value, L, "
                    "k, Ts/Tf)"
                )
            scale = tuple(
                check_real(f"residual_scale[{i}]", x, 0.0, 2.0) for i, x in enumerate(scale)
            )
        else:
            scale = check_real("residual_scale", scale, 0.0, 2.0, lo_open=True)
        s(self, "residual_scale", scale)
        base = self.residual_base
        if isinstance(base, Settings):
            s(self, "residual_base", base.replace(accel_law=self.accel_law))
        elif base is not None and not callable(base):
            raise ValueError(
                f"residual_base={base!r} must be a vfgym.Settings, a callable "
                "(scenario, plant) -> Settings, or None"
            )

    @property
    def plant(self) -> Plant:
        """The axis's plant: the base each scenario applies its load to."""
        return self.axis.plant

    @property
    def measures(self) -> Measures:
        """The axis's windows and bands of the measures."""
        return self.axis.measures

    def residual_scales(self) -> np.ndarray:
        """Each setting's ``residual_scale``, in the compiled mapping's order.

        Returns
        -------
        numpy.ndarray
            float, one per setting (value, L, k, Ts/Tf: ``SETTING_FIELDS``).
        """
        from vfgym.space import SPACE

        scale = self.residual_scale
        per = scale if isinstance(scale, tuple) else (scale,) * len(SPACE)
        by_name = {d.name: float(x) for d, x in zip(SPACE, per, strict=True)}
        return np.array([by_name[f] for f in SETTING_FIELDS])

    def default_base(self) -> Settings:
        """The base of residual actions when ``residual_base`` is None.

        Returns
        -------
        Settings
            The paper's settings, under ``accel_law``.
        """
        return PAPER_SETTINGS.replace(accel_law=self.accel_law)

    def base_settings(self, scenario: Scenario) -> Settings:
        """The base of residual actions on a move of ``scenario`` (without residual
        actions, :meth:`default_base`); a per-move base is asked with the env's plant
        (before the scenario's load, as a settings model takes it).

        Parameters
        ----------
        scenario : Scenario
            The move.

        Returns
        -------
        Settings
            The base, under ``accel_law``.

        Raises
        ------
        ValueError
            If a per-move base returns something other than a :class:`vfgym.Settings`.
        """
        base = self.residual_base
        if not self.residual or base is None:
            return self.default_base()
        if isinstance(base, Settings):
            return base
        out = base(scenario, self.plant)
        if not isinstance(out, Settings):
            raise ValueError(
                f"residual_base returned {out!r} for scenario {scenario.name!r}: "
                "expected vfgym.Settings"
            )
        return out.replace(accel_law=self.accel_law)

    def scenario_source(self) -> ScenarioSource:
        """Where the episodes' scenarios come from.

        Returns
        -------
        ScenarioSource
            On the axis's move sets.

        Raises
        ------
        ValueError
            If the scenario, split or seed range is bad (raised by :class:`ScenarioSource`).
        """
        return ScenarioSource(self.scenario, self.split, self.seed_range, self.axis)


def _check_scenario(sc: Any) -> str | Scenario:
    if not isinstance(sc, (str, Scenario)):
        raise ValueError(
            f"scenario={sc!r} is not allowed: give a scenario name (e.g. 'paper-step', "
            "'train-3') or a vfgym.Scenario"
        )
    return sc


def _check_range(seed_range: Any) -> tuple[int, int]:
    try:
        lo, hi = seed_range
    except (TypeError, ValueError):
        raise ValueError(
            f"seed_range={seed_range!r} is not allowed: give (low, high), whole numbers with "
            f"0 <= low < high <= {SEED_LIMIT}"
        ) from None
    lo = check_int("seed_range[0]", lo, 0, SEED_LIMIT - 1)
    hi = check_int("seed_range[1]", hi, lo + 1, SEED_LIMIT)
    return lo, hi


def check_options(options: Any) -> dict[str, Any]:
    """Reset options: ``scenario`` (a name or Scenario) or ``scenario_seed`` (a seed of the
    env's split); unknown keys raise ``ValueError``."""
    if options is None:
        return {}
    if not isinstance(options, dict):
        raise ValueError(f"options={options!r} must be a dict (or None)")
    unknown = sorted(set(options) - set(RESET_OPTIONS), key=str)
    if unknown:
        raise ValueError(
            f"options has unknown key(s) {', '.join(map(repr, unknown))}: allowed "
            f"{', '.join(RESET_OPTIONS)}"
        )
    if "scenario" in options and "scenario_seed" in options:
        raise ValueError("options: give either 'scenario' or 'scenario_seed', not both")
    if "plant" in options and not isinstance(options["plant"], PlantVariant):
        raise ValueError(
            f"options['plant']={options['plant']!r} must be a "
            "vfgym.axis.PlantVariant (the episode's true plant)"
        )
    return options


def check_scoring(weights: Any, bounds: Any) -> None:
    """The scoring path's weights and bounds have the right types."""
    for name, value, kind in (("weights", weights, CostWeights), ("bounds", bounds, Bounds)):
        if not isinstance(value, kind):
            raise ValueError(f"{name}={value!r} must be a vfgym {kind.__name__}")


def as_action(action: Any) -> np.ndarray:
    """An action as a float64 array of 4 numbers (range checks are the caller's)."""
    try:
        a = np.asarray(action, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"action={action!r} is not allowed: give 4 numbers in [-1, 1]") from None
    if a.shape != (4,):
        raise ValueError(f"action must hold 4 numbers in [-1, 1], got shape {a.shape}")
    return a


def scored_info(
    ep: Episode, metrics: dict[str, Any], cost: float, constraints: np.ndarray
) -> dict[str, Any]:
    """The info of a scored move: the scenario, every measure, the cost and each
    constraint value (feasible when ≤ 0)."""
    info: dict[str, Any] = {"scenario": ep.scenario.name}
    if not ep.variant.nominal:  # for evaluation only: a controller does not know it
        info["true_plant"] = ep.variant
    info.update(metrics)
    info["cost"] = float(cost)
    for name, value in zip(CONSTRAINTS, constraints, strict=True):
        info[f"constraint_{name}"] = float(value)
    info["feasible"] = bool(np.all(np.asarray(constraints) <= 0.0))
    return info
