"""The Mooney–Rivlin solid (Mooney 1940, Rivlin 1948).

W = C10·(I1_bar − 3) + C01·(I2_bar − 3) in the isochoric stretches, a bulk term K/2·(ln J)².
Small strain: mu0 = 2·(C10 + C01).  A fit samples E0 and the share f = C01/(C10 + C01):
C10 = (1 − f)·mu0/2, C01 = f·mu0/2 (f = 0: neo-Hookean).
"""

from __future__ import annotations

from .invariants import i1_law, i2_term
from .registry import MaterialLaw, ShapeParameter, isochoric, register

__all__ = ["LAW"]

_tau1, _dtau1 = i1_law(lambda i1, p: float(p["C10"]) + 0.0 * i1, lambda i1, p: 0.0 * i1)


def _tau_bar(lam, p):
    return _tau1(lam, p) + i2_term(lam, float(p["C01"]))[0]


def _dtau_bar(lam, p):
    return _dtau1(lam, p) + i2_term(lam, float(p["C01"]))[1]


def _natural(E0, s, nu):
    mu0 = E0 / (2.0 * (1.0 + nu))
    f = float(s.get("f", 0.0))
    return {"C10": (1.0 - f) * mu0 / 2.0, "C01": f * mu0 / 2.0}


_tau, _dtau = isochoric(_tau_bar, _dtau_bar)
LAW = register(MaterialLaw(
    name="mooney-rivlin", title="Mooney–Rivlin", parameters=(("C10", "Pa"), ("C01", "Pa")),
    energy="W = C10 (I1_bar - 3) + C01 (I2_bar - 3) + K/2 (ln J)^2",
    reference="Mooney M. 1940, J. Appl. Phys. 11:582; Rivlin R.S. 1948, Phil. Trans. R. Soc. A "
              "241:379",
    tau=_tau, dtau=_dtau, mu0=lambda p: 2.0 * (float(p["C10"]) + float(p["C01"])),
    shape=(ShapeParameter("f", (0.0, 1.0), 0.2, "C01/(C10 + C01), the second invariant's "
                          "share of the shear modulus"),),
    natural=_natural, order=20,
    stable=lambda p, lam: float(p["C10"]) + float(p["C01"]) > 0))
