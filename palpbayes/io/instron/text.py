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

__all__ = ["DELIMITERS", "read_lines", "split_cells", "is_number", "is_numeric_row",
           "find_column_row", "parse_header"]

#: Cell separators tried, in order.
DELIMITERS = (",", "\t", ";")


def read_lines(path: Path) -> tuple[list[str], str]:
    """The file's lines and the encoding that decoded it (UTF-8, else latin-1);
    :class:`DataFileError` when it cannot be read."""
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


def split_cells(line: str, delimiter: str) -> list[str]:
    """The stripped cells of one CSV line (the whole line as one cell if it does not parse)."""
    try:
        row = next(csv.reader([line], delimiter=delimiter, skipinitialspace=True), [])
    except csv.Error:
        return [line]
    return [c.strip() for c in row]


def is_number(cell: str) -> bool:
    """Whether ``cell`` reads as a finite number."""
    try:
        return math.isfinite(float(cell))
    except ValueError:
        return False


def is_numeric_row(cells: list[str]) -> bool:
    """A data row: at least two filled cells, all of them finite numbers."""
    filled = [c for c in cells if c != ""]
    return len(filled) >= 2 and all(is_number(c) for c in filled)


def find_column_row(lines: list[str]) -> tuple[int, str] | None:
    """Index of the column row and the delimiter, or None if there is none."""
    for i, line in enumerate(lines[:-1]):
        nxt = lines[i + 1]
        for delimiter in DELIMITERS:
            names = [c for c in split_cells(line, delimiter) if c]
            if len(names) < 2 or is_numeric_row(names):
                continue
            if is_numeric_row(split_cells(nxt, delimiter)):
                return i, delimiter
    return None


def parse_header(lines: list[str]) -> dict[str, str]:
    """The free header above the column row: 'key: value' lines by key; a first line without
    a colon is the sample name, any other such line is kept as 'Line n'."""
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
