"""``vfgym identify`` end to end, and every bad input as one line with exit status 2."""

from __future__ import annotations

import numpy as np
import pytest
from capture_synth import capture_vcd, draw_truth

from vfgym.axis import PAPER_AXIS, load_axis
from vfgym.cli import main
from vfgym.identify.plan import make_plan
from vfgym.io.trace_csv import write_trace_csv
from vfgym.io.vcd import trace_edges, train_edges, write_edges
from vfgym.moves.scenarios import SCENARIOS
from vfgym.params import PAPER_PLANT, PAPER_SETTINGS
from vfgym.plant import simulate


def test_plan_then_identify_from_the_command_line(tmp_path, capsys):
    assert main(["identify", "--plan", "--out", str(tmp_path / "plan")]) == 0
    out = capsys.readouterr().out
    assert "identify-step-fwd" in out and "identify-speed3-back" in out
    assert "identify-reverse" in out and "from about 2x the nominal inertia" in out
    # the plan's files are the user's now: a second --plan into the folder is refused
    assert main(["identify", "--plan", "--out", str(tmp_path / "plan")]) == 2
    err = capsys.readouterr().err
    assert "identify-moves.yaml' is not allowed: the file exists" in err and "--force" in err
    plan_axis = load_axis(tmp_path / "plan" / "identify-moves.yaml")
    names = [sc.name for sc in plan_axis.scenarios("train")]
    assert names == [sc.name for sc in make_plan(PAPER_AXIS).moves]
    # the VCD to replay holds the plan's pulse train, as pyvcd's reader sees it
    from vcd.reader import TokenKind, tokenize

    rises = 0
    with (tmp_path / "plan" / "identify-moves.vcd").open("rb") as fh:
        ids = {}
        level = {}
        for tok in tokenize(fh):
            if tok.kind is TokenKind.VAR:
                ids[tok.data.id_code] = tok.data.reference
            elif tok.kind is TokenKind.CHANGE_SCALAR and ids[tok.data.id_code] == "pulse":
                rises += tok.data.value == "1" and level.get("pulse") == "0"
                level["pulse"] = tok.data.value
    assert set(ids.values()) == {"pulse", "dir"}
    assert rises == np.count_nonzero(make_plan(PAPER_AXIS).pulses)
    # the dry run: a simulated capture of the moves on the nominal plant gives it back; it
    # starts before the drive's enable, which only --from-enable can say (nothing sags)
    dry = tmp_path / "plan" / "identify-moves-nominal.vcd"
    cmd = ["identify", "--capture", str(dry), "--out", str(tmp_path / "dry.yaml")]
    assert main([*cmd, "--from-enable"]) == 0
    out = capsys.readouterr().out
    assert "from the drive's enable (the axis moved +0 counts" in out
    assert "note: load_torque_nm" not in out
    assert load_axis(tmp_path / "dry.yaml").plant.motor.inertia_kgm2 == pytest.approx(
        PAPER_PLANT.motor.inertia_kgm2, rel=0.005
    )
    assert main([*cmd, "--force"]) == 0  # without it: the axis may have been held since
    out = capsys.readouterr().out
    assert "note: load_torque_nm: not excited" in out
    assert "note: torque_per_count: not separated" in out and "inertia/gain = " in out

    rng = np.random.default_rng([27_182, 1])
    truth = draw_truth(PAPER_PLANT, rng, inertia_ratio=(2.5, 4.0))
    cap = capture_vcd(truth.plant, make_plan(PAPER_AXIS).pulses, tmp_path / "cap.vcd", rng)
    out_axis = tmp_path / "identified.yaml"
    assert main(["identify", "--capture", str(cap), "--out", str(out_axis)]) == 0
    out = capsys.readouterr().out
    assert "beside the quantisation floor 0.289 counts RMS" in out
    ident = load_axis(out_axis)
    assert not ident.uncertainty.exact
    assert ident.plant.motor.inertia_kgm2 == pytest.approx(truth.plant.motor.inertia_kgm2, rel=0.02)


@pytest.fixture(scope="module")
def move():
    """A simulated move with rest before and after (the paper's reversal, delayed)."""
    sc = SCENARIOS["reversal"]
    f = PAPER_PLANT.tick_hz
    cmd = np.concatenate([np.zeros(round(0.02 * f)), sc.command(PAPER_PLANT)])
    return simulate(cmd, PAPER_SETTINGS, PAPER_PLANT)


def _vcd(move, path, **kw):
    start = kw.pop("start_s", 0.01)
    stop = kw.pop("stop_s", None)
    return write_edges(trace_edges(move, start_s=start, stop_s=stop), path, **kw)


def _csv(move, path, drop=None, cell=None):
    write_trace_csv(move, path)
    lines = path.read_text().splitlines()
    if drop:
        head = lines[0].split(",")
        k = head.index(drop)
        lines = [",".join(x for j, x in enumerate(row.split(",")) if j != k) for row in lines]
    if cell:
        row = lines[5].split(",")
        row[lines[0].split(",").index("time_s")] = cell
        lines[5] = ",".join(row)
    path.write_text("\n".join(lines) + "\n")
    return path


BAD = {
    "missing-file": (lambda m, d: d / "none.vcd", [], ["none.vcd", "cannot be read"]),
    "not-a-vcd": (
        lambda m, d: (d / "junk.vcd").write_bytes(b"\x00\x01 hello") and d / "junk.vcd",
        [],
        ["junk.vcd", "expected a VCD"],
    ),
    "corrupt-body": (
        lambda m, d: (
            (d / "c.vcd").write_text(_vcd(m, d / "c0.vcd").read_text().replace("#", "#x", 3))
            and d / "c.vcd"
        ),
        [],
        ["c.vcd", "is not a whole number"],
    ),
    "missing-signal": (
        lambda m, d: _vcd(m, d / "s.vcd", encoder=False),
        [],
        ["s.vcd", "signal 'enc_a'", "--signals"],
    ),
    "sigrok-names-unmapped": (
        lambda m, d: _vcd(m, d / "n.vcd", names=("D0", "D1", "D2", "D3"), scope="libsigrok"),
        [],
        ["n.vcd", "signal 'pulse' (named 'pulse') is missing", "D0"],
    ),
    "bad-signal-map": (
        lambda m, d: _vcd(m, d / "m.vcd"),
        ["--signals", "pulse:D0"],
        ["--signals='pulse:D0'", "signal=name"],
    ),
    "shorter-than-a-move": (
        lambda m, d: _vcd(m, d / "short.vcd", stop_s=0.05),
        [],
        ["short.vcd", "after its last pulse", "shorter than a move"],
    ),
    "starts-inside-a-move": (
        lambda m, d: _vcd(m, d / "late.vcd", start_s=0.03),
        [],
        ["late.vcd", "starts inside a move"],
    ),
    "no-pulse": (
        lambda m, d: write_edges(
            train_edges(np.zeros(1000, np.int8), PAPER_PLANT.tick_hz), d / "idle.vcd"
        ),
        [],
        ["idle.vcd", "no command pulse"],
    ),
    "csv-column-missing": (
        lambda m, d: _csv(m, d / "m.csv", drop="encoder_count"),
        [],
        ["m.csv", "column 'encoder_count' is missing", "time_s, pulse_count, encoder_count"],
    ),
    "csv-not-a-number": (
        lambda m, d: _csv(m, d / "x.csv", cell="abc"),
        [],
        ["x.csv", "line 6", "'time_s' holds 'abc'", "expected a number"],
    ),
}


@pytest.mark.parametrize("case", list(BAD))
def test_a_bad_capture_is_one_line_and_exit_2(move, tmp_path, capsys, case):
    make, extra, words = BAD[case]
    path = make(move, tmp_path)
    code = main(["identify", "--capture", str(path), "--out", str(tmp_path / "o.yaml"), *extra])
    err = capsys.readouterr().err
    assert code == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("vfgym identify: error: "), err
    for w in words:
        assert w in lines[0], (w, lines[0])
    assert not (tmp_path / "o.yaml").exists()


def test_identify_without_a_capture_or_with_both_is_refused(tmp_path, capsys):
    assert main(["identify", "--out", str(tmp_path / "o.yaml")]) == 2
    assert "--capture FILE is required" in capsys.readouterr().err
    code = main(["identify", "--plan", "--capture", "x.vcd", "--out", str(tmp_path)])
    assert code == 2
    assert "--capture is not allowed with --plan" in capsys.readouterr().err


def _faulty(d, **kw):
    """A capture of the plan's first two moves (rest before and after) with faults."""
    from vfgym.identify.plan import moves_pulses
    from vfgym.identify.simulated import record_capture, with_faults

    pulses = moves_pulses(make_plan(PAPER_AXIS).moves[:2], PAPER_PLANT)
    src = record_capture(PAPER_PLANT, pulses, d / "clean.vcd", start_s=0.05, rest_s=0.1)
    with_faults(src, d / "faulty.vcd", np.random.default_rng(3), **kw)
    return d / "faulty.vcd"


UNTRUSTED = {
    "encoder-edges-lost": ({"lost": 2}, ["faulty.vcd", "reverses at speed 2 times", "lost"]),
    "a-and-b-swapped": ({"swap": True}, ["faulty.vcd", "counts against the pulses", "--signals"]),
    "cut-mid-line": ({"cut_s": 0.05}, ["faulty.vcd", "ends mid-line", "truncated"]),
}


@pytest.mark.parametrize("case", list(UNTRUSTED))
def test_a_capture_that_cannot_be_trusted_is_refused(tmp_path, capsys, case):
    kw, words = UNTRUSTED[case]
    path = _faulty(tmp_path, **kw)
    out = tmp_path / "o.yaml"
    assert main(["identify", "--capture", str(path), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and err.startswith("vfgym identify: error: "), err
    for w in words:
        assert w in err, (w, err)
    assert not out.exists()


def test_out_never_replaces_a_users_file_unless_forced(tmp_path, capsys):
    nominal = tmp_path / "nominal.yaml"
    nominal.write_text("# my axis, with my comments\nname: mine\n")
    for out, words in ((nominal, "it is the --axis file, an input"), (tmp_path / "x.vcd",
                       "it is the --capture file"), (tmp_path / "other.yaml",
                       "the file exists")):  # fmt: skip
        out.touch()
        argv = ["identify", "--axis", str(nominal), "--capture", str(tmp_path / "x.vcd")]
        assert main([*argv, "--out", str(out)]) == 2
        err = capsys.readouterr().err
        assert words in err and "--force" in err and err.count("\n") == 1
    assert nominal.read_text().startswith("# my axis, with my comments")
    # with --force the command goes on (here to the capture, which is empty)
    assert main([*argv, "--out", str(nominal), "--force"]) == 2
    assert "x.vcd" in capsys.readouterr().err
    assert nominal.read_text().startswith("# my axis")


def test_a_true_axis_files_capture_round_trips_through_sigrok_csv(tmp_path, capsys):
    """The documented route to a capture of a "true" axis file: --plan --true-axis; then
    sigrok-cli's CSV of it (its time column) identifies that file's plant."""
    import shutil
    import subprocess

    true = tmp_path / "heavy.yaml"
    true.write_text(
        "plant:\n  motor: {preset: SGME-02A, inertia_ratio: 3.0, coulomb_nm: 0.004, "
        "load_torque_nm: -0.002}\n  servo: {follows_load: false}\n"
    )
    plan = tmp_path / "plan"
    assert main(["identify", "--plan", "--true-axis", str(true), "--out", str(plan)]) == 0
    capture = plan / "identify-moves-on-heavy.vcd"
    assert f"wrote {capture}" in capsys.readouterr().out
    if shutil.which("sigrok-cli") is None:
        pytest.skip("sigrok-cli is not installed (Debian package sigrok-cli)")
    csv = tmp_path / "heavy.csv"
    subprocess.run(["sigrok-cli", "-I", "vcd", "-i", str(capture), "-O", "csv:time=true",
                    "-o", str(csv)], check=True, capture_output=True, timeout=600)  # fmt: skip
    out = tmp_path / "identified.yaml"
    assert main(["identify", "--capture", str(csv), "--from-enable", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "torque_per_count" in text and "not separated" not in text
    ident = load_axis(out)
    want = load_axis(true).plant.motor
    assert ident.plant.motor.inertia_kgm2 == pytest.approx(want.inertia_kgm2, rel=0.02)
    assert ident.plant.motor.coulomb_nm == pytest.approx(want.coulomb_nm, abs=0.01 * 0.637)
    assert ident.plant.motor.load_torque_nm == pytest.approx(want.load_torque_nm, abs=0.01 * 0.637)
