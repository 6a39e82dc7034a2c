"""The axis file's parts read into their dataclasses: one strictness for every key.

Each mapping's keys are checked against the dataclass's own field names and every error
is one ``ValueError`` line naming its key path (the command line turns it into exit
status 2); :func:`vfgym.axis.axis_from_dict` assembles the parts.
"""

from __future__ import annotations

from dataclasses import asdict, fields
from typing import Any

from vfgym.axis._move_sets import MoveSet
from vfgym.moves.distribution import MoveDistribution
from vfgym.moves.scenarios import SCENARIOS, Scenario
from vfgym.params import MOTOR_PRESETS, PAPER_PLANT, SGME_02A, Motor, Plant, Servo, Transmission


def from_mapping(cls: type, data: Any, key: str, **given: Any) -> Any:
    """``cls(**data, **given)``: the keys checked against ``cls``'s fields, string and
    bool fields checked for their type, and every error named by its key path."""
    prefix = f"{key}." if key else ""
    if not isinstance(data, dict):
        raise ValueError(
            f"{key or 'the file'}={data!r} is not allowed: give a mapping of "
            f"vfgym.{cls.__name__} fields"
        )
    names = [f.name for f in fields(cls)]  # the given ones too: they were taken out of data
    for k, v in data.items():
        if k not in names or k in given:
            raise ValueError(
                f"{prefix}{k}={v!r} is not a key of vfgym.{cls.__name__}: allowed "
                f"{', '.join(names)}"
            )
    for f in fields(cls):
        v = data.get(f.name)
        if f.type == "str" and f.name in data and not isinstance(v, str):
            raise ValueError(f"{prefix}{f.name}={v!r} must be a string")
    try:
        return cls(**data, **given)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{prefix}{exc}") from None


def read_motor(data: Any, key: str) -> Motor:
    if not isinstance(data, dict):
        return from_mapping(Motor, data, key)
    data = dict(data)
    preset = data.pop("preset", SGME_02A.name)
    if not isinstance(preset, str) or preset not in MOTOR_PRESETS:
        raise ValueError(
            f"{key}.preset={preset!r} is not a known motor: choose one of "
            f"{', '.join(MOTOR_PRESETS)}"
        )
    return from_mapping(Motor, asdict(MOTOR_PRESETS[preset]) | data, key)


RESONANCE_KEYS = ("load_inertia_kgm2", "resonance_hz", "damping_ratio", "travel_mm_per_rad")
"""A transmission given by its resonance instead (:meth:`vfgym.Transmission.from_resonance`)."""


def read_transmission(data: Any, motor: Motor, key: str) -> Transmission:
    """A transmission: :class:`vfgym.Transmission`'s fields, or its load inertia with a
    resonance (Hz, seen from the motor) and a damping ratio, converted on ``motor``'s
    inertia (what turns rigidly with the rotor)."""
    if not isinstance(data, dict) or not {"resonance_hz", "damping_ratio"} & set(data):
        return from_mapping(Transmission, data, key)
    for k, v in data.items():
        if k not in RESONANCE_KEYS:
            raise ValueError(
                f"{key}.{k}={v!r} is not allowed with resonance_hz: give "
                f"{', '.join(RESONANCE_KEYS)}, or vfgym.Transmission's fields "
                "(stiffness_nm_rad, damping_nm_s_rad) instead"
            )
    for k in ("load_inertia_kgm2", "resonance_hz"):
        if k not in data:
            raise ValueError(
                f"{key}.{k} is missing: a resonance needs load_inertia_kgm2 and resonance_hz"
            )
    try:
        return Transmission.from_resonance(motor_inertia_kgm2=motor.inertia_kgm2, **data)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{key}.{exc}") from None


def read_plant(data: Any) -> Plant:
    if data is None:
        return PAPER_PLANT
    if not isinstance(data, dict):
        return from_mapping(Plant, data, "plant")
    data = dict(data)
    servo = from_mapping(Servo, data.pop("servo", {}) or {}, "plant.servo")
    motor = read_motor(data.pop("motor", {}) or {}, "plant.motor")
    tr = data.pop("transmission", None)
    tr = None if tr is None else read_transmission(tr, motor, "plant.transmission")
    return from_mapping(Plant, data, "plant", servo=servo, motor=motor, transmission=tr)


def read_scenario(item: Any, key: str) -> Scenario:
    if isinstance(item, str):
        if item not in SCENARIOS:
            raise ValueError(
                f"{key}={item!r} is not a named scenario: choose one of {', '.join(SCENARIOS)}, "
                "or give a move's fields (name, profile, distance_rad, duration_s, ...)"
            )
        return SCENARIOS[item]
    if isinstance(item, dict) and "name" not in item:
        raise ValueError(f"{key}={item!r} is not allowed: a move needs a name")
    return from_mapping(Scenario, item, key)


def read_move_set(data: Any, key: str) -> MoveSet:
    """A list of moves, or a mapping with ``random`` (a distribution) or ``moves``."""
    if isinstance(data, dict):
        for k, v in data.items():
            if k not in ("moves", "random") or len(data) > 1:
                raise ValueError(
                    f"{key}.{k}={v!r} is not allowed: give random: {{count: ..., "
                    "first_seed: ..., ranges}, or a list of moves"
                )
        if "random" in data:
            dist = from_mapping(MoveDistribution, data["random"] or {}, f"{key}.random")
            return MoveSet(random=dist)
        key, data = f"{key}.moves", data.get("moves")
    if not isinstance(data, list) or not data:
        raise ValueError(
            f"{key}={data!r} is not allowed: give one or more moves (vfgym.Scenario fields "
            "or a named scenario) or random: {count: ..., first_seed: ..., ranges}"
        )
    moves = tuple(read_scenario(item, f"{key}[{i}]") for i, item in enumerate(data))
    try:
        return MoveSet(moves=moves)
    except ValueError as exc:
        raise ValueError(f"{key}.{exc}") from None
