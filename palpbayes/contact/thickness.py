"""Finite-thickness corrections for a layer of thickness h on a rigid base.

Each function returns a multiplicative factor on the half-space force; the force stays linear
in E*, so least squares and the posterior keep their structure.  The ``*_tip_factor``
functions take a :class:`~palpbayes.contact.registry.Tip`: the law modules name them as their
``ContactLaw.thickness_factor``.

* Paraboloid / sphere: Dimitriadis et al., *Biophys. J.* 82 (2002) 2798-2810, eqs. 11-12 with
  chi = sqrt(R·d)/h, for general nu, bonded or non-bonded to the base.  The series is derived
  for small chi and is accurate to a few percent up to chi ~ 1 (validity stated in the paper as
  contact radius well below the thickness).  **Validity enforced here: chi <= 1**
  (:data:`DIMITRIADIS_CHI_MAX`); beyond it the truncated series is no longer a correction but
  an artefact of the truncation: at nu = 0.3 the bonded factor peaks near chi = 1.65 and turns
  negative at chi = 2.5 (nu = 0: at chi = 2.1), so :func:`dimitriadis_factor` raises
  :class:`~palpbayes.errors.GeometryError` rather than return it.  At nu = 0.5 the general form
  gives the bonded
  factor 1 + 1.133·chi + 1.283·chi² + 0.769·chi³ - 0.0975·chi⁴; the paper's printed table has
  +0.0975.  **palpbayes uses the general form (minus sign)**; the term is below 0.1 % for
  chi < 0.3.  A public implementation writes 4·a0²/pi instead of 4·a0²/pi²: this one does not
  (tested against the nu = 0.5 coefficients).  For the exact sphere the same factor is applied
  with chi = sqrt(R·d)/h (Dimitriadis' derivation is for the paraboloid).
* Flat punch bonded to the base: Hayes et al., *J. Biomech.* 5 (1972) 541-551, F = 2·a·E*·d·
  kappa(a/h, nu).  Tabulated kappa at a/h = 0.2/0.4/0.6/1.0 for nu = 0.3 and 0.5, interpolated
  with a monotone cubic (PCHIP) through kappa(0) = 1 in a/h and linearly in nu.  Valid for
  a/h <= 1 and 0.3 <= nu <= 0.5; nu in [0.2, 0.3) is linearly extrapolated (documented,
  < 3 % from the nu = 0.3 value at a/h <= 0.6); outside that it raises.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from scipy.interpolate import PchipInterpolator

from ..errors import GeometryError
from ..units import format_length

if TYPE_CHECKING:
    from .registry import Tip

__all__ = [
    "dimitriadis_coefficients",
    "dimitriadis_factor",
    "dimitriadis_tip_factor",
    "hayes_kappa",
    "hayes_tip_factor",
    "HAYES_A_OVER_H",
    "HAYES_KAPPA",
    "DIMITRIADIS_CHI_MAX",
]

#: Largest chi = sqrt(R·d)/h at which the Dimitriadis et al. (2002) series is used [-].
DIMITRIADIS_CHI_MAX = 1.0


def dimitriadis_coefficients(nu: float, bonded: bool = True) -> np.ndarray:
    """Coefficients [1, c1, c2, c3, c4] of the Dimitriadis polynomial in chi.

    Parameters
    ----------
    nu
        Poisson ratio [-], 0 <= nu < 0.5 (0.5 allowed as a limit).
    bonded
        True if the layer is bonded to the rigid base, False if it may slip.
    """
    if bonded:
        a0 = -(1.2876 - 1.4678 * nu + 1.3442 * nu**2) / (1.0 - nu)
        b0 = (0.6387 - 1.0277 * nu + 1.5164 * nu**2) / (1.0 - nu)
    else:
        a0 = -0.347 * (3.0 - 2.0 * nu) / (1.0 - nu)
        b0 = 0.056 * (5.0 - 2.0 * nu) / (1.0 - nu)
    pi = np.pi
    return np.array(
        [
            1.0,
            -2.0 * a0 / pi,
            4.0 * a0**2 / pi**2,
            -8.0 / pi**3 * (a0**3 + 4.0 * pi**2 * b0 / 15.0),
            16.0 * a0 / pi**4 * (a0**3 + 3.0 * pi**2 * b0 / 5.0),
        ]
    )


def dimitriadis_factor(
    depth: np.ndarray, radius: float, thickness: float, nu: float, bonded: bool = True
) -> np.ndarray:
    """Force correction factor for a paraboloid/sphere on a layer of thickness h [-].

    Parameters
    ----------
    depth
        [m] Indentation depth (non-positive gives factor 1).
    radius
        [m] Tip radius R.
    thickness
        [m] Layer thickness h.
    nu
        Poisson ratio [-].
    bonded
        Layer bonded to the base (True) or free to slip (False).

    Raises
    ------
    GeometryError
        If chi = sqrt(R·d)/h exceeds :data:`DIMITRIADIS_CHI_MAX` (= 1) at any depth: the series
        is outside its validity (Dimitriadis et al. 2002; see the module notes).
    """
    d = np.clip(np.asarray(depth, dtype=float), 0.0, None)
    chi = np.sqrt(radius * d) / thickness
    if chi.size and np.nanmax(chi) > DIMITRIADIS_CHI_MAX:
        i = int(np.nanargmax(chi))
        raise GeometryError(
            f"finite-thickness correction out of range: chi = sqrt(R*d)/h = "
            f"{chi.flat[i]:.3g} at depth d = {format_length(d.flat[i])} (R = "
            f"{format_length(radius, 6)}, h = {format_length(thickness, 6)}) exceeds "
            f"{DIMITRIADIS_CHI_MAX:g}, the validity of "
            "Dimitriadis' series; check the thickness (--thickness, thickness_m), fit a "
            "shallower window (--max-depth) or switch the correction off (drop "
            "--finite-thickness; thickness_correction=False in the API)"
        )
    c = dimitriadis_coefficients(nu, bonded)
    return c[0] + chi * (c[1] + chi * (c[2] + chi * (c[3] + chi * c[4])))


#: a/h grid of Hayes et al. (1972) as solved in docs/design.md §1.
HAYES_A_OVER_H = np.array([0.0, 0.2, 0.4, 0.6, 1.0])
#: kappa(a/h) for nu = 0.3 and nu = 0.5 (rows), bonded flat punch.
HAYES_KAPPA = np.array(
    [
        [1.0, 1.207, 1.473, 1.785, 2.484],
        [1.0, 1.281, 1.684, 2.213, 3.619],
    ]
)
_HAYES_NU = np.array([0.3, 0.5])
_HAYES_SPLINES = [PchipInterpolator(HAYES_A_OVER_H, row) for row in HAYES_KAPPA]


def hayes_kappa(radius: float, thickness: float, nu: float) -> float:
    """Hayes' correction kappa(a/h, nu) for a flat punch on a bonded layer [-].

    Parameters
    ----------
    radius
        [m] Punch radius a.
    thickness
        [m] Layer thickness h.
    nu
        Poisson ratio [-], 0.2 <= nu <= 0.5.

    Raises
    ------
    GeometryError
        If a/h > 1 or nu is outside [0.2, 0.5] (outside the tabulated solution).
    """
    ratio = radius / thickness
    if not 0.0 <= ratio <= 1.0:
        raise GeometryError(
            f"flat-punch radius/thickness a/h = {ratio:.3g} (a = {format_length(radius, 6)}, h = "
            f"{format_length(thickness, 6)}) is outside Hayes' table (0..1); check the thickness "
            "(--thickness, thickness_m) or switch the correction off (drop --finite-thickness; "
            "thickness_correction=False in the API)"
        )
    if not 0.2 <= nu <= 0.5:
        raise GeometryError(
            f"Poisson ratio {nu:g} is outside the Hayes correction's range 0.2..0.5; give "
            "--nu in that range or switch the correction off for this nu (drop "
            "--finite-thickness; thickness_correction=False in the API)"
        )
    k03, k05 = (float(s(ratio)) for s in _HAYES_SPLINES)
    w = (nu - 0.3) / 0.2
    return k03 + w * (k05 - k03)


def dimitriadis_tip_factor(depth: np.ndarray, tip: Tip, thickness: float, nu: float,
                           bonded: bool = True) -> np.ndarray:
    """:func:`dimitriadis_factor` at the radius of ``tip`` (paraboloid, sphere) [-]."""
    return dimitriadis_factor(depth, tip.radius, thickness, nu, bonded)


def hayes_tip_factor(depth: np.ndarray, tip: Tip, thickness: float, nu: float,
                     bonded: bool = True) -> np.ndarray:
    """:func:`hayes_kappa` for the flat punch ``tip``, at every depth [-].

    Raises
    ------
    GeometryError
        For a non-bonded layer (Hayes et al. solved the bonded one), and as
        :func:`hayes_kappa`.
    """
    if not bonded:
        raise GeometryError(
            "no non-bonded finite-thickness correction for the flat punch; drop "
            "--non-bonded (bonded=True in the API) or switch the correction off (drop "
            "--finite-thickness)"
        )
    return np.full_like(np.asarray(depth, dtype=float), hayes_kappa(tip.radius, thickness, nu))
