"""An axis file: one machine (its plant and measures), the moves it is tuned on (train)
and judged on (test) and its uncertainty, described by one YAML file.

The file's keys are the dataclasses' own field names, so nothing is named twice and the
same constructors validate every value::

    name: belt                  # optional (default: the file's stem)
    description: a heavy belt axis
    plant:                      # vfgym.Plant fields
      motor: {preset: SGME-02A, inertia_ratio: 8.0}   # vfgym.Motor fields over a preset
      servo: {sample_ticks: 70}                       # vfgym.Servo fields
    measures: {in_position_counts: 8}                 # vfgym.Measures fields
    moves:                      # vfgym.Scenario fields, or a named scenario
      train: [{name: a, profile: trapezoid, distance_rad: 6.0, duration_s: 0.3}, paper-step]
      test: {random: {count: 32, first_seed: 0, inertia_ratio: [0, 0]}}  # MoveDistribution

A move set is a list of moves (:class:`~vfgym.moves.scenarios.Scenario` fields, or the
name of a named scenario) or ``random:`` a :class:`~vfgym.moves.distribution.MoveDistribution`.
A move's load (``inertia_ratio``, friction, ``load_torque_nm``) is added to the axis's own.
Every problem raises one ``ValueError`` line naming the file, the key, the value and what
is allowed (the command line turns it into exit status 2).
"""

from __future__ import annotations

import functools
import hashlib
import json
import warnings
from dataclasses import asdict
from os import PathLike, fspath
from pathlib import Path
from typing import Any

from vfgym.axis._axis import Axis, _listed
from vfgym.axis._checks import check_holding, check_servo
from vfgym.axis._move_sets import MoveSet, MoveSets
from vfgym.axis._parts import from_mapping, read_move_set, read_plant
from vfgym.axis._uncertainty import EXACT, Uncertainty
from vfgym.io.runs import read_yaml, write_yaml
from vfgym.moves.scenarios import SPLITS
from vfgym.params import MOTOR_PRESETS, SGME_02A, Measures

AXIS_FILE = "axis.yaml"
"""The axis's copy in a run folder."""


class AxisNote(UserWarning):
    """Something true of an axis file a user should know, though the file is valid: a
    motor that cannot reach its stated acceleration limit, and the limit it is held to
    instead. ``vfgym`` prints each as one ``note:`` line once its command has finished.

    Parameters
    ----------
    message : str
        The note: the file, the key and what follows from its value.
    """

    def __init__(self, message: str) -> None:
        super().__init__(message)


def axis_from_dict(data: Any, name: str = "axis") -> Axis:
    """An :class:`Axis` from an axis file's mapping (see the module docstring).

    Parameters
    ----------
    data : Any
        The parsed YAML: a mapping with ``plant``, ``measures``, ``moves`` (each optional),
        ``name``, ``description``.
    name : str
        The axis's name when the mapping gives none (the file's stem).

    Returns
    -------
    Axis
        The axis.

    Raises
    ------
    ValueError
        One line naming the key path, for a bad key or value.
    """
    if data is None:
        data = {}
    if not isinstance(data, dict):
        raise ValueError(
            f"the file holds {type(data).__name__} {data!r}: allowed a mapping with keys "
            "name, description, plant, measures, moves, uncertainty"
        )
    data = dict(data)
    plant = read_plant(data.pop("plant", None))
    measures = from_mapping(Measures, data.pop("measures", {}) or {}, "measures")
    moves_data = data.pop("moves", {}) or {}
    if not isinstance(moves_data, dict):
        raise ValueError(f"moves={moves_data!r} is not allowed: give a mapping with train, test")
    unknown = sorted(set(moves_data) - set(SPLITS), key=str)
    if unknown:
        k = unknown[0]
        raise ValueError(f"moves.{k}={moves_data[k]!r} is not a key: allowed train, test")
    sets = {s: read_move_set(moves_data[s], f"moves.{s}") for s in SPLITS if s in moves_data}
    unc_data = data.pop("uncertainty", None)
    unc = EXACT if unc_data is None else from_mapping(Uncertainty, unc_data, "uncertainty")
    data.setdefault("name", name)
    return from_mapping(
        Axis, data, "", plant=plant, measures=measures, moves=MoveSets(**sets), uncertainty=unc
    )


def axis_to_dict(axis: Axis) -> dict[str, Any]:
    """The axis as an axis file's mapping, every field written out.

    A run folder's record so does not depend on today's defaults.

    Parameters
    ----------
    axis : Axis
        The axis.

    Returns
    -------
    dict
        The mapping; :func:`axis_from_dict` reads it back equal.
    """
    motor = axis.plant.motor
    preset = motor.name if motor.name in MOTOR_PRESETS else SGME_02A.name

    def move_set(ms: MoveSet) -> Any:
        if ms.random is not None:
            return {"random": asdict(ms.random)}
        return [asdict(sc) for sc in ms.moves]

    return {
        "name": axis.name,
        "description": axis.description,
        "plant": {
            "tick_hz": axis.plant.tick_hz,
            "pulse_rad": axis.plant.pulse_rad,
            "servo": asdict(axis.plant.servo),
            "motor": {"preset": preset, **asdict(motor)},
            # written only when stated, so a rigid axis keeps its digest
            **({} if (tr := axis.plant.transmission) is None else {"transmission": asdict(tr)}),
        },
        "measures": asdict(axis.measures),
        "moves": {s: move_set(axis.moves.of(s)) for s in SPLITS},
        # written only when stated, so an exactly known axis keeps its digest
        **({} if axis.uncertainty.exact else {"uncertainty": axis.uncertainty.to_dict()}),
    }


def as_axis(axis: Axis | str | PathLike[str], name: str = "axis") -> Axis:
    """An axis argument resolved: an :class:`Axis` as it is, an axis file's path loaded
    (:func:`load_axis`, once a file: the load is cached).

    The one place a public entry point (``vfgym.evaluate``, the envs, a tuner) turns what
    the user gave into the problem object; everything below it holds the :class:`Axis`.

    Parameters
    ----------
    axis : Axis, str or os.PathLike
        The axis, or its file.
    name : str
        The argument's name, for the error message.

    Returns
    -------
    Axis
        The axis.

    Raises
    ------
    ValueError
        If ``axis`` is neither, or its file is bad (one line naming the file).
    """
    if isinstance(axis, Axis):
        return axis
    if isinstance(axis, (str, PathLike)):
        return load_axis(fspath(axis))
    raise ValueError(f"{name}={axis!r} is not allowed: give a vfgym.Axis or an axis file's path")


def content_digest(data: Any) -> str:
    """12 hex digits of the SHA-256 of ``data`` as key-sorted JSON: the fingerprint of a
    run folder's axis (:func:`axis_digest`) and of a tuner's machine
    (:func:`vfgym.permove.tuners.machine_digest`)."""
    return hashlib.sha256(json.dumps(data, sort_keys=True).encode()).hexdigest()[:12]


def machine_digest(axis: Axis) -> str:
    """A fingerprint of what a tuner learns on besides the moves: the plant, the measures
    and what the axis does not know exactly (``machine`` in ``best.yaml`` and in a
    settings model's ``trained_on``).

    Parameters
    ----------
    axis : Axis
        The axis.

    Returns
    -------
    str
        12 hex digits of the SHA-256 of the plant, measures and (where stated) uncertainty
        of :func:`axis_to_dict`.
    """
    d = axis_to_dict(axis)
    # an axis with uncertainty is another machine to tune for; an exact one keeps its digest
    return content_digest({k: d[k] for k in ("plant", "measures", "uncertainty") if k in d})


def axis_digest(axis: Axis) -> str:
    """A fingerprint of everything the axis holds.

    So a study or a grid reference made on one axis is never mistaken for another's with
    the same move names.

    Parameters
    ----------
    axis : Axis
        The axis.

    Returns
    -------
    str
        ``name:hash`` (12 hex digits of the SHA-256 of :func:`axis_to_dict`).
    """
    return f"{axis.name}:{content_digest(axis_to_dict(axis))}"


def load_axis(path: str | Path) -> Axis:
    """The axis of a YAML file; any problem is one ``ValueError`` line starting with the
    file's name.

    Parameters
    ----------
    path : str or Path
        The axis file (e.g. ``experiments/axes/belt.yaml``).

    Returns
    -------
    Axis
        Named after the file's stem unless the file gives a ``name``.
    """
    p = Path(path)
    st = p.stat() if p.is_file() else None
    return _load(str(p), None if st is None else (st.st_mtime_ns, st.st_size))


@functools.lru_cache(maxsize=16)
def _load(path: str, stamp: tuple[int, int] | None) -> Axis:
    data = read_yaml(path)  # a missing or malformed file: "PATH: ..."
    if not data:
        raise ValueError(
            f"{path}: the file is empty: give at least one of plant, measures, moves "
            "(without --axis, vfgym uses the paper's axis)"
        )
    try:
        axis = axis_from_dict(data, Path(path).stem)
        # what the model says of the machine, for a file a command is to run on (an Axis
        # made in Python, e.g. one identified from a capture, is only noted)
        check_servo(axis.plant)  # a simulation: once a file, as the load is cached
        check_holding(axis.measures, axis.plant, _listed(axis))
    except ValueError as exc:
        raise ValueError(f"{path}: {exc}") from None
    for note in axis_notes(axis):  # once a file: the load is cached
        warnings.warn(f"{path}: {note}", AxisNote, stacklevel=3)
    return axis


def axis_notes(axis: Axis) -> list[str]:
    """What a user should know of a valid axis, one line each: a motor that cannot reach
    its stated limit, friction that may stop the motor outside the in-position window.

    Parameters
    ----------
    axis : Axis
        The axis.

    Returns
    -------
    list of str
        The notes, each naming its key.
    """
    notes = [f"plant.motor: {n}" for n in (axis.plant.motor.accel_note,) if n is not None]
    try:
        held = check_holding(axis.measures, axis.plant, _listed(axis))
    except ValueError as exc:  # (load_axis refuses it; an Axis made in Python is noted)
        held = str(exc)
    return notes + ([] if held is None else [held])


def write_axis(axis: Axis, path: str | Path) -> Path:
    """Write the axis as a YAML file (atomically) that :func:`load_axis` reads back equal.

    Parameters
    ----------
    axis : Axis
        The axis.
    path : str or Path
        The file, e.g. a run folder's ``axis.yaml``.

    Returns
    -------
    Path
        The file written.
    """
    return write_yaml(path, axis_to_dict(axis))
