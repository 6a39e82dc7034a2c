"""The envs' arguments as frozen configs (EnvConfig, ServoConfig: every default in one
place), the whole-ticks check (params.Plant.whole_ticks) and the observation clip
(envs._common.clip_feature, compiled in envs._batch) in one home each."""

from __future__ import annotations

import dataclasses
import inspect
import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from vfgym import PAPER_PLANT, PAPER_SETTINGS, Settings
from vfgym.envs import _batch as B
from vfgym.envs._common import EnvConfig
from vfgym.envs.servo import ServoConfig, ServoCore, VFServoEnv
from vfgym.envs.tune import TuneConfig, VFTuneEnv
from vfgym.envs.vector import VFServoVectorEnv, VFTuneVectorEnv
from vfgym.moves.features import OBS_BOUND, clip_feature


@settings(deadline=None)  # the first call compiles
@given(st.floats(allow_nan=True, allow_infinity=True))
def test_the_compiled_clip_is_the_python_one(x):
    a, b = clip_feature(x), B._clip(x)
    assert (math.isnan(a) and math.isnan(b)) or (
        a == b and math.copysign(1, a) == math.copysign(1, b)
    )
    if not math.isnan(x):
        assert -OBS_BOUND <= a <= OBS_BOUND and (a == x or abs(x) > OBS_BOUND)


@given(st.integers(1, 10**7))
def test_whole_ticks_of_a_whole_multiple(n):
    assert PAPER_PLANT.whole_ticks("interval_s", n / PAPER_PLANT.tick_hz) == n


@pytest.mark.parametrize(
    ("duration_s", "message"),
    [
        (1.5 / 140e3, "not a whole number of ticks"),
        (0.4 / 140e3, "not a whole number of ticks"),
        (1e-16, "not a whole number of ticks"),  # within the tolerance of 0 ticks
        (0.0, "out of range"),
        (-1e-3, "out of range"),
        (math.nan, "interval_s"),
        ("1 ms", "interval_s"),
    ],
)
def test_whole_ticks_bad_input_names_the_parameter(duration_s, message):
    with pytest.raises(ValueError, match=message) as e:
        PAPER_PLANT.whole_ticks("interval_s", duration_s)
    assert str(e.value).startswith("interval_s=")
    # the two callers say the same, each under its own name
    with pytest.raises(ValueError) as env_err:
        ServoConfig(interval_s=duration_s)
    assert str(env_err.value) == str(e.value)
    with pytest.raises(ValueError) as plant_err:
        PAPER_PLANT.with_sample_period(duration_s)
    assert str(plant_err.value) == str(e.value).replace("interval_s=", "sample_period_s=", 1)


def test_servo_config_holds_the_defaults_and_derives_the_ticks():
    cfg = ServoConfig()
    assert (cfg.interval_ticks, cfg.hold_ticks) == (140, 700)  # 1 ms and 5 ms at 140 kHz
    assert cfg.initial_settings == PAPER_SETTINGS and cfg.accel_law == "rise"
    slew = ServoConfig(accel_law="slew", interval_s=2e-3)
    assert slew.initial_settings.accel_law == "slew" and slew.interval_ticks == 280
    with pytest.raises(dataclasses.FrozenInstanceError):
        cfg.interval_s = 2e-3  # type: ignore[misc]
    assert isinstance(cfg, EnvConfig)
    # the envs take the configs' arguments and repeat none of their defaults
    for env in (VFTuneEnv, VFServoEnv, VFTuneVectorEnv, VFServoVectorEnv):
        params = inspect.signature(env.__init__).parameters
        assert not set(params) & {f.name for f in dataclasses.fields(ServoConfig)} - {"scenario"}
    env = VFServoEnv("short-move", interval_s=2e-3, accel_law="slew")
    assert env.core.config == ServoConfig("short-move", interval_s=2e-3, accel_law="slew")
    assert env.core.interval_ticks == 280 and env.accel_law == "slew"
    venv = VFServoVectorEnv(2, "short-move", interval_s=2e-3, accel_law="slew")
    assert venv.core.config == env.core.config
    assert VFTuneEnv(accel_law="slew").config == TuneConfig(accel_law="slew")
    assert isinstance(TuneConfig(), EnvConfig)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"violation_penalty": -1.0}, "violation_penalty"),
        ({"initial_settings": "paper"}, "initial_settings"),
        ({"accel_law": "jerk"}, "accel_law"),
        ({"axis": None}, "axis"),
        ({"weights": None}, "weights"),
        ({"settle_time_s": 2.0}, "settle_time_s"),
    ],
)
def test_servo_config_bad_input(kwargs, message):
    with pytest.raises(ValueError, match=message):
        ServoConfig(**kwargs)


def test_unknown_arguments_and_a_bare_core_are_refused():
    with pytest.raises(TypeError, match="interval_ms"):
        VFServoEnv(interval_ms=1.0)
    with pytest.raises(TypeError, match="interval_s"):
        VFTuneEnv(interval_s=1e-3)  # a VFServo-v0 argument
    with pytest.raises(ValueError, match="config="):
        ServoCore(Settings())  # type: ignore[arg-type]


def test_workspace_slots_do_not_overlap():
    """Every named slot of the compiled step's workspace row is its own (a name bound twice
    would write one slot for two things)."""
    import re
    from pathlib import Path

    text = Path(B.__file__).read_text()
    names = re.findall(r"^([CX]_[A-Z0-9_]+) = ", text, flags=re.M)
    assert len(names) == len(set(names))  # no name bound twice
    width = {"C_DIMS": 16, "C_RSCALE": 4, "C_BASE": 4, "X_SET": 4}
    taken: dict[int, str] = {}
    for name in names:
        for k in range(width.get(name, 1)):
            slot = getattr(B, name) + k
            assert slot not in taken, f"{name} and {taken.get(slot)} share slot {slot}"
            taken[slot] = name
