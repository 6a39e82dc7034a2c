"""The floor a servo that rings sets under the residual, on a compliant axis.

On a lightly damped transmission the servo's quantised loop keeps the load ringing
between and after the moves, and where it rings its response to a pulse train depends
on the state of rest it starts from far finer than any capture records: on the belt
axis, a start a thousandth of a count apart moves the simulated count by 1.5-2.5 counts
RMS over the plan (2026-12-06, docs/results/identify.md). The exact plant then leaves a
residual of that size, which says nothing against the fit. :func:`ringing_floor` measures
it on the fitted plant: the RMS change of its own simulated count when its start moves by
:data:`NUDGE_COUNTS` either way, or its servo phase by a tick either way, the median of
the four. ``vfgym identify`` judges a compliant axis's residual against the larger of it
and the quantisation floor (:attr:`vfgym.identify.written.Identified.floor_counts`); a
rigid axis's against the quantisation floor alone, as before.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from vfgym.identify.model import Record, Start, respond_many
from vfgym.params import Plant, Settings

NUDGE_COUNTS = 0.001
"""How far the start is moved (counts): far below what a capture can tell."""


NUDGES = 4
"""How many nudged starts :func:`nudged_starts` gives."""


def nudged_starts(start: Start, plant: Plant) -> list[Start]:
    """The starts no capture tells apart from ``start``: its held position moved by
    :data:`NUDGE_COUNTS` either way, its servo phase by a tick either way.

    Parameters
    ----------
    start : Start
        A capture's state of rest as fitted.
    plant : Plant
        Gives the servo's sample period (ticks).

    Returns
    -------
    list of Start
        :data:`NUDGES` starts.
    """
    ns = plant.servo.sample_ticks
    return [
        Start(start.held_counts + NUDGE_COUNTS, start.servo_phase),
        Start(start.held_counts - NUDGE_COUNTS, start.servo_phase),
        Start(start.held_counts, (start.servo_phase + 1) % ns),
        Start(start.held_counts, (start.servo_phase - 1) % ns),
    ]


def ringing_floor(
    records: Sequence[Record], plant: Plant, starts: Sequence[Start], settings: Settings
) -> float:
    """The RMS change of the plant's simulated count under starts no capture tells apart
    (module doc).

    Parameters
    ----------
    records : sequence of Record
        The captures on the tick grid.
    plant : Plant
        The fitted plant.
    starts : sequence of Start
        Each capture's state of rest as fitted.
    settings : Settings
        The servo's filter ratio in force.

    Returns
    -------
    float
        The median over the four nudged starts of the RMS change (counts), every capture's
        samples used.
    """
    nudged = [nudged_starts(s, plant) for s in starts]
    jobs = [(plant, list(starts))] + [
        (plant, [n[i] for n in nudged]) for i in range(len(nudged[0]))
    ]
    out = respond_many(records, jobs, settings)
    base = [r.used(resp.counts) for r, resp in zip(records, out[0], strict=True)]
    changes = []
    for resps in out[1:]:
        d = np.concatenate(
            [r.used(resp.counts) - b for r, resp, b in zip(records, resps, base, strict=True)]
        )
        changes.append(float(np.sqrt(np.mean(d**2))))
    return float(np.median(changes))


__all__ = ["NUDGES", "NUDGE_COUNTS", "nudged_starts", "ringing_floor"]
