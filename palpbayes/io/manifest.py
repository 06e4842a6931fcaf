"""Campaign manifests: one CSV row per trace (docs/design.md §5).

Columns (SI units; file paths relative to the manifest's folder):

=================  ==========================================================
``trace_id``       unique identifier (used for output file names)
``file``           trace CSV (canonical ``time_s, z_m, force_n``)
``specimen``       specimen label
``material``       material label (pooling group together with ``tip``; a map's
                   manifest may leave it out, ``read_manifest(default_material=...)``)
``tip``            a registered tip kind: flat | sphere | paraboloid | cone | power
``radius_m``       tip radius [m] (flat, paraboloid, sphere)
``half_angle_deg`` cone half-opening angle [deg] (cone only)
``profile_c``      power-law profile coefficient c of f = c·r^n (power only)
``profile_n``      power-law profile exponent n (power only)
``thickness_m``    specimen thickness [m]
``length_m``       specimen footprint: length and width of a block [m] (optional; with
``width_m``        ``thickness_m`` the fit uses the specimen's finite-element twin,
``diameter_m``     :mod:`palpbayes.twin`), or the diameter of a cylinder [m]
``repetition``     repetition number within (material, tip)
``rest_time_s``    rest time before this indentation [s] (empty if unknown)
=================  ==========================================================

The tip-size columns are those of :data:`palpbayes.contact.TIP_PARAMETERS` (a tip kind reads the
ones its law needs, :func:`palpbayes.contact.get_law`).  Optional: ``nu`` (Poisson ratio for
that row), ``law`` (that row's material law: ``linear`` or a registered hyperelastic law,
``fit --law``'s choices; empty: the run's) and ``x_m``, ``y_m`` (lateral position of the
palpation [m], for stiffness maps).
A manifest is recognised by its ``file`` and ``tip`` columns.

:func:`read_manifest` validates every row before any trace is read: ``trace_id``, ``file``,
``material`` and ``tip`` must not be empty, the numeric columns (:data:`NUMERIC_COLUMNS`) must
hold plain numbers in the units above (``0.02``, not ``2cm``), ``repetition`` a whole number.
Errors name the manifest, the row, the column and the value.  :func:`check_trace_headers`
checks that every trace file's header holds the columns the reader options ask for, reading
no data (``palpbayes map`` runs it before starting a cluster).
"""

# Long module: one job, reading and writing campaign manifests; the header checks name the file,
#   row and column of bad input.

from __future__ import annotations

import math
import os
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pandas as pd

from ..contact import TIP_PARAMETERS, Tip
from ..errors import DataFileError, GeometryError, InputError
from ..specimen import FOOTPRINT_COLUMNS, check_specimen_plausible, specimen_from_sizes
from ..trace import IndentationTrace
from .atomic import write_csv_atomic
from .tabular import sniff_delimiter
from .trace_csv import read_frame, read_trace, trace_from_frame

__all__ = [
    "MANIFEST_COLUMNS",
    "REQUIRED_COLUMNS",
    "NUMERIC_COLUMNS",
    "is_manifest",
    "read_manifest",
    "write_manifest",
    "tip_from_row",
    "tip_columns",
    "specimen_from_row",
    "footprint_metadata",
    "iter_traces",
    "load_trace",
    "check_trace_headers",
]

MANIFEST_COLUMNS = [
    "trace_id", "file", "specimen", "material", "tip",
    *(p.column for p in TIP_PARAMETERS.values()),
    "thickness_m", "repetition", "rest_time_s", *FOOTPRINT_COLUMNS,
]
REQUIRED_COLUMNS = ["trace_id", "file", "material", "tip"]
#: Numeric columns: (unit named in messages, example value, whole numbers only).
NUMERIC_COLUMNS = {
    **{p.column: (p.unit, p.example, False) for p in TIP_PARAMETERS.values()},
    "thickness_m": ("metres", "0.02", False),
    "length_m": ("metres", "0.05", False),
    "width_m": ("metres", "0.05", False),
    "diameter_m": ("metres", "0.05", False),
    "repetition": ("a whole number", "1", True),
    "rest_time_s": ("seconds", "60", False),
    "nu": ("-", "0.3", False),
    "x_m": ("metres", "0.012", False),
    "y_m": ("metres", "0.012", False),
}


def is_manifest(path: str | os.PathLike) -> bool:
    """True if ``path`` is a CSV whose header has the manifest's ``file`` and ``tip`` columns."""
    try:
        header = pd.read_csv(path, nrows=0, comment="#", sep=sniff_delimiter(path)).columns
    except (pd.errors.EmptyDataError, pd.errors.ParserError, UnicodeDecodeError, OSError):
        return False
    names = {str(c).strip() for c in header}
    return {"file", "tip"} <= names


def _blank(v) -> bool:
    """True for a missing or empty (whitespace-only) cell."""
    if isinstance(v, str):
        return v.strip() == ""
    try:
        return bool(pd.isna(v))
    except (TypeError, ValueError):  # array-like cell
        return False


def _numeric_columns(df: pd.DataFrame, path: Path) -> None:
    """Convert the numeric columns to float in place; a text cell raises naming row and value."""
    for col, (unit, example, whole) in NUMERIC_COLUMNS.items():
        if col not in df.columns:
            continue
        raw = df[col]
        values = pd.to_numeric(raw, errors="coerce")
        for i in range(len(df)):
            v, x = raw.iloc[i], values.iloc[i]
            if _blank(v):
                continue
            where = f"row {i + 1} (trace {df['trace_id'].iloc[i]!r}): column {col!r}"
            shown = repr(v.strip()) if isinstance(v, str) else f"{float(x):g}"
            fix = (f"write a whole number, e.g. {example}" if whole else
                   f"write a plain number in {unit}, e.g. {example}") + ", or leave it empty"
            if pd.isna(x):
                raise DataFileError(path, f"{where} holds {shown}, which is not a number", fix)
            if not math.isfinite(float(x)):
                raise DataFileError(path, f"{where} is {shown}, not a finite number", fix)
            if whole and float(x) != round(float(x)):
                raise DataFileError(path, f"{where} is {shown}, not a whole number", fix)
        df[col] = values.astype(float)


def read_manifest(path: str | os.PathLike, *,
                  default_material: str | None = None) -> pd.DataFrame:
    """Read and validate a manifest; ``file`` becomes an absolute path.

    The separator (comma, semicolon or tab) is detected from the header line.  The numeric
    columns (:data:`NUMERIC_COLUMNS`) are returned as float.

    Parameters
    ----------
    path
        The manifest CSV.
    default_material
        The ``material`` of rows without one (no such column, or an empty cell), e.g. ``""``
        for a stiffness map (one block, no pooling); None (default): the column is required
        (a campaign pools its traces by material and tip).

    Raises
    ------
    DataFileError
        Missing columns, an empty ``trace_id``/``file``/``material``/``tip`` cell, text in a
        numeric column (e.g. ``2cm``), a non-whole ``repetition``, a non-positive
        ``thickness_m`` or negative ``rest_time_s``, duplicated ``trace_id``, a referenced trace
        file that does not exist, or a row whose tip geometry is invalid (the message names the
        row, the trace, the column and the value).
    """
    path = Path(path)
    if path.is_dir():
        raise DataFileError(path, "is a folder, not a manifest file",
                            f"did you mean {path / 'manifest.csv'}?")
    if not path.is_file():
        raise DataFileError(path, "manifest not found", "check the path")
    try:
        df = pd.read_csv(path, comment="#", sep=sniff_delimiter(path),
                         dtype={"trace_id": str, "specimen": str, "material": str, "tip": str,
                                "file": str})
    except pd.errors.EmptyDataError:
        raise DataFileError(path, "manifest is empty") from None
    except (pd.errors.ParserError, UnicodeDecodeError) as exc:
        raise DataFileError(path, f"not a readable CSV ({exc})".replace("\n", " ")) from None
    df.columns = [str(c).strip() for c in df.columns]
    required = [c for c in REQUIRED_COLUMNS
                if not (c == "material" and default_material is not None)]
    missing = [c for c in required if c not in df.columns]
    if missing:
        raise DataFileError(path, f"manifest lacks column(s) {', '.join(missing)}",
                            f"a manifest needs {', '.join(required)}")
    if df.empty:
        raise DataFileError(path, "manifest has no rows")
    if default_material is not None:
        if "material" not in df.columns:
            df["material"] = default_material
        df["material"] = [default_material if _blank(v) else v for v in df["material"]]
    for i in range(len(df)):
        for col in required:
            if _blank(df[col].iloc[i]):
                tid = df["trace_id"].iloc[i]
                who = "" if _blank(tid) else f" (trace {str(tid).strip()!r})"
                fix = f"give every row its {col}"
                if col == "trace_id":
                    fix += ", a unique name used for the output file names"
                raise DataFileError(path, f"row {i + 1}{who}: column {col!r} is empty", fix)
    for col in REQUIRED_COLUMNS:
        df[col] = df[col].astype(str).str.strip()
    for col in MANIFEST_COLUMNS:
        if col not in df.columns:
            df[col] = np.nan
    df["specimen"] = df["specimen"].astype(object).where(df["specimen"].notna(), "")
    _numeric_columns(df, path)
    dup = df["trace_id"][df["trace_id"].duplicated()]
    if not dup.empty:
        raise DataFileError(path, f"trace_id {dup.iloc[0]!r} appears more than once",
                            "give every row its own trace_id")
    files = []
    for i, row in df.iterrows():
        where = f"row {i + 1} (trace {row['trace_id']!r})"
        f = Path(str(row["file"]))
        if not f.is_absolute():
            f = path.parent / f
        if not f.is_file():
            raise DataFileError(
                path, f"{where} points to missing file {f}",
                "fix the 'file' column or restore the file",
            )
        files.append(str(f))
        try:
            tip_from_row(row)
        except GeometryError as exc:
            raise DataFileError(path, f"{where}: {exc}") from None
        for col, ok, must in (("thickness_m", lambda v: v > 0, "positive"),
                              *((c, lambda v: v > 0, "positive") for c in FOOTPRINT_COLUMNS),
                              ("rest_time_s", lambda v: v >= 0, "non-negative")):
            v = row[col]
            if pd.notna(v) and not ok(v):
                unit, example, _ = NUMERIC_COLUMNS[col]
                raise DataFileError(path, f"{where}: column {col!r} is {v:g}, which must be "
                                    f"{must}", f"give it in {unit}, e.g. {example}, or leave "
                                    "it empty")
        try:
            spec = specimen_from_row(row)
            if spec is not None:
                check_specimen_plausible(spec)
        except GeometryError as exc:
            raise DataFileError(path, f"{where}: {exc}",
                                "give length_m and width_m (a block) or diameter_m (a "
                                "cylinder), with thickness_m, in metres") from None
        if "law" in df.columns and not _blank(row.get("law")):
            from ..material import LINEAR, material_law

            if str(row["law"]).strip().lower() != LINEAR:
                try:
                    material_law(str(row["law"]))
                except InputError as exc:
                    raise DataFileError(path, f"{where}: column 'law': {exc}") from None
        if "nu" in df.columns and pd.notna(row.get("nu")):
            from ..contact import check_nu

            try:
                check_nu(row["nu"])
            except InputError as exc:
                raise DataFileError(path, f"{where}: {exc}") from None
    df["file"] = files
    return df


def _opt(row: pd.Series, col: str) -> float | None:
    """The float in ``col`` of a row, None when the column is absent or the cell empty."""
    v = row.get(col)
    if _blank(v):
        return None
    try:
        return float(v)
    except (TypeError, ValueError):
        raise DataFileError(None, f"trace {row.get('trace_id')!r}: column {col!r} holds {v!r}, "
                            "which is not a number", "validate the table with read_manifest "
                            "first") from None


def tip_from_row(row: pd.Series) -> Tip:
    """Build the :class:`~palpbayes.contact.Tip` of one manifest row (its ``tip`` column and
    the tip-size columns of :data:`~palpbayes.contact.TIP_PARAMETERS`, in their units)."""
    sizes = {}
    for p in TIP_PARAMETERS.values():
        value = _opt(row, p.column)
        sizes[p.name] = None if value is None else p.from_user(value)
    return Tip(str(row["tip"]), **sizes)


def specimen_from_row(row: pd.Series):
    """The :class:`~palpbayes.twin.Specimen` of a manifest row (its footprint columns and
    ``thickness_m``), or None when the row gives no footprint."""
    return specimen_from_sizes(_opt(row, "thickness_m"),
                               *(_opt(row, c) for c in FOOTPRINT_COLUMNS))


def footprint_metadata(row: pd.Series) -> dict[str, float]:
    """The footprint columns a row gives, for a trace's metadata."""
    return {c: _opt(row, c) for c in FOOTPRINT_COLUMNS if _opt(row, c) is not None}


def tip_columns(tip: Tip) -> dict[str, float]:
    """The tip-size columns of a manifest row for ``tip`` (NaN for the parameters it lacks);
    the inverse of :func:`tip_from_row` with the ``tip`` column."""
    return {p.column: np.nan if getattr(tip, p.name) is None
            else p.to_user(getattr(tip, p.name)) for p in TIP_PARAMETERS.values()}


def load_trace(row: pd.Series, **read_options) -> IndentationTrace:
    """Read the trace of one (validated) manifest row with its metadata.

    ``read_options`` (``columns``, ``units``, ``force_sign``, ``z_sign``, ...) go to
    :func:`palpbayes.io.trace_csv.read_trace` for the row's file.
    """
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
        metadata={**({} if _opt(row, "nu") is None else {"nu": _opt(row, "nu")}),
                  **({} if _blank(row.get("law")) else {"law": str(row["law"]).strip()}),
                  **footprint_metadata(row)},
        **read_options,
    )


def iter_traces(manifest: str | os.PathLike | pd.DataFrame,
                **read_options) -> Iterator[IndentationTrace]:
    """Yield the traces of a manifest (path or DataFrame from :func:`read_manifest`)."""
    df = manifest if isinstance(manifest, pd.DataFrame) else read_manifest(manifest)
    for _, row in df.iterrows():
        yield load_trace(row, **read_options)


#: Options of :func:`palpbayes.io.trace_csv.trace_from_frame` that decide how a file's columns
#: are read (``delimiter`` is the other; ``tip``, ``check`` ... do not concern the header).
_COLUMN_OPTIONS = ("columns", "units", "force_sign", "z_sign", "tool_offset")


def _header_line(path: Path) -> str:
    """The first line of ``path`` that is neither blank nor a ``#`` comment ('' if none)."""
    with open(path, encoding="utf-8", newline="") as fh:
        for line in fh:
            if line.strip() and not line.lstrip().startswith("#"):
                return line.rstrip("\r\n")
    return ""


def _check_header(path: Path, read_options: dict) -> None:
    """Read the header of the trace CSV ``path`` and resolve its time, z (or joint angles)
    and force columns with ``read_options`` on three made-up rows: the reader's own column,
    unit and joint-angle logic, no data read."""
    source = str(path)
    header, _ = read_frame(path, read_options.get("delimiter", "auto"), nrows=0)
    # made-up rows (0, 1, 2 in every column: increasing time, segment codes in order) so that
    # only the header and the options can fail
    frame = pd.DataFrame({c: [0.0, 1.0, 2.0] for c in header.columns})
    opts = {k: v for k, v in read_options.items() if k in _COLUMN_OPTIONS}
    trace_from_frame(frame, source, check=False, **opts)


def check_trace_headers(manifest: pd.DataFrame, *, source: str | os.PathLike | None = None,
                        **read_options) -> None:
    """Check, from headers alone, that every trace file of a manifest can be read with
    ``read_options``: its columns exist and the units given are known.

    Reads the first non-comment line of every file and parses each distinct header once, so
    it takes some 30 ms per thousand files; the data rows are not read (a file whose
    data are bad is reported when its trace is read).

    Parameters
    ----------
    manifest
        Validated manifest (:func:`read_manifest`; ``file`` holds absolute paths).
    source
        The manifest's path, named in the error.
    **read_options
        The options of :func:`palpbayes.io.trace_csv.read_trace` the traces will be read with
        (``columns``, ``units``, ``force_sign``, ``z_sign``, ...; others are ignored here).

    Raises
    ------
    DataFileError
        Naming the first trace file whose header fails, its manifest row and trace, how many
        other files share that header, what is missing (with the option that maps a robot
        log's column) and the columns the file has.
    """
    groups: dict[str, list[int]] = {}
    for i, f in enumerate(manifest["file"]):
        path = Path(str(f))
        try:
            line = _header_line(path)
        except UnicodeDecodeError:
            raise DataFileError(path, "is not a text CSV (it does not start as UTF-8 text)",
                                "give trace CSVs in the manifest's 'file' column") from None
        except OSError as exc:
            raise DataFileError(path, f"cannot be read ({exc.strerror or exc})",
                                "fix the 'file' column or restore the file") from None
        groups.setdefault(line, []).append(i)
    where = f" of {source}" if source is not None else ""
    for rows in groups.values():
        i = rows[0]
        path = Path(str(manifest["file"].iloc[i]))
        try:
            _check_header(path, read_options)
        except DataFileError as exc:
            label = manifest.index[i]  # read_manifest's row number, also of a subset
            row = label + 1 if isinstance(label, (int, np.integer)) else i + 1
            tid = manifest["trace_id"].iloc[i] if "trace_id" in manifest else None
            trace = "" if tid is None else f" (trace {str(tid)!r})"
            more = (f", and {len(rows) - 1} other trace file(s) with the same header"
                    if len(rows) > 1 else "")
            raise DataFileError(exc.path, f"{exc.problem} [row {row}{trace}{where}{more}]",
                                exc.fix) from None


def write_manifest(df: pd.DataFrame, path: str | os.PathLike) -> Path:
    """Write a manifest with the standard column order (extra columns kept at the end)."""
    cols = [c for c in MANIFEST_COLUMNS if c in df.columns]
    cols += [c for c in df.columns if c not in cols]
    return write_csv_atomic(df[cols], path, float_format="%.10g")
