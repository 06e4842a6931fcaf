"""The Lee–Radok hereditary integral as regression columns, for many trial surfaces at once.

While the contact does not shrink, a rigid tip with elastic law F = C·E·d^m on a linear
viscoelastic half-space with relaxation modulus E(t) gives (Lee & Radok 1960; DESIGN §9)

    F(t) = C·∫_0^t E(t − s)·du/ds ds,    u(s) = d(s)^m,  d = z_s − z(s) (0 out of contact).

With u linear in time between samples (slope r_j on [t_j, t_{j+1}]) and Φ(x) = ∫_0^x E(y) dy,

    F(t_i) = C·Σ_{j<i} r_j·[Φ(t_i − t_j) − Φ(t_i − t_{j+1})] = C·(W·r)_i,

a lower-triangular matrix W on the measured time axis that does not depend on the surface
height z_s: every trial surface's column is one matrix product (BLAS), and the modulus enters
linearly.  Kernels (per unit modulus):

* power law (springpot) E(t) = (t/t0)^(−alpha): Φ(x) = t0^alpha·x^(1−alpha)/(1 − alpha);
* exponential branch E(t) = exp(−t/tau): Φ(x) = tau·(1 − exp(−x/tau));
* constant (the SLS's E_inf, the elastic limit): W·r = u(t_i) − u(t_0), no matrix.

The linear interpolation of u = d^m between samples is the one approximation, except in the
step where the contact starts: there u rises linearly from the crossing of d = 0 (found by
linear interpolation of d), not from the step's start (:func:`onset_correction`; without it
a flat punch's kink would leak ~1e-3 of the peak force into the power law's singular kernel).
Against :func:`palpbayes.contact.viscoelastic.hereditary_force` (exact per step) the columns
agree to ~1e-4 of the peak force on irregular axes of a few hundred samples (tested).
Ting's rule for a shrinking contact is not in the columns: the retract segment is not fitted
this way.
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError

__all__ = ["Lags", "lag_matrix", "kernel_matrix", "integrated_kernel", "onset_correction",
           "depth_power", "hereditary_columns", "lee_radok_columns", "KERNELS"]

#: Kernels of :func:`kernel_matrix`: parameter alpha [-] or tau [s].
KERNELS = ("power-law", "exponential")


class Lags:
    """Lags max(t_i − t_j, 0) [s] of a time axis, shape (N, N), and their logarithm (−inf at
    zero lag): built once per time axis, used by every kernel."""

    def __init__(self, t: np.ndarray):
        t = np.asarray(t, dtype=float)
        self.lags = np.clip(t[:, None] - t[None, :], 0.0, None)
        with np.errstate(divide="ignore"):
            self.log = np.log(self.lags)


def lag_matrix(t: np.ndarray) -> Lags:
    """:class:`Lags` of the time axis ``t`` [s]."""
    return Lags(t)


def kernel_matrix(lags: Lags, kernel: str, theta: float, t0: float = 1.0) -> np.ndarray:
    """W (N, N − 1) with W[i, j] = Φ(t_i − t_j) − Φ(t_i − t_{j+1}) [s] per unit modulus.

    Parameters
    ----------
    lags
        :func:`lag_matrix` of the time axis [s].
    kernel
        ``"power-law"`` (``theta`` = alpha in [0, 1)) or ``"exponential"`` (``theta`` = tau
        [s] > 0).
    t0
        [s] Reference time of the power law.
    """
    if kernel == "power-law":
        if not 0.0 <= theta < 1.0:
            raise InputError(f"alpha = {theta!r} must lie in [0, 1)")
        phi = np.exp((1.0 - theta) * lags.log) * (t0**theta / (1.0 - theta))
    elif kernel == "exponential":
        if not theta > 0:
            raise InputError(f"tau = {theta!r} s must be positive")
        phi = -theta * np.expm1(lags.lags * (-1.0 / theta))
    else:
        raise InputError(f"unknown kernel {kernel!r}; use one of {', '.join(KERNELS)}")
    return phi[:, :-1] - phi[:, 1:]


def integrated_kernel(x: np.ndarray, kernel: str, theta: float, t0: float = 1.0) -> np.ndarray:
    """Φ(x) = ∫_0^x K(y) dy [s] per unit modulus at lags ``x`` >= 0 (module docstring)."""
    x = np.clip(np.asarray(x, dtype=float), 0.0, None)
    if kernel == "power-law":
        return x ** (1.0 - theta) * (t0**theta / (1.0 - theta))
    return -theta * np.expm1(-x / theta)


def onset_correction(t: np.ndarray, depth: np.ndarray, m: float, kernel: str, theta: float,
                     t0: float = 1.0) -> np.ndarray:
    """Correction (G, N) [m^m·s⁰] to :func:`hereditary_columns` for the step where each row's
    contact starts: u = d^m rises linearly from the crossing s_c of d = 0 (linear in d between
    the two samples) to the step's end, instead of from the step's start.  ``depth`` (G, N)
    [m]; rows that start in contact or never touch get no correction."""
    t = np.asarray(t, dtype=float)
    G, N = depth.shape
    out = np.zeros((G, N))
    pos = depth > 0
    k = np.argmax(pos, axis=1)
    rows = np.flatnonzero(pos.any(axis=1) & (k >= 1))
    if not rows.size:
        return out
    kk = k[rows]
    d0, d1 = depth[rows, kk - 1], depth[rows, kk]
    ta, tb = t[kk - 1], t[kk]
    sc = ta + (tb - ta) * (-d0) / (d1 - d0)
    u1 = d1**m
    lag = t[None, :] - np.stack([ta, sc, tb])[:, :, None]  # (3, rows, N)
    phi_a, phi_c, phi_b = (integrated_kernel(x, kernel, theta, t0) for x in lag)
    rise = tb - sc  # 0 when d1 is so small that the crossing rounds onto the sample
    exact = (u1 / np.where(rise > 0, rise, 1.0) * (rise > 0))[:, None] * (phi_c - phi_b)
    linear = (u1 / (tb - ta))[:, None] * (phi_a - phi_b)
    after = np.arange(N)[None, :] >= kk[:, None]
    out[rows] = np.where(after, exact - linear, 0.0)
    return out


def depth_power(z_nodes: np.ndarray, z: np.ndarray, m: float) -> np.ndarray:
    """u = max(z_s − z, 0)^m [m^m] for every trial surface (rows) and sample (columns)."""
    return np.clip(np.asarray(z_nodes, float)[:, None] - np.asarray(z, float)[None, :], 0.0,
                   None) ** m


def hereditary_columns(t: np.ndarray, u: np.ndarray, W: np.ndarray | None) -> np.ndarray:
    """∫_0^{t_i} K(t_i − s)·du/ds ds [m^m·s⁰] for each row of ``u`` (G, N): ``W`` from
    :func:`kernel_matrix`, or None for the constant kernel K = 1 (u − u[:, :1])."""
    if W is None:
        return u - u[:, :1]
    r = np.diff(u, axis=1) / np.diff(t)[None, :]
    return r @ W.T


def lee_radok_columns(t: np.ndarray, lags: Lags, z_nodes: np.ndarray, z: np.ndarray, m: float,
                      kernel: str | None, theta: float = 0.0, t0: float = 1.0) -> np.ndarray:
    """∫_0^{t_i} K(t_i − s)·d/ds[d(s)^m] ds (G, N) for trial surfaces ``z_nodes`` (G,) [m]
    over heights ``z`` (N,) [m]: :func:`hereditary_columns` with :func:`onset_correction`;
    ``kernel`` None is the constant kernel (the SLS's E_inf, exact: d^m)."""
    u = depth_power(z_nodes, z, m)
    if kernel is None:
        return hereditary_columns(t, u, None)
    depth = np.asarray(z_nodes, float)[:, None] - np.asarray(z, float)[None, :]
    return (hereditary_columns(t, u, kernel_matrix(lags, kernel, theta, t0))
            + onset_correction(t, depth, m, kernel, theta, t0))
