"""The relaxation kernels of the viscoelastic columns, per unit modulus, and their integrals.

The columns of :mod:`~palpbayes.rheology.design` need, at lags x >= 0 [s], the kernel's first,
second and third integrals Φ(x) = ∫_0^x E(y) dy, Ψ(x) = ∫_0^x Φ and Ψ₂(x) = ∫_0^x Ψ (0 for
x <= 0), per unit modulus:

* power law (springpot) E(t) = (t/t0)^(−alpha): Φ(x) = t0^alpha·x^(1−alpha)/(1−alpha),
  Ψ(x) = Φ(x)·x/(2−alpha), Ψ₂(x) = Ψ(x)·x/(3−alpha);
* exponential branch E(t) = exp(−t/tau): Φ(x) = −tau·expm1(−x/tau),
  Ψ(x) = tau²·(y + expm1(−y)), Ψ₂(x) = tau³·(y²/2 − y − expm1(−y)), y = x/tau (their series
  where y is small: no cancellation);
* constant (the SLS's E_inf, the elastic limit): Φ = x, Ψ = x²/2, Ψ₂ = x³/6.

:class:`Lags` keeps lags that a record fixes with their logarithms, so that all three come from
one exponential per lag at any theta.
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError

__all__ = ["KERNELS", "Lags", "check_kernel", "integrated_kernel", "double_integrated_kernel",
           "triple_integrated_kernel", "psi_series", "psi2_series", "PSI_SERIES",
           "PSI2_SERIES"]

#: Kernels of the columns: parameter alpha [-] or tau [s]; ``None`` is the constant kernel.
KERNELS = ("power-law", "exponential")
#: y = x/tau [-] below which the exponential's Ψ and Ψ₂ take their Taylor series
#: (:func:`psi_series`, :func:`psi2_series`): the closed forms cancel there.
PSI_SERIES, PSI2_SERIES = 1e-3, 1e-2


def psi_series(y: np.ndarray) -> np.ndarray:
    """Ψ/tau² = y + expm1(−y) of the exponential by its Taylor series to y⁵ (used below
    :data:`PSI_SERIES`: the first term left out is y⁴/360 < 3e-15 of it there)."""
    return y * y * (0.5 - y * (1.0 / 6.0 - y * (1.0 / 24.0 - y / 120.0)))


def psi2_series(y: np.ndarray) -> np.ndarray:
    """Ψ₂/tau³ = y²/2 − y − expm1(−y) of the exponential by its Taylor series to y⁶ (used
    below :data:`PSI2_SERIES`: the first term left out is y⁴/840 < 1.2e-11 of it there)."""
    return y**3 * (1.0 / 6.0 - y * (1.0 / 24.0 - y * (1.0 / 120.0 - y / 720.0)))


def check_kernel(kernel: str | None, theta: float) -> None:
    """Raise :class:`~palpbayes.errors.InputError` unless ``kernel`` is one of
    :data:`KERNELS` or None and ``theta`` lies in its range (alpha in [0, 1), tau > 0 [s])."""
    if kernel == "power-law":
        if not 0.0 <= theta < 1.0:
            raise InputError(f"alpha = {theta!r} must lie in [0, 1)")
    elif kernel == "exponential":
        if not theta > 0:
            raise InputError(f"tau = {theta!r} s must be positive")
    elif kernel is not None:
        raise InputError(f"unknown kernel {kernel!r}; use one of {', '.join(KERNELS)}")


def integrated_kernel(x: np.ndarray, kernel: str | None, theta: float = 0.0,
                      t0: float = 1.0) -> np.ndarray:
    """Φ(x) = ∫_0^x K(y) dy [s] per unit modulus at lags ``x`` (0 for x <= 0)."""
    x = np.clip(np.asarray(x, dtype=float), 0.0, None)
    if kernel is None:
        return x
    if kernel == "power-law":
        return x ** (1.0 - theta) * (t0**theta / (1.0 - theta))
    return -theta * np.expm1(-x / theta)


def double_integrated_kernel(x: np.ndarray, kernel: str | None, theta: float = 0.0,
                             t0: float = 1.0) -> np.ndarray:
    """Ψ(x) = ∫_0^x Φ(y) dy [s²] per unit modulus (0 for x <= 0); for the exponential,
    tau²·(y + expm1(−y)) with y = x/tau, by its series below y = 1e-3 (no cancellation)."""
    x = np.clip(np.asarray(x, dtype=float), 0.0, None)
    if kernel is None:
        return 0.5 * x * x
    if kernel == "power-law":
        return x ** (2.0 - theta) * (t0**theta / ((1.0 - theta) * (2.0 - theta)))
    y = x / theta
    small = y < PSI_SERIES
    return theta**2 * np.where(small, psi_series(y), y + np.expm1(-np.where(small, 1.0, y)))


def triple_integrated_kernel(x: np.ndarray, kernel: str | None, theta: float = 0.0,
                             t0: float = 1.0) -> np.ndarray:
    """Ψ₂(x) = ∫_0^x Ψ(y) dy [s³] per unit modulus (0 for x <= 0)."""
    x = np.clip(np.asarray(x, dtype=float), 0.0, None)
    if kernel is None:
        return x**3 / 6.0
    if kernel == "power-law":
        return x ** (3.0 - theta) * (t0**theta / ((1.0 - theta) * (2.0 - theta)
                                                  * (3.0 - theta)))
    y = x / theta
    small = y < PSI2_SERIES
    big = 0.5 * y * y - y - np.expm1(-np.where(small, 1.0, y))
    return theta**3 * np.where(small, psi2_series(y), big)


class Lags:
    """Lags x [s] that a record fixes (knot and sample times, not theta nor the surface),
    clipped at 0, with their logarithms: Φ, Ψ and Ψ₂ at any theta from one exponential per lag
    and order set (the power law's x^(k − alpha) = x^(k−1)·exp((1 − alpha)·ln x))."""

    def __init__(self, x: np.ndarray, log: np.ndarray | None = None):
        """``x`` [s] clipped at 0; or, with ``log`` (ln x, from the caller), x >= 0 as given
        (no copy)."""
        self.x = np.maximum(x, 0.0) if log is None else x
        self._log = log

    def columns(self, index: np.ndarray) -> Lags:
        """The lags ``x[:, index].T`` (a column per index), with their logarithms when these
        are computed already."""
        x = self.x[:, index].T
        return Lags(x, None if self._log is None else self._log[:, index].T)

    @property
    def log(self) -> np.ndarray:
        """ln x (−inf at 0), computed on first use (the power law's alone)."""
        if self._log is None:
            with np.errstate(divide="ignore"):
                self._log = np.log(self.x)
        return self._log

    def integrals(self, orders: tuple[int, ...], kernel: str | None, theta: float = 0.0,
                  t0: float = 1.0) -> list[np.ndarray]:
        """Φ (order 1), Ψ (2) or Ψ₂ (3) per unit modulus at the lags, in ``orders``' order
        (as :func:`integrated_kernel`, :func:`double_integrated_kernel`,
        :func:`triple_integrated_kernel`).

        Raises
        ------
        InputError
            An unknown kernel or theta outside its range (:func:`check_kernel`).
        """
        check_kernel(kernel, theta)
        if kernel == "exponential":  # one expm1(−y), y = x/tau, for every order
            y = self.x / theta
            em = np.expm1(-y)
            out = []
            for k in orders:
                if k == 1:
                    f = em * -theta
                elif k == 2:
                    f = y + em
                    if (small := y < PSI_SERIES).any():
                        f[small] = psi_series(y[small])
                    f *= theta**2
                else:
                    f = 0.5 * y * y - y - em
                    if (small := y < PSI2_SERIES).any():
                        f[small] = psi2_series(y[small])
                    f *= theta**3
                out.append(f)
            return out
        if kernel is None:  # Φ = x, Ψ = x²/2, Ψ₂ = x³/6
            x = self.x
            return [x.copy() if k == 1 else x * x * (0.5 if k == 2 else x / 6.0)
                    for k in orders]
        base = np.multiply(self.log, 1.0 - theta)
        np.exp(base, out=base)
        base *= t0**theta / (1.0 - theta)  # Φ
        out = []
        for k in orders:
            f = base.copy() if k == 1 else base * self.x
            if k == 3:
                f *= self.x
            f *= {1: 1.0, 2: 1.0 / (2.0 - theta), 3: 1.0 / ((2.0 - theta) * (3.0 - theta))}[k]
            out.append(f)
        return out
