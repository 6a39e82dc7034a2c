"""experiments/axes/bare.yaml: the default axis's moves with the load held fixed, as its
comments say (the README's main job measures both)."""

from __future__ import annotations

from pathlib import Path

from vfgym.moves.axis import PAPER_AXIS, load_axis
from vfgym.params import PAPER_PLANT

AXES = Path(__file__).resolve().parents[2] / "experiments" / "axes"


def test_the_bare_axis_is_the_default_axis_with_its_load_fixed():
    bare = load_axis(AXES / "bare.yaml")
    assert bare.plant == PAPER_PLANT
    for split in ("train", "test"):
        mine, default = bare.scenarios(split), PAPER_AXIS.scenarios(split)
        assert [s.name for s in mine] == [s.name for s in default]
        assert len(mine) == {"train": 16, "test": 32}[split]
        for a, b in zip(mine, default, strict=True):
            # the same draw: distance, direction and profile
            assert (a.distance_rad, a.profile) == (b.distance_rad, b.profile)
            # no load of its own on any move
            loads = (a.inertia_ratio, a.coulomb_nm, a.viscous_nm_s_rad, a.load_torque_nm)
            assert loads == (0.0, 0.0, 0.0, 0.0)
        # the default axis's moves do carry loads
        assert max(s.inertia_ratio for s in default) > 3.0
