"""The exponential (isotropic Fung-type) solid of Demiray 1972, for gels and soft tissue that
stiffen with strain.

W = mu/(2 b)·(exp(b·(I1_bar − 3)) − 1) in the isochoric stretches, a bulk term K/2·(ln J)²;
b -> 0 is the neo-Hookean solid, b > 0 stiffens.  Small strain: mu0 = mu.  A fit samples E0
and b.
"""

from __future__ import annotations

import numpy as np

from .invariants import i1_law
from .registry import MaterialLaw, ShapeParameter, isochoric, register

__all__ = ["LAW"]


def _df(i1, p):
    return 0.5 * float(p["mu"]) * np.exp(float(p["b"]) * (i1 - 3.0))


def _d2f(i1, p):
    return float(p["b"]) * _df(i1, p)


_tau, _dtau = isochoric(*i1_law(_df, _d2f))
LAW = register(MaterialLaw(
    name="exponential", title="exponential (Demiray)", parameters=(("mu", "Pa"), ("b", "-")),
    energy="W = mu/(2 b) (exp(b (I1_bar - 3)) - 1) + K/2 (ln J)^2",
    reference="Demiray H. 1972, J. Biomech. 5:309; Fung Y.C. 1967, Am. J. Physiol. 213:1532",
    tau=_tau, dtau=_dtau, mu0=lambda p: float(p["mu"]),
    shape=(ShapeParameter("b", (0.0, 10.0), 0.5, "the stiffening exponent b"),),
    natural=lambda E0, s, nu: {"mu": E0 / (2.0 * (1.0 + nu)), "b": float(s.get("b", 0.5))},
    order=50, stable=lambda p, lam: float(p["mu"]) > 0 and float(p["b"]) >= 0))
