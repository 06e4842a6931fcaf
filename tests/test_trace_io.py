"""Canonical trace CSV, unit/sign options, validation errors and manifests."""

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from palpbayes.contact import Tip, force
from palpbayes.errors import DataFileError, NoContactError
from palpbayes.io.manifest import iter_traces, read_manifest, write_manifest
from palpbayes.io.trace_csv import read_trace, write_trace
from palpbayes.trace import IndentationTrace

TIP = Tip("paraboloid", radius=0.0117)


def make_trace(n=2400, seed=0):  # 1.33 mm deep, ~0.9 N
    rng = np.random.default_rng(seed)
    t = np.arange(n) / 800.0
    z = 0.1 + 1e-3 - 50 / 60e3 * t
    f = force(0.1 - z, 1.2e5, 0.3, TIP) + 0.008 * rng.standard_normal(n)
    return IndentationTrace(t, z, f, tip=TIP, trace_id="t1")


def test_canonical_round_trip(tmp_path):
    tr = make_trace()
    path = write_trace(tr, tmp_path / "t.csv", float_format="%.17g")
    back = read_trace(path)
    np.testing.assert_array_equal(back.time, tr.time)
    np.testing.assert_array_equal(back.z, tr.z)
    np.testing.assert_array_equal(back.force, tr.force)
    assert back.trace_id == "t"
    assert back.sample_rate == pytest.approx(800.0)


def test_mm_mN_flipped_sign_equals_canonical(tmp_path):
    tr = make_trace()
    canonical = read_trace(write_trace(tr, tmp_path / "c.csv", float_format="%.17g"))
    df = pd.DataFrame({"Time [ms]": tr.time * 1e3, "Z [mm]": tr.z * 1e3,
                       "Fz [mN]": -tr.force * 1e3})
    df.to_csv(tmp_path / "raw.csv", index=False, float_format="%.17g")
    other = read_trace(tmp_path / "raw.csv",
                       columns={"time": "Time [ms]", "z": "Z [mm]", "force": "Fz [mN]"},
                       units={"time": "ms", "z": "mm", "force": "mN"}, force_sign=-1)
    for name in ("time", "z", "force"):
        np.testing.assert_allclose(getattr(other, name), getattr(canonical, name),
                                   rtol=1e-14, atol=1e-16)
    # suffix-named columns are recognised without options
    df2 = pd.DataFrame({"time_ms": tr.time * 1e3, "z_mm": tr.z * 1e3, "force_mn": tr.force * 1e3})
    df2.to_csv(tmp_path / "suffix.csv", index=False, float_format="%.17g")
    np.testing.assert_allclose(read_trace(tmp_path / "suffix.csv").z, canonical.z, rtol=1e-14)


def _write(tmp_path, name, text):
    p = tmp_path / name
    p.write_text(text)
    return p


GOOD_HEADER = "time_s,z_m,force_n\n"


@pytest.mark.parametrize("name, text, match", [
    ("missing.csv", "time_s,z_m\n0,0.1\n0.1,0.09\n0.2,0.08\n", "missing column 'force_n'"),
    ("typo.csv", "time_s,z_m,froce_n\n0,0.1,0\n0.1,0.09,1\n0.2,0.08,2\n",
     "missing column 'force_n'"),
    ("nan.csv", GOOD_HEADER + "0,0.1,0\n0.1,0.09,nan\n0.2,0.08,2\n", "force.*NaN.*row 2"),
    ("inf.csv", GOOD_HEADER + "0,0.1,0\n0.1,inf,1\n0.2,0.08,2\n", "'z_m'.*infinite.*row 2"),
    ("text.csv", GOOD_HEADER + "0,0.1,0\n0.1,0.09,abc\n0.2,0.08,2\n", "non-numeric value 'abc'"),
    ("empty.csv", "", "empty"),
    ("header.csv", GOOD_HEADER, "no data rows"),
    ("backwards.csv", GOOD_HEADER + "0,0.1,0\n0.2,0.09,1\n0.1,0.08,2\n", "time decreases"),
    ("dupe.csv", GOOD_HEADER + "0,0.1,0\n0.1,0.09,1\n0.1,0.08,2\n", "time repeats"),
])
def test_bad_files_raise_data_file_error_naming_the_file(tmp_path, name, text, match):
    path = _write(tmp_path, name, text)
    with pytest.raises(DataFileError, match=match) as err:
        read_trace(path)
    assert str(path) in str(err.value)


def test_missing_file(tmp_path):
    with pytest.raises(DataFileError, match="file not found"):
        read_trace(tmp_path / "nope.csv")


def test_implausible_units_and_flipped_sign(tmp_path):
    tr = make_trace()
    # z written in mm but read as metres: a 1 m-scale "indentation"
    pd.DataFrame({"time_s": tr.time, "z_m": tr.z * 1e4, "force_n": tr.force}).to_csv(
        tmp_path / "z.csv", index=False)
    with pytest.raises(DataFileError, match="--z-unit"):
        read_trace(tmp_path / "z.csv")
    # force in mN read as N
    pd.DataFrame({"time_s": tr.time, "z_m": tr.z, "force_n": tr.force * 1e3}).to_csv(
        tmp_path / "f.csv", index=False)
    with pytest.raises(DataFileError, match="--force-unit"):
        read_trace(tmp_path / "f.csv")
    # pressing recorded as negative force
    pd.DataFrame({"time_s": tr.time, "z_m": tr.z, "force_n": -tr.force}).to_csv(
        tmp_path / "s.csv", index=False)
    with pytest.raises(DataFileError, match="--force-sign -1"):
        read_trace(tmp_path / "s.csv")
    assert read_trace(tmp_path / "s.csv", force_sign=-1).force.max() > 1.0


def test_loading_segment_drops_retract():
    t = np.arange(10.0)
    z = np.array([5, 4, 3, 2, 1, 0, 1, 2, 3, 4.0])
    tr = IndentationTrace(t, z, np.zeros(10))
    seg = tr.loading_segment()
    assert seg.n_points == 6 and seg.z[-1] == 0
    with pytest.raises(NoContactError, match="never moves down"):
        IndentationTrace(t, t, np.zeros(10)).loading_segment()


def test_manifest_round_trip_and_missing_file(tmp_path):
    tr = make_trace()
    write_trace(tr, tmp_path / "traces" / "a.csv")
    rows = pd.DataFrame([{"trace_id": "a", "file": "traces/a.csv", "specimen": "S1",
                          "material": "White", "tip": "paraboloid", "radius_m": 0.0117,
                          "thickness_m": 0.03, "repetition": 1, "rest_time_s": 60.0}])
    write_manifest(rows, tmp_path / "manifest.csv")
    (loaded,) = list(iter_traces(tmp_path / "manifest.csv"))
    assert loaded.tip == TIP and loaded.material == "White" and loaded.thickness == 0.03
    assert loaded.repetition == 1 and loaded.rest_time == 60.0
    rows.loc[0, "file"] = "traces/missing.csv"
    write_manifest(rows, tmp_path / "bad.csv")
    with pytest.raises(DataFileError, match=r"row 1 \(trace 'a'\) points to missing file"):
        read_manifest(tmp_path / "bad.csv")
    rows.loc[0, ["file", "radius_m"]] = ["traces/a.csv", -1.0]
    write_manifest(rows, tmp_path / "neg.csv")
    with pytest.raises(DataFileError, match="radius.*positive"):
        read_manifest(tmp_path / "neg.csv")


@settings(max_examples=25, deadline=None)
@given(z_unit=st.sampled_from(["m", "mm", "um", "cm"]),
       f_unit=st.sampled_from(["N", "mN", "uN", "kN"]),
       t_unit=st.sampled_from(["s", "ms"]), sign=st.sampled_from([1.0, -1.0]))
def test_unit_and_sign_round_trip_property(tmp_path_factory, z_unit, f_unit, t_unit, sign):
    """Writing SI values in any unit/sign and reading them back with that option is lossless."""
    from palpbayes.io.units import force_factor, length_factor, time_factor

    tr = make_trace(n=2400)
    d = tmp_path_factory.mktemp("units")
    pd.DataFrame({"t": tr.time / time_factor(t_unit), "zz": tr.z / length_factor(z_unit),
                  "f": sign * tr.force / force_factor(f_unit)}).to_csv(
        d / "x.csv", index=False, float_format="%.17g")
    back = read_trace(d / "x.csv", columns={"time": "t", "z": "zz", "force": "f"},
                      units={"time": t_unit, "z": z_unit, "force": f_unit}, force_sign=sign)
    np.testing.assert_allclose(back.time, tr.time, rtol=1e-14, atol=1e-15)
    np.testing.assert_allclose(back.z, tr.z, rtol=1e-14)
    np.testing.assert_allclose(back.force, tr.force, rtol=1e-13, atol=1e-15)
