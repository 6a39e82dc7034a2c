"""The search space of the tuned settings, defined once.

It drives Optuna's suggestions (:func:`suggest`), the agents' action scaling
(:func:`from_action` maps a point of [−1, 1]⁴ onto the settings, :func:`to_action` back),
the exhaustive grid (:func:`grid`) and the checks on settings files. Ranges spanning
decades are searched on a log scale. :class:`Relative` is the settings' one coordinate
system where the problem's shape matters (L relative to the value, k to the acceleration
limit's): the compass sampler, the settings models and the envs' residual actions.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from vfgym._validate import check_choice, check_int
from vfgym.params import ACCEL_LAWS, Settings

if TYPE_CHECKING:
    from optuna import Trial
    from optuna.distributions import BaseDistribution


@dataclass(frozen=True)
class Dim:
    """One tuned setting: its name in :class:`vfgym.Settings`, range and scale."""

    name: str
    low: float
    high: float
    log: bool
    doc: str

    def from_unit(self, u: float) -> float:
        """Map u ∈ [−1, 1] onto [low, high] (log-linearly if ``log``)."""
        t = (min(max(float(u), -1.0), 1.0) + 1.0) / 2.0
        if self.log:
            return float(
                math.exp(math.log(self.low) + t * (math.log(self.high) - math.log(self.low)))
            )
        return self.low + t * (self.high - self.low)

    def to_unit(self, x: float) -> float:
        """The inverse of :meth:`from_unit` (clipped to [−1, 1])."""
        if self.log:
            t = (math.log(x) - math.log(self.low)) / (math.log(self.high) - math.log(self.low))
        else:
            t = (x - self.low) / (self.high - self.low)
        return min(max(2.0 * t - 1.0, -1.0), 1.0)


SPACE: tuple[Dim, ...] = (
    Dim("value_rad", 0.05, 10.0, True, "V-F threshold value (rad)"),
    Dim("error_limit_rad", 0.05, 10.0, True, "error limit L (rad)"),
    Dim("k", 1.0, 10_000.0, True, "acceleration ratio k"),
    Dim("ts_over_tf", 0.02, 1.0, True, "servo filter ratio A = Ts/Tf"),
)
"""The four continuous settings; the acceleration law is a categorical choice."""

NAMES = tuple(d.name for d in SPACE)


def from_action(action: Any, accel_law: str = "rise") -> Settings:
    """Settings for an action in [−1, 1]⁴ (order: value, error limit, k, Ts/Tf)."""
    a = np.asarray(action, dtype=np.float64).reshape(-1)
    if a.shape != (len(SPACE),):
        raise ValueError(f"action must hold {len(SPACE)} numbers, got shape {np.shape(action)}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"action={a.tolist()} is out of range: allowed finite values in [-1, 1]")
    if np.any(np.abs(a) > 1.0 + 1e-6):
        raise ValueError(f"action={a.tolist()} is out of range: allowed [-1, 1] per entry")
    check_choice("accel_law", accel_law, ACCEL_LAWS)
    return Settings(
        **{d.name: d.from_unit(x) for d, x in zip(SPACE, a, strict=True)}, accel_law=accel_law
    )


def to_action(settings: Settings) -> np.ndarray:
    """The action in [−1, 1]⁴ that gives these settings (clipped to the space)."""
    return np.array([d.to_unit(getattr(settings, d.name)) for d in SPACE], dtype=np.float32)


def suggest(trial: Trial, laws: tuple[str, ...] = ("rise",)) -> Settings:
    """Settings suggested by an Optuna trial over :data:`SPACE` (and the law, if several)."""
    kw: dict[str, Any] = {
        d.name: trial.suggest_float(d.name, d.low, d.high, log=d.log) for d in SPACE
    }
    law = trial.suggest_categorical("accel_law", list(laws)) if len(laws) > 1 else laws[0]
    return Settings(**kw, accel_law=law)


def distributions(laws: tuple[str, ...] = ("rise",)) -> dict[str, BaseDistribution]:
    """Optuna distributions of the space (for enqueueing and grid samplers)."""
    import optuna

    out: dict[str, BaseDistribution] = {
        d.name: optuna.distributions.FloatDistribution(d.low, d.high, log=d.log) for d in SPACE
    }
    if len(laws) > 1:
        out["accel_law"] = optuna.distributions.CategoricalDistribution(list(laws))
    return out


def grid(
    points: int | dict[str, int] = 8,
    laws: tuple[str, ...] = ("rise",),
    fixed: dict[str, float] | None = None,
) -> list[Settings]:
    """A dense grid over the space: ``points`` values per dimension (log-spaced where the
    dimension is), every combination, for each law; ``fixed`` pins dimensions."""
    fixed = fixed or {}
    axes = []
    for d in SPACE:
        if d.name in fixed:
            axes.append([fixed[d.name]])  # Settings checks it (a string is not a number)
            continue
        n = check_int("points", points.get(d.name, 8) if isinstance(points, dict) else points, 1)
        u = np.linspace(-1.0, 1.0, max(1, n)) if n > 1 else np.array([0.0])
        axes.append([d.from_unit(x) for x in u])
    return [
        Settings(**dict(zip(NAMES, combo, strict=True)), accel_law=law)
        for law in laws
        for combo in itertools.product(*axes)
    ]


@dataclass(frozen=True)
class Relative:
    """The tuned settings' one coordinate system: the compass sampler searches its unit
    coordinates, the settings models learn its log coordinates (``k_ref`` the move's
    usable k: :mod:`vfgym.permove.targets`) and the envs' residual actions are offsets in
    it (:mod:`vfgym.envs`).

    The optimum sits on the acceleration limit, with the error limit tied to ``value``
    (the paper: most efficient when equal; below it, the top speed drops to L/value of
    δ·f). So ``k`` is taken relative to ``k_ref`` (the limit's k,
    :func:`vfgym.params.usable_k`) and ``L`` relative to ``value``; all four on log scales:

    ======  ====================  =====================================
    axis    coordinate            range
    ======  ====================  =====================================
    0       value_rad             :data:`SPACE`'s (0.05 – 10 rad)
    1       L / value             :data:`LIMIT_RATIO` (0.05 – 20)
    2       k / k_ref             :data:`SPACE`'s k range over ``k_ref``
    3       ts_over_tf            :data:`SPACE`'s (0.02 – 1)
    ======  ====================  =====================================

    Log coordinates are the natural logarithms of the four; unit coordinates u ∈ [0, 1]⁴
    map each range log-linearly. The settings a point stands for are clipped to
    :data:`SPACE` (L = ratio · value may leave it).
    """

    k_ref: float

    def __post_init__(self) -> None:
        if not (math.isfinite(self.k_ref) and self.k_ref > 0.0):
            raise ValueError(f"k_ref={self.k_ref!r} is out of range: allowed finite > 0")

    def bounds(self) -> np.ndarray:
        """(4, 2) array of the natural-log bounds of each axis."""
        v, _, k, a = SPACE
        return np.log(
            [
                [v.low, v.high],
                list(LIMIT_RATIO),
                [k.low / self.k_ref, k.high / self.k_ref],
                [a.low, a.high],
            ]
        )

    @staticmethod
    def widths() -> np.ndarray:
        """(4,) the width of each axis's log range (k's does not depend on ``k_ref``):
        the envs' residual actions move a coordinate by up to half of it times its scale."""
        b = Relative(1.0).bounds()
        return b[:, 1] - b[:, 0]

    def to_log(self, s: Settings) -> np.ndarray:
        """The log coordinates of ``s``: ln value, ln(L/value), ln(k/k_ref), ln Ts/Tf (not
        clipped); what the settings models learn (:mod:`vfgym.permove.targets`)."""
        return np.log(
            [s.value_rad, s.error_limit_rad / s.value_rad, s.k / self.k_ref, s.ts_over_tf]
        )

    def to_unit(self, s: Settings) -> np.ndarray:
        """The unit coordinates of ``s`` (clipped to [0, 1]⁴)."""
        b = self.bounds()
        return np.clip((self.to_log(s) - b[:, 0]) / (b[:, 1] - b[:, 0]), 0.0, 1.0)

    def from_log(self, x: Any, accel_law: str = "rise") -> Settings:
        """The settings at log coordinates ``x``, clipped to SPACE: the inverse of
        :meth:`to_log` on the whole space (L/value is not held to :data:`LIMIT_RATIO`,
        the sampler's range, but to what SPACE allows)."""
        b = self.bounds()
        v, lim, _, _ = SPACE
        b[1] = np.log([lim.low / v.high, lim.high / v.low])
        x = np.clip(np.asarray(x, dtype=np.float64).reshape(len(SPACE)), b[:, 0], b[:, 1])
        return self._at(x, accel_law)

    def settings(self, u: Any, accel_law: str = "rise") -> Settings:
        """The settings at unit coordinates ``u`` (clipped to [0, 1]⁴, then to SPACE)."""
        b = self.bounds()
        t = np.clip(np.asarray(u, dtype=np.float64).reshape(len(SPACE)), 0.0, 1.0)
        return self._at(b[:, 0] + t * (b[:, 1] - b[:, 0]), accel_law)

    def _at(self, x: np.ndarray, accel_law: str) -> Settings:
        value, ratio, k_ratio, a = np.exp(x)
        v, lim, k, ts = SPACE
        return Settings(
            value_rad=_clip(value, v),
            error_limit_rad=_clip(value * ratio, lim),
            k=_clip(k_ratio * self.k_ref, k),
            ts_over_tf=_clip(a, ts),
            accel_law=accel_law,
        )


LIMIT_RATIO = (0.05, 20.0)
"""Range of L / value searched in :class:`Relative`."""


def _clip(x: float, d: Dim) -> float:
    return float(min(max(x, d.low), d.high))


def settings_to_dict(s: Settings) -> dict[str, Any]:
    """Plain dict of settings, as written to YAML."""
    return {d.name: float(getattr(s, d.name)) for d in SPACE} | {"accel_law": s.accel_law}


def settings_from_dict(data: Any, source: str = "settings") -> Settings:
    """Settings from a mapping (e.g. a YAML file); unknown keys or bad values raise
    ``ValueError`` naming them. Missing keys keep the paper's values."""
    if not isinstance(data, dict):
        raise ValueError(f"{source}: expected a mapping of settings, got {type(data).__name__}")
    allowed = (*NAMES, "accel_law")
    unknown = sorted(set(data) - set(allowed))
    if unknown:
        raise ValueError(
            f"{source}: unknown key(s) {', '.join(unknown)}; allowed: {', '.join(allowed)}"
        )
    return Settings(**data)
