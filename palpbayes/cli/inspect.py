"""``palpbayes inspect PATH``: what a recording holds, before fitting it.

A ROS 2 bag: its topics with message type, count, rate and time span, and the topics ``fit``
would take.  An AFM file: its curves with modality, columns, points per segment and position.
A text table: its columns and number of rows.
"""

from __future__ import annotations

import argparse
from datetime import UTC, datetime
from pathlib import Path

from ..errors import DataFileError
from ..units import format_length

__all__ = ["register", "run"]

#: Curves of a force map listed one by one (the rest are summarised).
MAX_CURVES_SHOWN = 20


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "inspect", help="list what a recording holds (bag topics, AFM curves, CSV columns)",
        description="Show the topics of a ROS 2 bag (type, messages, rate, time span), the "
        "curves of an AFM file (segments, columns, position) or the columns of a trace table, "
        "to choose the options of 'palpbayes fit'.",
    )
    p.add_argument("path", metavar="PATH",
                   help="ROS 2 bag (folder, .mcap, .db3), AFM file or trace CSV")


def _bag(path: Path) -> None:
    from ..io.bagfile import FORCE_TYPE, JOINT_TYPE, POSE_TYPE
    from ..io.rosbag import list_topics

    topics = list_topics(path)
    starts = [t.start_s for t in topics if t.start_s is not None]
    t0 = min(starts) if starts else None
    when = ("" if t0 is None else
            f", starting {datetime.fromtimestamp(t0, UTC).isoformat(timespec='seconds')}")
    print(f"{path}: ROS 2 bag, {len(topics)} topic(s), "
          f"{sum(t.count for t in topics)} message(s){when}")
    rows = [("topic", "type", "messages", "rate", "span")]
    for t in topics:
        rate = "-" if t.rate_hz is None else f"{t.rate_hz:.4g} Hz"
        span = ("-" if t.start_s is None or t0 is None else
                f"{t.start_s - t0:.3f}..{t.end_s - t0:.3f} s")
        rows.append((t.topic, t.msgtype, str(t.count), rate, span))
    widths = [max(len(r[i]) for r in rows) for i in range(5)]
    for r in rows:
        print("  " + "  ".join(c.ljust(w) if i < 2 else c.rjust(w)
                               for i, (c, w) in enumerate(zip(r, widths, strict=True))))
    force = [t.topic for t in topics if t.msgtype == FORCE_TYPE]
    pose = [t.topic for t in topics if t.msgtype in (POSE_TYPE, JOINT_TYPE)]
    for role, found, option in (("force", force, "--force-topic"),
                                ("pose", pose, "--pose-topic")):
        if len(found) == 1:
            print(f"fit reads {role} from {found[0]} (or give {option})")
        elif found:
            print(f"{len(found)} {role} topics: choose one with {option}")
        else:
            print(f"no {role} topic palpbayes reads (force: WrenchStamped; pose: PoseStamped "
                  "or JointState)")


def _segment_counts(counts: dict[int, int], names: dict[int, str]) -> str:
    """Points per afmformats segment under their classified names, in time order, consecutive
    segments of one name joined: ``approach 256 + 2048, hold 7680, retract 1951``."""
    parts: list[tuple[str, list[int]]] = []
    for k in names or counts:
        name = names.get(k, f"segment {k}")
        if parts and parts[-1][0] == name:
            parts[-1][1].append(counts[k])
        else:
            parts.append((name, [counts[k]]))
    return ", ".join(f"{name} {' + '.join(map(str, ns))}" for name, ns in parts)


def _afm(path: Path) -> None:
    from ..io.afm import describe_afm
    from ..io.afm_workshop import is_afm_workshop_zip

    note = ""
    try:
        curves = describe_afm(path)
    except DataFileError:
        if not is_afm_workshop_zip(path):
            raise
        # the structure does not need the force's scale: read it with placeholders
        curves = describe_afm(path, {"spring constant": 1.0, "sensitivity": 1.0})
        note = ("AFM Workshop map without spring constant and sensitivity (nor a time "
                "column): give palpbayes map (or fit, replay) --spring-constant N/m "
                "--sensitivity m/V --sample-rate HZ")
    kinds = sorted({c.modality for c in curves})
    print(f"{path}: AFM file, {len(curves)} curve(s) ({', '.join(kinds)})")
    first = curves[0]
    print(f"  columns: {', '.join(first.columns)}")
    for c in curves[:MAX_CURVES_SHOWN]:
        segs = _segment_counts(c.segments, c.segment_names)
        where = ("" if c.x_m is None else
                 f"  at x = {format_length(c.x_m, 5)}, y = {format_length(c.y_m or 0.0, 5)}")
        print(f"  curve {c.index}: {segs} points{where}")
    if len(curves) > MAX_CURVES_SHOWN:
        print(f"  ... {len(curves) - MAX_CURVES_SHOWN} more")
    if len(curves) > 1:
        print("fit makes one trace per curve (a campaign); --curve I fits one of them")
    if len(curves) > 1 and all(c.x_m is not None for c in curves):
        print("map FILE --tip ... maps them (positions from the file)")
    if note:
        print(f"note: {note}")


def _table(path: Path) -> None:
    import pandas as pd

    from ..io.tabular import sniff_delimiter

    if not path.is_file():
        raise DataFileError(path, "file not found", "check the path")
    try:
        df = pd.read_csv(path, comment="#", sep=sniff_delimiter(path), skipinitialspace=True,
                         engine="python")
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as exc:
        raise DataFileError(path, f"not a readable table ({type(exc).__name__})",
                            "palpbayes reads trace CSVs, ROS 2 bags and AFM files") from None
    print(f"{path}: table, {len(df)} row(s), columns: {', '.join(map(str, df.columns))}")


def run(args: argparse.Namespace) -> int:
    from ..io.recording import recording_kind

    path = Path(args.path)
    if not path.exists():
        raise DataFileError(path, "not found", "check the path")
    {"bag": _bag, "afm": _afm, "table": _table}[recording_kind(path)](path)
    return 0
