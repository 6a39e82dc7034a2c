"""Gymnasium environments: ``vfgym/VFTune-v0`` (one move per step) and ``vfgym/VFServo-v0``
(online tuning, one control interval per step), each with a native vector env.

Importing this package registers both ids (entry points given as strings, so nothing heavy
is imported until an env is made)::

    import gymnasium as gym
    import vfgym.envs

    env = gym.make("vfgym/VFTune-v0")
    envs = gym.make_vec("vfgym/VFServo-v0", num_envs=64, vectorization_mode="vector_entry_point")

``gym.make("vfgym.envs:vfgym/VFTune-v0")`` imports and registers in one go.
"""

from __future__ import annotations

from typing import Any

import gymnasium

ENV_IDS = ("vfgym/VFTune-v0", "vfgym/VFServo-v0")
_ENTRY_POINTS = {
    "vfgym/VFTune-v0": (
        "vfgym.envs.tune:VFTuneEnv",
        "vfgym.envs.vector:VFTuneVectorEnv",
    ),
    "vfgym/VFServo-v0": (
        "vfgym.envs.servo:VFServoEnv",
        "vfgym.envs.vector:VFServoVectorEnv",
    ),
}
_LAZY = {
    "EnvConfig": "vfgym.envs._common",
    "CALIBRATION_PLANTS": "vfgym.envs._decision",
    "N_SIGNATURE": "vfgym.envs._decision",
    "alike_plants": "vfgym.envs._decision",
    "calibration_plants": "vfgym.envs._decision",
    "check_plants": "vfgym.envs._decision",
    "plant_spans": "vfgym.envs._decision",
    "VFTuneEnv": "vfgym.envs.tune",
    "VFServoEnv": "vfgym.envs.servo",
    "VFTuneVectorEnv": "vfgym.envs.vector",
    "VFServoVectorEnv": "vfgym.envs.vector",
}


def register_envs() -> None:
    """Register ``vfgym/VFTune-v0`` and ``vfgym/VFServo-v0`` with Gymnasium (idempotent)."""
    for env_id, (entry, vector_entry) in _ENTRY_POINTS.items():
        if env_id not in gymnasium.registry:
            gymnasium.register(
                id=env_id,
                entry_point=entry,
                vector_entry_point=vector_entry,
                nondeterministic=False,
            )


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'vfgym.envs' has no attribute {name!r}")


register_envs()

__all__ = [
    "CALIBRATION_PLANTS",
    "ENV_IDS",
    "N_SIGNATURE",
    "EnvConfig",
    "VFServoEnv",
    "VFServoVectorEnv",
    "VFTuneEnv",
    "VFTuneVectorEnv",
    "alike_plants",
    "calibration_plants",
    "check_plants",
    "plant_spans",
    "register_envs",
]
