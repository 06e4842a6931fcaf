"""``palpbayes inspect PATH``: what a recording holds, before fitting it.

A ROS 2 bag: its topics with message type, count, rate and time span, and the topics ``fit``
would take.  An AFM file: its curves with modality, columns, points per segment and position,
the calibration and approach settings the file records, and a ``palpbayes fit`` command for
it with the tip left to fill in (no AFM file records the tip).  A text table: its columns and
number of rows, and a ``palpbayes fit`` command with the column and unit options its header
tells (a robot log's ``timestamp, tcp_z_mm, fz``: ``--time-column timestamp --z-column
tcp_z_mm --z-unit mm --force-column fz``), ``--force-sign -1`` when the data press with a
negative force, and the tip to fill in; a campaign manifest, the command that fits it.
"""

# Long module: one job, the inspect command; one short printer per recording format.

from __future__ import annotations

import argparse
import math
import shlex
from collections.abc import Callable, Sequence
from datetime import UTC, datetime
from pathlib import Path

from ..errors import DataFileError
from ..units import LENGTH_PREFIXES, format_force, format_length, format_si

__all__ = ["register", "run", "fit_command", "RADIUS_PLACEHOLDER", "HEADER_DURATIONS",
           "COLUMN_PLACEHOLDERS"]

#: Curves of a force map listed one by one (the rest are summarised).
MAX_CURVES_SHOWN = 20

#: A position [m] smaller than this is shown as 0: far below an AFM stage's resolution, it is
#: the rounding residue of a stage at its origin (a JPK header's ``-1.434313216631226E-15``),
#: which :func:`~palpbayes.units.format_length` would write as ``-0.0014343 pm``.
POSITION_RESOLUTION_M = 1e-9

#: What the printed ``fit`` command has in place of the tip radius, for the user to fill in.
RADIUS_PLACEHOLDER = "R"

#: The header's durations (afmformats metadata), shown only for a curve without a time column
#: to measure them on.
HEADER_DURATIONS = ("duration approach", "duration intermediate")

#: Prefixes of a sampling rate: Hz, kHz, MHz.
RATE_PREFIXES: dict[int, str] = {0: "", 3: "k", 6: "M"}

#: How :func:`_calibration_lines` writes each of :data:`palpbayes.io.afm.CALIBRATION_KEYS`
#: (label, formatter of the SI value).
_CALIBRATION_FORMAT: dict[str, tuple[str, Callable[[float], str]]] = {
    "spring constant": ("spring constant", lambda v: f"{v:.4g} N/m"),
    "sensitivity": ("deflection sensitivity", lambda v: format_si(v, "m/V", LENGTH_PREFIXES, 4)),
    "setpoint": ("setpoint", lambda v: format_force(v, 4)),
    "speed approach": ("speed", lambda v: format_si(v, "m/s", LENGTH_PREFIXES, 4)),
    "rate approach": ("sampled at", lambda v: format_si(v, "Hz", RATE_PREFIXES, 4)),
    "duration approach": ("duration", lambda v: f"{v:.4g} s"),
    "duration intermediate": ("hold", lambda v: f"{v:.4g} s"),
}


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


def _segment_counts(counts: dict[int, int], names: dict[int, str],
                    durations: dict[int, float] | None = None) -> str:
    """Points per afmformats segment under their classified names, in time order, consecutive
    segments of one name joined, with their durations [s] when measured:
    ``approach 256 + 2048 points (1 + 1 s), hold 7680 (30 s), retract 1951 (0.9526 s)``, or
    without: ``approach 256 + 2048, hold 7680, retract 1951 points``."""
    parts: list[tuple[str, list[int]]] = []
    for k in names or counts:
        name = names.get(k, f"segment {k}")
        if parts and parts[-1][0] == name:
            parts[-1][1].append(k)
        else:
            parts.append((name, [k]))
    if not durations:
        return ", ".join(f"{name} {' + '.join(str(counts[k]) for k in ks)}"
                         for name, ks in parts) + " points"
    return ", ".join(
        f"{name} {' + '.join(str(counts[k]) for k in ks)}{' points' if i == 0 else ''} "
        f"({' + '.join(f'{durations[k]:.4g}' for k in ks)} s)"
        for i, (name, ks) in enumerate(parts))


def _position(x_m: float) -> str:
    """A curve's position [m] to 5 digits, 0 below :data:`POSITION_RESOLUTION_M`."""
    return format_length(0.0 if abs(x_m) < POSITION_RESOLUTION_M else x_m, 5)


def _value_range(values: Sequence[float], fmt: Callable[[float], str]) -> str:
    """``fmt`` of the one value the curves share, else ``'fmt(min) to fmt(max)'``."""
    lo, hi = min(values), max(values)
    if math.isclose(lo, hi, rel_tol=1e-9, abs_tol=0.0):
        return fmt(lo)
    return f"{fmt(lo)} to {fmt(hi)}"


def _calibration_lines(calibration: Sequence[dict[str, float]],
                       measured: bool = False) -> list[str]:
    """The calibration and approach settings of the curves, as ``inspect`` prints them.

    Parameters
    ----------
    calibration
        Per curve, afmformats metadata in SI units
        (:func:`palpbayes.io.afm.afm_calibration`).
    measured
        The segments' durations were measured on the time column (and shown with the
        curves): the header's durations (:data:`HEADER_DURATIONS`) are left out.  A JPK
        stress-relaxation file that holds 30 s has ``duration intermediate`` 1 s.

    Returns
    -------
    list of str
        ``calibration: ...`` (spring constant, deflection sensitivity) and ``approach: ...``
        (setpoint, speed, sampling rate, and unless ``measured`` the header's duration and
        hold), each left out when the file records none of its values; a value that differs
        between curves is given as a range.
    """
    shown = {}
    for key, (label, fmt) in _CALIBRATION_FORMAT.items():
        if measured and key in HEADER_DURATIONS:
            continue
        values = [c[key] for c in calibration if key in c]
        if values:
            shown[key] = f"{label} {_value_range(values, fmt)}"
    lines = []
    for title, keys in (("calibration", ("spring constant", "sensitivity")),
                        ("approach", ("setpoint", "speed approach", "rate approach",
                                      "duration approach", "duration intermediate"))):
        parts = [shown[k] for k in keys if k in shown]
        if parts:
            lines.append(f"{title}: {', '.join(parts)}")
    return lines


def _stem(path: Path) -> str:
    """The file name without its AFM suffix (``.jpk-force-map``, ``.zip`` ...)."""
    from ..io.afm_load import AFM_SUFFIXES

    name = path.name
    suffix = next((s for s in sorted(AFM_SUFFIXES, key=len, reverse=True)
                   if name.lower().endswith(s)), path.suffix)
    return name[: len(name) - len(suffix)] or name


def fit_command(path: str | Path, n_curves: int, *, uncalibrated: bool = False,
                command: str = "fit") -> str:
    """The ``palpbayes fit`` (or ``map``) command ``inspect`` prints for an AFM file.

    Parameters
    ----------
    path
        The AFM file, as the user named it.
    n_curves
        Its number of curves: a force map's ``fit`` command fits curve 0 (``--curve 0``).
    uncalibrated
        True for a file without spring constant and sensitivity (AFM Workshop): the command
        then has ``--spring-constant K --sensitivity S --sample-rate HZ`` to fill in too (it
        has no time column either).
    command
        ``"fit"`` or ``"map"`` (every curve of a force map, positions from the file).

    Returns
    -------
    str
        A shell command line, e.g. ``palpbayes fit spot.jpk-force --out spot-fit --tip
        paraboloid --radius R --nu 0.5``, where :data:`RADIUS_PLACEHOLDER` stands for the tip
        radius [m] the user must give.
    """
    path = Path(path)
    stem = _stem(path)
    words = ["palpbayes", command, str(path)]
    if command == "fit" and n_curves > 1:
        words += ["--curve", "0"]
        stem += "-curve0"
    words += ["--out", f"{stem}-{command}", "--tip", "paraboloid", "--radius",
              RADIUS_PLACEHOLDER, "--nu", "0.5"]
    if uncalibrated:
        words += ["--spring-constant", "K", "--sensitivity", "S", "--sample-rate", "HZ"]
    return " ".join(w if w in (RADIUS_PLACEHOLDER, "K", "S", "HZ") else shlex.quote(w)
                    for w in words)


def _fit_lines(path: Path, curves: Sequence, uncalibrated: bool) -> list[str]:
    """What ``inspect`` prints after an AFM file's curves: the ``fit`` (and, for a map with
    positions, ``map``) command to run, with what to fill in and when to add options."""
    many = len(curves) > 1
    fill = (f"replace {RADIUS_PLACEHOLDER} by the tip radius in metres (e.g. 5e-6), or give "
            "another --tip with its size (sphere --radius, cone --half-angle); --nu 0.5 is "
            "for cells and gels")
    if uncalibrated:
        fill += ("; K, S and HZ: the spring constant [N/m], deflection sensitivity [m/V] and "
                 "sample rate [Hz]")
    lines = [f"to fit {'curve 0' if many else 'it'} (no AFM file records the tip: {fill}):",
             "  " + fit_command(path, len(curves), uncalibrated=uncalibrated)]
    if many and all(c.x_m is not None for c in curves):
        lines += ["to map every curve (positions from the file):",
                  "  " + fit_command(path, len(curves), uncalibrated=uncalibrated,
                                     command="map")]
    lines.append("the tip's contact law holds to a depth of about its radius: if fit says "
                 "the indentation is deeper, add --max-depth M (e.g. the radius) to fit the "
                 "shallower part")
    if any(c.modality != "force-distance" for c in curves):
        lines.append("fit takes the approach; --rheology power-law,sls fits the hold too")
    return lines


def _afm(path: Path) -> None:
    from ..io.afm import afm_calibration, describe_afm
    from ..io.afm_workshop import is_afm_workshop_zip

    note, override = "", None
    try:
        curves = describe_afm(path)
    except DataFileError:
        if not is_afm_workshop_zip(path):
            raise
        # the structure does not need the force's scale: read it with placeholders
        override = {"spring constant": 1.0, "sensitivity": 1.0}
        curves = describe_afm(path, override)
        note = ("AFM Workshop map without spring constant and sensitivity (nor a time "
                "column): give palpbayes map (or fit, replay) --spring-constant N/m "
                "--sensitivity m/V --sample-rate HZ")
    kinds = sorted({c.modality for c in curves})
    print(f"{path}: AFM file, {len(curves)} curve(s) ({', '.join(kinds)})")
    first = curves[0]
    print(f"  columns: {', '.join(first.columns)}")
    for c in curves[:MAX_CURVES_SHOWN]:
        segs = _segment_counts(c.segments, c.segment_names, c.durations)
        where = ("" if c.x_m is None else
                 f"  at x = {_position(c.x_m)}, y = {_position(c.y_m or 0.0)}")
        print(f"  curve {c.index}: {segs}{where}")
    if len(curves) > MAX_CURVES_SHOWN:
        print(f"  ... {len(curves) - MAX_CURVES_SHOWN} more")
    measured = all(c.durations for c in curves)
    if measured:
        print("  durations measured on the time column (the file's header is not read for "
              "them)")
    calibration = _calibration_lines(afm_calibration(path, override), measured)
    for line in calibration:
        print(f"  {line}")
    if override is not None:
        print("  calibration: none recorded (no spring constant nor deflection sensitivity)")
    if len(curves) > 1:
        print("fit makes one trace per curve (a campaign); --curve I fits one of them")
    if len(curves) > 1 and all(c.x_m is not None for c in curves):
        print("map FILE --tip ... maps them (positions from the file)")
    for line in _fit_lines(path, curves, uncalibrated=override is not None):
        print(line)
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
    from ..io.manifest import is_manifest

    if is_manifest(path):
        print("a campaign manifest (its rows name the traces and their tips); to fit them:")
        print(f"  palpbayes fit {shlex.quote(str(path))} --out "
              f"{shlex.quote(path.parent.name or path.stem)}-fit")
        return
    for line in _table_fit_lines(path, df):
        print(line)


def _rtde(path: Path) -> None:
    from ..io.rtde import default_z_source, read_rtde

    source = default_z_source(path)
    trace = read_rtde(path, check=False, z_source=source)
    meta = trace.metadata
    z = ("the joints (actual_q, UR3e kinematics, plus --tool-offset)" if source == "q" else
         "the TCP pose (actual_TCP_pose_2: the TCP configured on the robot)")
    print(f"{path}: a UR RTDE log, {trace.n_points} samples over {trace.time[-1]:.4g} s; "
          f"z from {z}, force {meta.get('force_column')} x {meta.get('force_sign'):+g} (the "
          "sign that makes it grow as the tip goes down)")
    print(f"  z {1e3 * trace.z.min():.4g}..{1e3 * trace.z.max():.4g} mm, force "
          f"{format_force(float(trace.force.min()))}..{format_force(float(trace.force.max()))}")
    offset = " --tool-offset M" if source == "q" else ""
    print("to fit it (give the tip" + (", and the sensor + tip length along the flange"
                                        if offset else "") + "):")
    print(f"  palpbayes fit {shlex.quote(str(path))} --out {shlex.quote(_stem(path))}-fit "
          f"--tip sphere --radius R{offset}")


#: Placeholders of the columns a table's header does not name, per quantity.
COLUMN_PLACEHOLDERS = {"time": "TIME", "z": "Z", "force": "FORCE"}
_DEFAULT_UNITS = {"time": "s", "z": "m", "force": "N"}


def _trial_read(df, source: str, options: dict) -> tuple[float, str]:
    """(force sign, problem) of reading the table ``df`` with ``options`` as ``fit`` would:
    (1, '') when it reads, (-1, '') when it reads with the force's sign flipped only (its
    force falls as the tip goes down), else (1, the reader's problem)."""
    from ..errors import InputError
    from ..io.trace_csv import trace_from_frame

    try:
        trace_from_frame(df, source, **options)
        return 1.0, ""
    except InputError as exc:
        problem = getattr(exc, "problem", str(exc))
        fix = getattr(exc, "fix", "")
    try:
        trace_from_frame(df, source, force_sign=-1.0, **options)
        return -1.0, ""
    except InputError:
        return 1.0, problem + (f" ({fix})" if fix else "")


def _table_fit_lines(path: Path, df) -> list[str]:
    """What ``inspect`` prints after a trace table's columns: a ``fit`` command with the column
    and unit options the header tells (:func:`~palpbayes.io.trace_csv.suggest_read_options`),
    ``--force-sign -1`` when the data press with a negative force, and what to fill in."""
    from ..io.trace_csv import suggest_read_options

    options, unfound = suggest_read_options(df.columns)
    columns, units = options.get("columns", {}), options.get("units", {})
    words = ["palpbayes", "fit", str(path), "--out", f"{path.stem}-fit"]
    for q in ("time", "z", "force"):
        if q in columns:
            words += [f"--{q}-column", columns[q]]
        elif q in unfound:
            words += [f"--{q}-column", COLUMN_PLACEHOLDERS[q]]
        if q in units:
            words += [f"--{q}-unit", units[q]]
    sign, problem = (1.0, "") if unfound or df.empty else _trial_read(df, str(path), options)
    if sign < 0:
        words += ["--force-sign", "-1"]
    words += ["--tip", "sphere", "--radius", RADIUS_PLACEHOLDER]
    keep = {RADIUS_PLACEHOLDER, *COLUMN_PLACEHOLDERS.values()}
    lines = [f"to fit it (a table does not record the tip: replace {RADIUS_PLACEHOLDER} by the "
             "tip radius in metres (e.g. 0.01), or give another --tip with its size (paraboloid "
             "--radius, cone --half-angle); add --nu: foams 0.1-0.3, silicone, gels and tissue "
             "0.45-0.5, else 0.3):",
             "  " + " ".join(w if w in keep else shlex.quote(w) for w in words)]
    bare = [q for q in columns if q not in units]
    if bare:
        lines.append(f"{', '.join(columns[q] for q in bare)}: no unit in the name, read in "
                     f"{', '.join(_DEFAULT_UNITS[q] for q in bare)} (else "
                     f"{', '.join(f'--{q}-unit' for q in bare)})")
    if unfound:
        lines.append(f"{', '.join(COLUMN_PLACEHOLDERS[q] for q in unfound)}: the column(s) "
                     f"holding {', '.join(unfound)} (the header names none palpbayes knows), "
                     f"with {', '.join(f'--{q}-unit' for q in unfound)} when not in "
                     f"{', '.join(_DEFAULT_UNITS[q] for q in unfound)}")
    if sign < 0:
        lines.append("--force-sign -1: the force falls below its pre-contact level as the tip "
                     "goes down (the sensor reads pressing as negative)")
    if problem:
        lines.append(f"note: read so, the file is refused: {problem}")
    return lines


def run(args: argparse.Namespace) -> int:
    from ..io.recording import recording_kind

    path = Path(args.path)
    if not path.exists():
        raise DataFileError(path, "not found", "check the path")
    {"bag": _bag, "afm": _afm, "rtde": _rtde, "table": _table}[recording_kind(path)](path)
    return 0
