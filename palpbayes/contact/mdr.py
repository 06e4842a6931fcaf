"""General power-law contact through the Method of Dimensionality Reduction (MDR).

A rigid axisymmetric profile f(r) = c·r^n maps to the 1-D profile g(x) = kappa_n·c·|x|^n with
Hess's factor kappa_n = sqrt(pi)·Gamma(n/2 + 1) / Gamma(n/2 + 1/2).  The contact radius follows
from d = g(a) and the normal force is

    F(d) = (2n / (n+1)) · E* · a · d = (2n / (n+1)) · E* · (kappa_n·c)^(-1/n) · d^((n+1)/n).

Reference: V. L. Popov, M. Hess, *Method of Dimensionality Reduction in Contact Mechanics and
Friction*, Springer 2015, ch. 3.  The flat punch is the limit n -> infinity with c = a0^(-n),
where 2n/(n+1) -> 2 and a -> a0 (use :mod:`.flat` for it).  A helper of :mod:`.power` (the
``power`` tip kind); it registers no law.
"""

from __future__ import annotations

import numpy as np
from scipy.special import gammaln

__all__ = ["hess_factor", "power_law_exponent", "power_law_prefactor", "shape",
           "contact_radius"]


def hess_factor(n: float) -> float:
    """Hess's stretch factor kappa_n = sqrt(pi)·Gamma(n/2+1)/Gamma(n/2+1/2) [-]."""
    return float(np.exp(0.5 * np.log(np.pi) + gammaln(n / 2 + 1) - gammaln(n / 2 + 0.5)))


def power_law_exponent(n: float) -> float:
    """Force exponent m = (n+1)/n of the profile f = c·r^n [-]."""
    return (n + 1.0) / n


def power_law_prefactor(c: float, n: float) -> float:
    """Geometry factor g with F = E*·g·d^m for f = c·r^n [m^(2-m)].

    g = (2n/(n+1))·(kappa_n·c)^(-1/n).
    """
    return 2.0 * n / (n + 1.0) * (hess_factor(n) * c) ** (-1.0 / n)


def shape(depth: np.ndarray, c: float, n: float) -> np.ndarray:
    """Force per unit effective modulus, F/E* [m²], for the profile f = c·r^n.

    Parameters
    ----------
    depth
        [m] Indentation depth d; non-positive depths give 0.
    c, n
        Profile f(r) = c·r^n.
    """
    d = np.clip(np.asarray(depth, dtype=float), 0.0, None)
    return power_law_prefactor(c, n) * d ** power_law_exponent(n)


def contact_radius(depth: np.ndarray, c: float, n: float) -> np.ndarray:
    """Contact radius a = (d/(kappa_n·c))^(1/n) [m] of the profile f = c·r^n (the MDR's
    d = g(a)); 0 for non-positive depth."""
    d = np.clip(np.asarray(depth, dtype=float), 0.0, None)
    return (d / (hess_factor(n) * c)) ** (1.0 / n)
