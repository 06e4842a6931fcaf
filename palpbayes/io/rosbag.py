"""Read ROS 2 bags (rosbag2: MCAP or sqlite3) into a tip trace, without a ROS install.

:func:`read_bag` takes two topics of one bag and aligns them in time:

  ==========================================  ================================  ============
  topic (message type)                        field used                        unit
  ==========================================  ================================  ============
  force: ``geometry_msgs/msg/WrenchStamped``  ``wrench.force.{x|y|z}``          [N]
  pose: ``geometry_msgs/msg/PoseStamped``     ``pose.position.z`` (tip height)  [m]
  or: ``sensor_msgs/msg/JointState``          ``position`` of the six UR joints [rad]
  ==========================================  ================================  ============

A bag is the folder ``ros2 bag record`` writes (``metadata.yaml`` + ``.mcap`` or ``.db3``); the
single ``.mcap`` or ``.db3`` file inside it is accepted too.  Needs the optional extra
``pip install 'palpbayes[ros]'`` (the pure-Python ``rosbags`` library).

Time
----
Each message's ``header.stamp`` [s] is its time (the bag's receive time instead, with a warning,
when all of a topic's stamps are zero; messages with a zero stamp are dropped when only some
are).  The pose is interpolated linearly (``np.interp``) onto the
force stamps: the trace has one sample per force message inside the pose stream's time range.
``time_offset`` [s] is *added to the pose stamps* (a pose clock that runs behind the force clock).
Refused, naming the topic: clocks that do not overlap (the message gives the offset to pass),
a pose stream covering less than half of the force recording, a pose gap longer than
``max_gap`` × its median period inside the force recording (dropped messages: z cannot be
interpolated across it).

Units and signs
---------------
z is up in the frame of the PoseStamped (the robot base frame, ``base`` on a UR) [m]; with a
JointState z is the tip height by UR Denavit–Hartenberg forward kinematics
(:func:`palpbayes.kinematics.tip_z`, UR3e by default) plus ``tool_offset`` in the flange frame.
``tool_offset`` with a PoseStamped is an *additional* offset in the pose's own frame (a tip not in
the TCP).  The force is ``force_sign × wrench.force.<force_axis>`` in the wrench's own frame (the
sensor frame): a F/T sensor whose z axis points along the tool *out of the flange* reports
pressing as -Fz, the UR driver's ``/force_torque_sensor_broadcaster/wrench`` as either sign
depending on the sensor and its zeroing, so the default ``force_sign="auto"`` picks the sign
that makes the force grow as the tip goes down, as :func:`palpbayes.io.rtde.read_rtde` does;
the sign used is in ``trace.metadata["force_sign"]``.
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np

from ..contact import Tip
from ..errors import DataFileError, InputError
from ..kinematics import UR3E, DHParameters, as_offset, tip_z
from ..trace import IndentationTrace
from .bagfile import (
    FORCE_TYPE,
    JOINT_TYPE,
    POSE_TYPE,
    BagTopic,
    describe_topics,
    open_bag,
    read_messages,
)
from .tabular import (
    auto_force_sign,
    check_plausible,
    split_trace_metadata,
    validate_force_sign,
)

__all__ = ["read_bag", "list_topics", "UR_JOINT_NAMES", "AXES", "MAX_GAP_FACTOR", "BagTopic"]

#: UR joint names in kinematic order (a driver's prefix, e.g. ``ur3e_``, is allowed).
UR_JOINT_NAMES = ("shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint",
                  "wrist_1_joint", "wrist_2_joint", "wrist_3_joint")
#: Force axes by name.
AXES = ("x", "y", "z")
#: A pose gap longer than this many median periods inside the force recording is refused.
MAX_GAP_FACTOR = 5.0


@dataclass(frozen=True)
class _Stream:
    """One topic's samples: times [ns] (sorted, unique) and values, where the times came from."""

    topic: str
    msgtype: str
    t_ns: np.ndarray
    values: np.ndarray
    stamps: str  # "header" or "receive"
    duplicates: int


def list_topics(path: str | os.PathLike) -> list[BagTopic]:
    """Topics of a bag: name, message type, count, first/last receive time [s], rate [Hz].

    Raises
    ------
    DataFileError
        Not a bag, or unreadable.
    MissingExtraError
        ``rosbags`` is not installed.
    """
    with open_bag(path) as reader:
        return describe_topics(reader, str(path))


def _pick_topic(topics: list[BagTopic], name: str | None, types: tuple[str, ...], role: str,
                option: str, source: str) -> BagTopic:
    """The topic ``name`` (checked to exist and have one of ``types``), or the only topic of
    those types when ``name`` is None."""
    have = "; the bag has " + (", ".join(f"{t.topic} ({t.msgtype})" for t in topics)
                               or "no topics")
    wanted = " or ".join(types)
    if name is None:
        match = [t for t in topics if t.msgtype in types]
        if len(match) == 1:
            return match[0]
        which = "no" if not match else f"{len(match)}"
        raise DataFileError(source, f"{which} {role} topic{'s' if len(match) != 1 else ''} "
                            f"of type {wanted}{have}", f"name the {role} topic with {option}")
    by_name = {t.topic: t for t in topics}
    if name not in by_name:
        raise DataFileError(source, f"{role} topic {name!r} is not in the bag{have}",
                            f"give one of them with {option}")
    topic = by_name[name]
    if topic.msgtype not in types:
        raise DataFileError(source, f"{role} topic {name!r} has type {topic.msgtype}, not "
                            f"{wanted}", f"give a {wanted} topic with {option}")
    if topic.count == 0:
        raise DataFileError(source, f"{role} topic {name!r} has no messages",
                            "check that the topic was recorded")
    return topic


def _joint_index(names: list[str], n_positions: int, topic: str, source: str) -> list[int]:
    """Indices of the six UR joints in a JointState's ``name``/``position`` lists."""
    if not names and n_positions == 6:
        return list(range(6))
    index = []
    for joint in UR_JOINT_NAMES:
        hits = [i for i, n in enumerate(names) if n == joint or n.endswith(joint)]
        if len(hits) != 1:
            raise DataFileError(source, f"topic {topic!r}: joint {joint!r} "
                                f"{'is missing' if not hits else 'appears twice'}; the "
                                f"JointState names are {', '.join(names) or 'empty'}",
                                "record the UR arm's /joint_states")
        if hits[0] >= n_positions:
            raise DataFileError(source, f"topic {topic!r}: joint {joint!r} has no position")
        index.append(hits[0])
    return index


def _extractor(msgtype: str, axis: str, topic: str, source: str) -> Callable:
    """A function message -> (header stamp [ns], value) for the message type."""
    k = AXES.index(axis)
    cache: dict[tuple, list[int]] = {}

    def stamp(msg) -> int:
        return int(msg.header.stamp.sec) * 1_000_000_000 + int(msg.header.stamp.nanosec)

    if msgtype == FORCE_TYPE:
        return lambda m: (stamp(m), (m.wrench.force.x, m.wrench.force.y, m.wrench.force.z)[k])
    if msgtype == POSE_TYPE:
        return lambda m: (stamp(m), (m.pose.position.z, m.pose.orientation.x,
                                     m.pose.orientation.y, m.pose.orientation.z,
                                     m.pose.orientation.w))

    def joints(m):
        key = tuple(m.name)
        if key not in cache:
            cache[key] = _joint_index(list(m.name), len(m.position), topic, source)
        return stamp(m), np.asarray(m.position, dtype=float)[cache[key]]
    return joints


def _stream(topic: BagTopic, stamps: list[int], received: list[int], values: list,
            source: str) -> _Stream:
    """Sorted, de-duplicated samples of one topic; receive times when every stamp is zero
    (a driver that does not stamp), messages with a zero stamp dropped when only some are (a
    simulation clock starting at 0 must not switch one topic to wall-clock time)."""
    t = np.asarray(stamps, dtype=np.int64)
    v = np.asarray(values, dtype=float)
    kind = "header"
    zero = t <= 0
    if np.all(zero):
        warnings.warn(f"{source}: topic {topic.topic!r}: every header stamp is zero; using the "
                      "bag's receive times instead (they include transport delays)",
                      UserWarning, stacklevel=4)
        t, kind = np.asarray(received, dtype=np.int64), "receive"
    elif np.any(zero):
        warnings.warn(f"{source}: topic {topic.topic!r}: {int(zero.sum())} of {t.size} header "
                      "stamps are zero; those messages are dropped", UserWarning, stacklevel=4)
        t, v = t[~zero], v[~zero]
    order = np.argsort(t, kind="stable")
    t, v = t[order], v[order]
    keep = np.concatenate([[True], np.diff(t) > 0])
    n_dup = int(np.sum(~keep))
    if n_dup > 0.01 * t.size:
        warnings.warn(f"{source}: topic {topic.topic!r}: {n_dup} of {t.size} messages repeat an "
                      "earlier stamp and are dropped; check the publisher's clock",
                      UserWarning, stacklevel=4)
    return _Stream(topic.topic, topic.msgtype, t[keep], v[keep], kind, n_dup)


def _quat_z_row(q: np.ndarray) -> np.ndarray:
    """Third row of the rotation matrices of unit quaternions (x, y, z, w), shape (N, 3)."""
    x, y, z, w = (q[:, i] for i in range(4))
    n = np.sqrt(x * x + y * y + z * z + w * w)
    x, y, z, w = x / n, y / n, z / n, w / n
    return np.column_stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)])


def _fmt_s(ns: float) -> str:
    return f"{ns / 1e9:.6g} s"


def _align(force: _Stream, pose: _Stream, z_pose: np.ndarray, max_gap: float,
           source: str) -> tuple[np.ndarray, np.ndarray]:
    """The force samples kept (a mask: those inside the pose stream) and z interpolated onto
    them [m]; refuses misaligned clocks, too short an overlap and pose gaps (dropped
    messages)."""
    tf, tp = force.t_ns, pose.t_ns
    if tp.size < 2:
        raise DataFileError(source, f"pose topic {pose.topic!r} has {tp.size} message(s); z "
                            "needs at least 2 to interpolate", "check that it was recorded")
    f0, f1, p0, p1 = int(tf[0]), int(tf[-1]), int(tp[0]), int(tp[-1])
    offset = f0 - p0
    hint = (f"if the two clocks differ, pass --time-offset {offset / 1e9:.6g} (added to the pose "
            "stamps; time_offset in the API), or record both topics with one clock")
    if p1 < f0 or p0 > f1:
        where = "after" if p0 > f1 else "before"
        gap = p0 - f1 if p0 > f1 else f0 - p1
        raise DataFileError(
            source, f"the clocks of {force.topic!r} and {pose.topic!r} do not overlap: the pose "
            f"stream ({_fmt_s(p1 - p0)} long) ends/starts {_fmt_s(gap)} {where} the force "
            f"stream ({_fmt_s(f1 - f0)} long); their first stamps are {_fmt_s(abs(offset))} "
            "apart", hint)
    inside = (tf >= p0) & (tf <= p1)
    covered = (min(f1, p1) - max(f0, p0)) / max(f1 - f0, 1)
    if covered < 0.5:
        raise DataFileError(
            source, f"the pose stream {pose.topic!r} covers only {100 * covered:.0f} % of the "
            f"force recording {force.topic!r} (first stamps {_fmt_s(abs(offset))} apart)", hint)
    if np.count_nonzero(inside) < 3:
        raise DataFileError(source, f"only {np.count_nonzero(inside)} force message(s) lie "
                            f"inside the pose stream {pose.topic!r}", hint)
    dropped = int(np.count_nonzero(~inside))
    if dropped > 0.05 * tf.size:
        warnings.warn(f"{source}: {dropped} of {tf.size} force messages lie outside the pose "
                      f"stream {pose.topic!r} and are dropped", UserWarning, stacklevel=3)
    tf = tf[inside]
    period = float(np.median(np.diff(tp)))
    lo = max(int(np.searchsorted(tp, tf[0], side="right")) - 1, 0)
    hi = min(int(np.searchsorted(tp, tf[-1], side="left")), tp.size - 1)
    dt = np.diff(tp[lo:hi + 1])
    if dt.size and dt.max() > max_gap * period:
        i = lo + int(np.argmax(dt))
        raise DataFileError(
            source, f"pose topic {pose.topic!r} has a gap of {_fmt_s(float(dt.max()))} "
            f"({dt.max() / period:.0f}× its median period of {_fmt_s(period)}) at "
            f"t = {_fmt_s(float(tp[i] - tf[0]))} into the force recording: messages were "
            "dropped and z cannot be interpolated across the gap",
            "record again (a larger queue, fewer topics), or allow it with max_gap in the API")
    z = np.interp((tf - p0).astype(float), (tp - p0).astype(float), z_pose)
    return inside, z


# Many parameters: a ROS 2 bag's topics, axis, signs, time offset and tool geometry: each a reader
# option of `palpbayes fit`, by its flag's name.
def read_bag(
    path: str | os.PathLike,
    *,
    force_topic: str | None = None,
    pose_topic: str | None = None,
    force_axis: Literal["x", "y", "z"] = "z",
    force_sign: float | Literal["auto"] = "auto",
    time_offset: float = 0.0,
    tool_offset: float | tuple[float, float, float] = 0.0,
    dh: DHParameters = UR3E,
    max_gap: float = MAX_GAP_FACTOR,
    tip: Tip | None = None,
    trace_id: str | None = None,
    check: bool = True,
    **metadata,
) -> IndentationTrace:
    """Read a ROS 2 bag into an :class:`~palpbayes.trace.IndentationTrace` (SI units).

    Parameters
    ----------
    path
        Bag folder (``metadata.yaml`` + storage file) or its ``.mcap`` / ``.db3`` file.
    force_topic
        ``geometry_msgs/msg/WrenchStamped`` topic, e.g.
        ``/force_torque_sensor_broadcaster/wrench``; None: the bag's only WrenchStamped topic.
    pose_topic
        ``geometry_msgs/msg/PoseStamped`` (tip pose) or ``sensor_msgs/msg/JointState`` topic;
        None: the bag's only topic of those types.
    force_axis
        Component of the wrench's force along the indentation: ``"x"``, ``"y"`` or ``"z"``.
    force_sign
        +1 or -1 multiplying that component to make pressing positive, or ``"auto"`` (default;
        see the module notes).
    time_offset
        [s] Added to the pose stamps before the alignment (pose clock behind the force clock).
    tool_offset
        [m] JointState: sensor + tip length along the flange z axis (or a length-3 vector in the
        flange frame).  PoseStamped: an additional offset in the pose frame (default 0).
    dh
        DH table of the arm for JointState (default :data:`~palpbayes.kinematics.UR3E`).
    max_gap
        Refuse a pose gap longer than this many median pose periods inside the force recording.
    tip, trace_id, check, **metadata
        As for :func:`palpbayes.io.rtde.read_rtde`; ``trace_id`` defaults to the bag's name.

    Returns
    -------
    IndentationTrace
        time [s] from the first aligned force stamp, z [m] up, force [N]; ``metadata`` records
        the topics, types, axis, sign, offsets, stamp source and the first stamp ``t0_ns``.

    Raises
    ------
    DataFileError
        Not a bag; a topic missing (the message lists those present with their types), of the
        wrong type or empty; misaligned clocks; a pose gap; implausible sign or units.
    InputError
        Invalid options.
    MissingExtraError
        ``rosbags`` is not installed.
    """
    if force_axis not in AXES:
        raise InputError(f"force_axis must be x, y or z, got {force_axis!r}")
    sign = validate_force_sign(force_sign, allow_auto=True)
    if not (np.isfinite(time_offset) and np.isfinite(max_gap) and max_gap > 1):
        raise InputError(f"time_offset {time_offset!r} must be finite and max_gap "
                         f"{max_gap!r} a number above 1")
    offset = as_offset(tool_offset)
    path = Path(path)
    source = str(path)
    with open_bag(path) as reader:
        topics = describe_topics(reader, source, times=False)
        ft = _pick_topic(topics, force_topic, (FORCE_TYPE,), "force", "--force-topic", source)
        pt = _pick_topic(topics, pose_topic, (POSE_TYPE, JOINT_TYPE), "pose", "--pose-topic",
                         source)
        extract = {ft.topic: _extractor(ft.msgtype, force_axis, ft.topic, source),
                   pt.topic: _extractor(pt.msgtype, force_axis, pt.topic, source)}
        samples = read_messages(reader, [ft.topic, pt.topic], extract, source)
    force = _stream(ft, *samples[ft.topic], source)
    pose = _stream(pt, *samples[pt.topic], source)
    if force.t_ns.size < 3:
        raise DataFileError(source, f"force topic {ft.topic!r} has {force.t_ns.size} "
                            "message(s); a trace needs at least 3", "check the recording")
    pose = _Stream(pose.topic, pose.msgtype, pose.t_ns + round(time_offset * 1e9), pose.values,
                   pose.stamps, pose.duplicates)
    if pt.msgtype == JOINT_TYPE:
        z_pose = tip_z(pose.values, dh, offset)
    else:
        z_pose = pose.values[:, 0]
        if np.any(offset != 0.0):
            z_pose = z_pose + _quat_z_row(pose.values[:, 1:]) @ offset
    inside, z = _align(force, pose, z_pose, max_gap, source)
    t_ns, raw = force.t_ns[inside], force.values[inside]
    if not np.any(raw):
        raise DataFileError(source, f"force topic {ft.topic!r}: wrench.force.{force_axis} is 0 "
                            "in every message", "choose the axis along the indentation with "
                            "--force-axis x|y|z")
    if sign == "auto":
        sign = auto_force_sign(z, raw)
    kwargs, free = split_trace_metadata(metadata, {
        "reader": "rosbag2", "force_topic": ft.topic, "pose_topic": pt.topic,
        "pose_type": pt.msgtype, "force_axis": force_axis, "force_sign": sign,
        "time_offset_s": float(time_offset), "tool_offset_m": offset.tolist(),
        "stamps": force.stamps if force.stamps == pose.stamps else
        f"force {force.stamps}, pose {pose.stamps}",
        "t0_ns": int(t_ns[0]), "force_messages_dropped": int(np.count_nonzero(~inside)),
        "duplicate_stamps": force.duplicates + pose.duplicates,
        **({"robot": dh.name} if pt.msgtype == JOINT_TYPE else {}),
    })
    trace = IndentationTrace(
        time=(t_ns - t_ns[0]) / 1e9, z=z, force=sign * raw, tip=tip,
        trace_id=trace_id if trace_id is not None else (path.stem or path.name),
        source=source, metadata=free, **kwargs,
    )
    if check:
        check_plausible(trace, f"flip the sign: --force-sign {-sign:+g} (force_sign in the "
                        "API), or leave it to auto")
    return trace
