"""Per-move settings: the best settings of each move and the models that learn them,
torch-free (numpy and the scoring path only; no torch, no stable-baselines3).

- :func:`move_optima` searches each move's own best settings (:mod:`vfgym.permove.optima`),
  optionally robust across an axis's plants; :func:`read_optima` / :func:`write_optima`
  keep them in a CSV.
- :func:`fit_pick_model` learns a *pick model* from them (:mod:`vfgym.permove.pick`): a
  library of checked candidates ranked per move by its features; :func:`fit_settings_model`
  a ridge regression (:mod:`vfgym.permove.supervised`), both in the coordinates of
  :mod:`vfgym.permove.targets`.
- :func:`fit_axis` is ``vfgym fit``: optima, model and verdict for an axis file
  (:mod:`vfgym.permove.fit`); :func:`refine` polishes one move's settings with a short
  sweep (:mod:`vfgym.permove.refine`).
- :func:`load_tuner` makes a settings model (:data:`PRETRAINED`, the one vfgym ships, or a
  file of ``vfgym fit``) a :class:`Tuner`, move → settings, that warns in one line when
  used off its machine or its training moves (:mod:`vfgym.permove.tuners`). A trained
  VFTune-v0 agent is read by :func:`vfgym.agents.load_tuner` into the same :class:`Tuner`.
- :class:`EstimatingScheduler` adapts during the move on an axis whose plant is known only
  within ranges: the robust base first, the plant told from the response, then settings
  for that plant (:mod:`vfgym.permove.adaptive`).
"""

from vfgym.permove.adaptive import AdaptiveOptions, EstimatingScheduler
from vfgym.permove.fit import (
    FitConfig,
    FitResult,
    best_fixed,
    candidate_costs,
    checkpointed_optima,
    fit_axis,
)
from vfgym.permove.optima import (
    MoveOptimum,
    OptimumSearch,
    move_optima,
    read_optima,
    write_optima,
)
from vfgym.permove.pick import PickModel, fit_pick_model
from vfgym.permove.refine import Refinement, refine
from vfgym.permove.supervised import (
    PRETRAINED,
    SettingsModel,
    TrainConfig,
    fit_settings_model,
    load_settings_model,
    train_settings_model,
)
from vfgym.permove.targets import settings_targets, target_settings
from vfgym.permove.tuners import (
    Tuner,
    TunerWarning,
    default_warn,
    load_tuner,
    outside_ranges,
    trained_on,
)

__all__ = [
    "PRETRAINED",
    "AdaptiveOptions",
    "EstimatingScheduler",
    "FitConfig",
    "FitResult",
    "MoveOptimum",
    "OptimumSearch",
    "PickModel",
    "Refinement",
    "SettingsModel",
    "TrainConfig",
    "Tuner",
    "TunerWarning",
    "best_fixed",
    "candidate_costs",
    "checkpointed_optima",
    "default_warn",
    "fit_axis",
    "fit_pick_model",
    "fit_settings_model",
    "load_settings_model",
    "load_tuner",
    "move_optima",
    "outside_ranges",
    "read_optima",
    "refine",
    "settings_targets",
    "target_settings",
    "train_settings_model",
    "trained_on",
    "write_optima",
]
