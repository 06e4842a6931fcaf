"""ROS 2 bags: bags written here with rosbags (MCAP and sqlite3), read back equal to
the canonical CSV; time alignment, misaligned clocks, missing topics, wrong types and dropped
messages give clear errors."""

from __future__ import annotations

import sys

import numpy as np
import pytest

from palpbayes.contact import Tip
from palpbayes.errors import DataFileError, MissingExtraError
from palpbayes.io.rosbag import list_topics, read_bag
from palpbayes.io.rosbag_write import STORAGES, write_bag, write_trace_bag
from palpbayes.io.trace_csv import read_trace, write_trace
from palpbayes.kinematics import UR3E, tip_z
from palpbayes.sim import simulate_trace

PARA = Tip("paraboloid", radius=0.0117)
T0 = 1_700_000_000 * 10**9
FT = "/force_torque_sensor_broadcaster/wrench"


@pytest.fixture(scope="module")
def sim():
    return simulate_trace(50e3, PARA, depth=3e-3, rate=250.0, rng=3)


def _streams(trace, f_sign=-1.0):
    return (trace.time, f_sign * trace.force), (trace.time, trace.z)


@pytest.mark.parametrize("storage", STORAGES)
def test_bag_round_trip_equals_the_canonical_csv(sim, storage, tmp_path):
    """Simulated trace -> bag (force as -Fz, as an F/T sensor reports pressing) -> read_bag
    equals the same trace through the canonical CSV."""
    bag = write_trace_bag(sim, tmp_path / "bag", storage=storage, extra_topics={"/rosout": 3})
    got = read_bag(bag, tip=PARA)  # topics found by type, sign found by the physics
    csv = read_trace(write_trace(sim, tmp_path / "t.csv", float_format="%.17g"), tip=PARA)
    assert got.n_points == csv.n_points == sim.n_points
    np.testing.assert_array_equal(got.z, csv.z)
    np.testing.assert_array_equal(got.force, csv.force)
    np.testing.assert_allclose(got.time, csv.time - csv.time[0], atol=1e-9)
    assert got.metadata["force_sign"] == -1.0 and got.metadata["stamps"] == "header"
    assert got.metadata["force_topic"] == FT and got.metadata["t0_ns"] == T0 + round(
        sim.time[0] * 1e9)
    assert got.trace_id == "bag" and got.tip == PARA


@pytest.mark.parametrize("storage, suffix", [("mcap", ".mcap"), ("sqlite3", ".db3")])
def test_the_storage_file_inside_the_bag_folder_is_accepted(sim, storage, suffix, tmp_path):
    bag = write_trace_bag(sim, tmp_path / "rec", storage=storage)
    (file,) = bag.glob(f"*{suffix}")
    got = read_bag(file, force_topic=FT, pose_topic="/tcp_pose", force_sign=-1)
    np.testing.assert_array_equal(got.force, sim.force)
    assert got.trace_id == "rec"


def test_list_topics_gives_types_counts_and_rates(sim, tmp_path):
    bag = write_trace_bag(sim, tmp_path / "bag", extra_topics={"/rosout": 4})
    topics = {t.topic: t for t in list_topics(bag)}
    assert topics[FT].msgtype == "geometry_msgs/msg/WrenchStamped"
    assert topics["/tcp_pose"].count == sim.n_points
    assert topics[FT].rate_hz == pytest.approx(250.0, rel=1e-6)
    assert topics["/rosout"].msgtype == "std_msgs/msg/String" and topics["/rosout"].count == 4


def test_pose_is_interpolated_onto_the_force_stamps(tmp_path):
    """Force at 500 Hz, pose at 100 Hz with another phase: z at each force stamp is the linear
    interpolation of the pose stream; force samples outside the pose stream are dropped."""
    tf = np.arange(0.0, 2.0, 0.002)
    tp = np.arange(-0.0013, 2.0 - 0.005, 0.01)
    z_of = lambda t: 0.10 - 1e-3 * t  # noqa: E731 - linear, so interpolation is exact
    force = 5e5 * np.clip(1e-3 * tf - 5e-4, 0, None) ** 1.5  # contact at z = 99.95 mm
    write_bag(tmp_path / "b", (tf, force), pose=(tp, z_of(tp)), t0_ns=T0)
    got = read_bag(tmp_path / "b", force_sign=1)
    keep = tf <= tp[-1]
    assert got.n_points == int(keep.sum()) and got.metadata["force_messages_dropped"] == int(
        (~keep).sum())
    np.testing.assert_allclose(got.z, z_of(tf[keep]), atol=1e-12)
    np.testing.assert_allclose(got.time, tf[keep] - tf[0], atol=1e-9)


def test_joint_states_through_the_ur3e_kinematics(tmp_path):
    """JointState with a driver's prefix and alphabetical name order (as ros2_control publishes
    it): z is the UR3e forward kinematics of the joints plus the tool offset."""
    t = np.arange(0.0, 1.0, 0.004)
    q = np.tile([0.0, -1.2, 1.6, -1.97, -1.5708, 0.0], (t.size, 1))
    q[:, 1] += 0.02 * t  # the shoulder lifts: the tip goes down
    offset = 0.08
    z = tip_z(q, UR3E, np.array([0.0, 0.0, offset]))
    assert z[-1] < z[0]
    force = 2e4 * np.clip(z[0] - 1e-3 - z, 0, None)
    order = [2, 1, 0, 3, 4, 5]  # elbow, shoulder_lift, shoulder_pan, wrist_1..3
    names = ["ur3e_elbow_joint", "ur3e_shoulder_lift_joint", "ur3e_shoulder_pan_joint",
             "ur3e_wrist_1_joint", "ur3e_wrist_2_joint", "ur3e_wrist_3_joint"]
    write_bag(tmp_path / "b", (t, -force), joints=(t, q[:, order]), joint_names=tuple(names),
              t0_ns=T0, storage="sqlite3")
    got = read_bag(tmp_path / "b", tool_offset=offset)
    np.testing.assert_allclose(got.z, z, atol=1e-12)
    np.testing.assert_allclose(got.force, force)
    assert got.metadata["pose_type"] == "sensor_msgs/msg/JointState"
    assert got.metadata["robot"] == UR3E.name


def test_force_axis_and_explicit_sign(sim, tmp_path):
    force, pose = _streams(sim, f_sign=+1.0)
    write_bag(tmp_path / "b", force, pose=pose, force_axis="x", t0_ns=T0)
    got = read_bag(tmp_path / "b", force_axis="x", force_sign=1)
    np.testing.assert_array_equal(got.force, sim.force)
    with pytest.raises(DataFileError, match=r"flip the sign: --force-sign \+1"):
        read_bag(tmp_path / "b", force_axis="x", force_sign=-1)
    with pytest.raises(DataFileError, match=r"wrench.force.z is 0 in every message"):
        read_bag(tmp_path / "b")


def test_misaligned_clocks_name_the_offset_and_time_offset_fixes_them(sim, tmp_path):
    """The pose recorded with a clock one hour behind: refused with the offset to pass."""
    force, (tp, z) = _streams(sim)
    write_bag(tmp_path / "b", force, pose=(tp - 3600.0, z), t0_ns=T0)
    with pytest.raises(DataFileError) as err:
        read_bag(tmp_path / "b")
    msg = str(err.value)
    assert "do not overlap" in msg and "/tcp_pose" in msg and FT in msg
    assert "--time-offset 3600" in msg
    got = read_bag(tmp_path / "b", time_offset=3600.0)
    np.testing.assert_array_equal(got.z, sim.z)
    assert got.metadata["time_offset_s"] == 3600.0


def test_a_pose_stream_covering_too_little_is_refused(sim, tmp_path):
    force, (tp, z) = _streams(sim)
    shift = 0.7 * (tp[-1] - tp[0])
    write_bag(tmp_path / "b", force, pose=(tp + shift, z), t0_ns=T0)
    with pytest.raises(DataFileError, match=r"covers only 30 % of the force recording"):
        read_bag(tmp_path / "b")


def test_missing_topic_lists_the_topics_there_with_their_types(sim, tmp_path):
    bag = write_trace_bag(sim, tmp_path / "b", extra_topics={"/rosout": 2})
    with pytest.raises(DataFileError) as err:
        read_bag(bag, force_topic="/wrench")
    msg = str(err.value)
    assert "force topic '/wrench' is not in the bag" in msg
    assert f"{FT} (geometry_msgs/msg/WrenchStamped)" in msg
    assert "/rosout (std_msgs/msg/String)" in msg and "--force-topic" in msg


def test_a_topic_of_the_wrong_type_is_refused(sim, tmp_path):
    bag = write_trace_bag(sim, tmp_path / "b", extra_topics={"/rosout": 2})
    with pytest.raises(DataFileError, match=r"pose topic '/rosout' has type std_msgs/msg/String"):
        read_bag(bag, pose_topic="/rosout")
    with pytest.raises(DataFileError, match=r"force topic '/tcp_pose' has type "
                       r"geometry_msgs/msg/PoseStamped, not geometry_msgs/msg/WrenchStamped"):
        read_bag(bag, force_topic="/tcp_pose")


def test_dropped_pose_messages_are_refused_with_gap_and_time(sim, tmp_path):
    """A 0.2 s hole in a 250 Hz pose stream (50 periods) inside the force recording; a single
    dropped message (2 periods) is interpolated over."""
    force, (tp, z) = _streams(sim)
    hole = (tp > 2.0) & (tp < 2.2)
    write_bag(tmp_path / "b", force, pose=(tp[~hole], z[~hole]), t0_ns=T0)
    with pytest.raises(DataFileError) as err:
        read_bag(tmp_path / "b")
    msg = str(err.value)
    assert "pose topic '/tcp_pose' has a gap of 0.2 s" in msg
    assert "50× its median period of 0.004 s" in msg and "at t = 1.996 s" in msg
    assert "dropped" in msg
    one = np.arange(tp.size) == 300
    write_bag(tmp_path / "c", force, pose=(tp[~one], z[~one]), t0_ns=T0)
    got = read_bag(tmp_path / "c")
    np.testing.assert_allclose(got.z, sim.z, atol=1e-7)


def test_zero_header_stamps_fall_back_to_receive_times_with_a_warning(sim, tmp_path):
    bag = write_trace_bag(sim, tmp_path / "b", zero_stamps=True)
    with pytest.warns(UserWarning, match="every header stamp is zero; using the bag's receive"):
        got = read_bag(bag)
    assert got.metadata["stamps"] == "receive"
    np.testing.assert_array_equal(got.z, sim.z)


def test_a_simulation_clock_starting_at_zero_keeps_the_header_stamps(sim, tmp_path):
    """Sim time: the first messages are stamped 0; they are dropped, the others keep their
    header stamps (switching one topic to receive times would misalign the two)."""
    (tf, f), (tp, z) = _streams(sim)
    write_bag(tmp_path / "b", (tf - tf[0], f), pose=(tp - tp[0], z), t0_ns=0)
    with pytest.warns(UserWarning, match="1 of .* header stamps are zero; those messages are "
                                         "dropped"):
        got = read_bag(tmp_path / "b")
    assert got.metadata["stamps"] == "header"
    assert got.n_points == sim.n_points - 1
    np.testing.assert_allclose(got.z, sim.z[1:], atol=1e-7)


def test_not_a_bag_and_a_broken_bag_give_data_file_errors(sim, tmp_path):
    (tmp_path / "empty").mkdir()
    with pytest.raises(DataFileError, match="folder without metadata.yaml"):
        read_bag(tmp_path / "empty")
    bag = write_trace_bag(sim, tmp_path / "b")
    (file,) = bag.glob("*.mcap")
    broken = tmp_path / "broken.mcap"
    broken.write_bytes(file.read_bytes()[:3000])
    with pytest.raises(DataFileError, match=r"broken.mcap: "):
        read_bag(broken)
    with pytest.raises(DataFileError, match="bag not found"):
        read_bag(tmp_path / "nothing.mcap")


def test_the_missing_extra_is_named(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "rosbags.rosbag2", None)
    with pytest.raises(MissingExtraError,
                       match=r"reading ROS 2 bags needs the optional extra ros "
                             r"\(rosbags.rosbag2 is not installed\): pip install .*"
                             r"pip install 'palpbayes\[ros\]'"):
        read_bag(tmp_path / "x.mcap")
