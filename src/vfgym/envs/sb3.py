"""A stable-baselines3 ``VecEnv`` over a native vfgym vector env (imports SB3, hence torch).

SB3 expects same-step autoreset: when a sub-env's episode ends, ``step_wait`` returns the
first observation of the next episode, with the last one in
``infos[i]["terminal_observation"]`` and ``infos[i]["TimeLimit.truncated"]`` set for a
truncation; ``reset_infos[i]`` holds the new episode's reset info. The adapter drives the
batch directly (one compiled call per step) and returns what SB3's ``DummyVecEnv`` over N
single envs with the same seeds would return (tested), rewards as float32 like it.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import gymnasium as gym
import numpy as np
from stable_baselines3.common.vec_env.base_vec_env import (
    VecEnv,
    VecEnvIndices,
    VecEnvObs,
    VecEnvStepReturn,
)

from .vector import VFServoVectorEnv, VFTuneVectorEnv, _BatchVectorEnv

_VECTOR_ENVS = {"vfgym/VFTune-v0": VFTuneVectorEnv, "vfgym/VFServo-v0": VFServoVectorEnv}


class SB3VecEnv(VecEnv):
    """SB3's ``VecEnv`` interface to a :class:`vfgym.envs.vector.VFTuneVectorEnv` or
    :class:`~vfgym.envs.vector.VFServoVectorEnv` (whatever its own autoreset mode, the
    adapter resets ended sub-envs in the same step, as SB3 requires).

    Attributes are those of the vector env, shared by every sub-env: ``get_attr`` returns
    the vector env's value once per index, ``set_attr`` sets it on the vector env;
    ``env_method`` is not supported. Wrap in ``VecMonitor`` for episode statistics."""

    def __init__(self, venv: _BatchVectorEnv) -> None:
        if not isinstance(venv, _BatchVectorEnv):
            raise ValueError(
                f"venv={venv!r} must be a vfgym vector env (VFTuneVectorEnv, VFServoVectorEnv)"
            )
        self.venv = venv
        self._actions: np.ndarray | None = None
        super().__init__(venv.num_envs, venv.single_observation_space, venv.single_action_space)

    def reset(self) -> VecEnvObs:
        n = self.num_envs
        options = [o or None for o in self._options]
        self.reset_infos = self.venv._reset_indices(range(n), list(self._seeds), options)
        self._reset_seeds()
        self._reset_options()
        return self.venv._observations()

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = actions

    def step_wait(self) -> VecEnvStepReturn:
        if self._actions is None:
            raise RuntimeError("step_async() must come before step_wait()")
        rew, term, trunc, ends, finals = self.venv._step_same(self._actions)
        self._actions = None
        dones = term | trunc
        # a truncation (not a termination) is an ended episode's
        limits = (trunc & ~term).tolist() if ends else [False] * self.num_envs
        infos: list[dict[str, Any]] = [{"TimeLimit.truncated": x} for x in limits]
        running = self.venv.running_state()
        if running is not None:  # VFServo-v0: the motor's state, as a single env's info
            mask, arrays = running
            for i in np.flatnonzero(mask).tolist():
                infos[i].update({k: float(a[i]) for k, a in arrays.items()})
        for i, info in ends.items():
            info["TimeLimit.truncated"] = limits[i]
            infos[i] = info
        for i, (last_obs, reset_info) in finals.items():
            infos[i]["terminal_observation"] = last_obs
            self.reset_infos[i] = reset_info
        return self.venv._observations(), rew.astype(np.float32), dones, infos

    def close(self) -> None:
        self.venv.close()

    def get_attr(self, attr_name: str, indices: VecEnvIndices = None) -> list[Any]:
        value = getattr(self.venv, attr_name)
        return [value for _ in self._get_indices(indices)]

    def set_attr(self, attr_name: str, value: Any, indices: VecEnvIndices = None) -> None:
        setattr(self.venv, attr_name, value)

    def env_method(
        self, method_name: str, *method_args: Any, indices: VecEnvIndices = None, **kwargs: Any
    ) -> list[Any]:
        raise NotImplementedError(
            f"env_method({method_name!r}): the sub-envs of a vfgym vector env are not separate "
            "objects; use the vector env (.venv) directly"
        )

    def env_is_wrapped(
        self, wrapper_class: type[gym.Wrapper], indices: VecEnvIndices = None
    ) -> list[bool]:
        return [False for _ in self._get_indices(indices)]

    def get_images(self) -> Sequence[np.ndarray | None]:
        return [None for _ in range(self.num_envs)]


def make_sb3_vec_env(
    env_id: str = "vfgym/VFServo-v0", n_envs: int = 1, seed: int | None = None, **kwargs: Any
) -> SB3VecEnv:
    """An SB3 ``VecEnv`` of ``n_envs`` copies of ``env_id`` (VFTune-v0 or VFServo-v0), one
    native batch underneath; ``seed`` seeds sub-env i with seed + i at the first reset;
    ``kwargs`` are the env's arguments."""
    if env_id not in _VECTOR_ENVS:
        raise ValueError(
            f"env_id={env_id!r} is not allowed: choose one of {', '.join(_VECTOR_ENVS)}"
        )
    venv = SB3VecEnv(_VECTOR_ENVS[env_id](num_envs=n_envs, **kwargs))
    if seed is not None:
        venv.seed(seed)
    return venv
