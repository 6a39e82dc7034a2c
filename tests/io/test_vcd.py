"""The VCD export: parsed back by a small independent reader, its pulses, directions and
encoder edges are counted against the simulated trace; and ``vfgym export`` end to end."""

from __future__ import annotations

import csv
import math

import numpy as np
import pytest

from vfgym import PAPER_PLANT, Scenario, evaluate
from vfgym.cli import main
from vfgym.io.vcd import edge_counts, parse_timescale, vcd_text

F = PAPER_PLANT.tick_hz

# to +0.4 rad, back to −0.4 rad, then +0.2 rad: reversals of the pulse train and the motor
ZIGZAG = Scenario("zigzag", "multi", 0.0, 0.05, moves=((0.4, 0.012), (-0.8, 0.016), (0.6, 0.01)))


def parse_vcd(text: str) -> tuple[float, dict[str, list[tuple[int, int]]], dict[str, int]]:
    """Timescale (s), per signal name the (time, value) changes after the dump, and the
    initial values. Written from the VCD grammar, not from vfgym.io.vcd."""
    scale = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9, "ps": 1e-12, "fs": 1e-15}
    tokens = text.split()
    names: dict[str, str] = {}
    unit = math.nan
    i = 0
    while tokens[i] != "$enddefinitions":
        if tokens[i] == "$timescale":
            j = tokens.index("$end", i)
            spec = "".join(tokens[i + 1 : j])
            num = "".join(ch for ch in spec if ch.isdigit())
            unit = int(num) * scale[spec[len(num) :]]
            i = j
        elif tokens[i] == "$var":
            _kind, _width, ident, name = tokens[i + 1 : i + 5]
            names[ident] = name
            i += 5
        elif tokens[i] == "$comment":
            i = tokens.index("$end", i)
        i += 1
    i += 2  # $enddefinitions $end
    changes: dict[str, list[tuple[int, int]]] = {n: [] for n in names.values()}
    initial: dict[str, int] = {}
    t = -1
    in_dump = False
    for tok in tokens[i:]:
        if tok.startswith("#"):
            t_new = int(tok[1:])
            assert t_new >= t, "time went backwards"
            t = t_new
        elif tok == "$dumpvars":
            in_dump = True
        elif tok == "$end":
            in_dump = False
        else:
            value, ident = int(tok[0]), tok[1:]
            if in_dump:
                initial[names[ident]] = value
            else:
                changes[names[ident]].append((t, value))
    return unit, changes, initial


def quadrature_decode(changes_a, changes_b, initial):
    """Counts from A/B edges: (times, count after each edge) with Gray state order
    00 → 10 → 11 → 01 counting up. Raises on an illegal (double) transition."""
    gray = {(0, 0): 0, (1, 0): 1, (1, 1): 2, (0, 1): 3}
    ev = sorted([(t, "a", v) for t, v in changes_a] + [(t, "b", v) for t, v in changes_b])
    a, b = initial["enc_a"], initial["enc_b"]
    count = 0
    times, counts = [], []
    for t, ch, v in ev:
        before = gray[(a, b)]
        if ch == "a":
            a = v
        else:
            b = v
        step = (gray[(a, b)] - before) % 4
        assert step in (1, 3), "an edge that is no quadrature step"
        count += 1 if step == 1 else -1
        times.append(t)
        counts.append(count)
    return np.array(times), np.array(counts)


@pytest.fixture(scope="module", params=["paper", "fixed-frequency"])
def exported(request):
    ev = evaluate(request.param, [ZIGZAG], keep_traces=True)
    tr = ev.traces[0][0]
    return tr, vcd_text(tr)


def test_pulses_and_directions_match_the_trace(exported):
    tr, text = exported
    unit, ch, init = parse_vcd(text)
    assert unit == 1e-9
    p = tr.pulses
    ticks = np.flatnonzero(p)
    rises = [t for t, v in ch["pulse"] if v == 1]
    falls = [t for t, v in ch["pulse"] if v == 0]
    assert len(rises) == len(falls) == ticks.size == tr.metrics["pulse_count"]
    # rising edge in the middle of the pulse's tick, falling at its end
    np.testing.assert_array_equal(rises, np.rint((ticks + 0.5) * 1e9 / F).astype(int))
    np.testing.assert_array_equal(falls, np.rint((ticks + 1.0) * 1e9 / F).astype(int))
    # direction level at each rising edge
    dir_changes = ch["dir"]
    level, k, signs = init["dir"], 0, []
    for t in rises:
        while k < len(dir_changes) and dir_changes[k][0] <= t:
            level = dir_changes[k][1]
            k += 1
        signs.append(1 if level else -1)
    np.testing.assert_array_equal(signs, p[ticks])
    assert sum(signs) == tr.pulse_count[-1]
    # the train reverses: the direction wire changes, and only where needed
    reversals = int(np.count_nonzero(np.diff(p[ticks])))
    assert reversals >= 2
    assert len(dir_changes) == reversals


def test_encoder_edges_match_the_trace(exported):
    tr, text = exported
    _, ch, init = parse_vcd(text)
    counts = edge_counts(tr)
    times, decoded = quadrature_decode(ch["enc_a"], ch["enc_b"], init)
    assert len(times) == counts["encoder_steps"] > 100
    assert np.all(np.diff(times) > 0), "two encoder edges at one time stamp"
    q = tr.plant.motor.count_rad
    c = np.floor(tr.motor_rad / q).astype(np.int64)
    assert decoded[-1] == c[-1] == counts["final_count"]
    # at every tick boundary the decoded count is the simulated one
    boundary = np.rint((np.arange(c.size) + 1.0) * 1e9 / F).astype(np.int64)
    idx = np.searchsorted(times, boundary, side="right")
    decoded_at = np.where(idx > 0, decoded[np.maximum(idx - 1, 0)], 0)
    np.testing.assert_array_equal(decoded_at, c)


def test_only_changes_are_written(exported):
    _, text = exported
    _, ch, init = parse_vcd(text)
    for name, changes in ch.items():
        level = init[name]
        for _, v in changes:
            assert v != level, f"{name} written without a change"
            level = v


def test_timescale_and_bad_input():
    ev = evaluate("paper", ["short-move"], keep_traces=True)
    tr = ev.traces[0][0]
    unit, ch, _ = parse_vcd(vcd_text(tr, timescale="1 ps"))
    assert unit == 1e-12
    ticks = np.flatnonzero(tr.pulses)
    rises = [t for t, v in ch["pulse"] if v == 1]
    np.testing.assert_array_equal(rises, np.rint((ticks + 0.5) * 1e12 / F).astype(int))
    assert parse_timescale("100us") == pytest.approx(1e-4)
    with pytest.raises(ValueError, match="timescale"):
        parse_timescale("3 ns")
    with pytest.raises(ValueError, match="too coarse"):
        vcd_text(tr, timescale="10 us")
    dec = evaluate("paper", ["short-move"], keep_traces=True, decimation=4).traces[0][0]
    with pytest.raises(ValueError, match="decimation"):
        vcd_text(dec)


def test_export_cli_vcd_and_csv(tmp_path, capsys):
    out = tmp_path / "move.vcd"
    assert main(["export", "--format", "vcd", "--scenario", "short-move", "--out", str(out)]) == 0
    tr = evaluate("paper", ["short-move"], keep_traces=True).traces[0][0]
    _, ch, _ = parse_vcd(out.read_text())
    assert sum(v for _, v in ch["pulse"]) == tr.metrics["pulse_count"]

    out = tmp_path / "move.csv"
    args = ["export", "--format", "csv", "--scenario", "short-move", "--baseline", "scurve"]
    assert main([*args, "--out", str(out)]) == 0
    with out.open() as fh:
        rows = list(csv.DictReader(fh))
    ev = evaluate("scurve", ["short-move"], keep_traces=True)
    tr = ev.traces[0][0]
    assert len(rows) == tr.n_ticks
    assert sum(int(r["pulse"]) for r in rows) == tr.pulse_count[-1]
    # floats read back bit for bit
    np.testing.assert_array_equal([float(r["motor_rad"]) for r in rows], tr.motor_rad)
    assert [int(r["encoder_count"]) for r in rows][-1] == math.floor(
        tr.motor_rad[-1] / tr.plant.motor.count_rad
    )

    out = tmp_path / "dec.csv"
    assert main([*args, "--out", str(out), "--decimation", "10"]) == 0
    with out.open() as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == tr.n_ticks // 10
    assert rows[0]["tick"] == "9" and rows[0]["pulse"] == ""


@pytest.mark.parametrize(
    ("argv", "needle"),
    [
        (["--scenario", "nowhere"], "nowhere"),
        (["--settings", "missing.yaml"], "missing.yaml"),
        (["--timescale", "7 ns"], "timescale"),
        (["--scenario", "paper-sine", "--baseline", "scurve"], "does not apply"),
    ],
)
def test_export_cli_bad_input(tmp_path, capsys, argv, needle):
    out = tmp_path / "x.vcd"
    assert main(["export", "--format", "vcd", *argv, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert needle in err and "\n" not in err
    assert not out.exists()


def test_export_never_replaces_a_named_file_unless_forced(tmp_path, capsys, monkeypatch):
    out = tmp_path / "mine.vcd"
    out.write_text("a file of mine\n")
    argv = ["export", "--format", "vcd", "--scenario", "short-move", "--out", str(out)]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "the file exists" in err and "--force" in err and err.count("\n") == 1
    assert out.read_text() == "a file of mine\n"
    assert main([*argv, "--force"]) == 0
    assert out.read_text().startswith("$comment")
    # the default name (no --out): an earlier export is replaced, and the line says so
    monkeypatch.chdir(tmp_path)
    args = ["export", "--format", "csv", "--scenario", "short-move"]
    assert main(args) == 0
    assert "replacing" not in capsys.readouterr().out
    assert main(args) == 0
    assert "(replacing the earlier export)" in capsys.readouterr().out


def test_a_pulse_train_and_a_sampled_record_written_by_the_one_writer(tmp_path):
    """A plan's train alone (no encoder wires), and a record started at an arbitrary instant
    rounded to 1 µs samples: several edges may share a stamp, none is lost."""
    from vfgym.io.vcd import trace_edges, train_edges, write_edges

    p = np.zeros(400, np.int8)
    p[[10, 11, 12, 50, 51, 200]] = [1, 1, 1, -1, -1, 1]
    text = tmp_path / "t.vcd"
    write_edges(train_edges(p, F), text, encoder=False, comment="a train")
    unit, ch, init = parse_vcd(text.read_text())
    assert set(ch) == {"pulse", "dir"} and init["dir"] == 1
    rises = [t for t, v in ch["pulse"] if v == 1]
    np.testing.assert_array_equal(rises, np.rint((np.flatnonzero(p) + 0.5) * 1e9 / F))
    assert [v for _, v in ch["dir"]] == [0, 1]  # before the first -1 and back before +1

    ev = evaluate("paper", [ZIGZAG], keep_traces=True)
    tr = ev.traces[0][0]
    edges = trace_edges(tr, start_s=0.0012345)
    path = write_edges(edges, tmp_path / "r.vcd", timescale="1 us")
    unit, ch, init = parse_vcd(path.read_text())
    assert unit == 1e-6
    _, decoded = quadrature_decode(ch["enc_a"], ch["enc_b"], init)
    assert decoded[-1] == edges.count[-1]
    assert len([v for _, v in ch["pulse"] if v == 1]) == edges.pulse_s.size
