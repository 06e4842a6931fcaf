"""Segments of a cycle (approach, hold, retract) in the readers: told apart by the motion
(:func:`segments_from_motion`), kept in the canonical CSV's ``segment`` column, and classified
from afmformats' segments of real JPK files (stress relaxation with its pre-approach pause,
creep compliance with its creeping hold, force-distance read exactly as before)."""

from __future__ import annotations

import warnings

import numpy as np
import pandas as pd
import pytest

from palpbayes.errors import DataFileError, InputError
from palpbayes.io.afm import classify_segments, describe_afm, parse_segments, read_afm
from palpbayes.io.motion_segments import (
    default_hold_tolerance,
    segment_durations,
    segments_from_motion,
)
from palpbayes.io.trace_csv import read_trace, write_trace
from palpbayes.trace import SEGMENTS, IndentationTrace

RATE = 500.0  # [Hz]


def cycle(approach=2.0, hold=1.0, retract=2.0, depth=2e-3, noise=2e-6, rng=0):
    """Robot-like cycle: z from 0 down `depth` [m] at constant speed, hold, back up; white
    noise of sd `noise` [m]; returns time, z, and the true first index of hold and retract."""
    n_a, n_h, n_r = (round(d * RATE) for d in (approach, hold, retract))
    z = np.concatenate([np.linspace(0.0, -depth, n_a, endpoint=False), np.full(n_h, -depth),
                        np.linspace(-depth, 0.0, n_r)])
    z = z + np.random.default_rng(rng).normal(0.0, noise, z.size)
    return np.arange(z.size) / RATE, z, n_a, n_a + n_h


def runs(codes: np.ndarray) -> list[int]:
    """The codes in the order they occur, one per run."""
    return [int(c) for c in codes[np.r_[0, np.flatnonzero(np.diff(codes)) + 1]]]


# ------------------------------------------------------------------ segment_durations
def test_segment_durations_add_up_whatever_rate_each_segment_was_sampled_at():
    """A JPK stress-relaxation layout: a 1 s pause at 256 Hz, a 1 s approach at 2048 Hz, a
    30 s hold at 256 Hz, a retract of 1951 samples at 2048 Hz; each lasts its samples' span
    plus one of its own periods, in time order of its first sample."""
    rates, n = (256.0, 2048.0, 256.0, 2048.0), (256, 2048, 7680, 1951)
    t, seg, start = [], [], 0.0
    for i, (r, k) in enumerate(zip(rates, n, strict=True)):
        t.append(start + np.arange(k) / r)
        seg.append(np.full(k, i, dtype=np.uint8))
        start += k / r
    got = segment_durations(np.concatenate(t), np.concatenate(seg))
    assert list(got) == [0, 1, 2, 3]
    np.testing.assert_allclose(list(got.values()), [1.0, 1.0, 30.0, 1951 / 2048], rtol=1e-12)
    assert segment_durations([0.0, 0.1, 0.2], [5, 5, 7]) == pytest.approx({5: 0.2, 7: 0.0})
    with pytest.raises(InputError, match="one segment label per sample"):
        segment_durations([0.0, 0.1], [0])
    with pytest.raises(InputError, match="non-finite"):
        segment_durations([0.0, np.nan], [0, 0])


# ------------------------------------------------------------------ segments_from_motion
def test_noisy_ramp_hold_retract_is_split_where_the_motion_changes():
    t, z, hold, retract = cycle()
    z[1700] -= 0.5e-3  # a single spike below the hold (in the retract): not the deepest point
    z[1200] += 0.5e-3  # a single spike up in the hold: does not end it
    codes = segments_from_motion(t, z)
    assert codes.dtype == np.int8 and codes.shape == z.shape
    assert runs(codes) == [0, 1, 2]
    first_hold, first_retract = np.flatnonzero(np.diff(codes)) + 1
    # tolerance ~ 6 sd = 12 µm at 1 mm/s and 500 Hz: a handful of samples
    assert hold - 15 <= first_hold <= hold
    assert retract <= first_retract <= retract + 15
    assert default_hold_tolerance(z) == pytest.approx(6 * 2e-6, rel=0.3)
    trace = IndentationTrace(t, z, np.zeros_like(z), segment=codes)
    assert trace.segments("approach").n_points == first_hold


def test_a_trace_without_return_is_approach_and_hold():
    t, z, hold, retract = cycle(retract=0.0)
    codes = segments_from_motion(t, z)
    assert runs(codes) == [0, 1] and abs(int(np.argmax(codes == 1)) - hold) <= 15
    t, z, *_ = cycle(hold=0.0, retract=0.0, noise=0.0)  # ramp only: the last sample is deepest
    codes = segments_from_motion(t, z)
    assert runs(codes) == [0, 1] and np.count_nonzero(codes == 1) <= 2


def test_a_creeping_hold_needs_its_tolerance():
    t, z, hold, retract = cycle(noise=0.0)
    z[hold:retract] -= np.linspace(0.0, 20e-6, retract - hold)  # creeps 20 µm down
    z[retract:] -= 20e-6
    codes = segments_from_motion(t, z, hold_tolerance=25e-6)
    assert runs(codes) == [0, 1, 2]
    assert abs(int(np.argmax(codes == 1)) - hold) <= 15 and int(np.argmax(codes == 2)) >= retract
    default = segments_from_motion(t, z)  # the default (noise-free: 0.1 % of 2 mm) cuts it
    assert int(np.argmax(default == 1)) > hold + 0.5 * (retract - hold)


@pytest.mark.parametrize("time, z, kw, match", [
    ([0, 1, 2], [0, 1], {}, "time has 3 samples but z has 2"),
    ([0, 1], [0, 1], {}, "only 2 sample"),
    ([[0, 1, 2]], [[0, 1, 2]], {}, "one-dimensional"),
    ([0, 1, 2], [0, np.nan, 2], {}, "z has 1 non-finite value"),
    ([0, 2, 1], [0, 1, 2], {}, r"not strictly increasing at sample 2 \(2 s -> 1 s\)"),
    ([0, 1, 2], [0, -1, 0], {"hold_tolerance": -1e-6}, "hold_tolerance -1e-06 must be a "
     "non-negative number"),
    ([0, 1, 2], [0, -1, 0], {"hold_tolerance": "1"}, "hold_tolerance '1'"),
])
def test_bad_motion_input_is_an_input_error(time, z, kw, match):
    with pytest.raises(InputError, match=match):
        segments_from_motion(time, z, **kw)


# ------------------------------------------------------------------ canonical CSV
def _segmented_trace() -> IndentationTrace:
    t, z, hold, retract = cycle(approach=0.1, hold=0.05, retract=0.1, depth=2e-3)
    force = np.clip(-z - 1e-3, 0.0, None) * 100.0
    return IndentationTrace(t, z, force, trace_id="seg",
                            segment=segments_from_motion(t, z))


def test_segments_round_trip_through_the_csv(tmp_path):
    tr = _segmented_trace()
    path = write_trace(tr, tmp_path / "seg.csv", float_format="%.17g")
    df = pd.read_csv(path)
    assert list(df.columns) == ["time_s", "z_m", "force_n", "segment"]
    assert set(df["segment"]) == set(SEGMENTS)
    back = read_trace(path)
    np.testing.assert_array_equal(back.segment, tr.segment)
    np.testing.assert_array_equal(back.z, tr.z)
    assert back.segment_names == SEGMENTS
    assert back.segments("hold").n_points == np.count_nonzero(tr.segment == 1)


def test_a_csv_without_segments_reads_and_writes_as_before(tmp_path):
    tr = _segmented_trace().replace(segment=None)
    path = write_trace(tr, tmp_path / "plain.csv")
    assert path.read_text().splitlines()[0] == "time_s,z_m,force_n"
    assert read_trace(path).segment is None


@pytest.mark.parametrize("values", [
    ["0", "0", "1", "2", "2"], ["Approach", "approach ", "HOLD", "retract", "retract"],
    ["0", "approach", "hold", "2", "retract"]])
def test_segment_codes_and_names_are_read(tmp_path, values):
    rows = "".join(f"{i * 0.1:g},{-i * 1e-3:g},{i * 0.1:g},{v}\n" for i, v in enumerate(values))
    (tmp_path / "s.csv").write_text("time_s,z_m,force_n,segment\n" + rows)
    tr = read_trace(tmp_path / "s.csv", check=False)
    np.testing.assert_array_equal(tr.segment, [0, 0, 1, 2, 2])


@pytest.mark.parametrize("values, match", [
    (["approach", "approach", "press", "hold"], r"column 'segment' has 'press' at data row 3"),
    (["0", "0", "5", "2"], r"column 'segment' has 5 at data row 3"),
    (["approach", "", "hold", "hold"], r"column 'segment' is empty at data row 2"),
    (["approach", "hold", "approach", "retract"], r"segment goes back from hold to approach "
     r"at data row 3"),
])
def test_bad_segment_values_name_the_row(tmp_path, values, match):
    rows = "".join(f"{i * 0.1:g},{-i * 1e-3:g},{i * 0.1:g},{v}\n" for i, v in enumerate(values))
    path = tmp_path / "bad.csv"
    path.write_text("time_s,z_m,force_n,segment\n" + rows)
    with pytest.raises(DataFileError, match=match) as err:
        read_trace(path, check=False)
    assert str(err.value).startswith(str(path))


# ------------------------------------------------------------------ AFM segments
SR = "fmt-jpk-sr_cell1-0008.jpk-force"
CC = ["fmt-jpk-cc_pr14-brain-2021.06.30.jpk-force",
      "fmt-jpk-cc_pr14-polymergel-2021.06.30.jpk-force"]
FD = ["fmt-jpk-fd_spot3-0192.jpk-force", "fmt-jpk-fd_2020.02.07-16.29.05.036.jpk-qi-data",
      "fmt-jpk-fd_map2x2_extracted.jpk-force-map",
      "pyfmrheo-map-data-2022.10.29-12.27.34.564.jpk-force-map"]


@pytest.fixture(scope="module")
def afm_files(shared_data):
    return shared_data("afm-files", files=[SR, *CC, *FD])


@pytest.fixture(autouse=True)
def _quiet_afmformats():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # afmformats' own warnings about JPK metadata
        yield


def test_stress_relaxation_has_approach_with_its_pause_a_30_s_hold_and_retract(afm_files):
    path = afm_files / SR
    (full,) = read_afm(path, segments="all")
    assert full.segment_names == SEGMENTS
    assert full.metadata["afm_modality"] == "stress-relaxation"
    assert full.metadata["afm_segments"] == "0 approach, 1 approach, 2 hold, 3 retract"
    hold = full.segments("hold")
    assert hold.n_points == 7680 and hold.time[-1] - hold.time[0] == pytest.approx(30.0, abs=0.01)
    approach = full.segments("approach")
    assert approach.n_points == 256 + 2048  # the 1-s pause, then the ramp
    pause = approach.time < 0.99
    assert np.ptp(approach.z[pause]) < 0.01 * np.ptp(approach.z)  # the tip waits ...
    assert approach.z[-1] < approach.z[0] - 15e-6  # ... then moves down ~20 µm
    (default,) = read_afm(path)
    assert default.segment_names == ("approach",) and default.time[0] == 0.0
    np.testing.assert_array_equal(default.z, approach.z)
    np.testing.assert_array_equal(default.time, approach.time)
    (no_hold,) = read_afm(path, segments="approach,retract")
    assert no_hold.n_points == full.n_points - 7680 and no_hold.segment_names == (
        "approach", "retract")
    assert describe_afm(path)[0].segment_names == {0: "approach", 1: "approach", 2: "hold",
                                                   3: "retract"}


@pytest.mark.parametrize("name", CC)
def test_creep_compliance_has_three_segments_and_the_creep_is_hold(afm_files, name):
    (full,) = read_afm(afm_files / name, segments=["approach", "hold", "retract"])
    assert full.metadata["afm_modality"] == "creep-compliance"
    assert [full.segments(n).n_points for n in SEGMENTS] == [3000, 3000, 3000]
    hold = full.segments("hold")
    assert hold.z[-1] < hold.z[0]  # at constant force the tip creeps down
    (default,) = read_afm(afm_files / name)
    assert default.n_points == 3000 and default.segment_names == ("approach",)


@pytest.mark.parametrize("name", FD)
def test_force_distance_default_is_afmformats_segment_0(afm_files, name):
    import afmformats

    raw = afmformats.load_data(afm_files / name)
    traces = read_afm(afm_files / name)
    assert len(traces) == len(raw)
    for tr, curve in zip(traces, raw, strict=True):
        appr = np.asarray(curve["segment"]) == 0
        assert tr.n_points == int(appr.sum())
        np.testing.assert_array_equal(tr.force, np.asarray(curve["force"])[appr])
        assert tr.segment_names == ("approach",) and not tr.segment.any()
        assert tr.metadata["afm_modality"] == "force-distance"
    (both,) = read_afm(afm_files / name, curves=[0], segments="all")
    assert both.segment_names == ("approach", "retract") and both.n_points == len(raw[0])


def test_a_missing_segment_names_the_curve_what_it_has_and_what_is_missing(afm_files):
    path = afm_files / FD[0]
    with pytest.raises(DataFileError, match=r"curve 0 \(force-distance\) has no hold segment; "
                       r"it has approach, retract \(afmformats segments: 0 approach, 1 retract\)"
                       r" \(read segments=approach,retract instead\)"):
        read_afm(path, segments=("approach", "hold"))
    (retract,) = read_afm(path, segments="retract")
    assert retract.time[0] == 0.0 and retract.z[-1] > retract.z[0]
    assert retract.segment_names == ("retract",)


@pytest.mark.parametrize("segments, match", [
    ("press", "unknown segment 'press'"), ((), "no segment given"), (5, "must be 'all'")])
def test_bad_segment_names_are_input_errors(segments, match):
    with pytest.raises(InputError, match=match):
        parse_segments(segments)


def test_parse_segments_keeps_time_order():
    assert parse_segments("retract, approach") == ("approach", "retract")
    assert parse_segments("ALL") == SEGMENTS and parse_segments(["hold"]) == ("hold",)


# ------------------------------------------------------------------ classification rule
def _curve(moves, modality="force-distance", n=50):
    """Segment numbers and heights of segments moving by `moves` [fraction of 1 µm]."""
    seg = np.repeat(np.arange(len(moves)), n)
    start = 10e-6
    h = []
    for m in moves:
        h.append(np.linspace(start, start + m * 1e-6, n))
        start += m * 1e-6
    return classify_segments(seg, np.concatenate(h), modality)


@pytest.mark.parametrize("moves, modality, names", [
    ([-1, 1], "force-distance", "approach retract"),
    ([0, -1, 0, 0.95], "stress-relaxation", "approach approach hold retract"),
    ([-1, -0.05, 1], "creep-compliance", "approach hold retract"),
    ([-1, -0.3, 1.3], "creep-compliance", "approach hold retract"),  # a deep creep is hold
    ([-0.5, -0.5, 1], "force-distance", "approach approach retract"),  # two-speed approach
    ([-1, 1, 0, -1, 1], "force-distance", "approach retract retract ignored ignored"),
    ([0, 1], "force-distance", "hold retract"),  # no approach
    ([0, 0], "force-distance", "hold hold"),
])
def test_segments_are_classified_by_motion_then_order(moves, modality, names):
    assert list(_curve(moves, modality).values()) == names.split()


def test_without_a_height_the_order_decides():
    seg = np.repeat([0, 1, 2], 5)
    assert classify_segments(seg, None) == {0: "approach", 1: "hold", 2: "retract"}
    assert classify_segments(np.zeros(5, int), None) == {0: "approach"}


def test_one_segment_holding_a_whole_cycle_is_its_approach():
    """A curve recorded as one segment (no segment column) is read whole, as before."""
    h = np.concatenate([np.linspace(10e-6, 8e-6, 50), np.linspace(8e-6, 10.2e-6, 50)])
    assert classify_segments(np.zeros(100, int), h) == {0: "approach"}
