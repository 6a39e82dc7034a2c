"""Native vector envs: N copies of VFTune-v0 or VFServo-v0 simulated in one compiled call.

Sub-env i behaves exactly as a single env would: its own random generator (``reset(seed=s)``
seeds sub-env i with s + i, as Gymnasium's ``SyncVectorEnv`` does), the same scenario
draws, the same compiled arithmetic. Autoreset follows Gymnasium 1.x: ``next-step`` by
default (an episode's end is reported, the sub-env is reset on the next ``step`` and that
step's action for it is ignored), ``same-step`` (reset at once; the last observation and
info under ``info["final_obs"]``, ``info["final_info"]``) or ``disabled`` (reset with
``options={"reset_mask": mask}``). Infos are batched as ``SyncVectorEnv`` batches them.
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Callable
from typing import Any, ClassVar

import numpy as np
from gymnasium.error import ResetNeeded
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from vfgym._validate import check_int
from vfgym.moves.scenarios import Scenario
from vfgym.plant import _layout as L
from vfgym.space import settings_to_dict

from . import _batch as B
from ._common import Episode, scored_info
from ._decision import DecisionCore
from .servo import (
    MOTOR_STATE,
    ServoConfig,
    ServoCore,
    motor_state_rows,
    raise_bad_action,
    servo_spaces,
)
from .tune import ActionMap, TuneConfig, evaluate_pairs, tune_spaces

Infos = dict[str, Any]


def _autoreset_mode(mode: Any) -> AutoresetMode:
    if isinstance(mode, AutoresetMode):
        return mode
    try:
        return AutoresetMode(mode)
    except ValueError:
        allowed = ", ".join(repr(m.value) for m in AutoresetMode)
        raise ValueError(
            f"autoreset_mode={mode!r} is not allowed: choose one of {allowed}"
        ) from None


class _BatchVectorEnv(VectorEnv):
    """Seeding, reset options, autoreset and info batching; subclasses simulate."""

    metadata: ClassVar[dict[str, Any]] = {
        "render_modes": [],
        "autoreset_mode": AutoresetMode.NEXT_STEP,
    }

    def __init__(self, num_envs: int, autoreset_mode: Any, render_mode: str | None) -> None:
        self.num_envs = check_int("num_envs", num_envs, 1)
        self.autoreset_mode = _autoreset_mode(autoreset_mode)
        self.metadata = {**type(self).metadata, "autoreset_mode": self.autoreset_mode}
        if render_mode is not None:
            raise ValueError(
                f"render_mode={render_mode!r} is not allowed for a vector env: render a "
                "single env (gymnasium.make) instead"
            )
        self.render_mode = None
        self._rngs: list[np.random.Generator | None] = [None] * self.num_envs
        self._seeds: list[int | None] = [None] * self.num_envs
        self._autoreset = np.zeros(self.num_envs, dtype=np.bool_)
        self._started = False
        self._all = np.ones(self.num_envs, dtype=np.bool_)

    def _add_info(self, vector_infos: Infos, env_info: Infos, env_num: int) -> Infos:
        """Gymnasium's ``VectorEnv._add_info`` (the same arrays, dtypes and ``_key`` masks),
        without the mask it allocates for every key of every call only to throw it away:
        an ending episode's info has ~40 keys, and batching them took ~60 us a step."""
        n = self.num_envs
        for key, value in env_info.items():
            if key == "final_obs":
                array = vector_infos.get(key)
                if array is None:
                    array = np.full(n, fill_value=None, dtype=object)
                array[env_num] = value
            elif isinstance(value, dict):
                array = self._add_info(vector_infos.get(key, {}), value, env_num)
            else:
                if key in vector_infos:
                    array = vector_infos[key]
                elif type(value) in (int, float, bool) or issubclass(type(value), np.number):
                    array = np.zeros(n, dtype=type(value))
                elif isinstance(value, np.ndarray):
                    array = np.zeros((n, *value.shape), dtype=value.dtype)
                else:
                    array = np.full(n, fill_value=None, dtype=object)
                array[env_num] = value
            mask = vector_infos.get(f"_{key}")
            if mask is None:
                mask = np.zeros(n, dtype=np.bool_)
            mask[env_num] = True
            vector_infos[key], vector_infos[f"_{key}"] = array, mask
        return vector_infos

    # --- subclass hooks -------------------------------------------------------------------
    def _reset_one(self, i: int, options: dict[str, Any] | None) -> Infos:
        """Start a new episode in sub-env i (its rng is ready); return its reset info."""
        raise NotImplementedError

    def _simulate(
        self, actions: np.ndarray, active: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict[int, Infos]]:
        """Step the active sub-envs: rewards, terminated, truncated (0 / False for the
        inactive ones) and the infos of the sub-envs whose episode ended."""
        raise NotImplementedError

    def _observations(self) -> np.ndarray:
        """The current observations, a new (num_envs, n) float32 array."""
        raise NotImplementedError

    def _running_infos(self) -> Infos:
        """The batched info of the sub-envs the last step advanced whose episode goes on
        (none here; VFServo-v0: the motor's continuous state)."""
        return {}

    def running_state(self) -> tuple[np.ndarray, dict[str, np.ndarray]] | None:
        """The state in the info of the sub-envs whose episode goes on after a step.

        Returns
        -------
        tuple of (numpy.ndarray, dict) or None
            The sub-envs' mask and per-key arrays (:meth:`_running_infos`); None here.
        """
        return None

    _SIMULATE_CHECKS_ACTIONS = False
    """True when :meth:`_simulate` itself refuses a NaN or out-of-box action before it
    changes anything (VFServo-v0's compiled step), so that a step which resets nothing
    before simulating need not check them in Python first."""

    def _check_actions(self, actions: Any, active: np.ndarray, ranges: bool = True) -> np.ndarray:
        """The actions as a C-contiguous float array; a misshapen batch, or (with
        ``ranges``) a NaN or out-of-box action of an active sub-env, raises ``ValueError``
        before anything changes."""
        a = np.asarray(actions)
        m = (self.single_action_space.shape or (4,))[0]
        if a.shape != (self.num_envs, m) or a.dtype.kind not in "fiu":
            raise ValueError(
                f"actions must be a ({self.num_envs}, {m}) array of numbers in [-1, 1], "
                f"got shape {a.shape} dtype {a.dtype}"
            )
        if a.dtype not in (np.float32, np.float64) or not a.flags.c_contiguous:
            a = np.ascontiguousarray(a, dtype=np.float64)
        if not ranges:
            return a
        ok = (np.abs(a.astype(np.float64, copy=False)) <= 1.0 + B.ACTION_TOL).all(axis=1)
        bad = np.flatnonzero(active & ~ok)
        if bad.size:
            raise_bad_action(a[bad[0]], "rise", int(bad[0]))  # the law plays no part here
        return a

    # --- reset ----------------------------------------------------------------------------
    def _rng_for(self, i: int, seed: int | None) -> None:
        if seed is not None:
            self._rngs[i], self._seeds[i] = seeding.np_random(seed)
        elif self._rngs[i] is None:
            self._rngs[i], self._seeds[i] = seeding.np_random()

    def _seed_list(self, seed: Any) -> list[int | None]:
        if seed is None:
            return [None] * self.num_envs
        if isinstance(seed, (int, np.integer)) and not isinstance(seed, bool):
            return [int(seed) + i for i in range(self.num_envs)]
        seeds = list(seed)
        if len(seeds) != self.num_envs:
            raise ValueError(
                f"seed holds {len(seeds)} seeds: give one per sub-env ({self.num_envs}), "
                "an int (sub-env i gets seed + i) or None"
            )
        return [None if s is None else check_int(f"seed[{i}]", s, 0) for i, s in enumerate(seeds)]

    def _reset_indices(
        self,
        indices: Any,
        seeds: list[int | None],
        options: list[dict[str, Any] | None],
    ) -> list[Infos]:
        out = []
        for i in indices:
            self._rng_for(int(i), seeds[i])
            out.append(self._reset_one(int(i), options[i]))
            self._autoreset[i] = False
        self._started = True
        return out

    def reset(
        self,
        *,
        seed: int | list[int | None] | None = None,
        options: dict[str, Any] | None = None,
    ) -> tuple[np.ndarray, Infos]:
        """Reset every sub-env (or those in ``options["reset_mask"]``); ``seed``: None, an
        int (sub-env i gets seed + i) or one seed per sub-env. Other options (``scenario``,
        ``scenario_seed``) go to every sub-env reset."""
        seeds = self._seed_list(seed)
        if isinstance(seed, (int, np.integer)) and not isinstance(seed, bool):
            super().reset(seed=int(seed))
        if options is not None and not isinstance(options, dict):
            raise ValueError(f"options={options!r} must be a dict (or None)")
        opts = dict(options or {})
        mask = opts.pop("reset_mask", None)
        if mask is None:
            indices = range(self.num_envs)
        else:
            if not (
                isinstance(mask, np.ndarray)
                and mask.dtype == np.bool_
                and mask.shape == (self.num_envs,)
                and mask.any()
            ):
                raise ValueError(
                    f"options['reset_mask'] must be a bool array of shape ({self.num_envs},) "
                    "with at least one True"
                )
            indices = np.flatnonzero(mask)
        infos: Infos = {}
        per_env = self._reset_indices(indices, seeds, [opts or None] * self.num_envs)
        for i, info in zip(indices, per_env, strict=True):
            infos = self._add_info(infos, info, int(i))
        return self._observations(), infos

    # --- step -----------------------------------------------------------------------------
    def _step_same(
        self, actions: Any
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict[int, Infos], dict[int, Any]]:
        """Step every sub-env and reset those whose episode ended at once. Returns
        rewards, terminated, truncated, their end infos, and per ended sub-env
        (last observation, reset info)."""
        if not self._started:
            raise ResetNeeded("call reset() before step()")
        a = self._check_actions(actions, self._all, not self._SIMULATE_CHECKS_ACTIONS)
        rew, term, trunc, ends = self._simulate(a, self._all)
        finals: dict[int, Any] = {}
        if ends:  # the sub-envs whose episode ended (by _simulate's contract), in order
            last = self._observations()
            nones: list[Any] = [None] * self.num_envs
            for i in sorted(ends):
                finals[i] = (last[i], self._reset_indices([i], nones, nones)[0])
        return rew, term, trunc, ends, finals

    def step(
        self, actions: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, Infos]:
        if not self._started:
            raise ResetNeeded("call reset() before step()")
        n = self.num_envs
        per_env: dict[int, list[Infos]] = {}
        if self.autoreset_mode == AutoresetMode.SAME_STEP:
            rew, term, trunc, ends, finals = self._step_same(actions)
            for i, info in ends.items():
                obs_i, reset_info = finals[i]
                per_env[i] = [{"final_obs": obs_i, "final_info": info}, reset_info]
        else:
            active = (
                self._all if self.autoreset_mode == AutoresetMode.DISABLED else ~self._autoreset
            )
            a = self._check_actions(actions, active)
            if self.autoreset_mode == AutoresetMode.DISABLED:
                if self._autoreset.any():
                    raise ValueError(
                        f"sub-envs {np.flatnonzero(self._autoreset).tolist()} have ended: "
                        "reset them with options={'reset_mask': mask} before stepping "
                        "(autoreset_mode='Disabled')"
                    )
            else:
                resets = np.flatnonzero(self._autoreset)
                infos_r = self._reset_indices(resets, [None] * n, [None] * n)
                for i, info in zip(resets, infos_r, strict=True):
                    per_env.setdefault(int(i), []).append(info)
            rew, term, trunc, ends = self._simulate(a, active)
            for i, info in ends.items():
                per_env.setdefault(i, []).append(info)
            self._autoreset = term | trunc
        infos = self._running_infos()
        for i in sorted(per_env):
            for info in per_env[i]:
                infos = self._add_info(infos, info, i)
        return self._observations(), rew, term, trunc, infos

    @property
    def np_random_seed(self) -> tuple[int | None, ...]:  # type: ignore[override]
        """The seed of each sub-env's generator (−1 if set directly)."""
        return tuple(self._seeds)


class VFTuneVectorEnv(_BatchVectorEnv):
    """N VFTune-v0 envs; each ``step`` scores all N moves in one compiled, multi-threaded
    kernel call (:func:`vfgym.envs.tune.evaluate_pairs`).

    Made by ``gymnasium.make_vec("vfgym/VFTune-v0", num_envs=N)``. Its numbers equal those
    of N single envs reset with seeds s, s+1, ... (tested).

    Parameters
    ----------
    num_envs : int
        N, the sub-envs.
    scenario : str, Scenario or None
        As :class:`vfgym.envs.tune.VFTuneEnv`.
    autoreset_mode : str or gymnasium.vector.AutoresetMode
        ``"NextStep"``, ``"SameStep"`` or ``"Disabled"``.
    render_mode : str or None
        As :class:`vfgym.envs.tune.VFTuneEnv`, for each sub-env.
    **options
        As :class:`vfgym.envs.tune.VFTuneEnv` (:class:`vfgym.envs._common.EnvConfig`'s
        fields: ``split``, ``seed_range``, ``accel_law``, ``axis``, ``weights``,
        ``bounds``, ``residual*``).
    """

    def __init__(
        self,
        num_envs: int = 1,
        scenario: str | Scenario | None = None,
        *,
        autoreset_mode: str | AutoresetMode = AutoresetMode.NEXT_STEP,
        render_mode: str | None = None,
        **options: Any,
    ) -> None:
        super().__init__(num_envs, autoreset_mode, render_mode)
        self.config = TuneConfig(scenario, **options)
        self.accel_law = self.config.accel_law
        self.source = self.config.scenario_source()
        spaces = tune_spaces(self.config.residual)
        self.single_observation_space, self.single_action_space = spaces
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self.action_map = ActionMap(self.config)
        self._eps: list[Episode | None] = [None] * self.num_envs
        self._bases: list[Any] = [None] * self.num_envs
        self._obs = np.zeros(self.observation_space.shape, dtype=np.float32)

    def _reset_one(self, i: int, options: dict[str, Any] | None) -> Infos:
        ep = self.source.draw(self._rngs[i], options)
        self._eps[i] = ep
        self._bases[i] = self.action_map.base(ep)
        self._obs[i] = self.action_map.features(ep, self._bases[i])
        return {"scenario": ep.scenario.name}

    def _observations(self) -> np.ndarray:
        return self._obs.copy()

    def _step_same(
        self, actions: Any
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict[int, Infos], dict[int, Any]]:
        """As the base class's, but every episode is one step long, so each sub-env's next
        episode is drawn while the moves simulate (the draws depend on the sub-envs'
        generators alone): beside the compiled call when numba may use two threads,
        after it otherwise; the same numbers either way."""
        if not self._started:
            raise ResetNeeded("call reset() before step()")
        a = self._check_actions(actions, self._all)
        last = self._observations()
        resets: list[Infos] = []
        nones: list[Any] = [None] * self.num_envs

        def draw_next() -> None:
            resets.extend(self._reset_indices(range(self.num_envs), nones, nones))

        rew, term, trunc, ends = self._simulate(a, self._all, draw_next)
        return rew, term, trunc, ends, {i: (last[i], resets[i]) for i in sorted(ends)}

    def _simulate(
        self,
        actions: np.ndarray,
        active: np.ndarray,
        while_running: Callable[[], None] | None = None,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict[int, Infos]]:
        idx = np.flatnonzero(active)
        settings = []
        for i in idx:
            try:
                settings.append(self.action_map.settings(actions[i], self._bases[i]))
            except ValueError as e:
                raise ValueError(f"actions[{i}]: {e}") from None
        eps = [self._eps[i] for i in idx]
        rew = np.zeros(self.num_envs)
        term = np.zeros(self.num_envs, dtype=np.bool_)
        ends: dict[int, Infos] = {}
        if idx.size:
            results = evaluate_pairs(
                settings,
                eps,
                measures=self.config.measures,
                weights=self.config.weights,
                bounds=self.config.bounds,
                while_running=while_running,
            )
            for i, s, ep, res in zip(idx, settings, eps, results, strict=True):
                term[i] = True
                info = scored_info(ep, res.metrics, res.cost, res.constraints)
                rew[i] = self.config.reward(res.cost, info["feasible"])
                info.update(settings_to_dict(s))
                ends[int(i)] = info
        return rew, term, np.zeros(self.num_envs, dtype=np.bool_), ends


class VFServoVectorEnv(_BatchVectorEnv):
    """N VFServo-v0 envs; each ``step`` advances all N by one control interval in one
    compiled call: the envs' plants tick together in SIMD lanes, blocks of lanes on numba
    threads from 512 envs (:func:`vfgym.envs._batch.step_batch`).

    Made by ``gymnasium.make_vec("vfgym/VFServo-v0", num_envs=N)``. Its numbers equal those
    of N single envs reset with seeds s, s+1, ... (tested).

    Parameters
    ----------
    num_envs : int
        N, the sub-envs.
    scenario : str, Scenario or None
        As :class:`vfgym.envs.servo.VFServoEnv`.
    autoreset_mode : str or gymnasium.vector.AutoresetMode
        ``"NextStep"``, ``"SameStep"`` or ``"Disabled"``.
    render_mode : str or None
        As :class:`vfgym.envs.servo.VFServoEnv`, for each sub-env.
    **options
        As :class:`vfgym.envs.servo.VFServoEnv` (:class:`vfgym.envs.servo.ServoConfig`'s
        fields, ``axis`` among them).
    """

    def __init__(
        self,
        num_envs: int = 1,
        scenario: str | Scenario | None = None,
        *,
        autoreset_mode: str | AutoresetMode = AutoresetMode.NEXT_STEP,
        render_mode: str | None = None,
        **options: Any,
    ) -> None:
        super().__init__(num_envs, autoreset_mode, render_mode)
        self.core = ServoCore(ServoConfig(scenario, **options))
        n = self.num_envs
        obs_space, self.single_action_space = servo_spaces(self.core.config)
        self.single_observation_space = obs_space
        self.observation_space = batch_space(self.single_observation_space, n)
        self.action_space = batch_space(self.single_action_space, n)
        self._W = np.zeros((n, self.core.width), dtype=np.float64)
        self._RING = np.zeros((n, self.core.ring_len), dtype=np.float64)
        self._CMD = np.zeros((n, 1), dtype=np.float64)
        self._flags = np.zeros(n, dtype=np.int64)
        self._lanes = B.lane_scratch(n, self.core.interval_ticks, self.core.acc_window)
        self._eps: list[Episode | None] = [None] * n
        self._obs = slice(B.W_OBS, B.W_OBS + self.core.n_obs)
        self._running = np.zeros(n, dtype=np.bool_)  # stepped last, episode going on
        self._state = np.zeros((n, len(MOTOR_STATE)))
        self._decisions: list[DecisionCore] = []
        if self.core.config.decision == "once":  # one decision a move: each sub-env's own
            cache: OrderedDict = OrderedDict()  # the shield's hold states, shared
            self._decisions = [DecisionCore(self.core, cache) for _ in range(n)]
            self._once_obs: np.ndarray = np.zeros((n, *obs_space.shape), np.float32)
            self._SIMULATE_CHECKS_ACTIONS = False

    _SIMULATE_CHECKS_ACTIONS = True  # step_batch: every action checked before any step

    def running_state(self) -> tuple[np.ndarray, dict[str, np.ndarray]] | None:
        """The motor's continuous state after the last step, for the sub-envs it advanced
        whose episode goes on (those that ended have it in their end info); for
        evaluation only, as a single env's ``info``.

        Returns
        -------
        tuple of (numpy.ndarray, dict)
            The sub-envs' mask, and each of :data:`vfgym.envs.servo.MOTOR_STATE`'s
            quantities per sub-env.
        """
        return self._running, {k: self._state[:, j] for j, k in enumerate(MOTOR_STATE)}

    def _running_infos(self) -> Infos:
        if not self._running.any():
            return {}
        mask = self._running
        out: Infos = {}
        for j, k in enumerate(MOTOR_STATE):
            out[k] = np.where(mask, self._state[:, j], 0.0)
            out[f"_{k}"] = mask.copy()
        return out

    @property
    def accel_law(self) -> str:
        """The acceleration law the actions' settings use."""
        return self.core.accel_law

    @property
    def ticks_simulated(self) -> np.ndarray:
        """Ticks each sub-env's current move has simulated so far."""
        return self._W[:, B.W_ST + L.S_TICK].astype(np.int64)

    def _reset_one(self, i: int, options: dict[str, Any] | None) -> Infos:
        ep = self.core.source.draw(self._rngs[i], options)
        n = ep.command.size
        if n > self._CMD.shape[1]:
            grown = np.zeros((self.num_envs, max(n, 2 * self._CMD.shape[1])))
            grown[:, : self._CMD.shape[1]] = self._CMD
            self._CMD = grown
        self._CMD[i, :n] = ep.command
        self._eps[i] = ep
        if self._decisions:
            self._once_obs[i] = self._decisions[i].reset(ep)
            return {"scenario": ep.scenario.name}
        self.core.start(self._W[i], self._RING[i], self._CMD[i, :n], ep)
        return {"scenario": ep.scenario.name}

    def _observations(self) -> np.ndarray:
        if self._decisions:
            return self._once_obs.copy()
        return self._W[:, self._obs].astype(np.float32)

    def _simulate(
        self, actions: np.ndarray, active: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict[int, Infos]]:
        if self._decisions:  # one decision a move: every stepped episode ends
            rew = np.zeros(self.num_envs)
            decided: dict[int, Infos] = {}
            for i in np.flatnonzero(active).tolist():
                rew[i], decided[i] = self._decisions[i].decide(np.asarray(actions[i], np.float64))
            self._running[:] = False
            return rew, active.copy(), np.zeros(self.num_envs, dtype=np.bool_), decided
        bad = B.step_batch_balanced(
            actions, self._W, self._RING, self._CMD, active, self._flags, self._lanes
        )
        if bad >= 0:
            raise_bad_action(actions[bad], self.core.accel_law, bad)
        flags = self._flags
        self._running = active & ((flags & B.ENDED) == 0)
        self._state = motor_state_rows(self._W)
        if active is self._all:  # every sub-env stepped (same-step autoreset, SB3)
            rew = self._W[:, B.X_REWARD].copy()
        else:
            rew = np.where(active, self._W[:, B.X_REWARD], 0.0)
        ends: dict[int, Infos] = {}
        if not flags.any():  # most steps: no episode ended
            none = np.zeros(self.num_envs, dtype=np.bool_)
            return rew, none, none.copy(), ends
        for i in np.flatnonzero(flags & B.ENDED).tolist():
            rew[i], ends[i] = self.core.finish(self._W[i], self._eps[i], int(flags[i]))
        return rew, (flags & B.TERMINATED) != 0, (flags & B.TRUNCATED) != 0, ends
