"""Reading captures: against the simulated trace itself, through sigrok-cli, and as CSV."""

from __future__ import annotations

import shutil
import subprocess

import numpy as np
import pytest

from vfgym.identify.capture import parse_signal_map, read_capture
from vfgym.io.trace_csv import write_trace_csv
from vfgym.io.vcd import edge_counts, trace_edges, write_edges, write_vcd
from vfgym.moves.scenarios import SCENARIOS
from vfgym.params import PAPER_PLANT, PAPER_SETTINGS
from vfgym.plant import simulate


@pytest.fixture(scope="module")
def trace():
    """The paper's reversal move (both directions) by the V-F controller."""
    sc = SCENARIOS["reversal"]
    plant = sc.plant(PAPER_PLANT)
    return simulate(sc.command(plant), PAPER_SETTINGS, plant)


def _tick_end_counts(trace, cap, ticks):
    """The capture's count at the end of the given ticks (a hair after, for rounding)."""
    T = trace.plant.tick_s
    return cap.count_at((ticks + 1) * T + 1e-12)


def test_an_export_reads_as_the_trace_it_was_written_from(trace, tmp_path):
    path = write_vcd(trace, tmp_path / "move.vcd")
    cap = read_capture(path)
    want = edge_counts(trace)
    assert np.count_nonzero(cap.pulse_sign > 0) == want["pulses_pos"]
    assert np.count_nonzero(cap.pulse_sign < 0) == want["pulses_neg"]
    assert cap.count[-1] == want["final_count"]
    assert cap.end_s == pytest.approx(trace.n_ticks * trace.plant.tick_s, abs=1e-9)
    # the pulse of tick i rises half a tick in, with the sign of the train
    T = trace.plant.tick_s
    ticks = np.flatnonzero(trace.pulses)
    assert np.allclose(cap.pulse_s, (ticks + 0.5) * T, atol=1e-9)
    assert np.array_equal(cap.pulse_sign, trace.pulses[ticks])
    # the decoded count is floor(theta / q) at every tick boundary
    every = np.arange(0, trace.n_ticks, 7)
    q = trace.plant.motor.count_rad
    want_c = np.floor(trace.motor_rad[every] / q).astype(np.int64)
    assert np.array_equal(_tick_end_counts(trace, cap, every), want_c)


@pytest.mark.skipif(
    shutil.which("sigrok-cli") is None,
    reason="sigrok-cli is not installed (Debian package sigrok-cli; .ci/sigrok.sh installs it)",
)
def test_an_export_round_tripped_through_sigrok_reads_the_same(trace, tmp_path):
    src = write_vcd(trace, tmp_path / "move.vcd")
    out = tmp_path / "sigrok.vcd"
    subprocess.run(
        ["sigrok-cli", "-I", "vcd", "-i", str(src), "-O", "vcd", "-o", str(out)],
        check=True,
        capture_output=True,
        timeout=120,
    )
    assert b"libsigrok" in out.read_bytes()[:2000]
    a, b = read_capture(src), read_capture(out)
    for name in ("pulse_s", "pulse_sign", "count_s", "count"):
        assert np.array_equal(getattr(a, name), getattr(b, name)), name
    assert a.end_s == pytest.approx(b.end_s)


def test_sigrok_channel_names_are_mapped_with_signals(trace, tmp_path):
    rng_start = 0.0123456
    edges = trace_edges(trace, start_s=rng_start)
    path = write_edges(
        edges,
        tmp_path / "d.vcd",
        timescale="1 us",
        names=("D0", "D1", "D2", "D3"),
        scope="libsigrok",
    )
    with pytest.raises(ValueError, match=r"signal 'pulse' .*missing.*--signals"):
        read_capture(path)
    cap = read_capture(path, parse_signal_map("pulse=D0,dir=D1,enc_a=D2,enc_b=D3"))
    assert cap.pulse_s.size == edges.pulse_s.size
    assert cap.count[-1] == edges.count[-1]


def test_a_1mhz_record_keeps_every_pulse_and_the_count(trace, tmp_path):
    """Rounded to 1 µs the A/B edges of fast counting may share a sample: two steps on."""
    edges = trace_edges(trace, start_s=0.0004321)
    cap = read_capture(write_edges(edges, tmp_path / "r.vcd", timescale="1 us"))
    assert np.array_equal(cap.pulse_sign, edges.pulse_sign)
    assert np.max(np.abs(cap.pulse_s - edges.pulse_s)) <= 0.5e-6 + 1e-12
    assert cap.count[-1] == edges.count[-1]


def test_a_csv_trace_reads_as_the_trace(trace, tmp_path):
    path = write_trace_csv(trace, tmp_path / "move.csv")
    cap = read_capture(path)
    want = edge_counts(trace)
    assert np.count_nonzero(cap.pulse_sign > 0) == want["pulses_pos"]
    assert np.count_nonzero(cap.pulse_sign < 0) == want["pulses_neg"]
    assert cap.count[-1] == want["final_count"]
    T = trace.plant.tick_s
    ticks = np.flatnonzero(trace.pulses)
    assert np.allclose(cap.pulse_s, (ticks + 0.5) * T - T, atol=1e-9)  # from the first row


def test_signal_map_refuses_unknown_signals():
    with pytest.raises(ValueError, match="--signals="):
        parse_signal_map("clock=D0")
    assert parse_signal_map("pulse=D0")["enc_a"] == "enc_a"


def test_a_sampled_capture_reads_the_count_at_the_middle_of_its_sample(tmp_path):
    """On the tick grid, a 1 MHz record's count at each sample is the true count at the
    middle of the analyser's sample holding the tick's end (read_offset_s), and the true
    grid phase lies within the width the pulses leave."""
    from vfgym.identify.model import SAMPLE_TICKS, record_of

    plant = PAPER_PLANT
    T = plant.tick_s
    rng = np.random.default_rng(4)
    pulses = np.zeros(30000, np.int8)
    pulses[3000:9000] = 1  # the top speed: three counts a tick
    pulses[12000:20000:2] = -1
    tr = simulate(np.zeros(pulses.size), PAPER_SETTINGS, plant, pulses=pulses)
    start = 0.0031 + 1e-6 * rng.uniform()
    cap = read_capture(write_edges(trace_edges(tr, start_s=start), tmp_path / "s.vcd",
                                       timescale="1 us"))  # fmt: skip
    rec = record_of(cap, plant)
    true_phase = (-start / T) % 1.0
    miss = ((rec.phase - true_phase + 0.5) % 1.0 - 0.5) * T
    assert 0 < rec.phase_width_s < 0.5e-6 and abs(miss) <= rec.phase_width_s / 2 + 1e-9
    assert np.all(np.abs(rec.read_offset_s) <= 0.5e-6 + 1e-12)
    # the true count at the read instants, relative to the count at the record's start
    first = int(np.ceil(-rec.phase - 1e-9))
    ends = (np.arange(1, rec.measured.size + 1) * SAMPLE_TICKS + first + rec.phase) * T
    t_sim = np.arange(1, tr.n_ticks + 1) * T - start  # the trace's tick ends, record time
    q = plant.motor.count_rad
    at = np.floor(np.interp(ends + rec.read_offset_s, t_sim, tr.motor_rad) / q)
    c0 = np.floor(np.interp(0.0, t_sim, tr.motor_rad) / q)
    moving = np.abs(np.interp(ends, t_sim, tr.speed_rad_s)) > 100.0
    assert moving.sum() > 1000
    assert np.mean(rec.measured - 0.5 == at - c0) > 0.999
    # read at the ticks' ends instead, the count is off a count on many moving samples
    at_end = np.floor(np.interp(ends, t_sim, tr.motor_rad) / q)
    assert np.mean((rec.measured - 0.5 != at_end - c0)[moving]) > 0.05


SIGROK = pytest.mark.skipif(
    shutil.which("sigrok-cli") is None,
    reason="sigrok-cli is not installed (Debian package sigrok-cli; .ci/sigrok.sh installs it)",
)


def _sigrok(src, out, fmt):
    subprocess.run(["sigrok-cli", "-I", "vcd", "-i", str(src), "-O", fmt, "-o", str(out)],
                   check=True, capture_output=True, timeout=300)  # fmt: skip
    return out


@SIGROK
@pytest.mark.parametrize("fmt", ["csv", "csv:time=true", "csv:label=channel"])
def test_sigrok_csv_reads_as_the_vcd_it_was_made_from(trace, tmp_path, fmt):
    """sigrok-cli's CSV (comment lines, a header row of units or names, a row a sample,
    with or without its time column) holds the same pulses and count as the capture."""
    src = write_edges(trace_edges(trace, start_s=0.0004321), tmp_path / "c.vcd",
                      timescale="1 us", names=("D0", "D1", "D2", "D3"))  # fmt: skip
    out = _sigrok(src, tmp_path / "c.csv", fmt)
    head = out.read_text()[:400]
    assert head.startswith(";") and "Channels (4/4): D0, D1, D2, D3" in head
    names = parse_signal_map("pulse=D0,dir=D1,enc_a=D2,enc_b=D3")
    a, b = read_capture(src, names), read_capture(out, names)
    for name in ("pulse_s", "pulse_sign", "count_s", "count"):
        assert np.array_equal(getattr(a, name), getattr(b, name)), name
    assert b.resolution_s == 1e-6 and b.sampled
    assert 0 <= a.end_s - b.end_s <= 1e-6 + 1e-12  # the CSV ends at its last sample
    with pytest.raises(ValueError, match=r"signal 'pulse' \(named 'pulse'\) is missing.*D0"):
        read_capture(out)


def _sigrok_text(rows, *, time=None, rate="1 MHz", names=("pulse", "dir", "enc_a", "enc_b")):
    """A CSV as sigrok-cli writes it, from rows of levels (a time column in ``time``'s unit)."""
    lines = ["; CSV generated by libsigrok", f"; Channels (4/4): {', '.join(names)}"]
    if rate:
        lines.append(f"; Samplerate: {rate}")
    lines.append(",".join(([time] if time else []) + ["logic"] * 4))
    for t, row in rows:
        lines.append(",".join(([str(t)] if time else []) + [str(v) for v in row]))
    return "\n".join(lines) + "\n"


def _levels(n=4000):
    """Levels of a short capture: a rest, 20 pulses forward with the count following."""
    rows = []
    a = b = 0
    for i in range(n):
        p = int(1000 <= i < 1800 and (i - 1000) % 40 < 10)
        if 1000 <= i < 1800 and (i - 1000) % 10 == 5:  # four counts per pulse
            a, b = {(0, 0): (1, 0), (1, 0): (1, 1), (1, 1): (0, 1), (0, 1): (0, 0)}[(a, b)]
        rows.append((i, (p, 1, a, b)))
    return rows


def test_a_sigrok_csv_with_only_the_changes_is_placed_by_its_time_column(tmp_path):
    rows = _levels()
    every = tmp_path / "every.csv"
    every.write_text(_sigrok_text(rows))
    changed = [r for k, r in enumerate(rows) if k == 0 or k == len(rows) - 1
               or r[1] != rows[k - 1][1]]  # fmt: skip
    dedup = tmp_path / "dedup.csv"
    dedup.write_text(_sigrok_text(changed, time="microseconds"))
    a, b = read_capture(every), read_capture(dedup)
    assert a.pulse_s.size == 20 and a.count[-1] == 80
    for name in ("pulse_s", "pulse_sign", "count_s", "count"):
        assert np.array_equal(getattr(a, name), getattr(b, name)), name
    # the changes alone, without times (sigrok's time column empty): refused, not misread
    blank = tmp_path / "blank.csv"
    blank.write_text(_sigrok_text([(0, r) for _, r in changed], time="samples"))
    with pytest.raises(ValueError, match="only the rows that change"):
        read_capture(blank)
    # no sample rate and no time column: refused
    norate = tmp_path / "norate.csv"
    norate.write_text(_sigrok_text(rows, rate=None))
    with pytest.raises(ValueError, match="no sample rate"):
        read_capture(norate)
    # a file cut mid-row
    cut = tmp_path / "cut.csv"
    cut.write_text(_sigrok_text(rows)[:-5])
    with pytest.raises(ValueError, match="truncated"):
        read_capture(cut)


def test_glitches_are_taken_out_and_their_times_kept(tmp_path):
    rows = _levels()
    glitched = [(t, (p, d, 1 - a if t in (300, 2500) else a, 1 - b if t == 3100 else b))
                for t, (p, d, a, b) in rows]  # fmt: skip
    clean, dirty = tmp_path / "clean.csv", tmp_path / "dirty.csv"
    clean.write_text(_sigrok_text(rows))
    dirty.write_text(_sigrok_text(glitched))
    a, b = read_capture(clean), read_capture(dirty)
    for name in ("pulse_s", "pulse_sign", "count_s", "count"):
        assert np.array_equal(getattr(a, name), getattr(b, name)), name
    assert a.glitches == ()
    assert [(n, round(t * 1e6)) for n, t in b.glitches] == [
        ("enc_a", 300),
        ("enc_a", 2500),
        ("enc_b", 3100),
    ]


def test_a_vcd_cut_mid_line_is_named_truncated(trace, tmp_path):
    src = write_vcd(trace, tmp_path / "move.vcd")
    text = src.read_bytes()
    cut = tmp_path / "cut.vcd"
    cut.write_bytes(text[: text.rindex(b"\n#") + 4])
    with pytest.raises(ValueError, match=r"cut.vcd: the file ends mid-line .*truncated"):
        read_capture(cut)
