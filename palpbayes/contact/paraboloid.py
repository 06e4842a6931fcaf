"""Paraboloid (Hertz) contact: F = (4/3)·E*·sqrt(R)·d^(3/2) (Hertz 1882; Johnson 1985, eq. 4.22).

This is the law the paper fits to its spherical tip.  For the exact sphere use :mod:`.sphere`.
"""

from __future__ import annotations

import numpy as np

from ..units import format_length
from .registry import ContactLaw, register, scale_radius

__all__ = ["EXPONENT", "LAW", "contact_radius", "prefactor", "profile", "shape"]

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


def contact_radius(depth: np.ndarray, radius: float) -> np.ndarray:
    """Hertz contact radius a = sqrt(R·d) [m]; 0 for non-positive depth."""
    return np.sqrt(radius * np.clip(np.asarray(depth, dtype=float), 0.0, None))


def profile(r: np.ndarray, radius: float) -> np.ndarray:
    """The tip's height above its apex, r²/(2R) [m]."""
    r = np.asarray(r, dtype=float)
    return r * r / (2.0 * radius)


#: The paraboloid's entry of the registry.
LAW = register(ContactLaw(
    kind="paraboloid",
    parameters=("radius",),
    shape=lambda depth, tip: shape(depth, tip.radius),
    exponent=EXPONENT,
    prefactor=lambda tip: prefactor(tip.radius),
    reference=("H. Hertz. Über die Berührung fester elastischer Körper. Journal für die reine "
               "und angewandte Mathematik 92, 156–171 (1882); K. L. Johnson. Contact "
               "Mechanics. Cambridge University Press (1985), eq. 4.22"),
    name="Hertz",
    label="paraboloid (Hertz)",
    summary="Paraboloid (Hertz) of radius R: F = (4/3)·E*·sqrt(R)·d^(3/2).",
    describe=lambda tip: f"paraboloid R={format_length(tip.radius, 6)}",
    order=30,
    scaled=scale_radius,
    contact_radius=lambda depth, tip: contact_radius(depth, tip.radius),
    profile_exponent=lambda tip: 2.0,
    max_depth=lambda tip: tip.radius,
    max_depth_name="tip radius",
    profile=lambda r, tip: profile(r, tip.radius),
))
