"""The literature's closed-form bottom-effect corrections, beside the exact layer solution.

palpbayes computes the bottom effect of a layer on a rigid base from the exact linear-elastic
solution (:mod:`palpbayes.contact.layer`, used by :func:`palpbayes.contact.thickness_factor`).
The closed forms that AFM and indentation software use are kept here, with their sources, so
that they can be compared with it and used where a reader needs a published formula.  Their
validity, measured against the layer solution (``tests/unit/test_layer.py``):

* **Dimitriadis et al.**, *Biophys. J.* 82 (2002) 2798–2810, eqs. 11–12: paraboloid, chi =
  sqrt(R·d)/h, general nu, bonded or not.  A small-chi series, below the solution as chi grows:
  bonded at nu = 0.3 −0.6 % at chi = 0.2, −1.2 % at 0.27, −2.2 % at 0.36, −4 % at 0.49; at
  nu = 0.5 −1.1 %, −2.2 %, −4.3 %, −8 %.  The non-bonded form is within 0.8 % for chi <= 0.36
  at nu = 0.3 but +1.4 % at chi = 0.1 and +3.9 % at 0.27 at nu = 0.5: its coefficients
  depend on nu, the frictionless layer's exact kernel does not. At nu = 0.5 the general form gives
  the bonded 1 + 1.133·chi + 1.283·chi² + 0.769·chi³ − 0.0975·chi⁴ (the paper's table prints
  +0.0975; the general form is used here). A public implementation writes 4·a0²/pi for 4·a0²/pi²;
  this one does not.  **Validity enforced: chi <= 1** (:data:`DIMITRIADIS_CHI_MAX`): beyond it the
  truncated series is an artefact (at nu = 0.3 the bonded factor turns negative at chi = 2.5).
* **Garcia & Garcia**, *Biophys. J.* 114 (2018) 2923–2932: bonded, nu = 0.5 polynomials for
  the paraboloid (within 0.2 % of the solution for chi <= 0.35, 0.6 % at 0.49), the cone
  (within 0.3 % for x = d·tan(alpha)/h <= 0.75) and the flat punch (within 3 % for
  a/h <= 1).  Fits at nu = 0.5: **not valid at other nu** (at nu = 0.3 the paraboloid's is
  10 % above the solution at chi = 0.27).
* **Hayes et al.**, *J. Biomech.* 5 (1972) 541–551: the bonded flat punch's kappa(a/h, nu),
  tabulated here at a/h = 0.2/0.4/0.6/1.0 for nu = 0.3 and 0.5 (docs/design.md §1).  The layer
  solution reproduces these eight numbers to 4 digits and extends them to any nu, any a/h and
  the frictionless base.
"""

from __future__ import annotations

import numpy as np

from ..errors import GeometryError
from ..units import format_length

__all__ = [
    "DIMITRIADIS_CHI_MAX",
    "dimitriadis_coefficients",
    "dimitriadis_factor",
    "GARCIA_COEFFICIENTS",
    "garcia_factor",
    "HAYES_A_OVER_H",
    "HAYES_KAPPA",
    "HAYES_NU",
]

#: Largest chi = sqrt(R·d)/h at which the Dimitriadis et al. (2002) series is used [-].
DIMITRIADIS_CHI_MAX = 1.0


def dimitriadis_coefficients(nu: float, base: str = "bonded") -> np.ndarray:
    """Coefficients [1, c1, c2, c3, c4] of the Dimitriadis et al. (2002) polynomial in chi.

    Parameters
    ----------
    nu
        Poisson ratio [-], 0 <= nu < 0.5 (0.5 allowed as a limit).
    base
        ``"bonded"`` (layer bonded to the rigid base) or ``"free"`` (may slip).
    """
    if base == "bonded":
        a0 = -(1.2876 - 1.4678 * nu + 1.3442 * nu**2) / (1.0 - nu)
        b0 = (0.6387 - 1.0277 * nu + 1.5164 * nu**2) / (1.0 - nu)
    elif base == "free":
        a0 = -0.347 * (3.0 - 2.0 * nu) / (1.0 - nu)
        b0 = 0.056 * (5.0 - 2.0 * nu) / (1.0 - nu)
    else:
        raise GeometryError(f"unknown base condition {base!r}; use 'bonded' or 'free'")
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


def dimitriadis_factor(depth: np.ndarray, radius: float, thickness: float, nu: float,
                       base: str = "bonded") -> np.ndarray:
    """Dimitriadis et al. (2002)'s force factor for a paraboloid on a layer [-].

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
    base
        ``"bonded"`` or ``"free"``.

    Raises
    ------
    GeometryError
        If chi = sqrt(R·d)/h exceeds :data:`DIMITRIADIS_CHI_MAX` (= 1) at any depth.
    """
    d = np.clip(np.asarray(depth, dtype=float), 0.0, None)
    chi = np.sqrt(radius * d) / thickness
    if chi.size and np.nanmax(chi) > DIMITRIADIS_CHI_MAX:
        i = int(np.nanargmax(chi))
        raise GeometryError(
            f"Dimitriadis' series out of range: chi = sqrt(R*d)/h = {chi.flat[i]:.3g} at depth "
            f"d = {format_length(d.flat[i])} (R = {format_length(radius, 6)}, h = "
            f"{format_length(thickness, 6)}) exceeds {DIMITRIADIS_CHI_MAX:g}; use the layer "
            "solution (palpbayes.contact.thickness_factor), valid at any chi")
    c = dimitriadis_coefficients(nu, base)
    return c[0] + chi * (c[1] + chi * (c[2] + chi * (c[3] + chi * c[4])))


#: Garcia & Garcia (2018) bonded, nu = 0.5 polynomials [1, c1, c2, c3, c4] in their variable:
#: paraboloid chi = sqrt(R·d)/h, cone x = d·tan(alpha)/h, flat punch x = a/h (depth-free).
GARCIA_COEFFICIENTS = {
    "paraboloid": np.array([1.0, 1.133, 1.497, 1.469, 0.755]),
    "cone": np.array([1.0, 0.721, 0.650, 0.491, 0.225]),
    "flat": np.array([1.0, 1.133, 1.283, 0.598, -0.291]),
}


def garcia_factor(x: np.ndarray, kind: str) -> np.ndarray:
    """Garcia & Garcia (2018)'s bonded, nu = 0.5 bottom-effect polynomial [-] in the
    variable of :data:`GARCIA_COEFFICIENTS` for tip ``kind`` (paraboloid, cone, flat)."""
    try:
        c = GARCIA_COEFFICIENTS[kind]
    except KeyError:
        raise GeometryError(f"no Garcia & Garcia (2018) polynomial for tip {kind!r}; they "
                            f"give {', '.join(GARCIA_COEFFICIENTS)}") from None
    x = np.clip(np.asarray(x, dtype=float), 0.0, None)
    return c[0] + x * (c[1] + x * (c[2] + x * (c[3] + x * c[4])))


#: a/h of Hayes et al. (1972)'s bonded flat-punch table (docs/design.md §1).
HAYES_A_OVER_H = np.array([0.2, 0.4, 0.6, 1.0])
#: Poisson ratios of the rows of :data:`HAYES_KAPPA`.
HAYES_NU = np.array([0.3, 0.5])
#: kappa(a/h) for nu = 0.3 and nu = 0.5 (rows), bonded flat punch.
HAYES_KAPPA = np.array([[1.207, 1.473, 1.785, 2.484],
                        [1.281, 1.684, 2.213, 3.619]])
