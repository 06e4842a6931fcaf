"""Cylindrical flat punch of radius a: F = 2·a·E*·d (Boussinesq 1885; Sneddon 1965, eq. 6.5)."""

from __future__ import annotations

import math

import numpy as np

from ..units import format_length
from .registry import ContactLaw, register, scale_radius

__all__ = ["EXPONENT", "LAW", "prefactor", "profile", "shape"]

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


def profile(r: np.ndarray, radius: float) -> np.ndarray:
    """The punch's face: height 0 [m] for r <= a, ``inf`` beyond (no surface there)."""
    r = np.asarray(r, dtype=float)
    return np.where(r <= radius * (1.0 + 1e-12), 0.0, np.inf)


#: The flat punch's entry of the registry.
LAW = register(ContactLaw(
    kind="flat",
    parameters=("radius",),
    shape=lambda depth, tip: shape(depth, tip.radius),
    exponent=EXPONENT,
    prefactor=lambda tip: prefactor(tip.radius),
    reference=("J. Boussinesq. Application des potentiels à l'étude de l'équilibre et du "
               "mouvement des solides élastiques. Gauthier-Villars, Paris (1885); I. N. Sneddon. "
               "The relation between load and penetration in the axisymmetric Boussinesq "
               "problem for a punch of arbitrary profile. International Journal of Engineering "
               "Science 3, 47–57 (1965), eq. 6.5"),
    name="flat-punch",
    label="flat punch",
    summary="Flat punch of radius a: F = 2·a·E*·d.",
    describe=lambda tip: f"flat a={format_length(tip.radius, 6)}",
    order=10,
    scaled=scale_radius,
    # on a layer: Hayes et al. (1972)'s punch, solved for any nu and base (.layer)
    contact_radius=lambda depth, tip: np.full(np.shape(depth), float(tip.radius)),
    profile_exponent=lambda tip: math.inf,
    profile=lambda r, tip: profile(r, tip.radius),
    default_fit_fraction=0.2,  # the paper's: the start of a flat punch's contact is not linear
))
