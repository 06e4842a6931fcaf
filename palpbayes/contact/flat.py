"""Cylindrical flat punch of radius a: F = 2·a·E*·d (Boussinesq 1885; Sneddon 1965, eq. 6.5)."""

from __future__ import annotations

import numpy as np

__all__ = ["EXPONENT", "prefactor", "shape"]

#: Force exponent m in F = k·d^m.
EXPONENT = 1.0


def prefactor(radius: float) -> float:
    """Geometry factor g = 2a with F = E*·g·d [m]."""
    return 2.0 * radius


def shape(depth: np.ndarray, radius: float) -> np.ndarray:
    """F/E* = 2·a·d [m²]; 0 for non-positive depth.

    Parameters
    ----------
    depth
        [m] Indentation depth.
    radius
        [m] Punch radius a.
    """
    d = np.clip(np.asarray(depth, dtype=float), 0.0, None)
    return 2.0 * radius * d
