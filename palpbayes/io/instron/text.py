"""Text level of a compression-test export: lines, cells, the column row and the free header.

Private helpers of :mod:`palpbayes.io.instron.reader` (rules in its docstring): decode the file
(UTF-8, else Latin-1), split a line into cells, find the first row of at least two names that is
followed by a row of numbers, and turn the lines above it into ``header[key] = value``.
"""

from __future__ import annotations

import csv
import math
from pathlib import Path

from ...errors import DataFileError

__all__: list[str] = []

#: Cell separators tried, in order.
_DELIMITERS = (",", "\t", ";")


def _read_lines(path: Path) -> tuple[list[str], str]:
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        raise DataFileError(path, "file not found", "check the path") from None
    except IsADirectoryError:
        raise DataFileError(path, "is a folder, not a compression-test file") from None
    except OSError as exc:
        raise DataFileError(path, f"cannot be read ({exc.strerror or exc})") from None
    for encoding in ("utf-8-sig", "latin-1"):
        try:
            return raw.decode(encoding).splitlines(), encoding
        except UnicodeDecodeError:
            continue
    raise AssertionError("latin-1 decodes every byte string")  # pragma: no cover


def _cells(line: str, delimiter: str) -> list[str]:
    try:
        row = next(csv.reader([line], delimiter=delimiter, skipinitialspace=True), [])
    except csv.Error:
        return [line]
    return [c.strip() for c in row]


def _is_number(cell: str) -> bool:
    try:
        return math.isfinite(float(cell))
    except ValueError:
        return False


def _is_numeric_row(cells: list[str]) -> bool:
    filled = [c for c in cells if c != ""]
    return len(filled) >= 2 and all(_is_number(c) for c in filled)


def _find_column_row(lines: list[str]) -> tuple[int, str] | None:
    """Index of the column row and the delimiter, or None if there is none."""
    for i, line in enumerate(lines[:-1]):
        nxt = lines[i + 1]
        for delimiter in _DELIMITERS:
            names = [c for c in _cells(line, delimiter) if c]
            if len(names) < 2 or _is_numeric_row(names):
                continue
            if _is_numeric_row(_cells(nxt, delimiter)):
                return i, delimiter
    return None


def _parse_header(lines: list[str]) -> dict[str, str]:
    header: dict[str, str] = {}
    for n, line in enumerate(lines, start=1):
        text = line.strip().rstrip(";").strip().strip('"').strip()
        if not text:
            continue
        key, sep, value = text.partition(":")
        if sep and key.strip():
            header[key.strip()] = value.strip()
        elif "Sample name" not in header and not header:
            header["Sample name"] = text
        else:
            header[f"Line {n}"] = text
    return header
