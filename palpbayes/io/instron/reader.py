"""Read uniaxial compression-test exports (Instron style) into SI arrays.

Two layouts are read without options, and others like them:

* the Instron 5900 exports in ``shared/data/phantom-compression``: a sample name, free header
  lines (``Compression test;``, ``Cylinder Diameter: 50mm;``, ``Cylinder Height: 30mm;``,
  ``Speed (mm/min): 10;``, ...), then ``Time (s),Compression (mm),Load (N),...`` with compression
  and load positive in compression;
* the simulator's exports (:func:`palpbayes.simulate.write_compression_export`): header lines
  ``Block Width: 50mm;``, ``Block Length: 50mm;``, ``Block Height: 20mm;`` ..., then
  ``Time (s),Extension (mm),Load (kN)`` with extension and load **negative** in compression.

Rules
-----
Column row
    The first row with at least two cells that is followed by a row of numbers.  Everything
    above it is the header; ``Key: value;`` lines become ``header[key] = value``, the first free
    line is the ``"Sample name"``, other free lines ``"Line <n>"``.
Columns
    Time (``Time``), displacement (``Compression``, ``Extension``, ``Displacement``,
    ``Deflection``, ``Position``) and load (``Load``, ``Force``), the unit in brackets
    (``Load (kN)``, ``Time [ms]``) or as a suffix (``load_kn``): s/ms/min, m/mm/µm/um,
    N/kN/mN/µN/uN/nN/pN (lower-case suffixes ``_un``, ``_nn``, ``_pn`` too).
    ``Position`` is an absolute coordinate, so its first value is subtracted.
Signs
    Compression and load are returned positive in compression.  A displacement that mostly
    decreases from its first value, or a load that is mostly negative, is flipped (override with
    ``compression_sign`` / ``load_sign``).
Geometry
    Cross-section [m²] from an ``Area`` line, else ``Cylinder Diameter`` (pi·d²/4), else
    ``Block Width`` × ``Block Length``; height [m] from a ``... Height`` or ``Thickness`` line.
    The keywords ``area_m2`` and ``height_m`` take precedence over the header.
Tail and bad cells
    Blank lines and lines whose first cell is not a number at the end of the file (a footer)
    are dropped; any other blank or non-numeric cell in the time, displacement or load column
    raises :class:`~palpbayes.errors.DataFileError` with its line number and column.
"""

from __future__ import annotations

import csv
import math
import os
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from ..errors import DataFileError, InputError
from .units import force_factor, length_factor, time_factor

__all__ = [
    "CompressionTest",
    "read_compression_test",
    "looks_like_compression_test",
    "material_from_label",
    "DISPLACEMENT_NAMES",
    "LOAD_NAMES",
    "TIME_NAMES",
]

#: Column-name synonyms, in order of preference (lower case).
TIME_NAMES = ("time",)
DISPLACEMENT_NAMES = ("compression", "extension", "displacement", "deflection", "position")
LOAD_NAMES = ("load", "force")

_QUANTITIES = {"time": TIME_NAMES, "displacement": DISPLACEMENT_NAMES, "load": LOAD_NAMES}
_FACTOR = {"time": time_factor, "displacement": length_factor, "load": force_factor}
_UNIT_ALIASES = {"sec": "s", "secs": "s", "seconds": "s", "mins": "min", "minutes": "min",
                 "msec": "ms", "micron": "µm", "microns": "µm", "n": "N", "kn": "kN",
                 "un": "uN", "µn": "µN", "μn": "μN", "nn": "nN", "pn": "pN"}
_AREA_UNITS = {"m2": 1.0, "m²": 1.0, "m^2": 1.0, "cm2": 1e-4, "cm²": 1e-4, "cm^2": 1e-4,
               "mm2": 1e-6, "mm²": 1e-6, "mm^2": 1e-6}
_DELIMITERS = (",", "\t", ";")
_NUMBER = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(.*?)\s*$")
_BRACKET_UNIT = re.compile(r"^(?P<name>.*?)\s*[\(\[]\s*(?P<unit>[^\)\]]*?)\s*[\)\]]\s*$")
_SUFFIX = re.compile(r"[_\-\s](?:[A-Za-z]{1,2}\d+|[A-Za-z]_?sample_?\d+|sample_?\d+)$",
                     re.IGNORECASE)
#: Fewer data rows than this cannot give a modulus with an error bar.
MIN_ROWS = 3


@dataclass(frozen=True, eq=False)
class CompressionTest:
    """One uniaxial compression test in SI units.

    Parameters
    ----------
    time_s
        [s] Sample times.
    compression_m
        [m] Platen travel since the first sample, positive in compression.
    load_n
        [N] Load, positive in compression.
    specimen, material
        Labels (``material`` groups specimens for the summary).
    area_m2
        [m²] Initial cross-section of the specimen.
    height_m
        [m] Initial height of the specimen (loading direction).
    source
        The file read (or a description of the data's origin).
    header
        Header lines of the export, ``key -> value`` as strings.
    """

    time_s: np.ndarray
    compression_m: np.ndarray
    load_n: np.ndarray
    specimen: str
    material: str
    area_m2: float
    height_m: float
    source: str = ""
    header: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        where = self.source or f"compression test {self.specimen!r}"
        arrays = {}
        for name in ("time_s", "compression_m", "load_n"):
            a = np.asarray(getattr(self, name), dtype=float)
            if a.ndim != 1:
                raise DataFileError(where, f"{name} must be one-dimensional, got shape {a.shape}")
            if not np.all(np.isfinite(a)):
                raise DataFileError(where, f"{name} holds NaN or infinite values")
            arrays[name] = a
        sizes = {a.size for a in arrays.values()}
        if len(sizes) != 1:
            raise DataFileError(where, "time_s, compression_m and load_n differ in length "
                                f"({', '.join(str(a.size) for a in arrays.values())})")
        if arrays["time_s"].size < MIN_ROWS:
            raise DataFileError(where, f"only {arrays['time_s'].size} data row(s); a compression "
                                f"test needs at least {MIN_ROWS}")
        for name in ("area_m2", "height_m"):
            v = getattr(self, name)
            if not (isinstance(v, int | float | np.floating | np.integer)
                    and math.isfinite(v) and v > 0):
                raise DataFileError(where, f"{name} must be a positive number of metres "
                                    f"(squared for the area), got {v!r}",
                                    f"pass {name}= or fix the geometry in the header")
            object.__setattr__(self, name, float(v))
        for name, a in arrays.items():
            a.setflags(write=False)
            object.__setattr__(self, name, a)

    @property
    def n_points(self) -> int:
        """Number of samples."""
        return int(self.time_s.size)

    @property
    def strain(self) -> np.ndarray:
        """[-] Engineering strain, compression / height (positive in compression)."""
        return self.compression_m / self.height_m

    @property
    def stress_pa(self) -> np.ndarray:
        """[Pa] Engineering stress, load / initial area (positive in compression)."""
        return self.load_n / self.area_m2


# ----------------------------------------------------------------------------- labels


def material_from_label(label: str) -> str:
    """Material of a specimen label: strip a trailing replicate suffix.

    ``EF10_50T_A1`` -> ``EF10_50T``, ``White_S1`` -> ``White``,
    ``EF10_50T_A_sample_1`` -> ``EF10_50T``; a label without such a suffix is returned as is.
    """
    label = str(label).strip()
    stripped = _SUFFIX.sub("", label)
    return stripped or label


# ----------------------------------------------------------------------------- text level


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


# ----------------------------------------------------------------------------- columns


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


def _match_column(columns: list[str], quantity: str) -> str | None:
    names = [(_split_name(c)[0], c) for c in columns]
    for synonym in _QUANTITIES[quantity]:  # exact name first, in order of preference
        for name, col in names:
            if name == synonym:
                return col
    for synonym in _QUANTITIES[quantity]:  # then a word of the name ('Compressive load')
        for name, col in names:
            if synonym in re.split(r"[\s_\-/]+", name):
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


def _length_value(source: Path, key: str, value: str) -> float:
    """[m] from a header value like '50mm' (or '50' with the unit in the key, 'Height (mm)')."""
    m = _NUMBER.match(value)
    key_unit = _BRACKET_UNIT.match(key)
    if m:
        number, unit = float(m.group(1)), m.group(2).strip().rstrip(";").strip()
        if not unit and key_unit:
            unit = key_unit.group("unit")
        if unit:
            try:
                return number * length_factor(_UNIT_ALIASES.get(unit, unit))
            except InputError:
                pass
    raise DataFileError(source, f"header line '{key}: {value}' is not a length with a unit",
                        f"write it like '{key}: 30mm;'")


def _area_value(source: Path, key: str, value: str) -> float:
    m = _NUMBER.match(value)
    key_unit = _BRACKET_UNIT.match(key)
    if m:
        number, unit = float(m.group(1)), m.group(2).strip().rstrip(";").strip()
        if not unit and key_unit:
            unit = key_unit.group("unit")
        unit = unit.replace(" ", "")
        if unit in _AREA_UNITS:
            return number * _AREA_UNITS[unit]
    raise DataFileError(source, f"header line '{key}: {value}' is not an area with a unit",
                        f"write it like '{key}: 1963.5mm^2;'")


def _header_key(header: Mapping[str, str], *endings: str) -> str | None:
    for key in header:
        name = _BRACKET_UNIT.match(key)
        base = (name.group("name") if name else key).strip().lower()
        if "gauge" in base or "speed" in base or "rate" in base:
            continue
        if any(base == e or base.endswith(" " + e) for e in endings):
            return key
    return None


_GEOMETRY_HELP_AREA = ("add a header line 'Cylinder Diameter: 50mm;' or 'Block Width: 50mm;' and "
                       "'Block Length: 50mm;', or pass area_m2= (command line: --area-m2)")
_GEOMETRY_HELP_HEIGHT = ("add a header line 'Cylinder Height: 30mm;' (or 'Block Height: ...;'), "
                         "or pass height_m= (command line: --height-m)")


def _geometry(source: Path, header: Mapping[str, str], area_m2: float | None,
              height_m: float | None) -> tuple[float, float]:
    if area_m2 is None:
        key = _header_key(header, "area")
        if key is not None:
            area_m2 = _area_value(source, key, header[key])
        elif (key := _header_key(header, "diameter")) is not None:
            area_m2 = math.pi * _length_value(source, key, header[key]) ** 2 / 4.0
        else:
            wk = _header_key(header, "width")
            lk = _header_key(header, "length", "depth")
            if wk is not None and lk is not None:
                area_m2 = (_length_value(source, wk, header[wk])
                           * _length_value(source, lk, header[lk]))
            else:
                missing = ("a 'Block Length' line" if wk is not None else
                           "a 'Block Width' line" if lk is not None else
                           "the specimen cross-section")
                raise DataFileError(source, f"the header gives no {missing}",
                                    _GEOMETRY_HELP_AREA)
    if height_m is None:
        key = _header_key(header, "height", "thickness")
        if key is None:
            raise DataFileError(source, "the header gives no specimen height",
                                _GEOMETRY_HELP_HEIGHT)
        height_m = _length_value(source, key, header[key])
    for name, v in (("area_m2", area_m2), ("height_m", height_m)):
        if not (math.isfinite(v) and v > 0):
            raise DataFileError(source, f"{name} must be positive, got {v!r}",
                                "fix the header or the option")
    return float(area_m2), float(height_m)


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


# ----------------------------------------------------------------------------- public


def looks_like_compression_test(path: str | os.PathLike) -> bool:
    """True if ``path`` has a column row with displacement and load columns above numbers.

    Used to skip other CSV files (published tables, manifests) when scanning a folder; it reads
    the file but never raises.
    """
    try:
        lines, _ = _read_lines(Path(path))
    except DataFileError:
        return False
    found = _find_column_row(lines)
    if found is None:
        return False
    i, delimiter = found
    columns = _cells(lines[i], delimiter)
    return (_match_column(columns, "displacement") is not None
            and _match_column(columns, "load") is not None)


def read_compression_test(
    path: str | os.PathLike,
    *,
    area_m2: float | None = None,
    height_m: float | None = None,
    specimen: str | None = None,
    material: str | None = None,
    columns: Mapping[str, str] | None = None,
    units: Mapping[str, str] | None = None,
    compression_sign: int | None = None,
    load_sign: int | None = None,
) -> CompressionTest:
    """Read one compression-test export (see the module docstring for the rules).

    Parameters
    ----------
    path
        The export (CSV with a free header).
    area_m2
        [m²] Initial cross-section; overrides the header.
    height_m
        [m] Initial height; overrides the header.
    specimen
        Specimen label; default the file stem (``EF10_50T_A1``).
    material
        Material label; default the specimen label without its replicate suffix
        (``EF10_50T_A1`` -> ``EF10_50T``, ``White_S1`` -> ``White``).
    columns
        Explicit column names, keys ``time``, ``displacement``, ``load``.
    units
        Units for columns whose name carries none, keys as for ``columns``.
    compression_sign, load_sign
        +1 or -1 to multiply the file's values by, instead of detecting the sign.

    Returns
    -------
    CompressionTest
        Arrays in SI units, compression and load positive in compression.

    Raises
    ------
    DataFileError
        Empty file, no column row or no data (header only), a missing column, a blank or
        non-numeric cell in the data (line and column named), unknown units, or missing
        geometry (naming the header line or option needed).
    """
    source = Path(path)
    lines, encoding = _read_lines(source)
    if not any(line.strip() for line in lines):
        raise DataFileError(source, "the file is empty", "export the test again")
    found = _find_column_row(lines)
    if found is None:
        table = [i for i, line in enumerate(lines)
                 if any(sum(1 for c in _cells(line, d) if c) >= 2 for d in _DELIMITERS)]
        if any(_is_numeric_row(_cells(line, d)) for line in lines for d in _DELIMITERS):
            problem = "no column-name row (e.g. 'Time (s),Compression (mm),Load (N)') above " \
                      "the numbers"
        elif table and any(line.strip() for line in lines[table[0] + 1:]):
            problem = (f"no rows of numbers under the column row {lines[table[0]].strip()!r}: "
                       "this is not a compression-test export")
        else:
            problem = "the file holds only a header, no data rows"
        raise DataFileError(source, problem, "export the test with its column names and data")
    col_row, delimiter = found
    header = _parse_header(lines[:col_row])

    # the data block ends at the last line whose first cell is a number: a footer is dropped
    end = len(lines)
    while end > col_row + 1:
        cells = _cells(lines[end - 1], delimiter)
        if cells and _is_number(cells[0]):
            break
        end -= 1
    n_rows = end - col_row - 1
    try:
        df = pd.read_csv(source, sep=delimiter, skiprows=col_row, header=0, nrows=n_rows,
                         dtype=str, skip_blank_lines=False, skipinitialspace=True,
                         encoding=encoding, keep_default_na=False, engine="python")
    except (pd.errors.ParserError, ValueError) as exc:
        raise DataFileError(source, f"cannot be parsed as a table below line {col_row + 1} "
                            f"({str(exc).strip().splitlines()[-1]})",
                            "every data row must have the same cells as the column row") \
            from None
    df.columns = [str(c).strip() for c in df.columns]
    names = list(df.columns)

    chosen: dict[str, str] = {}
    for quantity in _QUANTITIES:
        explicit = (columns or {}).get(quantity)
        if explicit is not None:
            if explicit not in names:
                raise DataFileError(source, f"column {explicit!r} (given for {quantity}) is "
                                    f"missing; the file has {', '.join(names)}",
                                    "fix the column mapping")
            chosen[quantity] = explicit
            continue
        col = _match_column(names, quantity)
        if col is None:
            wanted = " / ".join(n.capitalize() for n in _QUANTITIES[quantity])
            raise DataFileError(source, f"no {quantity} column ({wanted}); the file has "
                                f"{', '.join(names)}",
                                f"add the column, or pass columns={{'{quantity}': ...}}")
        chosen[quantity] = col

    first_line = col_row + 2  # 1-based line number of the first data row
    values: dict[str, np.ndarray] = {}
    for quantity, col in chosen.items():
        unit = (units or {}).get(quantity) or _split_name(col)[1]
        factor = _unit_factor(source, col, quantity, unit)
        values[quantity] = _numeric_column(df, col, source, first_line) * factor

    disp = values["displacement"]
    if "position" in re.split(r"[\s_\-/]+", _split_name(chosen["displacement"])[0]):
        disp = disp - disp[0]  # an absolute coordinate: travel since the first sample
    disp = disp * _sign(disp, compression_sign, "compression", chosen["displacement"], source)
    load = values["load"]
    load = load * _sign(load, load_sign, "load", chosen["load"], source)

    area, height = _geometry(source, header, area_m2, height_m)
    label = specimen if specimen is not None else source.stem
    return CompressionTest(
        time_s=values["time"],
        compression_m=disp + 0.0,
        load_n=load + 0.0,
        specimen=str(label),
        material=str(material) if material is not None else material_from_label(label),
        area_m2=area,
        height_m=height,
        source=str(source),
        header=header,
    )
