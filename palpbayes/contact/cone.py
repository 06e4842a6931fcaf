"""Conical indenter: F = (2/pi)·E*·tan(alpha)·d² (Sneddon 1965, eq. 6.4; Love 1939).

alpha is the half-opening angle (axis to flank); the profile is f(r) = r·cot(alpha), as in
nanite's ``hertz_cone``.
"""

from __future__ import annotations

import math

import numpy as np

from .registry import ContactLaw, register

__all__ = ["EXPONENT", "LAW", "contact_radius", "prefactor", "profile", "shape"]

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


def contact_radius(depth: np.ndarray, half_angle: float) -> np.ndarray:
    """Contact radius a = (2/pi)·d·tan(alpha) [m] (Sneddon 1965); 0 for non-positive depth."""
    return 2.0 / np.pi * np.tan(half_angle) * np.clip(np.asarray(depth, dtype=float), 0.0, None)


def profile(r: np.ndarray, half_angle: float) -> np.ndarray:
    """The cone's height above its apex, r·cot(alpha) [m]."""
    return np.asarray(r, dtype=float) / np.tan(half_angle)


#: The cone's entry of the registry (no length scale: ``scaled`` is None).
LAW = register(ContactLaw(
    kind="cone",
    parameters=("half_angle",),
    shape=lambda depth, tip: shape(depth, tip.half_angle),
    exponent=EXPONENT,
    prefactor=lambda tip: prefactor(tip.half_angle),
    reference=("I. N. Sneddon. The relation between load and penetration in the axisymmetric "
               "Boussinesq problem for a punch of arbitrary profile. International Journal of "
               "Engineering Science 3, 47–57 (1965), eq. 6.4; A. E. H. Love. Boussinesq's "
               "problem for a rigid cone. Quarterly Journal of Mathematics 10, 161–175 (1939)"),
    name="Sneddon cone",
    label="cone",
    summary="Cone of half-opening angle alpha: F = (2/pi)·E*·tan(alpha)·d² (Sneddon).",
    describe=lambda tip: f"cone alpha={math.degrees(tip.half_angle):g} deg",
    order=40,
    contact_radius=lambda depth, tip: contact_radius(depth, tip.half_angle),
    profile_exponent=lambda tip: 1.0,
    profile=lambda r, tip: profile(r, tip.half_angle),
))
