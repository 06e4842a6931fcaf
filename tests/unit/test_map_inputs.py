"""What a map reads from its manifest, checked before any fit (issue 46): ``material`` is
optional for a map (and stays required for a campaign), and every trace file's header is read
with the reader options before a cluster starts."""

from __future__ import annotations

import pandas as pd
import pytest

from palpbayes.errors import DataFileError
from palpbayes.io.manifest import check_trace_headers, read_manifest
from palpbayes.maps import run
from palpbayes.maps.pertrace import PointOptions

UR = {"columns": {"time": "timestamp", "z": "actual_TCP_pose_2", "force": "fz"},
      "units": {"z": "mm"}, "force_sign": -1.0}


def _manifest(folder, header="timestamp,actual_TCP_pose_2,fz", *, n=12, material=None,
              odd=None):
    """n files with ``header`` and two data rows on a 4-column grid; row ``odd`` (index, header)
    gets another header."""
    rows = []
    for k in range(n):
        h = odd[1] if odd is not None and k == odd[0] else header
        (folder / f"t{k}.csv").write_text(f"# logger v1\n{h}\n0,100.0,0.1\n0.01,99.9,0.2\n")
        rows.append({"trace_id": f"t{k}", "file": f"t{k}.csv", "tip": "sphere",
                     "radius_m": 0.01, "x_m": (k % 4) * 2e-3, "y_m": (k // 4) * 2e-3,
                     **({} if material is None else {"material": material[k]})})
    path = folder / "manifest.csv"
    pd.DataFrame(rows).to_csv(path, index=False)
    return path


def test_a_map_manifest_may_leave_out_material_a_campaign_may_not(tmp_path):
    path = _manifest(tmp_path)
    with pytest.raises(DataFileError, match="lacks column.s. material"):
        read_manifest(path)  # fit's campaigns pool by material: unchanged
    m = read_manifest(path, default_material="")
    assert (m["material"] == "").all() and len(m) == 12
    labels = ["silicone"] * 11 + [""]  # an empty cell takes the default too
    path = _manifest(tmp_path, material=labels)
    with pytest.raises(DataFileError, match="row 12 .*column 'material' is empty"):
        read_manifest(path)
    m = read_manifest(path, default_material="block")
    assert m["material"].tolist() == ["silicone"] * 11 + ["block"]
    pd.read_csv(path).drop(columns="tip").to_csv(tmp_path / "no_tip.csv", index=False)
    with pytest.raises(DataFileError, match="lacks column.s. tip .a manifest needs trace_id, "
                       "file, tip.$"):
        read_manifest(tmp_path / "no_tip.csv", default_material="")


def test_headers_are_checked_with_the_reader_options(tmp_path):
    m = read_manifest(_manifest(tmp_path), default_material="")
    check_trace_headers(m, **UR)  # the options that read a UR log: no error
    with pytest.raises(DataFileError) as info:
        check_trace_headers(m, source="map.csv")
    msg = str(info.value)
    assert msg.startswith(str(tmp_path / "t0.csv")) and "row 1 (trace 't0') of map.csv" in msg
    assert "--time-column timestamp" in msg and "11 other trace file(s)" in msg
    with pytest.raises(DataFileError, match="column 'actual_TCP_pose_2': unknown.*furlong"):
        check_trace_headers(m, **{**UR, "units": {"z": "furlong"}})


def test_the_first_odd_header_is_named_with_its_row(tmp_path):
    m = read_manifest(_manifest(tmp_path, odd=(6, "timestamp,tcp_z,fz")), default_material="")
    with pytest.raises(DataFileError) as info:
        check_trace_headers(m, **UR)
    msg = str(info.value)
    assert str(tmp_path / "t6.csv") in msg and "row 7 (trace 't6')" in msg
    assert "'actual_TCP_pose_2' (given for z) is missing" in msg and "other trace" not in msg


def test_canonical_and_joint_angle_headers_need_no_options(tmp_path):
    m = read_manifest(_manifest(tmp_path, "time_s,z_mm,force_n"), default_material="")
    check_trace_headers(m)
    joints = ",".join(["time_s", *(f"q{i}_rad" for i in range(6)), "force_n"])
    m = read_manifest(_manifest(tmp_path, joints), default_material="")
    check_trace_headers(m)


def test_make_map_checks_the_headers_before_fitting(tmp_path, monkeypatch):
    """make_map (the API) runs the same check before fit_points, which would start Dask."""
    m = read_manifest(_manifest(tmp_path), default_material="")

    def no_fits(*args, **kwargs):
        raise AssertionError("fit_points was called")

    monkeypatch.setattr(run, "fit_points", no_fits)
    with pytest.raises(DataFileError, match="--time-column timestamp"):
        run.make_map(m, options=run.MapOptions(lump=False))
    with pytest.raises(AssertionError, match="fit_points was called"):
        run.make_map(m, point_options=PointOptions(read_options=UR),
                     options=run.MapOptions(lump=False))


def test_a_remote_cluster_checks_only_the_headers_this_machine_sees(tmp_path):
    """Review of issue 46: with --scheduler ADDRESS the workers may see files the client does
    not; the header check then skips files absent here (a local run still names them)."""
    from palpbayes.errors import DataFileError
    from palpbayes.maps.run import check_map_manifest

    rows = [{"trace_id": f"p{i}{j}", "file": str(tmp_path / f"absent-{i}{j}.csv"),
             "tip": "sphere", "radius_m": 0.01, "x_m": 3e-3 * i, "y_m": 3e-3 * j}
            for i in range(4) for j in range(3)]
    manifest = pd.DataFrame(rows)
    tip, thickness = check_map_manifest(manifest, lump=False, remote=True)
    assert tip.kind == "sphere" and thickness is None
    with pytest.raises(DataFileError, match="absent-00.csv"):
        check_map_manifest(manifest, lump=False)
