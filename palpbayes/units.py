"""Placeholder of the unit-formatting helpers (replaced by the units-msgs branch)."""

from __future__ import annotations

import math

__all__ = ["format_force", "format_length", "format_pressure"]


def _fmt(x: float, unit: str, prefixes, digits: int = 3) -> str:
    if not math.isfinite(x) or x == 0:
        return f"{x:g} {unit}"
    for p, f in prefixes:
        if abs(x) >= f * 0.9995:
            return f"{x / f:.{digits}g} {p}{unit}"
    p, f = prefixes[-1]
    return f"{x / f:.{digits}g} {p}{unit}"


_P = [("k", 1e3), ("", 1.0), ("m", 1e-3), ("µ", 1e-6), ("n", 1e-9), ("p", 1e-12)]


def format_force(x: float, digits: int = 3) -> str:
    return _fmt(float(x), "N", _P, digits)


def format_length(x: float, digits: int = 3) -> str:
    return _fmt(float(x), "m", _P[1:], digits)


def format_pressure(x: float, digits: int = 3) -> str:
    return _fmt(float(x), "Pa", [("G", 1e9), ("M", 1e6), ("k", 1e3), ("", 1.0)], digits)
