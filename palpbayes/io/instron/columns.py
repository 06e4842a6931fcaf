"""Columns of a compression-test export: which column is time, displacement and load, in which
unit, read as numbers, and with which sign.

Names and units follow the rules of :mod:`palpbayes.io.instron.reader`: a synonym of
:data:`TIME_NAMES`, :data:`DISPLACEMENT_NAMES` or :data:`LOAD_NAMES`, the unit in brackets
(``Load (kN)``) or as a suffix (``load_kn``).
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pandas as pd

from ...errors import DataFileError, InputError
from ..units import force_factor, length_factor, time_factor

__all__ = ["DISPLACEMENT_NAMES", "LOAD_NAMES", "TIME_NAMES", "QUANTITY_NAMES", "UNIT_ALIASES",
           "BRACKET_UNIT", "split_column_name", "name_words", "match_column", "unit_factor",
           "export_column_values", "column_sign"]

#: Column-name synonyms, in order of preference (lower case).
TIME_NAMES = ("time",)
DISPLACEMENT_NAMES = ("compression", "extension", "displacement", "deflection", "position")
LOAD_NAMES = ("load", "force")

#: The synonyms of each quantity's column.
QUANTITY_NAMES = {"time": TIME_NAMES, "displacement": DISPLACEMENT_NAMES, "load": LOAD_NAMES}
_FACTOR = {"time": time_factor, "displacement": length_factor, "load": force_factor}
#: Unit spellings of exports -> the unit names of :mod:`palpbayes.io.units`.
UNIT_ALIASES = {"sec": "s", "secs": "s", "seconds": "s", "mins": "min", "minutes": "min",
                 "msec": "ms", "micron": "µm", "microns": "µm", "n": "N", "kn": "kN",
                 "un": "uN", "µn": "µN", "μn": "μN", "nn": "nN", "pn": "pN"}
#: A column name with its unit in brackets: 'Load (kN)', 'Time [s]'.
BRACKET_UNIT = re.compile(r"^(?P<name>.*?)\s*[\(\[]\s*(?P<unit>[^\)\]]*?)\s*[\)\]]\s*$")


def split_column_name(column: str) -> tuple[str, str | None]:
    """('load', 'kN') from 'Load (kN)'; ('load', 'kN') from 'load_kn'; (name, None) else."""
    text = str(column).strip()
    m = BRACKET_UNIT.match(text)
    if m:
        return m.group("name").strip().lower(), m.group("unit").strip()
    base, sep, unit = text.rpartition("_")
    if sep and base and unit:
        return base.strip().lower(), unit.strip()
    return text.lower(), None


def name_words(name: str) -> list[str]:
    """The words of a lower-case column name ('compressive load' -> ['compressive', 'load'])."""
    return re.split(r"[\s_\-/]+", name)


def match_column(columns: list[str], quantity: str) -> str | None:
    """The column of ``quantity``: a synonym as its whole name, else as one of its words, in
    order of preference; None when no column matches."""
    names = [(split_column_name(c)[0], c) for c in columns]
    for synonym in QUANTITY_NAMES[quantity]:  # exact name first, in order of preference
        for name, col in names:
            if name == synonym:
                return col
    for synonym in QUANTITY_NAMES[quantity]:  # then a word of the name ('Compressive load')
        for name, col in names:
            if synonym in name_words(name):
                return col
    return None


def unit_factor(source: Path, column: str, quantity: str, unit: str | None) -> float:
    """Factor from the column's ``unit`` to SI; :class:`DataFileError` for none or an unknown
    one."""
    if unit is None or unit == "":
        raise DataFileError(
            source, f"column {column!r} has no unit",
            f"name it like '{column} (N)' / '{column} (mm)' / '{column} (s)', or pass "
            f"units={{'{quantity}': ...}}",
        )
    unit = UNIT_ALIASES.get(unit.strip(), unit.strip())
    try:
        return _FACTOR[quantity](unit)
    except InputError as exc:
        raise DataFileError(source, f"column {column!r}: {exc}") from None


def export_column_values(df: pd.DataFrame, column: str, source: Path, first_line: int
                         ) -> np.ndarray:
    """The column as floats; :class:`DataFileError` naming the first empty or non-numeric cell
    (``first_line`` is the file line of the first row)."""
    raw = df[column]
    text = raw.astype("string").str.strip()
    values = pd.to_numeric(text, errors="coerce").to_numpy(dtype=float)
    bad = ~np.isfinite(values)
    if bad.any():
        k = int(np.flatnonzero(bad)[0])
        cell = raw.iloc[k]
        what = "an empty cell" if pd.isna(cell) or str(cell).strip() == "" else \
            f"the non-numeric value {str(cell).strip()!r}"
        more = int(bad.sum()) - 1
        raise DataFileError(
            source, f"line {first_line + k}, column {column!r}: {what}"
            + (f" ({more} more bad cell(s) in this column)" if more else ""),
            "fix or delete the row; only a trailing footer is skipped automatically",
        )
    return values


def column_sign(values: np.ndarray, given: int | None, what: str, column: str,
                source: Path) -> float:
    """+1 or -1: the ``given`` sign, else the one that makes the column increase overall
    (:class:`DataFileError` when it never changes)."""
    if given is not None:
        if given not in (1, -1):
            raise InputError(f"{what}column_sign must be +1 or -1, got {given!r}")
        return float(given)
    change = values - values[0]
    total = float(np.sum(change))
    if total == 0.0 or not np.isfinite(total):
        raise DataFileError(source, f"column {column!r} never changes, so this is no "
                            "compression test", "check the file")
    return 1.0 if total > 0 else -1.0
