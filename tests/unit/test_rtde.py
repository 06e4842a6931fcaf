"""Tests of palpbayes.io.rtde: UR RTDE recordings and joint-angle traces."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from palpbayes.errors import DataFileError, InputError
from palpbayes.io.joint_trace import read_joint_trace, trace_from_joint_frame
from palpbayes.io.rtde import (
    RTDE_Q_COLUMNS,
    RTDE_TCP_FORCE_COLUMNS,
    RTDE_TCP_POSE_COLUMNS,
    read_rtde,
    rotvec_to_matrix,
)
from palpbayes.kinematics import UR5E, tip_z

PI = np.pi
TOOL_DOWN = np.array([0.0, -PI / 2, PI / 2, -PI / 2, -PI / 2, 0.0])
OFFSET = 0.05  # sensor + tip [m]
N = 120


def palpation(n: int = N, t0: float = 1234.5):
    """A synthetic palpation: shoulder joint moves the downward-facing tip ~3 mm down and up."""
    s = np.concatenate([np.linspace(0.0, 0.004, n // 2), np.linspace(0.004, 0.0, n - n // 2)])
    q = np.tile(TOOL_DOWN, (n, 1))
    q[:, 1] += s
    z = tip_z(q, tool_offset=OFFSET)
    z_surf = z[0] - 0.001
    force = 20.0 * np.clip(z_surf - z, 0.0, None) ** 1.5 * 1e4  # a few newtons
    t = t0 + 0.002 * np.arange(n)
    return t, q, z, force


def rtde_frame(t, q, z, force, *, force_raw_sign=-1.0, tcp_z=None):
    """Columns as the RTDE recorders write them (with a few unrelated fields)."""
    n = t.size
    cols = {"timestamp": t}
    for i in range(6):
        cols[f"target_q_{i}"] = q[:, i] + 1e-3
    for i, c in enumerate(RTDE_Q_COLUMNS):
        cols[c] = q[:, i]
    pose = np.zeros((n, 6))
    pose[:, 2] = z + 0.1 if tcp_z is None else tcp_z
    pose[:, 3] = PI  # tool pointing down: rotation of pi about x
    for i, c in enumerate(RTDE_TCP_POSE_COLUMNS):
        cols[c] = pose[:, i]
    wrench = np.zeros((n, 6))
    wrench[:, 2] = force_raw_sign * force
    wrench[:, 0] = 0.5 * force  # a lateral component, to tell the axes apart
    for i, c in enumerate(RTDE_TCP_FORCE_COLUMNS):
        cols[c] = wrench[:, i]
    cols["robot_mode"] = np.full(n, 7)
    return pd.DataFrame(cols)


def write(df: pd.DataFrame, path: Path, sep: str) -> Path:
    df.to_csv(path, sep=sep, index=False, float_format="%.17g")
    return path


@pytest.fixture
def data():
    return palpation()


@pytest.mark.parametrize("sep", [" ", ",", ";"], ids=["space", "comma", "semicolon"])
def test_read_rtde_z_from_joints(tmp_path, data, sep):
    t, q, z, force = data
    path = write(rtde_frame(t, q, z, force), tmp_path / "run01.csv", sep)
    tr = read_rtde(path, tool_offset=OFFSET)
    np.testing.assert_allclose(tr.z, tip_z(q, tool_offset=OFFSET), atol=1e-12)
    np.testing.assert_allclose(tr.z, z, atol=1e-12)
    np.testing.assert_allclose(tr.force, force, atol=1e-12)
    np.testing.assert_allclose(tr.time, t - t[0], atol=1e-9)
    assert tr.time[0] == 0.0
    assert tr.trace_id == "run01"
    assert tr.source == str(path)
    assert tr.metadata["t0_s"] == pytest.approx(t[0])
    assert tr.metadata["z_source"] == "q"
    assert tr.metadata["robot"] == "UR3e"
    assert tr.metadata["force_column"] == "actual_TCP_force_2"
    assert tr.metadata["tool_offset_m"] == [0.0, 0.0, OFFSET]


def test_record_py_style_header(tmp_path, data):
    """record.py writes space-separated values with csv.writer (repr floats, no index)."""
    t, q, z, force = data
    names = ["timestamp", *RTDE_Q_COLUMNS, *RTDE_TCP_FORCE_COLUMNS]
    lines = [" ".join(names)]
    for i in range(t.size):
        row = [t[i], *q[i], 0.0, 0.0, -force[i], 0.0, 0.0, 0.0]
        lines.append(" ".join(repr(float(v)) for v in row))
    path = tmp_path / "robot_data.csv"
    path.write_text("\n".join(lines) + "\n")
    tr = read_rtde(path, tool_offset=OFFSET)
    np.testing.assert_allclose(tr.z, z, atol=1e-12)
    np.testing.assert_allclose(tr.force, force, atol=1e-12)


def test_tool_offset_shifts_z(tmp_path, data):
    t, q, z, force = data
    path = write(rtde_frame(t, q, z, force), tmp_path / "a.csv", ",")
    z0 = read_rtde(path).z
    z1 = read_rtde(path, tool_offset=OFFSET).z
    np.testing.assert_allclose(z0 - z1, OFFSET, atol=1e-6)  # tool nearly vertical
    np.testing.assert_allclose(read_rtde(path, tool_offset=(0, 0, OFFSET)).z, z1, atol=0)


def test_z_from_tcp_pose(tmp_path, data):
    t, q, z, force = data
    tcp_z = np.linspace(0.2, 0.197, t.size)
    path = write(rtde_frame(t, q, z, force, tcp_z=tcp_z), tmp_path / "tcp.csv", " ")
    tr = read_rtde(path, z_source="tcp")
    np.testing.assert_allclose(tr.z, tcp_z, atol=1e-15)
    assert tr.metadata["z_source"] == "tcp"
    # An extra tip along the TCP z axis; the TCP points down (rotation pi about x).
    tr2 = read_rtde(path, z_source="tcp", tool_offset=0.01, check=False)
    np.testing.assert_allclose(tr2.z, tcp_z - 0.01, atol=1e-12)


def test_z_from_tcp_does_not_need_joints(tmp_path, data):
    t, q, z, force = data
    df = rtde_frame(t, q, z, force).drop(columns=list(RTDE_Q_COLUMNS))
    path = write(df, tmp_path / "nojoints.csv", ",")
    np.testing.assert_allclose(read_rtde(path, z_source="tcp").z, z + 0.1, atol=1e-15)
    with pytest.raises(DataFileError, match="actual_q"):
        read_rtde(path)


def test_force_sign_and_axis(tmp_path, data):
    t, q, z, force = data
    path = write(rtde_frame(t, q, z, force, force_raw_sign=+1.0), tmp_path / "plus.csv", ",")
    # A fixed -1 turns the +Fz reaction negative: rejected with the fix in the message.
    with pytest.raises(DataFileError, match=r"force_sign=\+1") as err:
        read_rtde(path, tool_offset=OFFSET, force_sign=-1)
    assert str(path) in str(err.value)
    # The default ("auto") picks the sign that makes pressing positive.
    assert read_rtde(path, tool_offset=OFFSET).metadata["force_sign"] == 1.0
    np.testing.assert_allclose(read_rtde(path, force_sign=1).force, force, atol=1e-12)
    auto = read_rtde(path, force_sign="auto")
    np.testing.assert_allclose(auto.force, force, atol=1e-12)
    assert auto.metadata["force_sign"] == 1.0
    minus = write(rtde_frame(t, q, z, force), tmp_path / "minus.csv", ",")
    assert read_rtde(minus, force_sign="auto").metadata["force_sign"] == -1.0
    # Unchecked, the sign is applied as asked.
    np.testing.assert_allclose(read_rtde(path, check=False, force_sign=-1).force, -force,
                               atol=1e-12)
    tr = read_rtde(path, force_axis=0, force_sign=1)
    np.testing.assert_allclose(tr.force, 0.5 * force, atol=1e-12)
    assert tr.metadata["force_column"] == "actual_TCP_force_0"


def test_metadata_routing(tmp_path, data):
    t, q, z, force = data
    path = write(rtde_frame(t, q, z, force), tmp_path / "m.csv", ",")
    tr = read_rtde(path, trace_id="white-sphere-3", specimen="W1", material="white",
                   thickness=0.03, repetition=3, rest_time=60.0, operator="ann")
    assert (tr.trace_id, tr.specimen, tr.material) == ("white-sphere-3", "W1", "white")
    assert (tr.thickness, tr.repetition, tr.rest_time) == (0.03, 3, 60.0)
    assert tr.metadata["operator"] == "ann"
    with pytest.raises(InputError, match="may not set"):
        read_rtde(path, z=1.0)


@pytest.mark.parametrize(
    "drop, match",
    [
        (["actual_q_3"], r"actual_q_3.*record the RTDE output field 'actual_q'"),
        (list(RTDE_Q_COLUMNS), r"missing columns actual_q_0, .*actual_q_5"),
        (["actual_TCP_force_2"], r"actual_TCP_force_2.*'actual_TCP_force'"),
        (["timestamp"], "missing column timestamp"),
    ],
)
def test_missing_columns(tmp_path, data, drop, match):
    t, q, z, force = data
    path = write(rtde_frame(t, q, z, force).drop(columns=drop), tmp_path / "bad.csv", " ")
    with pytest.raises(DataFileError, match=match) as err:
        read_rtde(path)
    assert str(err.value).startswith(str(path))


def test_missing_tcp_pose(tmp_path, data):
    t, q, z, force = data
    df = rtde_frame(t, q, z, force).drop(columns=list(RTDE_TCP_POSE_COLUMNS))
    path = write(df, tmp_path / "nopose.csv", ",")
    with pytest.raises(DataFileError, match="actual_TCP_pose_2.*'actual_TCP_pose'"):
        read_rtde(path, z_source="tcp")


@pytest.mark.parametrize("sep", [" ", ","], ids=["space", "comma"])
@pytest.mark.parametrize("value, match", [("nan", "empty"), ("abc", "non-numeric value 'abc'")])
def test_bad_cell_names_row(tmp_path, data, sep, value, match):
    t, q, z, force = data
    df = rtde_frame(t, q, z, force).astype(object)
    df.loc[4, "actual_q_2"] = value
    path = write(df, tmp_path / "cell.csv", sep)
    with pytest.raises(DataFileError, match=rf"actual_q_2.*{match}.*data row 5") as err:
        read_rtde(path)
    assert str(path) in str(err.value)


def test_too_few_rows(tmp_path, data):
    t, q, z, force = data
    path = write(rtde_frame(t, q, z, force).iloc[:2], tmp_path / "short.csv", ",")
    with pytest.raises(DataFileError, match="only 2 data row"):
        read_rtde(path)
    header_only = write(rtde_frame(t, q, z, force).iloc[:0], tmp_path / "hdr.csv", ",")
    with pytest.raises(DataFileError, match="only 0 data row"):
        read_rtde(header_only)


def test_time_not_increasing(tmp_path, data):
    t, q, z, force = data
    t = t.copy()
    t[10] = t[9]
    path = write(rtde_frame(t, q, z, force), tmp_path / "time.csv", ",")
    with pytest.raises(DataFileError, match="time repeats at data row 11"):
        read_rtde(path)


def test_unreadable_files(tmp_path):
    with pytest.raises(DataFileError, match="file not found"):
        read_rtde(tmp_path / "nope.csv")
    empty = tmp_path / "empty.csv"
    empty.write_text("")
    with pytest.raises(DataFileError, match="empty"):
        read_rtde(empty)
    binary = tmp_path / "robot_data.bin"
    binary.write_bytes(bytes(range(256)) * 4)
    with pytest.raises(DataFileError, match="binary"):
        read_rtde(binary)
    ragged = tmp_path / "ragged.csv"
    ragged.write_text("timestamp,actual_q_0\n1,2\n3,4,5,6\n")
    with pytest.raises(DataFileError, match="not a readable CSV"):
        read_rtde(ragged)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"z_source": "pose"}, "z_source"),
        ({"force_axis": 5}, "force_axis"),
        ({"force_sign": 2}, "force_sign"),
        ({"force_sign": "up"}, "force_sign"),
        ({"tool_offset": (0.0, 0.1)}, "tool_offset"),
    ],
)
def test_bad_options(tmp_path, data, kwargs, match):
    t, q, z, force = data
    path = write(rtde_frame(t, q, z, force), tmp_path / "opt.csv", ",")
    with pytest.raises(InputError, match=match):
        read_rtde(path, **kwargs)


def test_rotvec_to_matrix():
    R = rotvec_to_matrix(np.array([[PI, 0, 0], [0, 0, PI / 2], [0, 0, 0]]))
    np.testing.assert_allclose(R[0], np.diag([1.0, -1.0, -1.0]), atol=1e-15)
    np.testing.assert_allclose(R[1], [[0, -1, 0], [1, 0, 0], [0, 0, 1]], atol=1e-15)
    np.testing.assert_allclose(R[2], np.eye(3), atol=0)
    rng = np.random.default_rng(0)
    R = rotvec_to_matrix(rng.normal(size=(20, 3)))
    np.testing.assert_allclose(R @ np.swapaxes(R, 1, 2), np.broadcast_to(np.eye(3), R.shape),
                               atol=1e-12)


# ---------------------------------------------------------------------------- joint traces
def joint_frame(t, q, force, *, q_unit="rad", time_unit="s", force_unit="n", scale=None):
    scale = scale or {}
    cols = {f"time_{time_unit}": t * scale.get("time", 1.0)}
    for i in range(6):
        cols[f"q{i}_{q_unit}"] = q[:, i] * scale.get("q", 1.0)
    cols[f"force_{force_unit}"] = force * scale.get("force", 1.0)
    return pd.DataFrame(cols)


def test_read_joint_trace(tmp_path, data):
    t, q, z, force = data
    path = write(joint_frame(t - t[0], q, force), tmp_path / "joints.csv", ",")
    tr = read_joint_trace(path, tool_offset=OFFSET, material="pink")
    np.testing.assert_allclose(tr.z, tip_z(q, tool_offset=OFFSET), atol=1e-12)
    np.testing.assert_allclose(tr.force, force, atol=1e-12)
    np.testing.assert_allclose(tr.time, t - t[0], atol=1e-12)
    assert (tr.trace_id, tr.material, tr.source) == ("joints", "pink", str(path))
    tr5 = read_joint_trace(path, dh=UR5E, tool_offset=OFFSET, check=False)
    np.testing.assert_allclose(tr5.z, tip_z(q, UR5E, OFFSET), atol=1e-12)


def test_joint_trace_units(tmp_path, data):
    t, q, z, force = data
    df = joint_frame(t, q, force, q_unit="deg", time_unit="ms", force_unit="mN",
                     scale={"q": 180 / PI, "time": 1e3, "force": 1e3})
    tr = trace_from_joint_frame(df, "frame", tool_offset=OFFSET)
    np.testing.assert_allclose(tr.z, z, atol=1e-12)
    np.testing.assert_allclose(tr.time, t, atol=1e-9)
    np.testing.assert_allclose(tr.force, force, atol=1e-12)
    # Bare names with units given explicitly.
    bare = df.rename(columns=lambda c: c.split("_")[0])
    tr2 = trace_from_joint_frame(bare, "frame", tool_offset=OFFSET,
                                 units={"q": "deg", "time": "ms", "force": "mN"})
    np.testing.assert_allclose(tr2.z, z, atol=1e-12)
    with pytest.raises(InputError, match="unknown quantity"):
        trace_from_joint_frame(df, "frame", units={"z": "mm"})
    with pytest.raises(DataFileError, match="unknown angle unit"):
        trace_from_joint_frame(bare, "frame", units={"q": "grad"})


def test_joint_frame_errors(data):
    t, q, z, force = data
    df = joint_frame(t, q, force)
    with pytest.raises(DataFileError, match="frame.csv: missing column 'q3_rad'"):
        trace_from_joint_frame(df.drop(columns=["q3_rad"]), "frame.csv")
    with pytest.raises(DataFileError, match="missing column 'force_n'"):
        trace_from_joint_frame(df.drop(columns=["force_n"]), "frame.csv")
    with pytest.raises(DataFileError, match="no data rows"):
        trace_from_joint_frame(df.iloc[:0], "frame.csv")
    bad = df.astype(object)
    bad.loc[7, "q1_rad"] = "x"
    with pytest.raises(DataFileError, match="q1_rad.*data row 8"):
        trace_from_joint_frame(bad, "frame.csv")
    with pytest.raises(DataFileError, match="force falls .* below its pre-contact baseline"):
        trace_from_joint_frame(df.assign(force_n=-force), "frame.csv", tool_offset=OFFSET)
    neg = trace_from_joint_frame(df.assign(force_n=-force), "f", force_sign=-1)
    np.testing.assert_allclose(neg.force, force, atol=1e-12)


def test_canonical_reader_delegates(tmp_path, data):
    """palpbayes.io.trace_csv.read_trace hands q-column files to trace_from_joint_frame."""
    from palpbayes.io.trace_csv import read_trace

    t, q, z, force = data
    path = write(joint_frame(t - t[0], q, force), tmp_path / "canon.csv", ",")
    tr = read_trace(path)
    np.testing.assert_allclose(tr.z, tip_z(q), atol=1e-12)
    np.testing.assert_allclose(tr.force, force, atol=1e-12)


# --- reachable from pb.read and the command line (issue 57: io/rtde.py was wired to nothing) ---


def _log(tmp_path, data, **kw):
    t, q, z, force = data
    return write(rtde_frame(t, q, z, force, **kw), tmp_path / "press-rtde.csv", " ")


def test_a_log_is_recognised_by_its_header_and_read_as_fit_reads_it(tmp_path, data):
    from palpbayes import read
    from palpbayes.io.recording import read_recording, recording_kind

    t, q, z, force = data
    path = _log(tmp_path, data)
    assert recording_kind(path) == "rtde"
    assert recording_kind(write(pd.DataFrame({"time_s": t, "z_m": z, "force_n": force}),
                                tmp_path / "plain.csv", ",")) == "table"
    (tr,) = read_recording(path, tool_offset=OFFSET, force_axis="z")
    np.testing.assert_allclose(tr.z, z, atol=1e-12)
    np.testing.assert_allclose(tr.force, force, atol=1e-12)
    tr2 = read(path, tip="sphere", radius=0.01, tool_offset=OFFSET)
    np.testing.assert_allclose(tr2.force, force, atol=1e-12)
    assert tr2.tip.radius == 0.01 and tr2.metadata["reader"] == "rtde"
    with pytest.raises(InputError, match="a UR RTDE log: option 'columns'"):
        read_recording(path, columns={"z": "x"})


def test_a_log_without_joints_reads_its_tcp_pose(tmp_path, data):
    from palpbayes.io.recording import read_recording

    t, q, z, force = data
    df = rtde_frame(t, q, z, force).drop(columns=list(RTDE_Q_COLUMNS))
    path = write(df, tmp_path / "tcp-only.csv", ",")
    (tr,) = read_recording(path)
    assert tr.metadata["z_source"] == "tcp"
    np.testing.assert_allclose(tr.z, z + 0.1, atol=1e-12)


def test_fit_and_inspect_read_a_log(tmp_path, capsys):
    from palpbayes.cli import main

    path = _log(tmp_path, palpation(n=2000))
    assert main(["inspect", str(path)]) == 0
    text = capsys.readouterr().out
    assert "a UR RTDE log" in text and "--tool-offset M" in text
    out = tmp_path / "fit"
    assert main(["fit", str(path), "--out", str(out), "--tip", "sphere", "--radius", "0.01",
                 "--tool-offset", str(OFFSET), "--method", "lsq", "--f-unc", "0.01"]) == 0
    row = pd.read_csv(out / "summary.csv").iloc[0]
    assert row["E_pa"] > 0 and row["method"] == "lsq"
    capsys.readouterr()
    assert main(["fit", str(path), "--out", str(tmp_path / "bad"), "--tip", "sphere",
                 "--radius", "0.01", "--z-column", "z"]) == 2
    assert "a UR RTDE log" in capsys.readouterr().err
