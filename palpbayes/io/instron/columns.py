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

__all__ = ["DISPLACEMENT_NAMES", "LOAD_NAMES", "TIME_NAMES"]

#: Column-name synonyms, in order of preference (lower case).
TIME_NAMES = ("time",)
DISPLACEMENT_NAMES = ("compression", "extension", "displacement", "deflection", "position")
LOAD_NAMES = ("load", "force")

_QUANTITIES = {"time": TIME_NAMES, "displacement": DISPLACEMENT_NAMES, "load": LOAD_NAMES}
_FACTOR = {"time": time_factor, "displacement": length_factor, "load": force_factor}
_UNIT_ALIASES = {"sec": "s", "secs": "s", "seconds": "s", "mins": "min", "minutes": "min",
                 "msec": "ms", "micron": "µm", "microns": "µm", "n": "N", "kn": "kN",
                 "un": "uN", "µn": "µN", "μn": "μN", "nn": "nN", "pn": "pN"}
_BRACKET_UNIT = re.compile(r"^(?P<name>.*?)\s*[\(\[]\s*(?P<unit>[^\)\]]*?)\s*[\)\]]\s*$")


def _split_name(column: str) -> tuple[str, str | None]:
    """('load', 'kN') from 'Load (kN)'; ('load', 'kN') from 'load_kn'; (name, None) else."""
    text = str(column).strip()
    m = _BRACKET_UNIT.match(text)
    if m:
        return m.group("name").strip().lower(), m.group("unit").strip()
    base, sep, unit = text.rpartition("_")
    if sep and base and unit:
        return base.strip().lower(), unit.strip()
    return text.lower(), None


def _words(name: str) -> list[str]:
    """The words of a lower-case column name ('compressive load' -> ['compressive', 'load'])."""
    return re.split(r"[\s_\-/]+", name)


def _match_column(columns: list[str], quantity: str) -> str | None:
    names = [(_split_name(c)[0], c) for c in columns]
    for synonym in _QUANTITIES[quantity]:  # exact name first, in order of preference
        for name, col in names:
            if name == synonym:
                return col
    for synonym in _QUANTITIES[quantity]:  # then a word of the name ('Compressive load')
        for name, col in names:
            if synonym in _words(name):
                return col
    return None


def _unit_factor(source: Path, column: str, quantity: str, unit: str | None) -> float:
    if unit is None or unit == "":
        raise DataFileError(
            source, f"column {column!r} has no unit",
            f"name it like '{column} (N)' / '{column} (mm)' / '{column} (s)', or pass "
            f"units={{'{quantity}': ...}}",
        )
    unit = _UNIT_ALIASES.get(unit.strip(), unit.strip())
    try:
        return _FACTOR[quantity](unit)
    except InputError as exc:
        raise DataFileError(source, f"column {column!r}: {exc}") from None


def _numeric_column(df: pd.DataFrame, column: str, source: Path, first_line: int) -> np.ndarray:
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


def _sign(values: np.ndarray, given: int | None, what: str, column: str,
          source: Path) -> float:
    if given is not None:
        if given not in (1, -1):
            raise InputError(f"{what}_sign must be +1 or -1, got {given!r}")
        return float(given)
    change = values - values[0]
    total = float(np.sum(change))
    if total == 0.0 or not np.isfinite(total):
        raise DataFileError(source, f"column {column!r} never changes, so this is no "
                            "compression test", "check the file")
    return 1.0 if total > 0 else -1.0
