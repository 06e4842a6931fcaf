"""Uniaxial compression of a hyperelastic solid: the nominal (engineering) stress a compression
test between frictionless platens reads at each engineering strain.

Conventions of :mod:`palpbayes.compression`: compressive strain eps = compression / initial
height and compressive stress = load / initial cross-section, both positive in compression.
The stretch along the load is lambda = 1 − eps; the lateral faces are free:

* incompressible (nu = 0.5, not a foam): lambda_2 = lambda_3 = lambda^(−1/2), the pressure
  eliminated, P = (tau_1 − tau_2)/lambda (docs/design.md §14: neo-Hookean
  P = mu·(lambda − lambda^-2));
* compressible: lambda_2 solves tau_2 + kappa·ln J = 0 (Newton in ln lambda_2 from
  lambda^(−nu)), P = (tau_1 + kappa·ln J)/lambda.

A chord modulus over [eps_a, eps_b] is (sigma(eps_b) − sigma(eps_a))/(eps_b − eps_a): what a
straight line through the curve there reads; the linear law's chord is E at every strain.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from ..errors import FitError, InputError
from .registry import LINEAR, MaterialLaw, material_law

__all__ = ["compression_stress", "lateral_stretch", "chord_modulus", "MAX_STRAIN"]

#: Largest compressive engineering strain a curve is evaluated at (lambda = 0.05).
MAX_STRAIN = 0.95


def _strain(strain) -> np.ndarray:
    eps = np.asarray(strain, dtype=float)
    if not np.all(np.isfinite(eps)) or np.any(eps < 0) or np.any(eps > MAX_STRAIN):
        raise InputError(f"compressive strains must lie in [0, {MAX_STRAIN}], got "
                         f"{eps.min():.3g}..{eps.max():.3g}" if eps.size else "no strains")
    return eps


def lateral_stretch(law: MaterialLaw, p: Mapping[str, float], stretch,
                    nu: float | None = None) -> np.ndarray:
    """lambda_2 = lambda_3 [-] of free uniaxial loading to ``stretch`` lambda_1 [-].

    Raises
    ------
    FitError
        The lateral equilibrium has no solution within 50 Newton steps (an unstable set of
        parameters).
    """
    lam = np.asarray(stretch, dtype=float)
    nu0 = law.nu0(p, nu)
    if law.kind != "foam" and nu0 >= 0.5:
        return lam ** -0.5
    kappa = law.bulk(p, nu0)
    x = -nu0 * np.log(lam)  # ln lambda_2, exact for the foam and at small strain
    for _ in range(50):
        s = np.stack([lam, np.exp(x), np.exp(x)], axis=-1)
        lnj = np.log(lam) + 2.0 * x
        r = law.tau(s, p)[..., 1] + kappa * lnj
        d = law.dtau(s, p)
        dr = d[..., 1, 1] + d[..., 1, 2] + 2.0 * kappa
        step = r / dr
        x = x - step
        if np.all(np.abs(step) < 1e-14):
            return np.exp(x)
    raise FitError(f"{law.describe(p)}: no lateral equilibrium in uniaxial loading (an "
                   "unstable set of parameters)")


def compression_stress(law: str | MaterialLaw, p: Mapping[str, float], strain,
                       nu: float | None = None) -> np.ndarray:
    """Compressive nominal stress [Pa] at compressive engineering strains ``strain`` [-].

    Parameters
    ----------
    law
        A registered law (:func:`~palpbayes.material.material_law`) or ``"linear"``
        (``p = {"E": ...}``: sigma = E·eps).
    p
        The law's natural parameters.
    strain
        Compressive engineering strain(s) in [0, :data:`MAX_STRAIN`].
    nu
        The small-strain Poisson ratio of a law that is not a foam (None: 0.5, incompressible).
    """
    eps = _strain(strain)
    if law == LINEAR:
        return float(p["E"]) * eps
    law = material_law(law)
    lam = 1.0 - eps
    nu0 = law.nu0(p, nu)
    lat = lateral_stretch(law, p, lam, nu)
    s = np.stack([lam, lat, lat], axis=-1)
    tau = law.tau(s, p)
    if law.kind != "foam" and nu0 >= 0.5:
        first = tau[..., 0] - tau[..., 1]
    else:
        first = tau[..., 0] + law.bulk(p, nu0) * np.log(lam * lat * lat)
    return -first / lam


def chord_modulus(law: str | MaterialLaw, p: Mapping[str, float], lo: float, hi: float,
                  nu: float | None = None) -> float:
    """[Pa] (sigma(hi) − sigma(lo))/(hi − lo), compressive strains ``lo`` < ``hi``; the slope
    at ``lo`` when they are equal (a central difference of 1e-6)."""
    if hi < lo:
        raise InputError(f"a chord needs lo <= hi, got {lo:g}, {hi:g}")
    if hi - lo < 1e-6:
        lo, hi = max(lo - 5e-7, 0.0), lo + 5e-7
    s = compression_stress(law, p, np.array([lo, hi]), nu)
    return float((s[1] - s[0]) / (hi - lo))
