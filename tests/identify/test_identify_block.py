"""The identified axis's ``uncertainty:`` block: every plant the captures cannot rule out,
every range the user stated, no wider where the captures separate the gain.

A plant whose friction and load stop it within the in-position window (the only plants
on which a controller can make every move) keeps, where its torque saturates, a block whose
every plant stops within it too, else a tuner made robust to the block gives up moves the
true plant makes. Where it does not saturate, the block spans the drive's gain within its
prior, and with it the inertia and torques along J/K3 and τ/K3.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from capture_synth import Truth, capture_vcd, draw_truth, identify_vcd, outside_block

from vfgym.axis import PAPER_AXIS, PlantVariant, Uncertainty
from vfgym.identify.covariance import resolution
from vfgym.identify.fit import QUANTISATION_FLOOR
from vfgym.identify.model import respond
from vfgym.identify.plan import make_plan
from vfgym.identify.prior import scaled
from vfgym.identify.written import MARGIN
from vfgym.params import PAPER_SETTINGS

NOMINAL = PAPER_AXIS.plant
K3 = NOMINAL.torque_per_count_nm
WINDOW = PAPER_AXIS.measures.in_position_counts
RATED = NOMINAL.motor.rated_torque_nm
SEED = 27_182  # the drawn plants' stream (the benchmark draws from another)


def _within_window(rng: np.random.Generator, ratio: tuple[float, float], gain: float) -> Truth:
    """A drawn plant, its Coulomb friction and load scaled to stop it at 80 % of the window."""
    t = draw_truth(NOMINAL, rng, inertia_ratio=ratio, gain=gain)
    f = 0.8 * WINDOW * K3 * gain / (abs(t.load_torque_nm) + t.coulomb_nm)
    c, load = t.coulomb_nm * f, t.load_torque_nm * f
    m = NOMINAL.motor
    v = PlantVariant(
        inertia=t.inertia,
        coulomb_offset_nm=c - m.coulomb_nm,
        viscous_offset_nm_s_rad=t.viscous_nm_s_rad - m.viscous_nm_s_rad,
        load_offset_nm=load - m.load_torque_nm,
        torque_per_count=gain,
    )
    return replace(t, plant=v.apply(NOMINAL), coulomb_nm=c, load_torque_nm=load)


@pytest.fixture(scope="module")
def plan():
    return make_plan(PAPER_AXIS)


def test_a_separated_gain_keeps_the_block_within_the_window(plan, tmp_path):
    rng = np.random.default_rng([SEED, 5])
    truth = _within_window(rng, (5.0, 8.0), 1.04)
    ident, _, _ = identify_vcd(capture_vcd(truth.plant, plan.pulses, tmp_path / "c.vcd", rng,
                                           from_enable=True))  # fmt: skip
    unc = ident.axis.uncertainty
    gain = ident.fit.estimate("torque_per_count")
    assert gain.excited and ident.profile is None
    k3 = ident.axis.plant.torque_per_count_nm
    # the block's worst plant stops within the window, as the true one does
    worst = (unc.coulomb_nm[1] + max(map(abs, unc.load_torque_nm))) / (k3 * unc.torque_per_count[0])
    assert 0.8 * WINDOW < worst < WINDOW
    assert outside_block(ident, truth) == []
    assert unc.inertia[1] / unc.inertia[0] < 1.01
    load = ident.fit.estimate("load_torque_nm")
    assert 0.0 < load.resolution < QUANTISATION_FLOOR * k3  # finer: the servo no longer holds it
    half = max(MARGIN * (load.high - load.value), load.resolution)
    assert unc.load_torque_nm[1] == pytest.approx(load.value + half, rel=1e-9)


@pytest.fixture(scope="module")
def light(plan, tmp_path_factory):
    """A light plant whose drive's gain is 1.06 times the one set, identified with a nominal
    axis that states a payload's range and a load torque's."""
    rng = np.random.default_rng([SEED, 7])
    truth = _within_window(rng, (0.0, 0.8), 1.06)
    stated = Uncertainty(inertia=(0.95, 1.25), load_torque_nm=(-0.01 * RATED, 0.012 * RATED))
    axis = replace(PAPER_AXIS, uncertainty=stated)
    path = capture_vcd(truth.plant, plan.pulses, tmp_path_factory.mktemp("light") / "c.vcd", rng,
                       from_enable=True)  # fmt: skip
    ident, records, _ = identify_vcd(path, axis)
    return truth, axis, ident, records


def test_the_block_spans_the_gains_prior_where_the_gain_is_not_separated(light):
    truth, _, ident, _ = light
    assert outside_block(ident, truth) == []
    unc = ident.axis.uncertainty
    assert ident.profile is not None and not ident.profile.refitted[0]
    assert unc.torque_per_count == (0.9, 1.1)
    # the inertia along the line: 0.9 to 1.1 times the estimate, and its own interval
    fits = ident.profile.fits
    j = [f.estimate("inertia").value for f in fits]
    assert j[0] == pytest.approx(0.9 * j[1], rel=1e-12)  # scaled: the same response
    # (at the high end the torque reaches its limit: fitted again there, near the line)
    assert j[2] == pytest.approx(1.1 * j[1], rel=1e-12 if not ident.profile.refitted[1] else 0.01)
    own = [f.estimate("inertia") for f in fits]
    assert unc.inertia[0] * j[1] <= own[0].low and unc.inertia[1] * j[1] >= own[2].high
    # below the torque limit a load torque shifts the error the servo holds by τ/K3 counts:
    # the least change a reading of the count shows is the floor's worth of K3 (at the
    # prior's high end, the gain's)
    load = ident.fit.estimate("load_torque_nm")
    assert load.resolution == pytest.approx(QUANTISATION_FLOOR * K3 * 1.1, rel=0.25)
    line = [n for n in ident.notes if n.startswith("torque_per_count: not separated")]
    assert len(line) == 1 and "span the gain within its prior [0.9, 1.1]" in line[0]


def test_a_scaled_end_of_the_prior_makes_the_same_response(light):
    """Along J/K3 and τ/K3 the plant makes the same capture below its torque limit."""
    _, axis, ident, records = light
    fit1 = ident.profile.fits[1]
    for g in (0.9, 0.95):  # below the gain as set: the torque stays below its limit
        end = scaled(fit1, axis.plant, g)
        a = respond(records[0], fit1.plant, PAPER_SETTINGS, fit1.starts[0])
        b = respond(records[0], end.plant, PAPER_SETTINGS, fit1.starts[0])
        assert np.max(np.abs(a.counts - b.counts)) < 1e-6
        assert end.plant.motor.inertia_kgm2 == pytest.approx(g * fit1.plant.motor.inertia_kgm2)


def test_the_stated_ranges_are_kept_and_said(light):
    truth, _, ident, _ = light
    unc = ident.axis.uncertainty
    j = ident.fit.estimate("inertia").value
    assert unc.inertia[0] * j <= 0.95 + 1e-12 and unc.inertia[1] * j >= 1.25 - 1e-12
    assert unc.load_torque_nm[0] <= -0.01 * RATED and unc.load_torque_nm[1] >= 0.012 * RATED
    kept = {line.split(":")[0]: line for line in ident.kept}
    assert set(kept) == {"inertia", "load_torque_nm"}
    assert "[0.95, 1.25] x nominal total kept" in kept["inertia"]
    assert "one capture cannot measure" in kept["load_torque_nm"]
    # the capture's own range too where it reaches past the stated one: widened, not narrowed
    own = [f.estimate("inertia") for f in ident.profile.fits]
    assert unc.inertia[0] * j <= min(e.low for e in own) + 1e-12
    assert unc.inertia[1] * j >= max(e.high for e in own) - 1e-12
    assert unc.inertia[0] * j <= truth.inertia <= unc.inertia[1] * j


def test_the_resolution_is_the_floor_over_the_largest_sensitivity():
    jac = np.array([[0.5, -4.0, 0.0], [-2.0, 1.0, 0.0]])
    r = resolution(jac, QUANTISATION_FLOOR)
    assert r[:2] == pytest.approx([QUANTISATION_FLOOR / 2.0, QUANTISATION_FLOOR / 4.0])
    assert r[2] == np.inf  # no sample responds: nothing resolves it


def test_the_gains_prior_comes_from_the_option_the_file_or_the_default():
    from vfgym.identify.prior import GAIN_PRIOR, gain_prior

    stated = replace(PAPER_AXIS, uncertainty=Uncertainty(torque_per_count=(0.95, 1.08)))
    assert gain_prior(PAPER_AXIS) == (1.0 - GAIN_PRIOR, 1.0 + GAIN_PRIOR)
    assert gain_prior(stated) == (0.95, 1.08)
    assert gain_prior(stated, 0.2) == (0.8, 1.2)
    with pytest.raises(ValueError, match=r"--gain-prior=1\.5 is out of range"):
        gain_prior(PAPER_AXIS, 1.5)
