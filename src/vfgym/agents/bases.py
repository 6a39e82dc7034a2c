"""What an agent's environment is made of: the env arguments of a hyperparameter file
made objects, above all the residual base (the per-move settings an agent's actions are
offsets from), and the env itself.

Torch-free: both the training (:mod:`vfgym.agents.training`) and the loading of a trained
agent (:mod:`vfgym.agents.loaded`) build their envs here, so neither imports the other
for it.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from vfgym.io.runs import read_yaml
from vfgym.moves.scenarios import Scenario


def env_options(env_kwargs: dict[str, Any] | None) -> dict[str, Any]:
    """The env arguments of a hyperparameter file made objects: ``residual_base`` written
    as ``paper`` (the paper's settings), ``model`` (the shipped per-move settings model as
    ``vfgym predict`` uses it: its best-ranked candidates simulated on the move, the best
    kept; :class:`CheckedBase`), ``model-lookup`` (its look-up alone, unsimulated: the
    best-ranked candidate), ``model:FILE.json`` / ``model-lookup:FILE.json`` or a bare
    ``FILE.json`` (the same of a settings model of ``vfgym fit``, e.g. an axis's own), a
    settings file (a mapping of the settings, or one under ``settings:`` as ``best.yaml``)
    or a trained VFTune-v0 agent (its ``.zip``: the settings it picks for each move). A
    model's check keeps the settings feasible on the axis's design plants."""
    kw = dict(env_kwargs or {})
    base = kw.get("residual_base")
    if isinstance(base, str):
        kw["residual_base"] = _residual_base(base, _measures_of(kw), _design_of(kw))
    return kw


BASE_SPECS = ("paper", "model", "model-lookup")
"""The named bases a hyperparameter file's ``residual_base`` may be (or a file's path; a
settings model's as ``model:FILE.json`` or ``model-lookup:FILE.json``)."""


class CheckedBase:
    """A settings model's settings for each move, remembered per (move, plant): with its
    check on (:attr:`vfgym.agents.pick.PickModel.check`) each new move simulates its
    candidates once (a few ms), and the validation moves, scored again at every
    evaluation, only the first time.

    Parameters
    ----------
    model : PickModel or SettingsModel
        The model.
    measures : Measures
        What the check scores with (an axis's).
    size : int
        Moves remembered; the oldest are forgotten beyond it.
    plants : tuple of PlantVariant
        True plants the check keeps the settings feasible on (an axis's design).
    """

    def __init__(self, model: Any, measures: Any, size: int = 1024, plants: Any = ()) -> None:
        self.model, self.measures, self.size, self.plants = model, measures, size, plants
        self._seen: dict[tuple[Scenario, Any], Any] = {}

    def __call__(self, scenario: Scenario, plant: Any) -> Any:
        """The model's settings for ``scenario`` on the base plant ``plant``."""
        key = (scenario, plant)
        out = self._seen.get(key)
        if out is None:
            if len(self._seen) >= self.size:
                del self._seen[next(iter(self._seen))]
            out = self._seen[key] = self.model.settings(scenario, plant, self.measures, self.plants)
        return out


def _measures_of(kw: dict[str, Any]) -> Any:
    from vfgym.params import DEFAULT_MEASURES

    axis = kw.get("axis")
    if axis is None:
        return kw.get("measures", DEFAULT_MEASURES)
    from vfgym.moves.axis import load_axis

    return (load_axis(axis) if isinstance(axis, (str, Path)) else axis).measures


def _design_of(kw: dict[str, Any]) -> Any:
    axis = kw.get("axis")
    if axis is None:
        return ()
    from vfgym.moves.axis import load_axis

    return (load_axis(axis) if isinstance(axis, (str, Path)) else axis).design_plants()


def _residual_base(spec: str, measures: Any = None, plants: Any = ()) -> Any:
    from vfgym.agents.supervised import PRETRAINED
    from vfgym.params import DEFAULT_MEASURES, PAPER_SETTINGS
    from vfgym.space import settings_from_dict

    if spec == "paper":
        return PAPER_SETTINGS
    kind, _, path = spec.partition(":")
    if spec.endswith(".json") and kind not in BASE_SPECS:
        kind, path = "model", spec
    if kind in ("model", "model-lookup"):
        from dataclasses import replace

        from vfgym.agents.supervised import PickModel, load_settings_model

        try:
            model = load_settings_model(path or PRETRAINED)
        except ValueError as exc:  # its message names --model; here the key is residual_base
            raise ValueError(f"residual_base={spec!r}: {exc}".replace("--model ", "")) from None
        if kind == "model-lookup" and isinstance(model, PickModel):
            model = replace(model, check=0)
        on = DEFAULT_MEASURES if measures is None else measures
        return CheckedBase(model, on, plants=tuple(plants))
    if spec.endswith(".zip") and Path(spec).is_file():
        from vfgym.agents import policy_settings

        pick = policy_settings(spec)
        return lambda scenario, plant: pick(scenario)
    if not Path(spec).is_file():
        raise ValueError(
            f"residual_base={spec!r} is not allowed: {', '.join(BASE_SPECS)} (the shipped "
            "settings model, checked on the move, or its look-up alone), model:FILE.json "
            "(a settings model of vfgym fit), a settings file or a VFTune-v0 agent's .zip"
        )
    data = read_yaml(spec)
    data = data["settings"] if isinstance(data, dict) and "settings" in data else data
    return settings_from_dict(data, source=spec)


def make_env(env_id: str, env_kwargs: dict[str, Any] | None = None, **kw: Any) -> Any:
    """One (non-vector) environment (``env_kwargs`` through :func:`env_options`)."""
    import gymnasium as gym

    import vfgym.envs  # noqa: F401  (registers the ids)

    return gym.make(env_id, **env_options(env_kwargs), **kw)


__all__ = ["BASE_SPECS", "CheckedBase", "env_options", "make_env"]
