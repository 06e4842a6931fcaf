"""Read and write indentation traces as CSV (docs/design.md §5).

The canonical file has the columns ``time_s, z_m, force_n`` (SI, z up, force positive when
pressing) or, instead of ``z_m``, the joint angles ``q0_rad … q5_rad`` from which z follows by
forward kinematics.  Other files are read through a column mapping, unit and sign options::

    read_trace("run.csv", columns={"time": "t", "z": "Z", "force": "Fz"},
               units={"z": "mm", "force": "mN"}, force_sign=-1)

An optional column ``segment`` says which segment of the cycle each row belongs to: the names
``approach``, ``hold``, ``retract`` (any case) or the codes 0, 1, 2, non-decreasing in time; it
becomes :attr:`~palpbayes.trace.IndentationTrace.segment`, and :func:`write_trace` writes it
(as names) when the trace has segments.

Columns named ``<quantity>_<unit>`` (``z_mm``, ``force_mn``, ``time_ms``; AFM ``z_um``, ``z_nm``,
``force_nn``, ``force_pn``) are recognised without options, case-insensitively (``force_mn``
is millinewtons: no one records in meganewtons).  The separator (comma, semicolon, tab or
blanks) is detected from the header line; decimal commas are not read but reported as such.
Every problem is raised as :class:`~palpbayes.errors.DataFileError` naming the file, the column or
value, and the fix.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pandas as pd

from ..contact import Tip
from ..errors import DataFileError, InputError
from ..trace import SEGMENTS, IndentationTrace
from .atomic import write_text_atomic
from .joint_trace import trace_from_joint_frame
from .tabular import (
    MAX_FORCE_N,
    MAX_Z_SPAN_M,
    check_file,
    check_plausible,
    numeric_column,
    sniff_delimiter,
)
from .units import FORCE_UNITS, LENGTH_UNITS, TIME_UNITS, force_factor, length_factor, time_factor

__all__ = ["read_trace", "read_frame", "write_trace", "trace_from_frame", "check_plausible",
           "sniff_delimiter", "MAX_Z_SPAN_M", "MAX_FORCE_N", "ROBOT_LOG_NAMES",
           "robot_log_column", "column_hint", "suggest_read_options"]

_QUANTITIES = {"time": TIME_UNITS, "z": LENGTH_UNITS, "force": FORCE_UNITS}
_FACTORS = {"time": time_factor, "z": length_factor, "force": force_factor}
#: Name of the optional segment column (matched case-insensitively).
SEGMENT_COLUMN = "segment"


def _segment_column(df: pd.DataFrame, source: str) -> np.ndarray | None:
    """The ``segment`` column as names or codes for :class:`IndentationTrace` (which checks
    them and names the data row of a bad one), or None when the file has no such column.

    Code strings ("0", "1", "2") in a column of names are read as codes; an empty cell is an
    error naming its data row.
    """
    col = next((c for c in df.columns if str(c).strip().lower() == SEGMENT_COLUMN), None)
    if col is None:
        return None
    raw = df[col]
    empty = raw.isna().to_numpy()
    if empty.any():
        i = int(np.argmax(empty))
        raise DataFileError(source, f"column {str(col)!r} is empty at data row {i + 1}",
                            f"give every row a segment ({', '.join(SEGMENTS)}) or drop the "
                            "column")
    if raw.dtype.kind in "iuf":  # codes: IndentationTrace checks them
        return raw.to_numpy()
    text = raw.astype(str).str.strip().str.lower()
    codes = {str(c): name for c, name in enumerate(SEGMENTS)}
    return text.map(lambda v: codes.get(v, v)).to_numpy(dtype=object)


#: Column names of common robot logs, per quantity (lower case): a file that has one of them
#: instead of the canonical name, alone or with a unit suffix (``tcp_z_mm``), gets the options
#: that map it in its error message (the mapping is not silent: sign and unit conventions
#: differ between loggers).
ROBOT_LOG_NAMES = {
    "time": ("timestamp", "t", "time", "stamp", "header.stamp", "elapsed_s"),
    "z": ("actual_tcp_pose_2", "tcp_z", "pose_z", "z_tcp", "position_z", "tool_z"),
    "force": ("fz", "force_z", "actual_tcp_force_2", "ft_fz", "wrench.force.z", "tcp_fz"),
}


def robot_log_column(names, quantity: str) -> tuple[str, str | None] | None:
    """The column of a common robot log among ``names`` that holds ``quantity`` (``time``,
    ``z`` or ``force``), and its unit when the name ends with one: ``timestamp`` -> (
    ``timestamp``, None), ``tcp_z_mm`` -> (``tcp_z_mm``, ``mm``); matched case-insensitively
    (:data:`ROBOT_LOG_NAMES`); None when there is none."""
    lower = {str(c).strip().lower(): str(c) for c in names}
    for name in ROBOT_LOG_NAMES[quantity]:
        if name in lower:
            return lower[name], None
        for u in _QUANTITIES[quantity]:
            if f"{name}_{u}".lower() in lower:
                return lower[f"{name}_{u}".lower()], u
    return None


def column_hint(names, quantity: str, wanted: str, given: bool) -> str:
    """What to add to "missing column ``wanted`` (for ``quantity``)" when the columns are
    ``names``: the column that differs from it in case (or surrounding blanks) only, else,
    unless the user ``given`` the name, a robot log's column (:func:`robot_log_column`) with
    the options that map it; '' when neither.

    Examples: ``" (the header's 'Fz' differs from it in case only: --force-column Fz)"``,
    ``" (a robot log's 'tcp_z_mm'? map it with --z-column tcp_z_mm --z-unit mm, and check
    its sign)"``.
    """
    key = wanted.strip().lower()
    same = next((str(c) for c in names if str(c).strip().lower() == key and str(c) != wanted),
                None)
    if same is not None:
        return (f" (the header's {same!r} differs from it in case only: --{quantity}-column "
                f"{same})")
    found = None if given else robot_log_column(names, quantity)
    if found is None:
        return ""
    col, unit = found
    option = f"--{quantity}-column {col}" + (f" --{quantity}-unit {unit}" if unit else "")
    check = "its sign" if unit else "its unit and sign"
    return f" (a robot log's {col!r}? map it with {option}, and check {check})"


def _find_column(df: pd.DataFrame, quantity: str, explicit: str | None, unit: str | None
                 ) -> tuple[str, str] | str:
    """(column name, unit) for ``quantity`` ('time', 'z' or 'force'), or the problem as text
    (:func:`_find_columns` reports every problem of a file at once)."""
    if explicit is not None:
        if explicit not in df.columns:
            return (f"column {explicit!r} (given for {quantity}) is missing"
                    f"{column_hint(df.columns, quantity, explicit, given=True)}")
        return explicit, unit or ("s" if quantity == "time" else "m" if quantity == "z" else "N")
    lower = {str(c).strip().lower(): c for c in df.columns}
    for u in _QUANTITIES[quantity]:
        name = f"{quantity}_{u}".lower()
        if name in lower:
            return lower[name], unit or u
    if quantity in lower:
        return lower[quantity], unit or ("s" if quantity == "time" else
                                         "m" if quantity == "z" else "N")
    canon = {"time": "time_s", "z": "z_m", "force": "force_n"}[quantity]
    return (f"missing column '{canon}' (for {quantity})"
            f"{column_hint(df.columns, quantity, canon, given=False)}")


def suggest_read_options(names) -> tuple[dict[str, dict[str, str]], list[str]]:
    """The reader options that read a table whose header is ``names``, as far as the header
    tells them (``palpbayes inspect`` prints them as ``--*-column`` and ``--*-unit``).

    A quantity the reader finds without options (``time_s``, ``z_mm`` ..., any case; z of a
    table of joint angles) needs none; one held by a robot log's column
    (:func:`robot_log_column`: ``timestamp``, ``tcp_z_mm``, ``fz`` ...) gets its column and,
    when the name ends with one, its unit.  Signs are not in a header.

    Returns
    -------
    options, unfound
        ``{"columns": {...}, "units": {...}}`` (each only when needed), and the quantities
        (``time``, ``z``, ``force``) the header does not tell.
    """
    frame = pd.DataFrame(columns=[str(c) for c in names])
    lower = {str(c).strip().lower() for c in names}
    joints = not any(c.startswith("z") for c in lower) and any(c.startswith("q0_") for c in lower)
    columns, units, unfound = {}, {}, []
    for q in ("time", "z", "force"):
        if (q == "z" and joints) or not isinstance(_find_column(frame, q, None, None), str):
            continue
        found = robot_log_column(names, q)
        if found is None:
            unfound.append(q)
            continue
        columns[q] = found[0]
        if found[1] is not None:
            units[q] = found[1]
    options = {k: v for k, v in (("columns", columns), ("units", units)) if v}
    return options, unfound


def _find_columns(df: pd.DataFrame, columns: dict[str, str], units: dict[str, str],
                  source: str) -> dict[str, tuple[str, str]]:
    """(column, unit) of time, z and force; every missing one named in one error."""
    found = {q: _find_column(df, q, columns.get(q), units.get(q)) for q in ("time", "z", "force")}
    problems = [v for v in found.values() if isinstance(v, str)]
    if problems:
        raise DataFileError(
            source,
            f"{'; '.join(problems)}; the file has "
            f"{', '.join(map(str, df.columns)) or 'no columns'}",
            "rename the columns to time_s, z_m, force_n or map them with --time-column, "
            "--z-column, --force-column (and --time-unit, --z-unit, --force-unit, "
            "--force-sign, --z-sign)",
        )
    return found


def trace_from_frame(
    df: pd.DataFrame,
    source: str,
    *,
    columns: dict[str, str] | None = None,
    units: dict[str, str] | None = None,
    force_sign: float = 1.0,
    z_sign: float = 1.0,
    check: bool = True,
    tool_offset: float = 0.0,
    **metadata,
) -> IndentationTrace:
    """Build a trace from a parsed table; see :func:`read_trace` for the options.

    A ``segment`` column (names or codes) becomes the trace's ``segment`` unless ``segment``
    is given in ``metadata``.
    """
    columns = dict(columns or {})
    units = dict(units or {})
    unknown = set(columns) | set(units)
    unknown -= {"time", "z", "force"}
    if unknown:
        raise InputError(f"unknown quantity {sorted(unknown)}; use time, z and force")
    if force_sign not in (1, -1, 1.0, -1.0) or z_sign not in (1, -1, 1.0, -1.0):
        raise InputError("force_sign and z_sign must be +1 or -1")
    if df.shape[0] == 0:
        raise DataFileError(source, "no data rows (header only or empty)",
                            "check that the recording was saved")
    if "segment" not in metadata:
        segment = _segment_column(df, source)
        if segment is not None:
            metadata["segment"] = segment
    lower = {str(c).strip().lower() for c in df.columns}
    has_q = any(c.startswith("q0_") for c in lower)
    if "z" not in columns and not any(c.startswith("z") for c in lower) and has_q:
        joint_units = {k: v for k, v in units.items() if k in ("time", "force")}
        return trace_from_joint_frame(df, source, tool_offset=tool_offset,
                                      units=joint_units or None, force_sign=force_sign,
                                      check=check, **metadata)
    arrays = {}
    for q, (col, unit) in _find_columns(df, columns, units, source).items():
        try:
            factor = _FACTORS[q](unit)
        except InputError as exc:
            raise DataFileError(source, f"column {col!r}: {exc}") from None
        arrays[q] = numeric_column(df, col, source) * factor
    trace = IndentationTrace(
        time=arrays["time"],
        z=z_sign * arrays["z"],
        force=force_sign * arrays["force"],
        source=source,
        **metadata,
    )
    if check:
        check_plausible(trace)
    return trace


def read_trace(
    path: str | os.PathLike,
    *,
    columns: dict[str, str] | None = None,
    units: dict[str, str] | None = None,
    force_sign: float = 1.0,
    z_sign: float = 1.0,
    tip: Tip | None = None,
    check: bool = True,
    delimiter: str | None = "auto",
    **metadata,
) -> IndentationTrace:
    """Read one trace CSV into an :class:`~palpbayes.trace.IndentationTrace` (SI units).

    Parameters
    ----------
    path
        CSV file; lines starting with ``#`` are comments.  Besides time, z (or joint angles)
        and force it may have a ``segment`` column: approach/hold/retract or 0/1/2 per row.
    columns
        Mapping from quantity (``time``, ``z``, ``force``) to the file's column name.
    units
        Mapping from quantity to unit: time s/ms/min, z m/cm/mm/um (µm)/nm/pm, force
        N/kN/mN/uN (µN)/nN/pN.
    force_sign, z_sign
        +1 or -1: multiply force (to make pressing positive) or z (to make up positive).
    tip
        The indenter, stored in the trace.
    check
        Apply :func:`check_plausible` (units and sign sanity).
    delimiter
        Column separator; ``"auto"`` (default) detects comma, semicolon, tab or blanks from the
        header line (:func:`~palpbayes.io.tabular.sniff_delimiter`); None lets pandas sniff it
        (slower).
    **metadata
        Stored on the trace (``trace_id``, ``specimen``, ``material``, ``thickness`` ...).

    Raises
    ------
    DataFileError
        Missing file or column, a folder instead of a file, non-numeric or non-finite cell,
        decimal commas, empty file, time not strictly increasing, implausible units or flipped
        sign, a ``segment`` cell that is empty, not a segment, or goes back in the cycle (the
        message names its data row).  The message names the file.
    """
    path = Path(path)
    source = str(path)
    if path.is_dir():
        manifest = path / "manifest.csv"
        raise DataFileError(source, "is a folder, not a trace file",
                            f"did you mean {manifest}?" if manifest.is_file()
                            else "give the path of a trace CSV")
    check_file(path, source)
    df, delimiter = read_frame(path, delimiter)
    if not isinstance(df.index, pd.RangeIndex):  # rows longer than the header became an index
        raise DataFileError(
            source, f"the data rows have {df.index.nlevels} more field(s) than the header "
            f"({len(df.columns)} columns){_extra_fields_hint(delimiter)}",
            "write decimal points, or repair the header",
        )
    metadata.setdefault("trace_id", path.stem)
    return trace_from_frame(df, source, columns=columns, units=units, force_sign=force_sign,
                            z_sign=z_sign, check=check, tip=tip, **metadata)


def read_frame(path: Path, delimiter: str | None = "auto", nrows: int | None = None
               ) -> tuple[pd.DataFrame, str | None]:
    """The delimited table of a trace file as :func:`read_trace` reads it (``#`` comments,
    blanks after separators; ``nrows=0``: the header alone), and the delimiter used.

    Raises
    ------
    DataFileError
        An empty or unparsable file, naming it.
    """
    source = str(path)
    try:
        if delimiter == "auto":
            delimiter = sniff_delimiter(path)
        df = pd.read_csv(path, comment="#", sep=delimiter, nrows=nrows,
                         engine="c" if delimiter else "python", skipinitialspace=True)
    except pd.errors.EmptyDataError:
        raise DataFileError(source, "file is empty", "check that the recording was saved") from None
    except (pd.errors.ParserError, UnicodeDecodeError) as exc:
        raise DataFileError(source, f"not a readable CSV ({exc})".replace("\n", " ")
                            + _extra_fields_hint(delimiter)) from None
    return df, delimiter


def _extra_fields_hint(delimiter: str | None) -> str:
    if delimiter == ",":
        return ("; decimal commas in a comma-separated file? '0,5' reads as two fields")
    return ""


def write_trace(trace: IndentationTrace, path: str | os.PathLike, *,
                float_format: str = "%.10g") -> Path:
    """Write the canonical CSV ``time_s, z_m, force_n`` atomically; return the path.

    A trace with segments (:attr:`~palpbayes.trace.IndentationTrace.segment` not None) gets a
    fourth column ``segment`` holding their names (approach, hold, retract).

    ``float_format`` "%.10g" keeps z to 1e-10 m and force to 10 significant digits; use
    "%.17g" for a bit-exact round trip.
    """
    cols = [trace.time, trace.z, trace.force]
    header, fmt = "time_s,z_m,force_n", [float_format] * 3
    if trace.segment is not None:
        cols.append(np.asarray(SEGMENTS, dtype=object)[trace.segment])
        header, fmt = header + f",{SEGMENT_COLUMN}", fmt + ["%s"]
    # one %-format of the whole table (a trace's samples are finite): the bytes pandas'
    # to_csv wrote, without its value-by-value formatter (~45 ms of a 2,400-sample trace's 50)
    rows = np.column_stack([np.asarray(c, dtype=object) for c in cols]).ravel().tolist()
    text = ((",".join(fmt) + "\n") * trace.n_points) % tuple(rows)
    return write_text_atomic(f"{header}\n{text}", path)
