"""Read uniaxial compression-test exports (Instron style) into SI arrays.

Two layouts are read without options, and others like them:

* the Instron 5900 exports in ``shared/data/phantom-compression``: a sample name, free header
  lines (``Compression test;``, ``Cylinder Diameter: 50mm;``, ``Cylinder Height: 30mm;``,
  ``Speed (mm/min): 10;``, ...), then ``Time (s),Compression (mm),Load (N),...`` with compression
  and load positive in compression;
* the simulator's exports (:func:`palpbayes.sim.write_compression_export`): header lines
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

import os
from collections.abc import Mapping
from pathlib import Path

import numpy as np
import pandas as pd

from ...errors import DataFileError
from .columns import (
    QUANTITY_NAMES,
    column_sign,
    export_column_values,
    match_column,
    name_words,
    split_column_name,
    unit_factor,
)
from .geometry import specimen_geometry
from .record import CompressionTest, material_from_label
from .text import (
    DELIMITERS,
    find_column_row,
    is_number,
    is_numeric_row,
    parse_header,
    read_lines,
    split_cells,
)

__all__ = ["read_compression_test", "looks_like_compression_test"]


def looks_like_compression_test(path: str | os.PathLike) -> bool:
    """True if ``path`` has a column row with displacement and load columns above numbers.

    Used to skip other CSV files (published tables, manifests) when scanning a folder; it reads
    the file but never raises.
    """
    try:
        lines, _ = read_lines(Path(path))
    except DataFileError:
        return False
    found = find_column_row(lines)
    if found is None:
        return False
    i, delimiter = found
    columns = split_cells(lines[i], delimiter)
    return (match_column(columns, "displacement") is not None
            and match_column(columns, "load") is not None)


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
    lines, encoding = read_lines(source)
    if not any(line.strip() for line in lines):
        raise DataFileError(source, "the file is empty", "export the test again")
    found = find_column_row(lines)
    if found is None:
        table = [i for i, line in enumerate(lines)
                 if any(sum(1 for c in split_cells(line, d) if c) >= 2 for d in DELIMITERS)]
        if any(is_numeric_row(split_cells(line, d)) for line in lines for d in DELIMITERS):
            problem = "no column-name row (e.g. 'Time (s),Compression (mm),Load (N)') above " \
                      "the numbers"
        elif table and any(line.strip() for line in lines[table[0] + 1:]):
            problem = (f"no rows of numbers under the column row {lines[table[0]].strip()!r}: "
                       "this is not a compression-test export")
        else:
            problem = "the file holds only a header, no data rows"
        raise DataFileError(source, problem, "export the test with its column names and data")
    col_row, delimiter = found
    header = parse_header(lines[:col_row])

    # the data block ends at the last line whose first cell is a number: a footer is dropped
    end = len(lines)
    while end > col_row + 1:
        cells = split_cells(lines[end - 1], delimiter)
        if cells and is_number(cells[0]):
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
    for quantity in QUANTITY_NAMES:
        explicit = (columns or {}).get(quantity)
        if explicit is not None:
            if explicit not in names:
                raise DataFileError(source, f"column {explicit!r} (given for {quantity}) is "
                                    f"missing; the file has {', '.join(names)}",
                                    "fix the column mapping")
            chosen[quantity] = explicit
            continue
        col = match_column(names, quantity)
        if col is None:
            wanted = " / ".join(n.capitalize() for n in QUANTITY_NAMES[quantity])
            raise DataFileError(source, f"no {quantity} column ({wanted}); the file has "
                                f"{', '.join(names)}",
                                f"add the column, or pass columns={{'{quantity}': ...}}")
        chosen[quantity] = col

    first_line = col_row + 2  # 1-based line number of the first data row
    values: dict[str, np.ndarray] = {}
    for quantity, col in chosen.items():
        unit = (units or {}).get(quantity) or split_column_name(col)[1]
        factor = unit_factor(source, col, quantity, unit)
        values[quantity] = export_column_values(df, col, source, first_line) * factor

    disp = values["displacement"]
    if "position" in name_words(split_column_name(chosen["displacement"])[0]):
        disp = disp - disp[0]  # an absolute coordinate: travel since the first sample
    disp = disp * column_sign(disp, compression_sign, "compression", chosen["displacement"], source)
    load = values["load"]
    load = load * column_sign(load, load_sign, "load", chosen["load"], source)

    area, height = specimen_geometry(source, header, area_m2, height_m)
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
