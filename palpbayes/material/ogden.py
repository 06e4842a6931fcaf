"""The Ogden solid, one to three terms (Ogden 1972), in docs/design.md §14's convention.

W = sum_p mu_p/alpha_p·(lambda1_bar^alpha_p + lambda2_bar^alpha_p + lambda3_bar^alpha_p − 3)
in the isochoric stretches, a bulk term K/2·(ln J)²: tau_bar_i = sum_p mu_p·lambda_i^alpha_p.
Small strain: mu0 = 1/2·sum_p mu_p·alpha_p (Abaqus writes 2 mu_p/alpha_p² and mu0 = sum mu_p).
A fit samples E0, the exponents alpha_p and the shares w_p = mu_p·alpha_p/(2 mu0) (each term
stable: mu_p·alpha_p > 0).  ``ogden`` is the one-term law (alpha = 2: neo-Hookean;
Shojaeifard & Bacca 2025 fit it to Ecoflex), ``ogden-2`` and ``ogden-3`` more terms.
"""

from __future__ import annotations

import numpy as np

from .registry import MaterialLaw, ShapeParameter, isochoric, register

__all__ = ["LAWS", "MIN_ALPHA"]

#: |alpha| below this is refused (the term's mu = 2 w mu0/alpha diverges).
MIN_ALPHA = 0.05


def _terms(p) -> list[tuple[float, float]]:
    out, i = [], 1
    while f"mu_{i}" in p:
        out.append((float(p[f"mu_{i}"]), float(p[f"alpha_{i}"])))
        i += 1
    return out


def _tau_bar(lam, p):
    return sum(mu * np.power(lam, a) for mu, a in _terms(p))


def _dtau_bar(lam, p):
    diag = sum(mu * a * np.power(lam, a) for mu, a in _terms(p))
    return diag[..., :, None] * np.eye(3)


def _stable(p, lam):
    """A positive shear modulus and no exponent near 0 (mu_p·alpha_p > 0 for every term is
    sufficient, not necessary: fitted Ogden laws often have a term without it)."""
    terms = _terms(p)
    return sum(mu * a for mu, a in terms) > 0 and all(abs(a) >= MIN_ALPHA for _, a in terms)


def _law(n: int) -> MaterialLaw:
    alphas = (2.5, -2.0, 8.0)
    shape = tuple(ShapeParameter(f"alpha_{i}", (-10.0, 25.0), alphas[i - 1],
                                 f"the exponent of term {i}") for i in range(1, n + 1))
    shape += tuple(ShapeParameter(f"w_{i}", (0.0, 1.0), 1.0 / n,
                                  f"term {i}'s share of the shear modulus, mu_{i}·alpha_{i}/"
                                  "(2 mu0)") for i in range(1, n))

    def natural(E0, s, nu):
        mu0 = E0 / (2.0 * (1.0 + nu))
        w = [float(s.get(f"w_{i}", 1.0 / n)) for i in range(1, n)]
        w.append(1.0 - sum(w))
        out = {}
        for i in range(1, n + 1):
            a = float(s.get(f"alpha_{i}", alphas[i - 1]))
            out[f"mu_{i}"] = 2.0 * w[i - 1] * mu0 / a if a != 0 else float("inf")
            out[f"alpha_{i}"] = a
        return out

    name = "ogden" if n == 1 else f"ogden-{n}"
    return register(MaterialLaw(
        name=name, title=f"Ogden ({n} term{'s' if n > 1 else ''})",
        parameters=tuple(x for i in range(1, n + 1)
                         for x in ((f"mu_{i}", "Pa"), (f"alpha_{i}", "-"))),
        energy="sum_p mu_p/alpha_p (l1_bar^a_p + l2_bar^a_p + l3_bar^a_p - 3) + K/2 (ln J)^2",
        reference="Ogden R.W. 1972, Proc. R. Soc. A 326:565",
        tau=_tau, dtau=_dtau, mu0=lambda p: 0.5 * sum(mu * a for mu, a in _terms(p)),
        shape=shape, natural=natural, order=40 + n, stable=_stable))


_tau, _dtau = isochoric(_tau_bar, _dtau_bar)
LAWS = tuple(_law(n) for n in (1, 2, 3))
