"""An axis that cannot work says so: an empty file, a units slip in the acceleration
limit, friction and load torque that hold the motor outside its in-position window (an
error where no controller can arrive, a note where it may not), an option the axis
overrides. Each is one line naming the key, the value and the reason."""

from __future__ import annotations

import warnings
from pathlib import Path

import pytest
import yaml

from vfgym import PAPER_AXIS, Settings, cli, evaluate, load_axis
from vfgym.axis import AxisNote, axis_notes
from vfgym.axis._checks import holding_counts

K3 = PAPER_AXIS.plant.torque_per_count_nm  # 5.3e-4 N·m per count on the bare paper motor


@pytest.mark.parametrize(
    ("text", "needle"),
    [
        ("", "the file is empty: give at least one of plant, measures, moves"),
        ("{}\n", "the file is empty"),
        ("plant: {motor: {accel_limit_rad_s2: 20}}\n", "accel_limit_rad_s2=20 is out of range"),
        ("plant: {servo: {torque_per_count_nm: 0.005}}\n", "speed_gain_b=12.5 and sample_ticks"),
        ("plant: {servo: {torque_per_count_nm: 0.005}}\n", "is unstable: after a step of 8"),
        (
            "plant: {motor: {coulomb_nm: 0.001, load_torque_nm: 0.01}}\n",
            "no controller can arrive",
        ),
    ],
)
def test_an_axis_that_cannot_work_is_one_line_with_status_2(tmp_path, capsys, text, needle):
    f = tmp_path / "ax.yaml"
    f.write_text(text)
    code = cli.main(["simulate", "--axis", str(f), "--scenario", "short-move"])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and needle in err, err
    assert str(f) in err


def test_the_units_slip_bound_lets_a_real_low_limit_through(tmp_path):
    reach = PAPER_AXIS.plant.motor.torque_accel_rad_s2  # 180 krad/s²
    f = tmp_path / "slow.yaml"
    f.write_text(f"plant: {{motor: {{accel_limit_rad_s2: {reach / 99:.6g}}}}}\n")
    assert load_axis(f).plant.motor.accel_limit_rad_s2 == pytest.approx(reach / 99, rel=1e-5)


def test_the_holding_band_is_friction_and_load_over_the_drive_gain():
    p = PAPER_AXIS.plant.with_motor(coulomb_nm=0.002, load_torque_nm=-0.003)
    lo, hi = holding_counts(p)
    assert lo == pytest.approx(0.001 / K3) and hi == pytest.approx(0.005 / K3)


def test_friction_beyond_the_window_is_noted_and_the_note_is_true(tmp_path):
    """τc/K3 = 18.9 counts against a window of 8: the note says moves may not arrive, and
    indeed none of these moves does, for the paper's settings, the rule of thumb, the
    S-curve source or a tuned setting."""
    f = tmp_path / "sticky.yaml"
    f.write_text("plant: {motor: {coulomb_nm: 0.01}}\n")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        axis = load_axis(f)
    notes = [str(w.message) for w in caught if issubclass(w.category, AxisNote)]
    assert len(notes) == 1 and "may stop the motor up to 18.9 counts" in notes[0]
    tuned = Settings(value_rad=0.882, error_limit_rad=0.872, k=430.9, ts_over_tf=1.0)
    ev = evaluate(
        ["paper", "rule-of-thumb", "scurve", tuned], axis.scenarios("test")[:6], axis=axis
    )
    assert not ev.feasible.any()
    assert axis_notes(PAPER_AXIS) == []


def test_an_option_the_axis_overrides_is_refused(tmp_path, capsys):
    axes = Path(__file__).resolve().parents[2] / "experiments" / "axes"
    for flag in ("--scenario-count", "--first-seed"):
        code = cli.main(["sweep", "--axis", str(axes / "belt.yaml"), flag, "4", "--runs-dir",
                         str(tmp_path)])  # fmt: skip
        err = capsys.readouterr().err
        assert code == 2 and f"{flag}='4' is ignored with --axis" in err
    assert not (tmp_path / "sweep").exists()


def test_a_best_yaml_used_on_another_axis_is_noted(tmp_path, capsys):
    axes = Path(__file__).resolve().parents[2] / "experiments" / "axes"
    runs = str(tmp_path / "runs")
    assert cli.main(["sweep", "--scenarios", "short-move", "--trials", "3", "--no-progress",
                     "--study", "s", "--runs-dir", runs]) == 0  # fmt: skip
    best = tmp_path / "runs" / "sweep" / "s" / "best.yaml"
    assert yaml.safe_load(best.read_text())["machine"]
    capsys.readouterr()
    args = ["evaluate", "--settings", str(best), "--against", "paper", "--runs-dir", runs]
    assert cli.main([*args, "--scenarios", "short-move", "--name", "same"]) == 0
    assert "note:" not in capsys.readouterr().err
    assert cli.main([*args, "--axis", str(axes / "belt.yaml"), "--name", "other"]) == 0
    err = capsys.readouterr().err
    assert err.count("tuned on axis paper, used on axis belt") == 1, err
    lu = str(axes / "loads-uncertain.yaml")
    assert cli.main(["simulate", "--settings", str(best), "--axis", lu, "--scenario",
                     "short-move"]) == 0  # fmt: skip
    assert "used on axis loads-uncertain" in capsys.readouterr().err


def test_a_users_earlier_work_is_not_replaced_without_a_word(tmp_path, capsys):
    """A fit of an edited axis under the same name, and a study continued in another kind
    of storage, are refused in one line before anything is written."""
    from vfgym.axis import write_axis

    axes = Path(__file__).resolve().parents[2] / "experiments" / "axes"
    runs = tmp_path / "runs"
    (runs / "fit" / "x").mkdir(parents=True)
    write_axis(load_axis(axes / "belt.yaml"), runs / "fit" / "x" / "axis.yaml")
    before = sorted(p.name for p in (runs / "fit" / "x").iterdir())
    code = cli.main(["fit", "--axis", str(axes / "paper.yaml"), "--name", "x", "--runs-dir",
                     str(runs), "--no-progress"])  # fmt: skip
    err = capsys.readouterr().err
    assert code == 2 and "holds a fit of another axis" in err and err.count("\n") == 1
    assert sorted(p.name for p in (runs / "fit" / "x").iterdir()) == before
    sweep = ["sweep", "--scenarios", "short-move", "--trials", "2", "--no-progress",
             "--study", "s", "--runs-dir", str(runs)]  # fmt: skip
    assert cli.main(sweep) == 0
    capsys.readouterr()
    assert cli.main([*sweep, "--storage", "journal"]) == 2
    err = capsys.readouterr().err
    assert "its study lives in sqlite:" in err and err.count("\n") == 1
    assert not (runs / "sweep" / "s" / "journal.log").exists()
    assert cli.main([*sweep, "--trials", "3"]) == 0  # the same storage continues


def test_a_stable_servo_passes_the_stability_check(tmp_path):
    """Twice the default gain, or half the speed gain B, still settles: the check takes the
    loop's own response, not a fixed bound."""
    for text in ("plant: {servo: {torque_per_count_nm: 0.002}}\n",
                 "plant: {servo: {speed_gain_b: 3}}\n"):  # fmt: skip
        f = tmp_path / f"s{len(text)}.yaml"
        f.write_text(text)
        load_axis(f)
