"""Axis files: the dataclasses' own keys, a round trip through a run folder, one-line
errors naming the file, the key, the value and what is allowed; the move distribution."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st

from vfgym import PAPER_PLANT, PAPER_SETTINGS
from vfgym.axis import (
    AXIS_FILE,
    PAPER_AXIS,
    Axis,
    MoveSet,
    axis_digest,
    axis_from_dict,
    load_axis,
    write_axis,
)
from vfgym.moves.baselines import baseline, rule_of_thumb
from vfgym.moves.distribution import (
    DEFAULT_DISTRIBUTION,
    LOAD_DISTRIBUTION,
    MoveDistribution,
    get_scenario,
    random_scenario,
    scenario_set,
)
from vfgym.moves.scenarios import SCENARIOS, Scenario, ideal_move_time_s
from vfgym.params import paper_k

AXES = Path(__file__).resolve().parents[2] / "experiments" / "axes"
AXIS_FILES = sorted(AXES.glob("*.yaml"))


def test_the_axes_folder_holds_the_paper_axis_and_two_engineered_ones():
    assert {p.stem for p in AXIS_FILES} >= {"paper", "belt", "vertical"}


@pytest.mark.parametrize("path", AXIS_FILES, ids=lambda p: p.stem)
def test_an_axis_file_round_trips_through_a_run_folder(path, tmp_path):
    axis = load_axis(path)
    assert axis.name == path.stem
    copy = write_axis(axis, tmp_path / "run" / AXIS_FILE)
    again = load_axis(copy)
    assert again == axis
    assert again.scenarios("train") == axis.scenarios("train")
    assert again.scenarios("test") == axis.scenarios("test")
    assert axis_digest(again) == axis_digest(axis)
    # every comment in the source aside, the file says what the copy says
    assert axis_from_dict(yaml.safe_load(copy.read_text()), "x") == axis


def test_the_paper_axis_file_is_the_default_axis():
    axis = load_axis(AXES / "paper.yaml")
    assert dataclasses.replace(axis, description="") == PAPER_AXIS
    assert axis.plant == PAPER_PLANT
    # its moves are what the commands take without --axis: scenario_set and get_scenario
    assert axis.scenarios("test") == scenario_set("test", 32, 0)
    assert axis.scenarios("train") == scenario_set("train", 16, 0)
    assert axis.scenario("train-123") == get_scenario("train-123")
    assert [s.name for s in axis.scenarios("train")] == [f"train-{i}" for i in range(16)]


def test_the_paper_axis_is_one_machine_and_loads_is_its_moves_across_loads():
    """An axis is one machine: on the default one no move adds a load, and the moves vary
    in distance, direction and profile; loads.yaml is the same draws with a load each,
    the environments' distribution (vfgym.random_scenario)."""
    paper, loads = PAPER_AXIS, load_axis(AXES / "loads.yaml")
    assert loads.plant == paper.plant
    for split, count in (("train", 16), ("test", 32)):
        mine, loaded = paper.scenarios(split), loads.scenarios(split)
        assert len(mine) == count
        assert loaded == [random_scenario(s, split) for s in range(count)]
        for a, b in zip(mine, loaded, strict=True):
            assert a.name == b.name
            # the same draw: distance, direction and profile
            assert (a.distance_rad, a.profile) == (b.distance_rad, b.profile)
            assert (a.inertia_ratio, a.coulomb_nm, a.viscous_nm_s_rad, a.load_torque_nm) == (
                0.0,
                0.0,
                0.0,
                0.0,
            )
        assert max(s.inertia_ratio for s in loaded) > 3.0
        # moves vary: both directions and every drawn profile occur
        assert {s.distance_rad > 0 for s in mine} == {True, False}
        assert {s.profile for s in mine} == {"step", "trapezoid", "scurve"}


def test_the_engineered_axes_hold_what_their_comments_say():
    belt = load_axis(AXES / "belt.yaml")
    m = belt.plant.motor
    assert m.inertia_ratio == 8.1 and m.coulomb_nm == 0.024
    # the axis sets its own limit, below what the loaded motor could give
    assert m.peak_torque_nm / m.inertia_kgm2 == pytest.approx(20.0e3, rel=0.01)
    assert m.usable_accel_rad_s2 == 10_500.0
    assert belt.moves.train.random is None and len(belt.moves.train.moves) == 6
    vert = load_axis(AXES / "vertical.yaml")
    m = vert.plant.motor
    assert m.load_torque_nm == 0.007 and m.inertia_ratio == 3.0
    assert m.usable_accel_rad_s2 == pytest.approx(1.91 / (4 * 0.106e-4))  # 45 krad/s²
    # the P-type servo's standing error under gravity: 3.3 counts, inside the window
    error_counts = m.load_torque_nm / vert.plant.torque_per_count_nm
    assert error_counts == pytest.approx(3.3, abs=0.05)
    assert error_counts < vert.measures.in_position_counts


@pytest.mark.parametrize("path", AXIS_FILES, ids=lambda p: p.stem)
def test_paper_stays_the_papers_settings_and_the_rule_of_thumb_follows_the_axis(path):
    axis = load_axis(path)
    for sc in axis.scenarios("train")[:4]:
        plant = sc.plant(axis.plant)
        assert baseline("paper", plant) == PAPER_SETTINGS
        a = plant.motor.usable_accel_rad_s2
        assert rule_of_thumb(plant).k == pytest.approx(max(1.0, paper_k(plant, a)))


def test_a_moves_load_is_added_to_the_axis_own():
    axis = load_axis(AXES / "belt.yaml")
    carry = axis.scenario("carry-500mm")
    plant = carry.plant(axis.plant)
    assert plant.motor.inertia_ratio == pytest.approx(8.1 + 1.55)
    assert plant.motor.coulomb_nm == 0.024
    # on the paper's plant (no load of its own) a scenario's load is its own, as before
    hl = SCENARIOS["heavy-load"].plant()
    assert hl.motor.inertia_ratio == 5.0


def test_named_moves_and_seeds_resolve_on_the_axis():
    axis = load_axis(AXES / "vertical.yaml")
    assert axis.scenario("paper-step") is SCENARIOS["paper-step"]
    t7 = axis.scenario("test-7")
    assert t7 == axis.moves.test.random.draw(7, "test", axis.plant)
    assert t7 != random_scenario(7, "test")  # its own ranges, not the default ones
    assert axis.scenario_set("train,paper-step")[-1] == SCENARIOS["paper-step"]
    assert axis.scenario_set("test")[:3] == axis.scenarios("test")[:3]
    belt = load_axis(AXES / "belt.yaml")
    with pytest.raises(ValueError, match=r"scenario='train-3' is not known on axis 'belt'"):
        belt.scenario("train-3")  # a listed set is named by its moves' names
    # the environments' draws: a listed set cycles through its moves
    moves = belt.moves.train.moves
    assert [belt.moves.train.pick(s, "train").name for s in (0, 5, 6, 13)] == [
        moves[0].name,
        moves[5].name,
        moves[0].name,
        moves[1].name,
    ]


# --- the distribution -------------------------------------------------------------------


def test_random_scenario_is_the_load_distribution_and_names_the_default_axis_moves():
    assert MoveDistribution() == DEFAULT_DISTRIBUTION
    for seed in range(50):
        for split in ("train", "test"):
            loaded = random_scenario(seed, split)
            assert LOAD_DISTRIBUTION.draw(seed, split) == loaded
            assert get_scenario(f"{split}-{seed}") == DEFAULT_DISTRIBUTION.draw(seed, split)
            # the load distribution differs from the default in its load ranges alone
            unloaded = dataclasses.replace(
                LOAD_DISTRIBUTION,
                inertia_ratio=(0.0, 0.0),
                coulomb_nm=(0.0, 0.0),
                viscous_nm_s_rad=(0.0, 0.0),
                load_torque_nm=(0.0, 0.0),
            )
            assert unloaded == DEFAULT_DISTRIBUTION


FIXED = {
    "distance_rad": [3.0, 3.0],
    "inertia_ratio": [2.0, 2.0],
    "coulomb_nm": [0.0, 0.0],
    "viscous_nm_s_rad": [0.0, 0.0],
    "load_torque_nm": [0.0, 0.0],
}


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**40), key=st.sampled_from(sorted(FIXED)))
def test_changing_one_range_changes_that_quantity_alone(seed, key):
    """Every draw takes the same random numbers whatever the ranges."""
    a = LOAD_DISTRIBUTION.draw(seed, "train")
    b = dataclasses.replace(LOAD_DISTRIBUTION, **{key: FIXED[key]}).draw(seed, "train")
    changed = {
        f.name
        for f in dataclasses.fields(Scenario)
        if f.compare and getattr(a, f.name) != getattr(b, f.name)
    }
    # the distance and the inertia set the duration (the ideal move time) too
    allowed = {key, "duration_s"} if key in ("distance_rad", "inertia_ratio") else {key}
    assert changed <= allowed


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**40))
def test_a_draw_lasts_its_ideal_time_times_the_factor_plus_settling(seed):
    d = MoveDistribution(time_factor=1.5, settle_s=0.1, both_directions=False)
    base = PAPER_PLANT.with_motor(inertia_ratio=2.0)
    sc = d.draw(seed, "test", base)
    assert sc.distance_rad > 0
    plant = sc.plant(base)
    assert plant.motor.inertia_ratio == pytest.approx(2.0 + sc.inertia_ratio)
    t = ideal_move_time_s(sc.distance_rad, plant)
    assert sc.duration_s == pytest.approx(1.5 * t + 0.1, abs=2e-4)  # rounded to 0.1 ms
    assert sc.ideal_time_s(plant) == t


def test_the_ideal_move_time_uses_the_usable_acceleration():
    plant = PAPER_PLANT.with_motor(inertia_ratio=3.0)
    v, a = plant.pulse_top_speed_rad_s, 1.91 / (4 * 0.106e-4)
    assert ideal_move_time_s(10.0, plant) == pytest.approx(10.0 / v + v / a, rel=1e-12)
    assert ideal_move_time_s(-0.5, plant) == pytest.approx(2 * (0.5 / a) ** 0.5, rel=1e-12)
    hl = SCENARIOS["heavy-load"]
    assert hl.ideal_time_s(hl.plant()) == pytest.approx(10.0 / v + v / (1.91 / 6.36e-5))


# --- bad axis files: one line naming the file, the key, the value, what is allowed ---------

GOOD_MOVE = {"name": "a", "profile": "trapezoid", "distance_rad": 6.0, "duration_s": 0.3}

BAD = [
    (
        "unknown key",
        {"plant": {"motor": {"inertia_rato": 3.0}}},
        "plant.motor.inertia_rato=3.0 is not a key of vfgym.Motor: allowed name, "
        "rotor_inertia_kgm2, inertia_ratio",
    ),
    ("unknown top key", {"moves_train": []}, "moves_train=[] is not a key of vfgym.Axis"),
    (
        "wrong type",
        {"plant": {"servo": {"sample_ticks": "seventy"}}},
        "plant.servo.sample_ticks='seventy' must be one of the whole numbers in [1, inf)",
    ),
    (
        "wrong type bool",
        {"plant": {"servo": {"follows_load": "yes"}}},
        "plant.servo.follows_load='yes' must be true or false",
    ),
    ("wrong type str", {"name": 3}, "name=3 must be a string"),
    (
        "wrong type mapping",
        {"measures": [8]},
        "measures=[8] is not allowed: give a mapping of vfgym.Measures fields",
    ),
    (
        "out of range",
        {"plant": {"motor": {"inertia_ratio": -1.0}}},
        "plant.motor.inertia_ratio=-1.0 is out of range: allowed [0, 200]",
    ),
    (
        "out of range measures",
        {"measures": {"in_position_counts": -2}},
        "measures.in_position_counts=-2 is out of range: allowed (0, inf)",
    ),
    (
        "preset",
        {"plant": {"motor": {"preset": "SGME-99"}}},
        "plant.motor.preset='SGME-99' is not a known motor: choose one of SGME-02A",
    ),
    (
        "empty move set",
        {"moves": {"train": []}},
        "moves.train=[] is not allowed: give one or more moves",
    ),
    (
        "empty distribution",
        {"moves": {"test": {"random": {"count": 0}}}},
        "moves.test.random.count=0 is out of range: allowed whole numbers in [1, inf)",
    ),
    (
        "bad range",
        {"moves": {"test": {"random": {"distance_rad": [5.0, 1.0]}}}},
        "moves.test.random.distance_rad[1]=1.0 is out of range: allowed [5, inf)",
    ),
    (
        "bad profile",
        {"moves": {"test": {"random": {"profiles": ["step", "sine"]}}}},
        "moves.test.random.profiles[1]='sine' is not allowed: choose one of step, ramp",
    ),
    (
        "move too short",
        {"moves": {"train": [GOOD_MOVE | {"duration_s": 0.015}]}},
        "moves.train[0].duration_s=0.015 is too short for move 'a' to arrive: allowed more "
        "than its ideal move time on this axis, 0.01704 s",
    ),
    (
        "move too short for its own profile",
        {"moves": {"train": [GOOD_MOVE | {"profile": "ramp", "speed_rad_s": 10.0}]}},
        "moves.train[0].duration_s=0.3 is too short for move 'a' to arrive: its ramp "
        "command reaches 3 of 6 rad by then; allowed more than the 0.6 s the command takes",
    ),
    (
        "a move's bad value",
        {"moves": {"train": [GOOD_MOVE | {"profile": "jerk"}]}},
        "moves.train[0].profile='jerk' is not allowed: choose one of step, sine",
    ),
    (
        "a move without a name",
        {"moves": {"train": [{"distance_rad": 1.0}]}},
        "moves.train[0]={'distance_rad': 1.0} is not allowed: a move needs a name",
    ),
    (
        "two moves of one name",
        {"moves": {"train": [GOOD_MOVE, GOOD_MOVE]}},
        "moves.train.moves[1].name='a' is not allowed: the name of moves[0] already",
    ),
    (
        "an unknown named scenario",
        {"moves": {"train": ["paper-stepp"]}},
        "moves.train[0]='paper-stepp' is not a named scenario: choose one of paper-step",
    ),
    (
        "a bad multi move",
        {"moves": {"train": [{"name": "m", "profile": "multi", "moves": [[1.0]]}]}},
        "moves.train[0].moves[0]=[1.0] is not allowed: give a pair [distance_rad, dwell_s]",
    ),
    ("not a mapping", ["plant"], "the file holds list ['plant']: allowed a mapping"),
]


@pytest.mark.parametrize(("case", "data", "message"), BAD, ids=[b[0] for b in BAD])
def test_a_bad_axis_file_is_one_line_naming_file_key_value_and_what_is_allowed(
    case, data, message, tmp_path
):
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump(data))
    with pytest.raises(ValueError) as info:
        load_axis(path)
    text = str(info.value)
    assert "\n" not in text
    assert text.startswith(f"{path}: {message}"), text


def test_a_missing_or_malformed_axis_file_names_itself(tmp_path):
    with pytest.raises(ValueError, match=r"nope\.yaml: no such file"):
        load_axis(tmp_path / "nope.yaml")
    bad = tmp_path / "broken.yaml"
    bad.write_text("plant: [unclosed")
    with pytest.raises(ValueError, match=r"broken\.yaml: not valid YAML"):
        load_axis(bad)


def test_an_edited_file_is_read_again(tmp_path):
    path = tmp_path / "a.yaml"
    path.write_text(yaml.safe_dump({"measures": {"in_position_counts": 8}}))
    assert load_axis(path).measures.in_position_counts == 8
    path.write_text(yaml.safe_dump({"measures": {"in_position_counts": 12}}))
    assert load_axis(path).measures.in_position_counts == 12


def test_an_axis_in_python_validates_as_the_file_does():
    with pytest.raises(ValueError, match=r"moves.train\[0\].duration_s=0.01 is too short"):
        Axis(moves=dataclasses.replace(PAPER_AXIS.moves, train=MoveSet(moves=(
            Scenario("x", distance_rad=5.0, duration_s=0.01),
        ))))  # fmt: skip
    with pytest.raises(ValueError, match="give one or more moves"):
        MoveSet()
    with pytest.raises(ValueError, match="plant=1 must be a vfgym Plant"):
        Axis(plant=1)  # type: ignore[arg-type]
