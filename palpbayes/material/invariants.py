"""Principal stresses of laws written in the first and second invariants, I1 = sum lambda_i²
and I2 = sum_(i<j) lambda_i²·lambda_j² (of the isochoric stretches, where the laws use them).

For W = f(I1):       tau_i = 2 f'·lambda_i²,
                     dtau_i/d ln lambda_j = 4 f'·lambda_i²·delta_ij + 4 f''·lambda_i²·lambda_j².
For W = g·(I2 − 3):  tau_i = 2 g·lambda_i²·(I1 − lambda_i²),
                     dtau_i/d ln lambda_j = g·[(4 lambda_i² I1 − 8 lambda_i⁴)·delta_ij
                                               + 4 lambda_i²·lambda_j²].
(d lambda_i²/d ln lambda_j = 2 lambda_i²·delta_ij, dI1/d ln lambda_j = 2 lambda_j².)
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

__all__ = ["i1_law", "i2_term"]


def i1_law(df: Callable, d2f: Callable) -> tuple[Callable, Callable]:
    """(tau, dtau) of W = f(I1) given ``df(I1, p)`` = f' and ``d2f(I1, p)`` = f'' [Pa]."""
    def tau(lam, p):
        sq = np.square(lam)
        return 2.0 * df(sq.sum(axis=-1), p)[..., None] * sq

    def dtau(lam, p):
        sq = np.square(lam)
        i1 = sq.sum(axis=-1)
        a = 4.0 * df(i1, p)[..., None, None] * (sq[..., :, None] * np.eye(3))
        return a + 4.0 * d2f(i1, p)[..., None, None] * sq[..., :, None] * sq[..., None, :]

    return tau, dtau


def i2_term(lam: np.ndarray, g: float) -> tuple[np.ndarray, np.ndarray]:
    """(tau, dtau) of W = g·(I2 − 3) at stretches ``lam`` (..., 3)."""
    sq = np.square(lam)
    i1 = sq.sum(axis=-1, keepdims=True)
    tau = 2.0 * g * sq * (i1 - sq)
    diag = (4.0 * sq * i1 - 8.0 * sq * sq)[..., :, None] * np.eye(3)
    return tau, g * (diag + 4.0 * sq[..., :, None] * sq[..., None, :])
