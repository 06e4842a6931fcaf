"""Campaign manifests: one CSV row per trace (DESIGN §5).

Columns (SI units; file paths relative to the manifest's folder):

=================  ==========================================================
``trace_id``       unique identifier (used for output file names)
``file``           trace CSV (canonical ``time_s, z_m, force_n``)
``specimen``       specimen label
``material``       material label (pooling group together with ``tip``)
``tip``            flat | paraboloid | sphere | cone | power
``radius_m``       tip radius [m] (flat, paraboloid, sphere)
``half_angle_deg`` cone half-opening angle [deg] (cone only)
``profile_c``      power-law profile coefficient c of f = c·r^n (power only)
``profile_n``      power-law profile exponent n (power only)
``thickness_m``    specimen thickness [m]
``repetition``     repetition number within (material, tip)
``rest_time_s``    rest time before this indentation [s] (empty if unknown)
=================  ==========================================================

Optional: ``nu`` (Poisson ratio for that row).  A manifest is recognised by its ``file`` and
``tip`` columns.
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pandas as pd

from ..contact import Tip
from ..errors import DataFileError, GeometryError, InputError
from ..trace import IndentationTrace
from .atomic import write_csv_atomic
from .trace_csv import read_trace

__all__ = [
    "MANIFEST_COLUMNS",
    "REQUIRED_COLUMNS",
    "is_manifest",
    "read_manifest",
    "write_manifest",
    "tip_from_row",
    "iter_traces",
    "load_trace",
]

MANIFEST_COLUMNS = [
    "trace_id", "file", "specimen", "material", "tip", "radius_m", "half_angle_deg",
    "profile_c", "profile_n", "thickness_m", "repetition", "rest_time_s",
]
REQUIRED_COLUMNS = ["trace_id", "file", "material", "tip"]


def is_manifest(path: str | os.PathLike) -> bool:
    """True if ``path`` is a CSV whose header has the manifest's ``file`` and ``tip`` columns."""
    try:
        header = pd.read_csv(path, nrows=0, comment="#").columns
    except (pd.errors.EmptyDataError, pd.errors.ParserError, UnicodeDecodeError, OSError):
        return False
    names = {str(c).strip() for c in header}
    return {"file", "tip"} <= names


def read_manifest(path: str | os.PathLike) -> pd.DataFrame:
    """Read and validate a manifest; ``file`` becomes an absolute path.

    Raises
    ------
    DataFileError
        Missing columns, duplicated ``trace_id``, a referenced trace file that does not exist,
        or a row whose tip geometry is invalid (the message names the row and trace).
    """
    path = Path(path)
    if not path.is_file():
        raise DataFileError(path, "manifest not found", "check the path")
    try:
        df = pd.read_csv(path, comment="#", dtype={"trace_id": str, "specimen": str,
                                                  "material": str, "tip": str, "file": str})
    except pd.errors.EmptyDataError:
        raise DataFileError(path, "manifest is empty") from None
    df.columns = [str(c).strip() for c in df.columns]
    missing = [c for c in REQUIRED_COLUMNS if c not in df.columns]
    if missing:
        raise DataFileError(path, f"manifest lacks column(s) {', '.join(missing)}",
                            f"a manifest needs {', '.join(REQUIRED_COLUMNS)}")
    if df.empty:
        raise DataFileError(path, "manifest has no rows")
    for col in MANIFEST_COLUMNS:
        if col not in df.columns:
            df[col] = np.nan
    df["specimen"] = df["specimen"].astype(object).where(df["specimen"].notna(), "")
    dup = df["trace_id"][df["trace_id"].duplicated()]
    if not dup.empty:
        raise DataFileError(path, f"trace_id {dup.iloc[0]!r} appears more than once",
                            "give every row its own trace_id")
    files = []
    for i, row in df.iterrows():
        f = Path(str(row["file"]))
        if not f.is_absolute():
            f = path.parent / f
        if not f.is_file():
            raise DataFileError(
                path, f"row {i + 1} (trace {row['trace_id']!r}) points to missing file {f}",
                "fix the 'file' column or restore the file",
            )
        files.append(str(f))
        try:
            tip_from_row(row)
        except GeometryError as exc:
            raise DataFileError(path, f"row {i + 1} (trace {row['trace_id']!r}): {exc}") from None
        if "nu" in df.columns and pd.notna(row.get("nu")):
            from ..contact import check_nu

            try:
                check_nu(row["nu"])
            except InputError as exc:
                raise DataFileError(path, f"row {i + 1}: {exc}") from None
    df["file"] = files
    return df


def _opt(row: pd.Series, col: str) -> float | None:
    v = row.get(col)
    if v is None or (isinstance(v, float) and math.isnan(v)) or v == "":
        return None
    return float(v)


def tip_from_row(row: pd.Series) -> Tip:
    """Build the :class:`~palpbayes.contact.Tip` of one manifest row."""
    angle = _opt(row, "half_angle_deg")
    return Tip(
        str(row["tip"]),
        radius=_opt(row, "radius_m"),
        half_angle=None if angle is None else math.radians(angle),
        c=_opt(row, "profile_c"),
        n=_opt(row, "profile_n"),
    )


def load_trace(row: pd.Series, **read_options) -> IndentationTrace:
    """Read the trace of one (validated) manifest row with its metadata."""
    rep = _opt(row, "repetition")
    return read_trace(
        row["file"],
        tip=tip_from_row(row),
        trace_id=str(row["trace_id"]),
        specimen=str(row.get("specimen", "")),
        material=str(row["material"]),
        thickness=_opt(row, "thickness_m"),
        repetition=None if rep is None else int(rep),
        rest_time=_opt(row, "rest_time_s"),
        metadata={} if _opt(row, "nu") is None else {"nu": _opt(row, "nu")},
        **read_options,
    )


def iter_traces(manifest: str | os.PathLike | pd.DataFrame,
                **read_options) -> Iterator[IndentationTrace]:
    """Yield the traces of a manifest (path or DataFrame from :func:`read_manifest`)."""
    df = manifest if isinstance(manifest, pd.DataFrame) else read_manifest(manifest)
    for _, row in df.iterrows():
        yield load_trace(row, **read_options)


def write_manifest(df: pd.DataFrame, path: str | os.PathLike) -> Path:
    """Write a manifest with the standard column order (extra columns kept at the end)."""
    cols = [c for c in MANIFEST_COLUMNS if c in df.columns]
    cols += [c for c in df.columns if c not in cols]
    return write_csv_atomic(df[cols], path, float_format="%.10g")
