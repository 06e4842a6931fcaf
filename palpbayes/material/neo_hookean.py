"""The neo-Hookean solid (Rivlin 1948; compressible form of docs/design.md §14).

W = mu/2·(I1 − 3 − 2 ln J) + lambda/2·(ln J)², I1 = sum lambda_i² (Ciarlet 1988, Bonet & Wood
2008, §6.4.3): tau_i = mu·(lambda_i² − 1) + lambda·ln J.  Incompressible (nu = 0.5): W =
mu/2·(I1 − 3), nominal stress in uniaxial compression P = mu·(lambda − lambda^-2).
Small strain: mu0 = mu, E0 = 2·mu·(1 + nu).
"""

from __future__ import annotations

import numpy as np

from .registry import MaterialLaw, register

__all__ = ["LAW"]


def _tau(lam, p):
    return float(p["mu"]) * (np.square(lam) - 1.0)


def _dtau(lam, p):
    return 2.0 * float(p["mu"]) * np.square(lam)[..., :, None] * np.eye(3)


LAW = register(MaterialLaw(
    name="neo-hookean", title="neo-Hookean", parameters=(("mu", "Pa"),),
    energy="W = mu/2 (I1 - 3 - 2 ln J) + lambda/2 (ln J)^2",
    reference="Rivlin R.S. 1948, Phil. Trans. R. Soc. A 241:379; compressible form: Bonet J. & "
              "Wood R.D. 2008, Nonlinear Continuum Mechanics for Finite Element Analysis, §6.4.3",
    tau=_tau, dtau=_dtau, mu0=lambda p: float(p["mu"]), shape=(),
    natural=lambda E0, s, nu: {"mu": E0 / (2.0 * (1.0 + nu))}, kind="lame", order=10,
    stable=lambda p, lam: float(p["mu"]) > 0))
