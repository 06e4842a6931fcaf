"""What every text-table reader shares: the separator sniffer, reading a table, numeric
columns, trace metadata and force-sign options, sanity checks.

Lower than :mod:`palpbayes.io.trace_csv`, :mod:`palpbayes.io.rtde` and
:mod:`palpbayes.io.joint_trace` (all import from here, so they do not import each other for
these).  Every problem is raised as
:class:`~palpbayes.errors.DataFileError` naming the file, the column or value, and the fix.
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import fields
from pathlib import Path

import numpy as np
import pandas as pd

from ..baseline import sign_flipped
from ..errors import DataFileError, InputError
from ..trace import IndentationTrace
from ..units import format_force, format_length

__all__ = ["SEPARATORS", "WHITESPACE", "sniff_delimiter", "is_decimal_comma", "numeric_column",
           "check_force_sign", "check_plausible", "parse_bool", "MAX_Z_SPAN_M", "MAX_FORCE_N",
           "check_file", "read_table", "split_trace_metadata", "validate_force_sign",
           "auto_force_sign"]

#: Plausibility limits: a palpation moves the tip by less than this [m] ...
MAX_Z_SPAN_M = 0.5
#: ... and presses with less than this [N] (soft materials; pass ``check=False`` to skip).
MAX_FORCE_N = 500.0

#: Single-character column separators a header line is searched for, with their names.
SEPARATORS = {",": "comma", ";": "semicolon", "\t": "tab"}
#: pandas separator for runs of blanks (the RTDE client library's ``record.py`` output).
WHITESPACE = r"\s+"

_DECIMAL_COMMA = re.compile(r"^\s*[-+]?\d*,\d+(?:[eE][-+]?\d+)?\s*$")
_TRACE_FIELDS = {f.name for f in fields(IndentationTrace)} - {"time", "z", "force", "source"}


def _header_line(path: Path) -> str:
    """First line that is neither empty nor a ``#`` comment ('' if none)."""
    with open(path, encoding="utf-8", newline="") as fh:
        for i, line in enumerate(fh):
            if line.strip() and not line.lstrip().startswith("#"):
                return line.rstrip("\r\n")
            if i > 10_000:
                break
    return ""


def sniff_delimiter(path: str | os.PathLike) -> str:
    """The column separator of a CSV file from its header line: ``','``, ``';'``, tab or blanks.

    The most frequent of comma, semicolon and tab in the header wins (comma on a tie).  A header
    with none of them but blanks between names gives :data:`WHITESPACE` (``r"\\s+"``, e.g. the
    RTDE ``record.py`` output); a one-column header gives ``','``.  Unreadable files give
    ``','`` (the reader then reports them).

    Raises
    ------
    UnicodeDecodeError
        The file does not start as UTF-8 text (a binary file); readers report it.
    """
    try:
        header = _header_line(Path(path))
    except OSError:
        return ","
    counts = {sep: header.count(sep) for sep in SEPARATORS}
    best = max(counts, key=lambda sep: (counts[sep], sep == ","))
    if counts[best] > 0:
        return best
    return WHITESPACE if len(header.split()) > 1 else ","


def is_decimal_comma(value) -> bool:
    """True for a string cell like ``'0,5'`` (a number written with a decimal comma)."""
    return isinstance(value, str) and bool(_DECIMAL_COMMA.match(value))


def parse_bool(value) -> bool:
    """A boolean cell of a CSV (or a value read from one): ``True``, ``"true"``/``"True"``,
    ``"1"``, ``"1.0"``, a non-zero number are true; ``False``, ``"false"``, ``"0"``, an empty
    cell, None and NaN are false."""
    if isinstance(value, str):
        return value.strip().lower() in ("true", "1", "1.0")
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return False
    return bool(value)


def numeric_column(df: pd.DataFrame, col: str, source: str) -> np.ndarray:
    """Float values of one column; a non-numeric (decimal comma named as such), NaN or infinite
    cell raises :class:`DataFileError` naming the column and the data row."""
    raw = df[col]
    values = pd.to_numeric(raw, errors="coerce")
    bad = values.isna() & raw.notna()
    if bad.any():
        i = int(np.argmax(bad.to_numpy()))
        value = raw.iloc[i]
        if is_decimal_comma(value):
            raise DataFileError(
                source,
                f"column {col!r} has a non-numeric value {value!r} at data row {i + 1}: the "
                "file uses decimal commas",
                "write decimal points, e.g. save it from a spreadsheet set to an English locale",
            )
        raise DataFileError(
            source,
            f"column {col!r} has a non-numeric value {value!r} at data row {i + 1}",
            "remove or repair that row",
        )
    arr = values.to_numpy(dtype=float)
    if np.isnan(arr).any():
        i = int(np.argmax(np.isnan(arr)))
        raise DataFileError(source, f"column {col!r} is empty (NaN) at data row {i + 1}",
                            "remove or repair that row")
    if np.isinf(arr).any():
        i = int(np.argmax(np.isinf(arr)))
        raise DataFileError(source, f"column {col!r} is infinite at data row {i + 1}",
                            "remove or repair that row")
    return arr


def check_force_sign(source: str, trace: IndentationTrace, fix: str) -> None:
    """Reject a trace whose force falls below its pre-contact baseline at the deepest
    indentation (:func:`palpbayes.baseline.sign_flipped`); ``fix`` says how to flip it."""
    load = trace.loading_segment()
    flipped, rise, base = sign_flipped(load.z, load.force)
    if flipped:
        raise DataFileError(
            source,
            f"force falls {format_force(-rise)} below its pre-contact baseline "
            f"({format_force(base.level)}) at the deepest indentation; the compressive force "
            "must rise",
            fix,
        )


def check_plausible(trace: IndentationTrace,
                    sign_fix: str = "flip the force sign with --force-sign -1") -> None:
    """Reject traces whose units or signs cannot be right for a palpation.

    Raises :class:`DataFileError` when z spans more than :data:`MAX_Z_SPAN_M`, when |force|
    exceeds :data:`MAX_FORCE_N`, or when the force at the deepest indentation falls below its
    pre-contact baseline (sign flipped, :func:`palpbayes.baseline.sign_flipped`; ``sign_fix``
    is the reader's advice for that case).
    """
    src = trace.source or trace.trace_id
    span = float(np.ptp(trace.z))
    if span > MAX_Z_SPAN_M:
        raise DataFileError(
            src, f"z spans {format_length(span)}, more than a palpation can "
            f"({format_length(MAX_Z_SPAN_M)})",
            "is z in mm? give the z unit, e.g. --z-unit mm",
        )
    fmax = float(np.max(np.abs(trace.force)))
    if fmax > MAX_FORCE_N:
        raise DataFileError(
            src, f"|force| reaches {format_force(fmax)}, implausible for soft-material palpation",
            "is force in mN? give the force unit, e.g. --force-unit mN",
        )
    check_force_sign(src, trace, sign_fix)


def check_file(path: Path, source: str) -> None:
    """Raise :class:`DataFileError` (naming ``source``) when ``path`` is no file or is empty."""
    if not path.is_file():
        raise DataFileError(source, "file not found", "check the path")
    if path.stat().st_size == 0:
        raise DataFileError(source, "file is empty", "check that the recording was saved")
    with open(path, "rb") as fh:
        head = fh.read(4096).lstrip(b"\xef\xbb\xbf \t\r\n")
    # '{"' or '[' then '{', '[', '"' or a number: JSON (an INI-like '[Data]' section is not)
    if re.match(rb'\{\s*"|\[\s*[\[{"\d.-]', head):
        raise DataFileError(
            source, "is JSON, not a delimited table (it opens with "
            f"{head[:1].decode()!r})",
            "palpbayes reads trace CSVs (columns time_s, z_m, force_n or mapped with "
            "--time-column ...), ROS 2 bags and AFM files: write the recording as CSV, e.g. "
            f"pandas.read_json({path.name!r}).to_csv('trace.csv', index=False)")


def read_table(path: str | os.PathLike, delimiter: str | None) -> tuple[pd.DataFrame, str]:
    """A robot recording (delimited text, ``#`` comments) as a DataFrame, and its source name.

    ``delimiter`` None sniffs the separator (:func:`sniff_delimiter`); column names are
    stripped.  A missing, empty, binary or ragged file raises :class:`DataFileError`.
    """
    path = Path(path)
    source = str(path)
    check_file(path, source)
    try:
        sep = delimiter if delimiter is not None else sniff_delimiter(path)
        df = pd.read_csv(path, sep=sep, comment="#", skipinitialspace=True,
                         engine="c", encoding="utf-8")
    except UnicodeDecodeError:
        raise DataFileError(
            source, "not a text file (a binary RTDE recording?)",
            "record without --binary, or convert the file to CSV first",
        ) from None
    except pd.errors.EmptyDataError:
        raise DataFileError(source, "file is empty", "check that the recording was saved") from None
    except pd.errors.ParserError as exc:
        raise DataFileError(
            source, f"not a readable CSV ({exc})".replace("\n", " "),
            "check that every row has the same number of columns",
        ) from None
    df.columns = [str(c).strip() for c in df.columns]
    return df, source


def split_trace_metadata(metadata: dict, extra: dict) -> tuple[dict, dict]:
    """Split keyword metadata into :class:`~palpbayes.trace.IndentationTrace` fields and the
    free-form ``metadata`` dict (to which ``extra``, the reader's own record, is added)."""
    reserved = {"time", "z", "force", "source"} & set(metadata)
    if reserved:
        raise InputError(f"metadata may not set {sorted(reserved)}; they come from the file")
    kwargs = {k: v for k, v in metadata.items() if k in _TRACE_FIELDS and k != "metadata"}
    free = dict(metadata.get("metadata") or {})
    free.update({k: v for k, v in metadata.items() if k not in _TRACE_FIELDS})
    free.update(extra)
    return kwargs, free


def validate_force_sign(force_sign: float | str, allow_auto: bool) -> float | str:
    """``force_sign`` as +1.0 or -1.0 (or ``"auto"`` when ``allow_auto``); else InputError."""
    if allow_auto and isinstance(force_sign, str):
        if force_sign.lower() == "auto":
            return "auto"
        raise InputError(f"force_sign must be +1, -1 or 'auto', got {force_sign!r}")
    if force_sign not in (1, -1):
        allowed = "+1, -1 or 'auto'" if allow_auto else "+1 or -1"
        raise InputError(f"force_sign must be {allowed}, got {force_sign!r}")
    return float(force_sign)


def auto_force_sign(z: np.ndarray, raw_force: np.ndarray) -> float:
    """+1 or -1: the sign making the force larger at the deepest point (lowest z [m]) than at
    the start (median of the first and last tenth of the loading samples) [N]."""
    end = int(np.argmin(z)) + 1
    f = raw_force[:end] if end >= 3 else raw_force
    head = np.median(f[: max(1, f.size // 10)])
    tail = np.median(f[int(0.9 * f.size):])
    return 1.0 if tail >= head else -1.0
