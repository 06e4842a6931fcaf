"""Specimen geometry from the header of a compression-test export: cross-section and height.

Cross-section [m²] from an ``Area`` line, else ``Cylinder Diameter`` (pi·d²/4), else
``Block Width`` × ``Block Length``; height [m] from a ``... Height`` or ``Thickness`` line.
Values carry their unit (``50mm``, ``1963.5mm^2``) or take it from the key (``Height (mm): 30``).
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Mapping
from pathlib import Path

from ...errors import DataFileError, InputError
from ..units import length_factor
from .columns import BRACKET_UNIT, UNIT_ALIASES

__all__ = ["specimen_geometry"]

_AREA_UNITS = {"m2": 1.0, "m²": 1.0, "m^2": 1.0, "cm2": 1e-4, "cm²": 1e-4, "cm^2": 1e-4,
               "mm2": 1e-6, "mm²": 1e-6, "mm^2": 1e-6}
_NUMBER = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(.*?)\s*$")


def _length_unit(unit: str) -> float | None:
    """[m] per ``unit`` ('mm', 'microns', ...), None if it is no length unit."""
    if not unit:
        return None
    try:
        return length_factor(UNIT_ALIASES.get(unit, unit))
    except InputError:
        return None


def _area_unit(unit: str) -> float | None:
    """[m²] per ``unit`` ('mm^2', 'cm²', ...), None if it is no area unit."""
    return _AREA_UNITS.get(unit.replace(" ", ""))


#: kind -> (unit -> SI factor or None, what it is, an example value).
_HEADER_QUANTITIES: dict[str, tuple[Callable[[str], float | None], str, str]] = {
    "length": (_length_unit, "a length", "30mm"),
    "area": (_area_unit, "an area", "1963.5mm^2"),
}


def _header_value(source: Path, key: str, value: str, kind: str) -> float:
    """SI value of a header line ``key: value`` holding a ``kind`` ("length" [m], "area" [m²]).

    The unit follows the number ('50mm') or, when it does not, is the key's ('Height (mm)').
    """
    to_si, what, example = _HEADER_QUANTITIES[kind]
    m = _NUMBER.match(value)
    key_unit = BRACKET_UNIT.match(key)
    if m:
        number, unit = float(m.group(1)), m.group(2).strip().rstrip(";").strip()
        if not unit and key_unit:
            unit = key_unit.group("unit")
        factor = to_si(unit)
        if factor is not None:
            return number * factor
    raise DataFileError(source, f"header line '{key}: {value}' is not {what} with a unit",
                        f"write it like '{key}: {example};'")


def _header_key(header: Mapping[str, str], *endings: str) -> str | None:
    for key in header:
        name = BRACKET_UNIT.match(key)
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


def specimen_geometry(source: Path, header: Mapping[str, str], area_m2: float | None,
                      height_m: float | None) -> tuple[float, float]:
    """([m²], [m]) cross-section and height: the arguments when given, else the header's."""
    if area_m2 is None:
        key = _header_key(header, "area")
        if key is not None:
            area_m2 = _header_value(source, key, header[key], "area")
        elif (key := _header_key(header, "diameter")) is not None:
            area_m2 = math.pi * _header_value(source, key, header[key], "length") ** 2 / 4.0
        else:
            wk = _header_key(header, "width")
            lk = _header_key(header, "length", "depth")
            if wk is not None and lk is not None:
                area_m2 = (_header_value(source, wk, header[wk], "length")
                           * _header_value(source, lk, header[lk], "length"))
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
        height_m = _header_value(source, key, header[key], "length")
    for name, v in (("area_m2", area_m2), ("height_m", height_m)):
        if not (math.isfinite(v) and v > 0):
            raise DataFileError(source, f"{name} must be positive, got {v!r}",
                                "fix the header or the option")
    return float(area_m2), float(height_m)
