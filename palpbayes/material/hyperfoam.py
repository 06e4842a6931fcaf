"""The Ogden–Hill compressible foam (Hill 1978; Storåkers 1986; Abaqus HYPERFOAM), one or two
terms, all terms with one Poisson ratio nu.

W = sum_p 2 mu_p/alpha_p²·(lambda1^alpha_p + lambda2^alpha_p + lambda3^alpha_p − 3
                          + (J^(−alpha_p·beta) − 1)/beta),        beta = nu/(1 − 2 nu):
tau_i = sum_p 2 mu_p/alpha_p·(lambda_i^alpha_p − J^(−alpha_p·beta)).  Small strain:
mu0 = sum_p mu_p, nu0 = nu (nu = 0: no lateral expansion, as in many foams).  In uniaxial
compression the lateral stretch is lambda^(−nu) exactly.  The foam carries its own
compressibility: it has no bulk term.  A fit samples E0, nu, the exponents and (two terms) the
first term's share w = mu_1/mu0.  With a large alpha the stress levels off after the linear
range into a plateau, the cell walls buckling (Gibson & Ashby 1997), and rises again as
1/lambda (densification): at nu = 0 and E0 = 100 kPa, one term with alpha = 20 reads 4.9, 6.2,
7.1 and 8.3 kPa at 10, 20, 30 and 40 % strain, where alpha = 2 reads 10.6, 22.5, 36.4 and
53.3 kPa and the linear law 10, 20, 30 and 40 kPa.
"""

from __future__ import annotations

import numpy as np

from .registry import MaterialLaw, ShapeParameter, register

__all__ = ["LAWS"]


def _terms(p) -> list[tuple[float, float]]:
    out, i = [], 1
    while f"mu_{i}" in p:
        out.append((float(p[f"mu_{i}"]), float(p[f"alpha_{i}"])))
        i += 1
    return out


def _beta(p) -> float:
    nu = float(p["nu"])
    return nu / (1.0 - 2.0 * nu)


def _tau(lam, p):
    lam = np.asarray(lam, dtype=float)
    j = np.prod(lam, axis=-1, keepdims=True)
    b = _beta(p)
    return sum(2.0 * mu / a * (np.power(lam, a) - np.power(j, -a * b)) for mu, a in _terms(p))


def _dtau(lam, p):
    lam = np.asarray(lam, dtype=float)
    j = np.prod(lam, axis=-1)
    b = _beta(p)
    out = 0.0
    for mu, a in _terms(p):
        diag = np.power(lam, a)[..., :, None] * np.eye(3)
        out = out + 2.0 * mu * (diag + b * np.power(j, -a * b)[..., None, None])
    return out


def _stable(p, lam):
    terms = _terms(p)
    return (0.0 <= float(p["nu"]) < 0.5 and sum(mu for mu, _ in terms) > 0
            and all(a != 0 for _, a in terms))


def _law(n: int) -> MaterialLaw:
    alphas = (8.0, -2.0)
    shape = (ShapeParameter("nu", (0.0, 0.45), 0.1, "the small-strain Poisson ratio"),)
    shape += tuple(ShapeParameter(f"alpha_{i}", (-10.0, 25.0), alphas[i - 1],
                                  f"the exponent of term {i}") for i in range(1, n + 1))
    if n == 2:
        shape += (ShapeParameter("w_1", (0.0, 1.0), 0.5, "mu_1/mu0, term 1's share"),)

    def natural(E0, s, nu):
        nu = float(s.get("nu", 0.1))
        mu0 = E0 / (2.0 * (1.0 + nu))
        w = [float(s.get("w_1", 1.0))] if n == 2 else [1.0]
        if n == 2:
            w.append(1.0 - w[0])
        out = {"nu": nu}
        for i in range(1, n + 1):
            out[f"mu_{i}"] = w[i - 1] * mu0
            out[f"alpha_{i}"] = float(s.get(f"alpha_{i}", alphas[i - 1]))
        return out

    name = "hyperfoam" if n == 1 else f"hyperfoam-{n}"
    return register(MaterialLaw(
        name=name, title=f"hyperfoam ({n} term{'s' if n > 1 else ''})",
        parameters=(("nu", "-"),) + tuple(x for i in range(1, n + 1)
                                          for x in ((f"mu_{i}", "Pa"), (f"alpha_{i}", "-"))),
        energy="sum_p 2 mu_p/a_p^2 (l1^a_p + l2^a_p + l3^a_p - 3 + (J^(-a_p beta) - 1)/beta)",
        reference="Hill R. 1978, Adv. Appl. Mech. 18:1; Storåkers B. 1986, J. Mech. Phys. Solids "
                  "34:125",
        tau=_tau, dtau=_dtau, mu0=lambda p: sum(mu for mu, _ in _terms(p)), shape=shape,
        natural=natural, kind="foam", nu_parameter="nu", order=60 + n, stable=_stable))


LAWS = tuple(_law(n) for n in (1, 2))
