"""Contact laws for rigid axisymmetric tips on an elastic half-space (docs/design.md §1).

Every law is written as F = E*·s(d), with E* = E/(1-nu²) the effective modulus and s(d) the
*shape function* [m²] of the tip (0 for d <= 0).  Power laws have s(d) = g·d^m, so
F = k·d^m with k = E*·g; the exact sphere has no power form but stays linear in E*.  An optional
finite-thickness factor (see :mod:`.thickness`) multiplies s(d).

The registry :data:`LAWS` maps each tip kind to its law::

    >>> from palpbayes.contact import Tip, force
    >>> round(float(force(1e-3, E=100e3, nu=0.3, tip=Tip("paraboloid", radius=0.01))), 4)
    0.4633
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..errors import GeometryError
from ..units import format_length
from . import cone, flat, mdr, paraboloid, sphere, thickness
from .geometry import TIP_KINDS, Tip

__all__ = [
    "Tip",
    "TIP_KINDS",
    "ContactLaw",
    "LAWS",
    "get_law",
    "shape",
    "force",
    "force_star",
    "exponent",
    "prefactor",
    "effective_modulus",
    "youngs_modulus",
    "k_from_modulus",
    "modulus_from_k",
    "check_nu",
    "check_tip_plausible",
    "MAX_TIP_RADIUS_M",
    "half_angle_from_degrees",
    "thickness_factor",
]


@dataclass(frozen=True)
class ContactLaw:
    """One entry of the registry.

    Attributes
    ----------
    kind
        Tip kind.
    shape
        ``shape(depth, tip) -> F/E*`` [m²] on the half-space.
    exponent
        ``exponent(tip) -> m`` or None when the law is not a power law.
    prefactor
        ``prefactor(tip) -> g`` [m^(2-m)] with s = g·d^m, or None.
    reference
        Where the law comes from.
    """

    kind: str
    shape: Callable[[np.ndarray, Tip], np.ndarray]
    exponent: Callable[[Tip], float | None]
    prefactor: Callable[[Tip], float | None]
    reference: str


LAWS: dict[str, ContactLaw] = {
    "flat": ContactLaw(
        "flat",
        lambda d, t: flat.shape(d, t.radius),
        lambda t: flat.EXPONENT,
        lambda t: flat.prefactor(t.radius),
        "Boussinesq 1885; Sneddon 1965",
    ),
    "paraboloid": ContactLaw(
        "paraboloid",
        lambda d, t: paraboloid.shape(d, t.radius),
        lambda t: paraboloid.EXPONENT,
        lambda t: paraboloid.prefactor(t.radius),
        "Hertz 1882",
    ),
    "sphere": ContactLaw(
        "sphere",
        lambda d, t: sphere.shape(d, t.radius),
        lambda t: None,
        lambda t: None,
        "Sneddon 1965 (exact sphere)",
    ),
    "cone": ContactLaw(
        "cone",
        lambda d, t: cone.shape(d, t.half_angle),
        lambda t: cone.EXPONENT,
        lambda t: cone.prefactor(t.half_angle),
        "Sneddon 1965",
    ),
    "power": ContactLaw(
        "power",
        lambda d, t: mdr.shape(d, t.c, t.n),
        lambda t: mdr.power_law_exponent(t.n),
        lambda t: mdr.power_law_prefactor(t.c, t.n),
        "Popov & Hess 2015 (MDR)",
    ),
}


def get_law(tip: Tip) -> ContactLaw:
    """The registry entry for ``tip.kind``."""
    return LAWS[tip.kind]


def check_nu(nu: float) -> float:
    """Validate a Poisson ratio: finite and 0 <= nu <= 0.5 (0.5: incompressible, the usual
    choice for silicone, gels and tissue); return it as float.  Corrections undefined at 0.5
    refuse it themselves."""
    try:
        v = float(nu)
    except (TypeError, ValueError):
        raise GeometryError(f"Poisson ratio {nu!r} is not a number") from None
    if not (math.isfinite(v) and 0.0 <= v <= 0.5):
        raise GeometryError(
            f"Poisson ratio nu = {nu!r} is outside [0, 0.5]; "
            "give a value such as 0.3 for foam or 0.49 for silicone"
        )
    return v


#: [m] Largest plausible tip radius for palpation; a larger radius was almost surely given in mm.
MAX_TIP_RADIUS_M = 0.1


def _mm_as_metres(value: float) -> str:
    """``value`` divided by 1000, written like 0.010 or 0.0117 (the value if it was in mm)."""
    v = value * 1e-3
    text = f"{v:.3f}"
    return text if abs(float(text) - v) <= 1e-12 else f"{v:.4g}"


def check_tip_plausible(tip: Tip) -> None:
    """Reject a tip whose size cannot be meant for palpation (a unit slip).

    A radius (flat, paraboloid, sphere) above :data:`MAX_TIP_RADIUS_M` = 0.1 m is taken for a
    value in millimetres given as metres (``--radius 10`` for a 10 mm tip).

    Raises
    ------
    GeometryError
        Naming the radius and the value in metres it probably should be.
    """
    if tip.radius is not None and tip.radius > MAX_TIP_RADIUS_M:
        raise GeometryError(
            f"tip radius {format_length(tip.radius, 6)} is implausibly large for palpation (more "
            f"than {format_length(MAX_TIP_RADIUS_M)}); --radius is in metres (so is the "
            "manifest's radius_m): "
            f"did you mean {_mm_as_metres(tip.radius)}?"
        )


def half_angle_from_degrees(degrees) -> float:
    """A cone half-opening angle given in degrees, validated, as radians [rad].

    The command line (``--half-angle``) and the manifest (``half_angle_deg``) give the angle in
    degrees while :class:`Tip` takes radians; validating here keeps the error in the user's
    unit.

    Raises
    ------
    GeometryError
        If the angle is not a number strictly between 0 and 90 degrees.
    """
    try:
        v = float(degrees)
    except (TypeError, ValueError):
        raise GeometryError(f"cone half-angle {degrees!r} deg is not a number "
                            "(give --half-angle / half_angle_deg in degrees, e.g. 70)") from None
    if not (math.isfinite(v) and 0.0 < v < 90.0):
        raise GeometryError(
            f"cone half-angle {degrees!r} deg must lie strictly between 0 and 90 deg (the "
            "half-opening angle, axis to flank, in degrees: --half-angle / half_angle_deg)"
        )
    return math.radians(v)


def effective_modulus(E, nu: float):
    """E* = E/(1-nu²) [Pa]."""
    return E / (1.0 - nu * nu)


def youngs_modulus(Estar, nu: float):
    """E = E*·(1-nu²) [Pa]."""
    return Estar * (1.0 - nu * nu)


def thickness_factor(
    depth: np.ndarray, tip: Tip, thickness_m: float, nu: float, bonded: bool = True
) -> np.ndarray:
    """Finite-thickness factor on the force for ``tip`` on a layer of thickness h [m].

    Dimitriadis et al. (2002) for paraboloid and sphere, Hayes et al. (1972) for the bonded flat
    punch; see :mod:`palpbayes.contact.thickness` for sources and validity.

    Raises
    ------
    GeometryError
        For cone and power-law tips (no published correction implemented), for a non-bonded
        flat punch, or outside the correction's range (Dimitriadis: chi = sqrt(R·d)/h <= 1;
        Hayes: a/h <= 1 and 0.2 <= nu <= 0.5).
    """
    if not (thickness_m is not None and math.isfinite(thickness_m) and thickness_m > 0):
        raise GeometryError(f"specimen thickness {thickness_m!r} m must be positive")
    depth = np.asarray(depth, dtype=float)
    if tip.kind in ("paraboloid", "sphere"):
        return thickness.dimitriadis_factor(depth, tip.radius, thickness_m, nu, bonded)
    if tip.kind == "flat":
        if not bonded:
            raise GeometryError(
                "no non-bonded finite-thickness correction for the flat punch; drop "
                "--non-bonded (bonded=True in the API) or switch the correction off (drop "
                "--finite-thickness)"
            )
        return np.full_like(depth, thickness.hayes_kappa(tip.radius, thickness_m, nu))
    raise GeometryError(
        f"no finite-thickness correction for tip '{tip.kind}' (only paraboloid, sphere and flat "
        "have one); switch the correction off: drop --finite-thickness on the command line "
        "(thickness_correction=False, or thickness_m=None, in the API)"
    )


def shape(
    depth: np.ndarray,
    tip: Tip,
    *,
    thickness_m: float | None = None,
    nu: float | None = None,
    bonded: bool = True,
) -> np.ndarray:
    """Force per unit effective modulus F/E* [m²] (0 for non-positive depth).

    Parameters
    ----------
    depth
        [m] Indentation depth d = z_surf - z_tip, any shape.
    tip
        The indenter.
    thickness_m
        [m] Specimen thickness for the finite-thickness correction; None for a half-space.
    nu
        Poisson ratio [-], needed only with ``thickness_m``.
    bonded
        Specimen bonded to the base (finite-thickness correction only).
    """
    s = get_law(tip).shape(depth, tip)
    if thickness_m is not None:
        if nu is None:
            raise GeometryError("the finite-thickness correction needs the Poisson ratio nu")
        s = s * thickness_factor(depth, tip, thickness_m, nu, bonded)
    return s


def force_star(depth: np.ndarray, Estar, tip: Tip, **kwargs) -> np.ndarray:
    """Force F = E*·s(d) [N] for effective modulus E* [Pa]; keywords as :func:`shape`."""
    return Estar * shape(depth, tip, **kwargs)


def force(
    depth: np.ndarray,
    E,
    nu: float,
    tip: Tip,
    *,
    thickness_m: float | None = None,
    bonded: bool = True,
) -> np.ndarray:
    """Contact force F [N] of ``tip`` pressed ``depth`` [m] into a material (E [Pa], nu [-]).

    F = E/(1-nu²)·s(d); 0 for non-positive depth.  Vectorised over ``depth`` (and ``E`` by
    broadcasting).
    """
    nu = check_nu(nu)
    s = shape(depth, tip, thickness_m=thickness_m, nu=nu, bonded=bonded)
    return effective_modulus(E, nu) * s


def exponent(tip: Tip) -> float | None:
    """Exponent m of F = k·d^m, or None for the exact sphere."""
    return get_law(tip).exponent(tip)


def prefactor(tip: Tip) -> float | None:
    """Geometry factor g of s(d) = g·d^m [m^(2-m)], or None for the exact sphere."""
    return get_law(tip).prefactor(tip)


def _power_prefactor(tip: Tip) -> float:
    g = prefactor(tip)
    if g is None:
        raise GeometryError(
            f"tip '{tip.kind}' has no power-law form F = k*d^m; use tip 'paraboloid' for the "
            "Hertz approximation"
        )
    return g


def k_from_modulus(E, nu: float, tip: Tip):
    """Power-law prefactor k = E/(1-nu²)·g of F = k·d^m [N/m^m]."""
    return effective_modulus(E, check_nu(nu)) * _power_prefactor(tip)


def modulus_from_k(k, nu: float, tip: Tip):
    """Young's modulus E = k·(1-nu²)/g [Pa] from F = k·d^m.

    For the paraboloid this is the paper's E = k·3(1-nu²)/(4·sqrt(R)).
    """
    return youngs_modulus(k / _power_prefactor(tip), check_nu(nu))
