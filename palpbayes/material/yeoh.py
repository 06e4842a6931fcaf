"""The Yeoh solid, one to three terms (Yeoh 1993).

W = sum_(i=1..n) Ci0·(I1_bar − 3)^i in the isochoric stretches, a bulk term K/2·(ln J)².
Small strain: mu0 = 2·C10.  A fit samples E0 and the ratios c2 = C20/C10, c3 = C30/C10.
``yeoh`` is the three-term law (the best law of the phantom database, with 2-term Ogden),
``yeoh-2`` two terms; one term is the neo-Hookean solid.
"""

from __future__ import annotations

import numpy as np

from .invariants import i1_law
from .registry import MaterialLaw, ShapeParameter, isochoric, register

__all__ = ["LAWS"]

_NAMES = ("C10", "C20", "C30")


def _coefficients(p) -> list[float]:
    return [float(p.get(n, 0.0)) for n in _NAMES]


def _df(i1, p):
    c = _coefficients(p)
    x = i1 - 3.0
    return c[0] + 2.0 * c[1] * x + 3.0 * c[2] * x * x


def _d2f(i1, p):
    c = _coefficients(p)
    return 2.0 * c[1] + 6.0 * c[2] * (i1 - 3.0)


def _stable(p, lam):
    """C10 > 0 and W' = dW/dI1 > 0 wherever the stretches ``lam`` take I1_bar (a positive
    shear stiffness along the path)."""
    lam = np.asarray(lam, dtype=float)
    bar = lam * np.prod(lam, axis=-1, keepdims=True) ** (-1.0 / 3.0)
    return bool(np.all(_df(np.square(bar).sum(axis=-1), p) > 0)) and _coefficients(p)[0] > 0


_tau, _dtau = isochoric(*i1_law(_df, _d2f))
_SHAPE = (ShapeParameter("c2", (-0.5, 0.5), 0.0, "C20/C10"),
          ShapeParameter("c3", (-0.05, 0.5), 0.0, "C30/C10"))


def _law(n: int) -> MaterialLaw:
    def natural(E0, s, nu):
        c10 = E0 / (4.0 * (1.0 + nu))
        out = {"C10": c10}
        for name, sp in zip(_NAMES[1:n], _SHAPE, strict=False):
            out[name] = float(s.get(sp.name, sp.default)) * c10
        return out

    name = "yeoh" if n == 3 else f"yeoh-{n}"
    return register(MaterialLaw(
        name=name, title=f"Yeoh ({n} terms)", parameters=tuple((c, "Pa") for c in _NAMES[:n]),
        energy=" + ".join(f"C{i}0 (I1_bar - 3)^{i}" for i in range(1, n + 1))
        + " + K/2 (ln J)^2",
        reference="Yeoh O.H. 1993, Rubber Chem. Technol. 66:754",
        tau=_tau, dtau=_dtau, mu0=lambda p: 2.0 * float(p["C10"]), shape=_SHAPE[:n - 1],
        natural=natural, order=30 + n, stable=_stable))


LAWS = (_law(2), _law(3))
