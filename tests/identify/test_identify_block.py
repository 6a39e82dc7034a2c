"""The identified axis's ``uncertainty:`` block: what the captures warrant, no wider.

A plant whose friction and load stop it within the in-position window (the only plants
on which a controller can make every move) must keep a block whose every plant stops
within it too, else a tuner made robust to the block gives up moves the true plant makes.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from capture_synth import Truth, capture_vcd, draw_truth

from vfgym.axis import PAPER_AXIS, PlantVariant
from vfgym.identify.capture import read_capture
from vfgym.identify.covariance import resolution
from vfgym.identify.fit import QUANTISATION_FLOOR, fit
from vfgym.identify.model import record_of
from vfgym.identify.plan import make_plan
from vfgym.identify.written import MARGIN, identify_report
from vfgym.params import PAPER_SETTINGS

NOMINAL = PAPER_AXIS.plant
K3 = NOMINAL.torque_per_count_nm
WINDOW = PAPER_AXIS.measures.in_position_counts
SEED = 27_182  # the drawn plants' stream (the benchmark draws from another)


def _within_window(rng: np.random.Generator, ratio: tuple[float, float]) -> Truth:
    """A drawn plant, its Coulomb friction and load scaled to stop it at 80 % of the window."""
    t = draw_truth(NOMINAL, rng, inertia_ratio=ratio)
    f = 0.8 * WINDOW * K3 / (abs(t.load_torque_nm) + t.coulomb_nm)
    c, load = t.coulomb_nm * f, t.load_torque_nm * f
    m = NOMINAL.motor
    v = PlantVariant(
        inertia=t.inertia,
        coulomb_offset_nm=c - m.coulomb_nm,
        viscous_offset_nm_s_rad=t.viscous_nm_s_rad - m.viscous_nm_s_rad,
        load_offset_nm=load - m.load_torque_nm,
    )
    return replace(t, plant=v.apply(NOMINAL), coulomb_nm=c, load_torque_nm=load)


@pytest.fixture(scope="module")
def plan():
    return make_plan(PAPER_AXIS)


@pytest.mark.parametrize(("case", "ratio"), [("heavy", (5.0, 8.0)), ("light", (0.0, 1.0))])
def test_the_block_of_a_plant_within_the_window_stays_within_it(plan, tmp_path, case, ratio):
    rng = np.random.default_rng([SEED, len(case)])
    truth = _within_window(rng, ratio)
    path = capture_vcd(truth.plant, plan.pulses, tmp_path / "c.vcd", rng, from_enable=True)
    rec = record_of(read_capture(path), NOMINAL, True)
    result = fit([rec], NOMINAL, PAPER_SETTINGS)
    ident = identify_report(PAPER_AXIS, result, [rec])
    unc = ident.axis.uncertainty
    k3 = ident.axis.plant.torque_per_count_nm
    gain = result.estimate("torque_per_count")
    assert gain.excited == (case == "heavy")
    g_lo = unc.torque_per_count[0] if gain.excited else 1.0
    # the block's worst plant stops within the window, as the true one does
    worst = (unc.coulomb_nm[1] + max(map(abs, unc.load_torque_nm))) / (k3 * g_lo)
    assert 0.8 * WINDOW < worst < WINDOW
    # …and holds the true plant (the block's factors are on the estimates)
    assert unc.inertia[0] <= truth.inertia / result.estimate("inertia").value <= unc.inertia[1]
    for name in ("coulomb_nm", "viscous_nm_s_rad", "load_torque_nm"):
        lo, hi = getattr(unc, name)
        assert lo <= truth.value(name) <= hi, name
    # without a saturating move, the gain is left out and the inertia not widened by it
    assert (unc.torque_per_count is None) == (not gain.excited)
    assert unc.inertia[1] / unc.inertia[0] < 1.01
    # below the torque limit a load torque shifts the error the servo holds by τ/K3
    # counts: the least change a reading of the count shows is the floor's worth of K3
    # (finer where the torque saturates: the servo no longer holds the load back)
    load = result.estimate("load_torque_nm")
    if gain.excited:
        assert 0.0 < load.resolution < QUANTISATION_FLOOR * k3
    else:
        assert load.resolution == pytest.approx(QUANTISATION_FLOOR * k3, rel=0.25)
    half = max(MARGIN * (load.high - load.value), load.resolution)
    assert unc.load_torque_nm[1] == pytest.approx(load.value + half, rel=1e-9)
    if not gain.excited:
        line = [n for n in ident.notes if n.startswith("torque_per_count: not excited")]
        assert len(line) == 1 and "leaves the gain out" in line[0], ident.notes
        assert "so g is below" in line[0] and "out of the uncertainty block" in line[0]


def test_the_resolution_is_the_floor_over_the_largest_sensitivity():
    jac = np.array([[0.5, -4.0, 0.0], [-2.0, 1.0, 0.0]])
    r = resolution(jac, QUANTISATION_FLOOR)
    assert r[:2] == pytest.approx([QUANTISATION_FLOOR / 2.0, QUANTISATION_FLOOR / 4.0])
    assert r[2] == np.inf  # no sample responds: nothing resolves it
