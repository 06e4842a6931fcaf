"""Canonical trace CSV, unit/sign options, validation errors and manifests."""

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from propbudget import examples

from palpbayes.contact import Tip, force
from palpbayes.errors import DataFileError, InputError, NoContactError
from palpbayes.io.manifest import is_manifest, iter_traces, read_manifest, write_manifest
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



def make_afm_trace(n=2000, seed=1):  # AFM scale: 1 µm approach + 400 nm deep, 340 pN
    rng = np.random.default_rng(seed)
    tip = Tip("paraboloid", radius=20e-9)
    t = np.arange(n) / 2000.0
    z = 1e-6 - 1.4e-6 * t / t[-1]
    f = force(np.maximum(-z, 0.0), 5e3, 0.49, tip) + 2e-11 * rng.standard_normal(n)
    return IndentationTrace(t, z, f, tip=tip, trace_id="afm")


def test_afm_nn_nm_columns_read_as_si(tmp_path):
    """A canonical trace written in nN/nm columns reads back as the SI trace."""
    tr = make_afm_trace()
    assert 1e-10 < tr.force.max() < 1e-7  # nN scale, so the columns really are in nN
    canonical = read_trace(write_trace(tr, tmp_path / "c.csv", float_format="%.17g"))
    pd.DataFrame({"time_s": tr.time, "z_nm": tr.z / 1e-9, "force_nn": tr.force / 1e-9}).to_csv(
        tmp_path / "afm.csv", index=False, float_format="%.17g")
    afm = read_trace(tmp_path / "afm.csv")
    for name in ("time", "z", "force"):
        np.testing.assert_allclose(getattr(afm, name), getattr(canonical, name),
                                   rtol=1e-14, atol=0)


@pytest.mark.parametrize("z_col, z_factor", [
    ("z_um", 1e-6), ("Z_UM", 1e-6), ("z_µm", 1e-6), ("z_μm", 1e-6), ("z_nm", 1e-9),
    ("z_pm", 1e-12), ("z_mm", 1e-3), ("z_cm", 1e-2), ("z_m", 1.0),
])
@pytest.mark.parametrize("f_col, f_factor", [
    ("force_nn", 1e-9), ("force_nN", 1e-9), ("force_pn", 1e-12), ("Force_pN", 1e-12),
    ("force_un", 1e-6), ("force_uN", 1e-6), ("force_µN", 1e-6), ("force_μn", 1e-6),
    ("force_mn", 1e-3), ("force_MN", 1e-3), ("force_kn", 1e3), ("force_n", 1.0),
])
def test_unit_suffixed_columns_are_recognised(tmp_path, z_col, z_factor, f_col, f_factor):
    """``<quantity>_<unit>`` names in any case, incl. the AFM units, without options."""
    tr = make_afm_trace(n=300)
    pd.DataFrame({"time_s": tr.time, z_col: tr.z / z_factor, f_col: tr.force / f_factor}).to_csv(
        tmp_path / "x.csv", index=False, float_format="%.17g", encoding="utf-8")
    back = read_trace(tmp_path / "x.csv")
    np.testing.assert_allclose(back.z, tr.z, rtol=1e-14, atol=0)
    np.testing.assert_allclose(back.force, tr.force, rtol=1e-14, atol=0)


@pytest.mark.parametrize("unit, factor", [("pN", 1e-12), ("nN", 1e-9), ("uN", 1e-6),
                                          ("µN", 1e-6), ("μN", 1e-6)])
def test_afm_force_units_as_options(tmp_path, unit, factor):
    tr = make_afm_trace(n=300)
    pd.DataFrame({"t": tr.time, "h": tr.z / 1e-6, "F": tr.force / factor}).to_csv(
        tmp_path / "x.csv", index=False, float_format="%.17g", encoding="utf-8")
    back = read_trace(tmp_path / "x.csv", columns={"time": "t", "z": "h", "force": "F"},
                      units={"z": "um", "force": unit})
    np.testing.assert_allclose(back.z, tr.z, rtol=1e-14, atol=0)
    np.testing.assert_allclose(back.force, tr.force, rtol=1e-14, atol=0)


def test_force_unit_options_stay_case_sensitive():
    from palpbayes.io.units import force_factor, length_factor

    assert force_factor("pN") == 1e-12 and length_factor("pm") == 1e-12
    assert length_factor("PM") == 1e-12 and length_factor("NM") == 1e-9  # lengths: any case
    for wrong in ("PN", "MN", "nn", "pn"):  # petanewton/meganewton are not pN/mN
        with pytest.raises(InputError, match=f"unknown force unit '{wrong}'.*pN"):
            force_factor(wrong)

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



def test_messages_print_forces_and_lengths_with_a_fitting_prefix():
    from dataclasses import replace

    from palpbayes.io.trace_csv import check_plausible

    afm = make_afm_trace()
    with pytest.raises(DataFileError,
                       match=r"^afm: force falls \d\d\d pN below its pre-contact baseline \("
                             r"-?\d+(\.\d+)? pN\) at the deepest"):
        check_plausible(replace(afm, force=-afm.force))
    tr = make_trace()
    with pytest.raises(DataFileError, match=r"\|force\| reaches 1\.11 kN, implausible"):
        check_plausible(replace(tr, force=tr.force * 1e3))
    with pytest.raises(DataFileError, match=r"z spans 25 m, more than a palpation can \(500 mm\)"):
        check_plausible(replace(tr, z=tr.z * 1e4))
    assert repr(tr) == ("IndentationTrace('t1', 2400 points, paraboloid R=11.7 mm, "
                        "z 98.501 mm..101 mm, F -31.2 mN..1.11 N)")
    assert "paraboloid R=20 nm, z -400 nm..1 µm, F -71 pN..340 pN)" in repr(afm)

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


@settings(max_examples=examples(25), deadline=None)
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


# ----------------------------------------------------------------------------- separators


@pytest.mark.parametrize("sep", [";", "\t"])
def test_semicolon_and_tab_separated_files_are_read(tmp_path, sep):
    tr = make_trace()
    canonical = read_trace(write_trace(tr, tmp_path / "c.csv", float_format="%.17g"))
    pd.DataFrame({"time_s": tr.time, "z_m": tr.z, "force_n": tr.force}).to_csv(
        tmp_path / "x.csv", sep=sep, index=False, float_format="%.17g")
    back = read_trace(tmp_path / "x.csv")
    np.testing.assert_array_equal(back.z, canonical.z)
    np.testing.assert_array_equal(back.force, canonical.force)


def test_decimal_commas_are_named(tmp_path):
    tr = make_trace()
    df = pd.DataFrame({"time_s": tr.time, "z_m": tr.z, "force_n": tr.force})
    df.to_csv(tmp_path / "semi.csv", sep=";", decimal=",", index=False)
    with pytest.raises(DataFileError, match=r"non-numeric value '0,0' at data row 1: the "
                       r"file uses decimal commas \(write decimal points"):
        read_trace(tmp_path / "semi.csv")
    # comma-separated with decimal commas: pandas would silently make the extra fields an index
    (tmp_path / "comma.csv").write_text("time_s,z_m,force_n\n0,0,0,1,0,003\n0,1,0,099,0,2\n"
                                        "0,2,0,098,0,4\n")
    with pytest.raises(DataFileError, match=r"3 more field\(s\) than the header \(3 columns\); "
                       "decimal commas"):
        read_trace(tmp_path / "comma.csv")


def test_folder_instead_of_file(tmp_path):
    with pytest.raises(DataFileError, match="is a folder, not a trace file"):
        read_trace(tmp_path)
    (tmp_path / "manifest.csv").write_text("trace_id,file,material,tip\n")
    with pytest.raises(DataFileError, match=f"did you mean {tmp_path / 'manifest.csv'}"):
        read_trace(tmp_path)
    with pytest.raises(DataFileError, match="is a folder, not a manifest file"):
        read_manifest(tmp_path)


# ----------------------------------------------------------------------------- the trace object


def test_trace_does_not_freeze_or_share_the_callers_arrays():
    t = np.arange(10.0)
    z = 1.0 - 0.1 * t
    f = 0.1 * t
    tr = IndentationTrace(t, z, f)
    assert t.flags.writeable and z.flags.writeable and f.flags.writeable
    z[0] = 99.0  # the caller's array is still theirs ...
    assert tr.z[0] == 1.0  # ... and the trace does not change with it
    assert not tr.z.flags.writeable
    seg = tr.loading_segment()  # a view of the trace's own read-only arrays is not copied
    assert np.shares_memory(seg.z, tr.z)


@pytest.mark.parametrize("kwargs, match", [
    ({"thickness": "0.02"}, "thickness '0.02' is not a number"),
    ({"thickness": -0.02}, "thickness -0.02 m must be positive"),
    ({"rest_time": "60 s"}, "rest_time '60 s' is not a number"),
    ({"rest_time": -1.0}, "must be non-negative"),
    ({"repetition": 1.5}, "repetition 1.5 is not a whole number"),
])
def test_trace_metadata_types_raise_package_errors(kwargs, match):
    t = np.arange(5.0)
    with pytest.raises(DataFileError, match=match):
        IndentationTrace(t, -t, t, **kwargs)
    ok = IndentationTrace(t, -t, t, thickness=np.float64(0.02), repetition=np.int64(2))
    assert ok.thickness == 0.02 and ok.repetition == 2 and isinstance(ok.repetition, int)


def test_narrow_depth_window_names_the_window_not_the_file():
    tr = make_trace().replace(source="run.csv")
    with pytest.raises(InputError, match=r"only \d of 2400 samples have a depth in "
                       r"\[0 m, 1 µm\] below z_surf = 100 mm;.*widen the window") as info:
        tr.depth_window(0.1, 0.0, 1e-6)
    assert "whole recording" not in str(info.value)
    with pytest.raises(InputError, match=r"only 0 of 2400 samples have a depth of at least "
                       r"50 mm below z_surf = 100 mm;"):
        tr.depth_window(0.1, 0.05)
    with pytest.raises(InputError, match="have z >= 1 m;"):
        tr.above(1.0)
    assert tr.depth_window(0.1, 0.0, 5e-4).n_points > 3


def test_tip_never_moving_down_names_the_z_sign_option():
    t = np.arange(10.0)
    with pytest.raises(NoContactError, match="--z-sign -1"):
        IndentationTrace(t, t, np.zeros(10)).loading_segment()


# ----------------------------------------------------------------------------- manifests


def _manifest(tmp_path, **changes):
    write_trace(make_trace(), tmp_path / "a.csv")
    row = {"trace_id": "a", "file": "a.csv", "specimen": "S1", "material": "White",
           "tip": "paraboloid", "radius_m": "0.0117", "thickness_m": "0.03",
           "repetition": "1", "rest_time_s": "60"}
    row.update(changes)
    path = tmp_path / "manifest.csv"
    pd.DataFrame([row]).to_csv(path, index=False)
    return path


@pytest.mark.parametrize("changes, match", [
    ({"radius_m": "abc"}, r"row 1 \(trace 'a'\): column 'radius_m' holds 'abc', which is not a "
     r"number \(write a plain number in metres, e\.g\. 0\.01"),
    ({"repetition": "first"}, r"column 'repetition' holds 'first', which is not a number "
     r"\(write a whole number"),
    ({"repetition": "1.5"}, "column 'repetition' is 1.5, not a whole number"),
    ({"thickness_m": "2cm"}, "column 'thickness_m' holds '2cm', which is not a number"),
    ({"thickness_m": "0"}, "column 'thickness_m' is 0, which must be positive"),
    ({"rest_time_s": "-3"}, "column 'rest_time_s' is -3, which must be non-negative"),
    ({"rest_time_s": "inf"}, "column 'rest_time_s' is inf, not a finite number"),
    ({"nu": "0.3x"}, "column 'nu' holds '0.3x'"),
    ({"half_angle_deg": "70deg", "tip": "cone"}, "column 'half_angle_deg' holds '70deg'"),
    ({"trace_id": ""}, r"row 1: column 'trace_id' is empty \(give every row its trace_id"),
    ({"trace_id": "  "}, "column 'trace_id' is empty"),
    ({"material": ""}, r"row 1 \(trace 'a'\): column 'material' is empty"),
    ({"tip": ""}, "column 'tip' is empty"),
    ({"file": ""}, "column 'file' is empty"),
    ({"tip": "cone", "radius_m": "", "half_angle_deg": "95"},
     "cone half-angle 95.0 deg must lie strictly between 0 and 90 deg"),
])
def test_manifest_cells_are_validated(tmp_path, changes, match):
    path = _manifest(tmp_path, **changes)
    with pytest.raises(DataFileError, match=match) as info:
        read_manifest(path)
    assert str(path) in str(info.value)


def test_manifest_numbers_parse_and_semicolon_manifest(tmp_path):
    path = _manifest(tmp_path)
    df = read_manifest(path)
    assert df["radius_m"].dtype == float and df["repetition"].iloc[0] == 1.0
    (loaded,) = list(iter_traces(df))
    assert loaded.repetition == 1 and loaded.thickness == 0.03 and loaded.rest_time == 60.0
    pd.read_csv(path).to_csv(tmp_path / "semi.csv", sep=";", index=False)
    assert is_manifest(tmp_path / "semi.csv")
    assert read_manifest(tmp_path / "semi.csv")["trace_id"].tolist() == ["a"]


def test_manifest_traces_take_the_read_options(tmp_path):
    tr = make_trace()
    pd.DataFrame({"t": tr.time, "zz": tr.z * 1e3, "f": -tr.force}).to_csv(
        tmp_path / "a.csv", index=False, float_format="%.17g")
    pd.DataFrame([{"trace_id": "a", "file": "a.csv", "material": "W", "tip": "paraboloid",
                   "radius_m": 0.0117}]).to_csv(tmp_path / "m.csv", index=False)
    with pytest.raises(DataFileError, match="missing column 'time_s'"):
        list(iter_traces(tmp_path / "m.csv"))
    (back,) = iter_traces(tmp_path / "m.csv", columns={"time": "t", "z": "zz", "force": "f"},
                          units={"z": "mm"}, force_sign=-1)
    np.testing.assert_allclose(back.z, tr.z, rtol=1e-14)
    np.testing.assert_allclose(back.force, tr.force, rtol=1e-13, atol=1e-15)


def test_every_missing_column_is_named_in_one_error(tmp_path):
    """Three wrong column names: one error that names all three, not the first only."""
    path = tmp_path / "three.csv"
    path.write_text("t_ms,height,load\n0,0.1,0\n1,0.09,0.1\n2,0.08,0.2\n")
    with pytest.raises(DataFileError) as info:
        read_trace(path)
    msg = str(info.value)
    for canon in ("'time_s'", "'z_m'", "'force_n'"):
        assert f"missing column {canon}" in msg, msg
    assert "three.csv" in msg and "t_ms, height, load" in msg
    assert "--time-column" in msg and "--force-sign" in msg


def test_a_robot_log_gets_the_options_that_map_its_columns(tmp_path):
    """A UR RTDE-style log (timestamp, actual_TCP_pose_2, fz): the error says which option
    maps each column (not a silent mapping: loggers differ in units and sign), and the mapping
    it suggests reads the file."""
    path = tmp_path / "ur3e.csv"
    path.write_text("timestamp,actual_TCP_pose_2,fz\n0,0.100,0.0\n0.00125,0.0999,0.01\n"
                    "0.0025,0.0998,0.02\n")
    with pytest.raises(DataFileError) as info:
        read_trace(path)
    msg = str(info.value)
    assert "--time-column timestamp" in msg
    assert "--z-column actual_TCP_pose_2" in msg
    assert "--force-column fz" in msg
    trace = read_trace(path, columns={"time": "timestamp", "z": "actual_TCP_pose_2",
                                      "force": "fz"}, check=False)
    assert trace.n_points == 3


def test_the_hint_maps_the_readmes_robot_log_and_points_out_case_only_differences(tmp_path):
    """Issue 58, item 7: the README's robot log (timestamp, tcp_z_mm, fz) got no hint for
    tcp_z_mm, and a column given in another case (--force-column fz for a file's Fz, the
    README's spelling) was only "missing".  Now tcp_z_mm gets --z-column and --z-unit mm, and
    a column that differs in case only is named with the option that reads it."""
    path = tmp_path / "press.csv"
    path.write_text("timestamp,tcp_z_mm,fz\n0,25.0,0.21\n0.004,24.996,0.21\n")
    with pytest.raises(DataFileError) as info:
        read_trace(path)
    msg = str(info.value)
    assert ("missing column 'z_m' (for z) (a robot log's 'tcp_z_mm'? map it with --z-column "
            "tcp_z_mm --z-unit mm, and check its sign)") in msg
    assert "--time-column timestamp" in msg and "--force-column fz" in msg
    path = tmp_path / "case.csv"
    path.write_text("Time_S,TCP_Z_MM,Fz\n0,25.0,0.21\n0.004,24.996,0.21\n0.008,24.992,0.2\n")
    with pytest.raises(DataFileError) as info:
        read_trace(path, columns={"time": "time_s", "z": "tcp_z_mm", "force": "fz"},
                   units={"z": "mm"})
    msg = str(info.value)
    for name, there, q in (("time_s", "Time_S", "time"), ("tcp_z_mm", "TCP_Z_MM", "z"),
                            ("fz", "Fz", "force")):
        assert (f"column '{name}' (given for {q}) is missing (the header's '{there}' differs "
                f"from it in case only: --{q}-column {there})") in msg
    trace = read_trace(path, columns={"time": "Time_S", "z": "TCP_Z_MM", "force": "Fz"},
                       units={"z": "mm"}, check=False)
    assert trace.z[0] == pytest.approx(0.025)
