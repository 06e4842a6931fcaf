"""Write ROS 2 bags (MCAP or sqlite3) of a force and a pose stream, e.g. from a simulated trace.

The inverse of :func:`palpbayes.io.rosbag.read_bag`, for tests, demonstrations and pipelines that
want a bag: a ``geometry_msgs/msg/WrenchStamped`` force topic and either a
``geometry_msgs/msg/PoseStamped`` tip pose or a ``sensor_msgs/msg/JointState`` of the six UR
joints, each with its own stamps (so misaligned clocks and dropped messages can be written on
purpose).  Needs the optional extra ``pip install 'palpbayes[ros]'``.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Literal

import numpy as np

from ..errors import DataFileError, InputError
from ..trace import IndentationTrace
from .bagfile import FORCE_TYPE, JOINT_TYPE, POSE_TYPE, typestore
from .extras import import_extra
from .rosbag import AXES, UR_JOINT_NAMES

__all__ = ["write_bag", "write_trace_bag", "STORAGES"]

#: Storage plugins of rosbag2 that ``rosbags`` writes.
STORAGES = ("mcap", "sqlite3")


def _ns(t: np.ndarray, t0_ns: int) -> np.ndarray:
    return np.round(np.asarray(t, dtype=float) * 1e9).astype(np.int64) + np.int64(t0_ns)


# Many parameters: a bag's topics, frames and units, mirroring read_bag's options so a test writes
# what the reader reads.
def write_bag(
    path: str | os.PathLike,
    force: tuple[np.ndarray, np.ndarray],
    pose: tuple[np.ndarray, np.ndarray] | None = None,
    joints: tuple[np.ndarray, np.ndarray] | None = None,
    *,
    storage: Literal["mcap", "sqlite3"] = "mcap",
    force_topic: str = "/force_torque_sensor_broadcaster/wrench",
    pose_topic: str | None = None,
    force_axis: Literal["x", "y", "z"] = "z",
    joint_names: tuple[str, ...] = UR_JOINT_NAMES,
    zero_stamps: bool = False,
    extra_topics: dict[str, int] | None = None,
    t0_ns: int = 0,
) -> Path:
    """Write a rosbag2 folder with a force topic and a pose or joint-state topic.

    Parameters
    ----------
    path
        Bag folder to create (must not exist).
    force
        (times [s], force [N]) written as ``wrench.force.<force_axis>`` of WrenchStamped.
    pose
        (times [s], tip height z [m]) written as ``pose.position.z`` of PoseStamped; or
    joints
        (times [s], joint angles [rad] of shape (N, 6)) written as a JointState.
    storage
        ``"mcap"`` or ``"sqlite3"``.
    force_topic, pose_topic
        Topic names (pose default ``/tcp_pose``, joints ``/joint_states``).
    force_axis
        Force component that carries the force.
    joint_names
        JointState names, in the order of the columns of ``joints``.
    zero_stamps
        Write zero header stamps (drivers that leave them unset); receive times still set.
    extra_topics
        Further ``std_msgs/msg/String`` topics with this many messages (what else a bag holds).
    t0_ns
        [ns] Added to every time (e.g. a Unix time, so that times can be given from 0 in
        seconds without losing the nanoseconds to rounding).

    Returns
    -------
    Path
        The bag folder.  Times are written both as header stamps and as receive times.
    """
    rosbag2 = import_extra("ros", "writing ROS 2 bags", "rosbags.rosbag2")
    if storage not in STORAGES:
        raise InputError(f"storage must be one of {', '.join(STORAGES)}, got {storage!r}")
    if (pose is None) == (joints is None):
        raise InputError("give either pose=(t, z) or joints=(t, q)")
    if force_axis not in AXES:
        raise InputError(f"force_axis must be x, y or z, got {force_axis!r}")
    path = Path(path)
    if path.exists():
        raise DataFileError(path, "exists already", "remove it or choose another path")
    store = typestore()
    T = store.types
    header, stamp_t = T["std_msgs/msg/Header"], T["builtin_interfaces/msg/Time"]
    vec, point, quat = (T["geometry_msgs/msg/Vector3"], T["geometry_msgs/msg/Point"],
                        T["geometry_msgs/msg/Quaternion"])

    def hdr(ns: int, frame: str):
        ns = 0 if zero_stamps else int(ns)
        return header(stamp=stamp_t(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000),
                      frame_id=frame)

    def wrench(ns: int, f: float):
        xyz = {a: (float(f) if a == force_axis else 0.0) for a in AXES}
        return T[FORCE_TYPE](header=hdr(ns, "tool0"), wrench=T["geometry_msgs/msg/Wrench"](
            force=vec(**xyz), torque=vec(x=0.0, y=0.0, z=0.0)))

    def pose_msg(ns: int, z: float):
        return T[POSE_TYPE](header=hdr(ns, "base"), pose=T["geometry_msgs/msg/Pose"](
            position=point(x=0.0, y=0.0, z=float(z)), orientation=quat(x=1.0, y=0.0, z=0.0,
                                                                       w=0.0)))

    def joint_msg(ns: int, q: np.ndarray):
        return T[JOINT_TYPE](header=hdr(ns, ""), name=list(joint_names),
                             position=np.ascontiguousarray(q, dtype=np.float64),
                             velocity=np.zeros(0), effort=np.zeros(0))

    if pose is not None:
        second, make, msgtype = pose, pose_msg, POSE_TYPE
        pose_topic = pose_topic or "/tcp_pose"
    else:
        second, make, msgtype = joints, joint_msg, JOINT_TYPE
        pose_topic = pose_topic or "/joint_states"
    messages = [(t, 0, wrench(t, f)) for t, f in zip(_ns(force[0], t0_ns), force[1], strict=True)]
    messages += [(t, 1, make(t, v)) for t, v in zip(_ns(second[0], t0_ns), second[1], strict=True)]
    messages.sort(key=lambda m: (m[0], m[1]))
    plugin = (rosbag2.StoragePlugin.MCAP if storage == "mcap" else
              rosbag2.StoragePlugin.SQLITE3)
    with rosbag2.Writer(path, version=9, storage_plugin=plugin) as writer:
        conns = [writer.add_connection(force_topic, FORCE_TYPE, typestore=store),
                 writer.add_connection(pose_topic, msgtype, typestore=store)]
        types = [FORCE_TYPE, msgtype]
        for t, k, msg in messages:
            writer.write(conns[k], int(t), store.serialize_cdr(msg, types[k]))
        t0 = int(messages[0][0]) if messages else 0
        for name, n in (extra_topics or {}).items():
            conn = writer.add_connection(name, "std_msgs/msg/String", typestore=store)
            for i in range(n):
                data = store.serialize_cdr(T["std_msgs/msg/String"](data=f"{i}"),
                                           "std_msgs/msg/String")
                writer.write(conn, t0 + i * 100_000_000, data)
    return path


def write_trace_bag(trace: IndentationTrace, path: str | os.PathLike, *,
                    storage: Literal["mcap", "sqlite3"] = "mcap", force_sign: float = -1.0,
                    t0_ns: int = 1_700_000_000 * 10**9, **options) -> Path:
    """Write a trace as a bag: its force (times ``force_sign``, the F/T sensor's convention)
    on the force topic and its z as a PoseStamped, both stamped ``t0_ns`` + ``trace.time``.
    ``options`` go to :func:`write_bag`."""
    t = trace.time
    return write_bag(path, (t, force_sign * trace.force), pose=(t, trace.z), storage=storage,
                     t0_ns=t0_ns, **options)
