"""The axis: vfgym's problem object. One machine (its plant and measures), the moves it is
tuned on (train) and judged on (test), and what it does not know exactly (its uncertainty
and the true plants drawn within it).

Every tuner, env, scheduler and evaluation holds an :class:`Axis`, resolved once where the
user's input enters (a command line's ``--axis FILE``, a config file, a constructor):
:data:`PAPER_AXIS` by default (the environments': :data:`LOADS_AXIS`). It sits between the
moves (``vfgym.moves``: what the plant is asked to do) and the scoring path
(``vfgym.scoring``), which judges a controller on an axis's moves and plants.

Modules (private; everything public is named here)
--------------------------------------------------
``_axis``
    :class:`Axis` and :data:`PAPER_AXIS`.
``_file``
    The axis file: read (:func:`load_axis`, once a file a run), written
    (:func:`write_axis`), its notes and fingerprints.
``_parts``, ``_checks``, ``_move_sets``
    The file's parts read into their dataclasses; what an axis must hold; its train and
    test move sets.
``_uncertainty``
    The ranges of the true plant (:class:`Uncertainty`), one true plant
    (:class:`PlantVariant`), a tuner's design plants and a verdict's held-out plants.
"""

from vfgym.axis._axis import LOADS_AXIS, PAPER_AXIS, Axis
from vfgym.axis._file import (
    AXIS_FILE,
    AxisNote,
    as_axis,
    axis_digest,
    axis_from_dict,
    axis_notes,
    axis_to_dict,
    content_digest,
    load_axis,
    machine_digest,
    write_axis,
)
from vfgym.axis._move_sets import MoveSet, MoveSets
from vfgym.axis._uncertainty import (
    DESIGN_DRAWN,
    DESIGN_SEED,
    EXACT,
    FACTOR_RANGE,
    NOMINAL,
    SENSITIVITY_INERTIA,
    VERDICT_PLANT_SEED,
    VERDICT_PLANTS,
    PlantVariant,
    Uncertainty,
    draw_plant,
    draw_plants,
    plant_design,
    sensitivity_variants,
)

__all__ = [
    "AXIS_FILE",
    "DESIGN_DRAWN",
    "DESIGN_SEED",
    "EXACT",
    "FACTOR_RANGE",
    "LOADS_AXIS",
    "NOMINAL",
    "PAPER_AXIS",
    "SENSITIVITY_INERTIA",
    "VERDICT_PLANTS",
    "VERDICT_PLANT_SEED",
    "Axis",
    "AxisNote",
    "MoveSet",
    "MoveSets",
    "PlantVariant",
    "Uncertainty",
    "as_axis",
    "axis_digest",
    "axis_from_dict",
    "axis_notes",
    "axis_to_dict",
    "content_digest",
    "draw_plant",
    "draw_plants",
    "load_axis",
    "machine_digest",
    "plant_design",
    "sensitivity_variants",
    "write_axis",
]
