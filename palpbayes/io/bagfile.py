"""Open a ROS 2 bag with ``rosbags`` and read its messages, every library error wrapped.

The layer under :mod:`palpbayes.io.rosbag` (alignment, units) and ``palpbayes inspect``: it knows
the bag layout (a folder with ``metadata.yaml``, or one ``.mcap``/``.db3`` file), the message
types palpbayes reads, and turns ``rosbags`` exceptions into
:class:`~palpbayes.errors.DataFileError` naming the bag, the topic and the fix.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

from ..errors import DataFileError
from .extras import import_extra

__all__ = ["FORCE_TYPE", "POSE_TYPE", "JOINT_TYPE", "BAG_SUFFIXES", "BagTopic", "is_bag",
           "open_bag", "describe_topics", "read_messages", "typestore"]

#: Message types read by :func:`palpbayes.io.rosbag.read_bag`.
FORCE_TYPE = "geometry_msgs/msg/WrenchStamped"
POSE_TYPE = "geometry_msgs/msg/PoseStamped"
JOINT_TYPE = "sensor_msgs/msg/JointState"
#: Storage files of rosbag2 (MCAP, sqlite3).
BAG_SUFFIXES = (".mcap", ".db3")


@dataclass(frozen=True)
class BagTopic:
    """One topic of a bag.

    Attributes
    ----------
    topic, msgtype
        Name and ROS 2 message type.
    count
        Number of messages.
    start_s, end_s
        [s] First and last receive time (Unix time), None when not read or no messages.
    """

    topic: str
    msgtype: str
    count: int
    start_s: float | None = None
    end_s: float | None = None

    @property
    def rate_hz(self) -> float | None:
        """[Hz] Mean message rate, None with fewer than two messages or no times."""
        if self.start_s is None or self.end_s is None or self.count < 2 or \
                self.end_s <= self.start_s:
            return None
        return (self.count - 1) / (self.end_s - self.start_s)


def is_bag(path: str | os.PathLike) -> bool:
    """True for a rosbag2 folder (with ``metadata.yaml``) or a ``.mcap``/``.db3`` file."""
    path = Path(path)
    if path.is_dir():
        return (path / "metadata.yaml").is_file()
    return path.suffix.lower() in BAG_SUFFIXES


def typestore():
    """The ``rosbags`` type store of ROS 2 Humble (the standard messages read here have not
    changed since Foxy)."""
    typesys = import_extra("ros", "reading ROS 2 bags", "rosbags.typesys")
    return typesys.get_typestore(typesys.Stores.ROS2_HUMBLE)


@contextmanager
def open_bag(path: str | os.PathLike) -> Iterator:
    """An open ``rosbags.rosbag2.Reader`` for a bag folder or storage file, closed on exit.

    Raises
    ------
    DataFileError
        Missing path, a folder without ``metadata.yaml``, an unknown suffix, an unreadable or
        broken bag (the library's message is quoted).
    MissingExtraError
        ``rosbags`` is not installed.
    """
    path = Path(path)
    source = str(path)
    rosbag2 = import_extra("ros", "reading ROS 2 bags", "rosbags.rosbag2")
    if not path.exists():
        raise DataFileError(source, "bag not found", "check the path")
    if path.is_dir() and not (path / "metadata.yaml").is_file():
        files = sorted(p.name for p in path.iterdir() if p.suffix in BAG_SUFFIXES)
        raise DataFileError(source, "is a folder without metadata.yaml, so not a rosbag2 bag",
                            f"give the storage file instead: {path / files[0]}" if files else
                            "give the folder that 'ros2 bag record' wrote")
    if path.is_file() and path.suffix.lower() not in BAG_SUFFIXES:
        raise DataFileError(source, f"unknown bag storage {path.suffix!r}",
                            "give the bag folder, or its .mcap or .db3 file")
    try:
        reader = rosbag2.Reader(path)
        reader.open()
    except Exception as exc:  # ReaderError, sqlite/MCAP errors of every kind
        raise DataFileError(source, f"cannot open the bag ({type(exc).__name__}: {exc})",
                            "check that the recording finished (ros2 bag reindex repairs an "
                            "interrupted one) or give the bag folder") from None
    try:
        yield reader
    finally:
        reader.close()


def describe_topics(reader, source: str, times: bool = True) -> list[BagTopic]:
    """The topics of an open bag, in its order; with ``times`` the first and last receive time
    of each (one pass over the messages without decoding them)."""
    conns = reader.connections
    span: dict[str, list[int]] = {}
    if times:
        try:
            for conn, t, _ in reader.messages():
                s = span.setdefault(conn.topic, [t, t])
                s[0], s[1] = min(s[0], t), max(s[1], t)
        except Exception as exc:
            raise DataFileError(source, f"cannot read the messages ({type(exc).__name__}: "
                                f"{exc})", "check that the recording finished") from None
    out, seen = [], {}
    for c in conns:  # a topic split over several files has one connection per file
        if c.topic in seen:
            prev = out[seen[c.topic]]
            out[seen[c.topic]] = BagTopic(prev.topic, prev.msgtype, prev.count + c.msgcount,
                                          prev.start_s, prev.end_s)
            continue
        seen[c.topic] = len(out)
        s = span.get(c.topic)
        out.append(BagTopic(c.topic, c.msgtype, int(c.msgcount),
                            None if s is None else s[0] / 1e9, None if s is None else s[1] / 1e9))
    return out


def read_messages(reader, topics: Sequence[str], extract: dict[str, Callable],
                  source: str) -> dict[str, tuple[list[int], list[int], list]]:
    """Decode the messages of ``topics`` in one pass.

    ``extract[topic](msg)`` returns (header stamp [ns], value).  Returns, per topic, the stamps,
    the bag's receive times [ns] and the values, in file order.
    """
    store = typestore()
    conns = [c for c in reader.connections if c.topic in topics]
    out: dict[str, tuple[list[int], list[int], list]] = {t: ([], [], []) for t in topics}
    topic = "?"
    try:
        for conn, received, raw in reader.messages(connections=conns):
            topic = conn.topic
            stamp, value = extract[topic](store.deserialize_cdr(raw, conn.msgtype))
            lists = out[topic]
            lists[0].append(stamp)
            lists[1].append(received)
            lists[2].append(value)
    except DataFileError:
        raise
    except Exception as exc:  # a truncated file, a message that does not decode
        n = len(out.get(topic, ((),))[0])
        raise DataFileError(source, f"topic {topic!r}: message {n + 1} cannot be read "
                            f"({type(exc).__name__}: {exc})",
                            "check that the recording finished (ros2 bag reindex)") from None
    return out
