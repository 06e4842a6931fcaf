"""Paraboloid (Hertz) contact: F = (4/3)·E*·sqrt(R)·d^(3/2) (Hertz 1882; Johnson 1985, eq. 4.22).

This is the law the paper fits to its spherical tip.  For the exact sphere use :mod:`.sphere`.
"""

from __future__ import annotations

import numpy as np

__all__ = ["EXPONENT", "prefactor", "shape"]

EXPONENT = 1.5


def prefactor(radius: float) -> float:
    """Geometry factor g = (4/3)·sqrt(R) with F = E*·g·d^(3/2) [m^(1/2)]."""
    return 4.0 / 3.0 * np.sqrt(radius)


def shape(depth: np.ndarray, radius: float) -> np.ndarray:
    """F/E* = (4/3)·sqrt(R)·d^(3/2) [m²]; 0 for non-positive depth.

    Parameters
    ----------
    depth
        [m] Indentation depth.
    radius
        [m] Radius of curvature R at the apex.
    """
    d = np.clip(np.asarray(depth, dtype=float), 0.0, None)
    return prefactor(radius) * d * np.sqrt(d)
