"""Conical indenter: F = (2/pi)·E*·tan(alpha)·d² (Sneddon 1965, eq. 6.4; Love 1939).

alpha is the half-opening angle (axis to flank); the profile is f(r) = r·cot(alpha), as in
nanite's ``hertz_cone``.
"""

from __future__ import annotations

import numpy as np

__all__ = ["EXPONENT", "prefactor", "shape"]

EXPONENT = 2.0


def prefactor(half_angle: float) -> float:
    """Geometry factor g = (2/pi)·tan(alpha) with F = E*·g·d² [-]."""
    return 2.0 / np.pi * np.tan(half_angle)


def shape(depth: np.ndarray, half_angle: float) -> np.ndarray:
    """F/E* = (2/pi)·tan(alpha)·d² [m²]; 0 for non-positive depth.

    Parameters
    ----------
    depth
        [m] Indentation depth.
    half_angle
        [rad] Half-opening angle alpha.
    """
    d = np.clip(np.asarray(depth, dtype=float), 0.0, None)
    return prefactor(half_angle) * d * d
