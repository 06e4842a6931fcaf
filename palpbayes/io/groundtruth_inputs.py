"""Inputs of the ground-truth analysis: find compression-test exports and read manifests.

:func:`scan_inputs` sorts paths (files, folders searched recursively, ground-truth manifests)
into manifests, test files and skipped files; :func:`read_groundtruth_manifest` reads the tests
a manifest lists, with its geometry and labels; :func:`collect_tests` does both and returns
:class:`~palpbayes.io.instron.CompressionTest` objects for
:func:`palpbayes.compression.analyse`.  The tests are read by
:func:`palpbayes.io.instron.read_compression_test`.

A ground-truth manifest is a CSV with a ``file`` column (paths relative to the manifest's
folder) and ``area_m2`` and/or ``height_m``; optional ``specimen`` and ``material`` labels.
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterable
from pathlib import Path

import pandas as pd

from ..errors import DataFileError
from .instron import CompressionTest, looks_like_compression_test, read_compression_test

__all__ = [
    "collect_tests",
    "scan_inputs",
    "is_groundtruth_manifest",
    "read_groundtruth_manifest",
]



def _csv_columns(path: Path) -> list[str] | None:
    try:
        return [str(c).strip() for c in pd.read_csv(path, nrows=0).columns]
    except (pd.errors.EmptyDataError, pd.errors.ParserError, UnicodeDecodeError, OSError,
            ValueError):
        return None


def is_groundtruth_manifest(path: str | os.PathLike) -> bool:
    """True if ``path`` is a CSV with a ``file`` column and ``area_m2`` or ``height_m``.

    (A palpation campaign manifest, which has a ``tip`` column, is not one.)
    """
    cols = _csv_columns(Path(path))
    return bool(cols) and "file" in cols and "tip" not in cols and \
        bool({"area_m2", "height_m"} & set(cols))


def _optional_float(value, manifest: Path, line: int, column: str) -> float | None:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return None
    text = str(value).strip()
    if text == "" or text.lower() == "nan":
        return None
    try:
        v = float(text)
    except ValueError:
        v = math.nan
    if not (math.isfinite(v) and v > 0):
        raise DataFileError(manifest, f"line {line}, column {column!r}: {text!r} is not a "
                            "positive number [SI units]",
                            "write the value in metres (squared for the area) or leave it "
                            "empty to use the file's header")
    return v


def _manifest_rows(path: Path) -> pd.DataFrame:
    if not path.is_file():
        raise DataFileError(path, "manifest not found", "check the path")
    try:
        df = pd.read_csv(path, dtype=str, keep_default_na=False)
    except pd.errors.EmptyDataError:
        raise DataFileError(path, "the manifest is empty",
                            "write a header 'file,specimen,material,area_m2,height_m' and one "
                            "row per test") from None
    except (pd.errors.ParserError, UnicodeDecodeError) as exc:
        raise DataFileError(path, f"cannot be parsed as CSV ({exc})") from None
    df.columns = [str(c).strip() for c in df.columns]
    if "file" not in df.columns:
        raise DataFileError(path, f"the manifest has no 'file' column (it has "
                            f"{', '.join(df.columns)})",
                            "columns: file, specimen, material, area_m2, height_m")
    if df.empty:
        raise DataFileError(path, "the manifest lists no tests", "add one row per test")
    return df


def _manifest_files(path: Path) -> list[Path]:
    df = _manifest_rows(path)
    return [(path.parent / str(f).strip()) for f in df["file"]]


def read_groundtruth_manifest(
    path: str | os.PathLike,
    *,
    area_m2: float | None = None,
    height_m: float | None = None,
) -> list[CompressionTest]:
    """Read the tests listed in a ground-truth manifest.

    Columns: ``file`` (required; relative to the manifest's folder or absolute) and, optional
    (empty cells fall back to the file), ``specimen``, ``material``, ``area_m2`` [m²] and
    ``height_m`` [m].

    Parameters
    ----------
    path
        The manifest CSV.
    area_m2, height_m
        [m²], [m] Geometry for every test, overriding the manifest and the headers.

    Returns
    -------
    list of CompressionTest

    Raises
    ------
    DataFileError
        Missing manifest or ``file`` column, no rows, a listed file that does not exist or a
        bad geometry cell (naming the manifest line), or an error in a listed file.
    """
    path = Path(path)
    df = _manifest_rows(path)
    tests = []
    for i, row in enumerate(df.to_dict("records")):
        line = i + 2
        name = str(row["file"]).strip()
        if not name:
            raise DataFileError(path, f"line {line}: empty 'file' cell", "name the test file")
        file = path.parent / name
        if not file.is_file():
            raise DataFileError(path, f"line {line}: test file {name!r} not found (looked for "
                                f"{file})", "file paths are relative to the manifest's folder")
        area = area_m2 if area_m2 is not None else _optional_float(
            row.get("area_m2"), path, line, "area_m2")
        height = height_m if height_m is not None else _optional_float(
            row.get("height_m"), path, line, "height_m")
        labels = {k: str(row[k]).strip() for k in ("specimen", "material")
                  if k in row and str(row[k]).strip()}
        tests.append(read_compression_test(file, area_m2=area, height_m=height, **labels))
    return tests


def scan_inputs(
    inputs: Iterable[str | os.PathLike],
) -> tuple[list[Path], list[Path], list[Path]]:
    """Sort input paths into (manifests, test files, skipped files).

    Folders are searched recursively for ``*.csv`` (hidden files skipped).  A CSV found there
    is a manifest (:func:`is_groundtruth_manifest`), a compression test
    (:func:`~palpbayes.io.instron.looks_like_compression_test`) or skipped (published tables,
    palpation traces, results).  Test files listed by a manifest are left to the manifest.
    Files named explicitly are never skipped: a file that is neither a manifest nor a test is
    read as a test, so its error is reported.

    Raises
    ------
    DataFileError
        An input path that does not exist.
    """
    manifests: list[Path] = []
    tests: list[Path] = []
    skipped: list[Path] = []
    for item in inputs:
        p = Path(item)
        if p.is_dir():
            for f in sorted(p.rglob("*.csv")):
                if any(part.startswith(".") for part in f.relative_to(p).parts):
                    continue
                if is_groundtruth_manifest(f):
                    manifests.append(f)
                elif looks_like_compression_test(f):
                    tests.append(f)
                else:
                    skipped.append(f)
        elif p.is_file():
            (manifests if is_groundtruth_manifest(p) else tests).append(p)
        else:
            raise DataFileError(p, "no such file or folder", "check the path")
    listed = {f.resolve() for m in manifests for f in _manifest_files(m)}
    unique: dict[Path, Path] = {}
    for f in tests:
        r = f.resolve()
        if r not in listed and r not in unique:
            unique[r] = f
    return _dedupe(manifests), list(unique.values()), skipped


def _dedupe(paths: list[Path]) -> list[Path]:
    out: dict[Path, Path] = {}
    for p in paths:
        out.setdefault(p.resolve(), p)
    return list(out.values())


def collect_tests(
    inputs: str | os.PathLike | CompressionTest | Iterable[str | os.PathLike | CompressionTest],
    *,
    area_m2: float | None = None,
    height_m: float | None = None,
) -> list[CompressionTest]:
    """Read every compression test named by ``inputs`` (files, folders, manifests, tests).

    Parameters
    ----------
    inputs
        One or several paths (see :func:`scan_inputs`) or :class:`CompressionTest` objects.
    area_m2, height_m
        [m²], [m] Geometry for every file read, overriding manifests and headers.

    Raises
    ------
    DataFileError
        No test found, or an error in a file.
    """
    if isinstance(inputs, str | os.PathLike | CompressionTest):
        inputs = [inputs]
    items = list(inputs)
    given = [t for t in items if isinstance(t, CompressionTest)]
    paths = [p for p in items if not isinstance(p, CompressionTest)]
    manifests, files, skipped = scan_inputs(paths)
    tests = list(given)
    for m in manifests:
        tests.extend(read_groundtruth_manifest(m, area_m2=area_m2, height_m=height_m))
    tests.extend(read_compression_test(f, area_m2=area_m2, height_m=height_m) for f in files)
    if not tests:
        where = ", ".join(str(p) for p in paths) or None
        extra = f"; skipped {len(skipped)} other CSV file(s)" if skipped else ""
        raise DataFileError(where, f"no compression tests found{extra}",
                            "a test export has a column row with displacement and load "
                            "columns, e.g. 'Time (s),Compression (mm),Load (N)'")
    return tests
