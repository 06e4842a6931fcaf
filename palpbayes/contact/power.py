"""Power-law profile f(r) = c·r^n: F = E*·g·d^((n+1)/n) by the Method of Dimensionality
Reduction (Popov & Hess 2015); the formulas are in :mod:`.mdr`."""

from __future__ import annotations

import numpy as np

from .mdr import contact_radius, power_law_exponent, power_law_prefactor, shape
from .registry import ContactLaw, Tip, register

__all__ = ["LAW"]


def _scaled(tip: Tip, factor: float) -> Tip:
    """Lengths scaled by ``factor``: f = c·r^n maps to c·factor^(1-n)."""
    return Tip("power", c=tip.c * factor ** (1.0 - tip.n), n=tip.n)


#: The power-law profile's entry of the registry.
LAW = register(ContactLaw(
    kind="power",
    parameters=("c", "n"),
    shape=lambda depth, tip: shape(depth, tip.c, tip.n),
    exponent=lambda tip: power_law_exponent(tip.n),
    prefactor=lambda tip: power_law_prefactor(tip.c, tip.n),
    reference=("V. L. Popov, M. Hess. Method of Dimensionality Reduction in Contact Mechanics "
               "and Friction. Springer, Berlin Heidelberg (2015), ch. 3"),
    name="MDR power-law",
    label="power-law profile",
    summary=("Power-law profile f = c·r^n by the method of dimensionality reduction: "
             "F = (2n/(n+1))·E*·(kappa_n·c)^(-1/n)·d^((n+1)/n)."),
    describe=lambda tip: f"power c={tip.c:g} n={tip.n:g}",
    order=50,
    scaled=_scaled,
    contact_radius=lambda depth, tip: contact_radius(depth, tip.c, tip.n),
    profile_exponent=lambda tip: float(tip.n),
    profile=lambda r, tip: tip.c * np.asarray(r, dtype=float) ** tip.n,
))
