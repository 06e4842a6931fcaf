"""Unit factors to SI for lengths, forces and times found in data files.

Units are matched case-sensitively first; lengths and times then also case-insensitively
(``MM`` is mm), forces never (``MN`` is not ``mN``, ``PN`` is not ``pN``).  Micro is accepted as
``u``, the MICRO SIGN ``µ`` (U+00B5, what palpbayes prints, see :mod:`palpbayes.units`) and the
Greek ``μ`` (U+03BC).  AFM units are included: pm and nm, pN and nN.
"""

from __future__ import annotations

from ..errors import InputError

__all__ = ["length_factor", "force_factor", "time_factor", "LENGTH_UNITS", "FORCE_UNITS",
           "TIME_UNITS"]

LENGTH_UNITS = {"m": 1.0, "cm": 1e-2, "mm": 1e-3, "um": 1e-6, "µm": 1e-6, "μm": 1e-6,
                "nm": 1e-9, "pm": 1e-12}
FORCE_UNITS = {"N": 1.0, "kN": 1e3, "mN": 1e-3, "uN": 1e-6, "µN": 1e-6, "μN": 1e-6,
               "nN": 1e-9, "pN": 1e-12}
TIME_UNITS = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "µs": 1e-6, "min": 60.0, "h": 3600.0}


def _factor(unit: str, table: dict[str, float], what: str) -> float:
    key = str(unit).strip()
    if key in table:
        return table[key]
    lowered = {k.lower(): v for k, v in table.items()}
    if key.lower() in lowered and what != "force":  # 'MN' vs 'mN' must not be confused
        return lowered[key.lower()]
    raise InputError(
        f"unknown {what} unit {unit!r}; use one of {', '.join(sorted(set(table)))}"
    )


def length_factor(unit: str) -> float:
    """Factor converting a length in ``unit`` to metres."""
    return _factor(unit, LENGTH_UNITS, "length")


def force_factor(unit: str) -> float:
    """Factor converting a force in ``unit`` to newtons (case-sensitive: mN is not MN)."""
    return _factor(unit, FORCE_UNITS, "force")


def time_factor(unit: str) -> float:
    """Factor converting a time in ``unit`` to seconds."""
    return _factor(unit, TIME_UNITS, "time")
