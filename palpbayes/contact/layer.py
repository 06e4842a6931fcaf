"""Indentation of an elastic layer on a rigid base: the bottom-effect factor, solved numerically.

A rigid axisymmetric tip pressed into a layer of thickness h that rests on a rigid base feels
more force than on a half-space (the base carries load).  This module computes the factor
f = F_layer(d) / F_half-space(d) from the exact linear-elastic solution, for any tip profile
f(r) = c·r^n (flat punch, paraboloid, cone, power law; the sphere through its contact radius),
any Poisson ratio and both base conditions:

* **bonded** (no slip at the base): kernel of Hayes et al. (1972) / Lebedev & Ufliand (1958),
  K(t) = (2k·sinh 2t − 4t) / (2k·cosh 2t + 1 + k² + 4t²), k = 3 − 4·nu;
* **free** (frictionless base, the layer may slip): K(t) = (cosh 2t − 1) / (sinh 2t + 2t),
  which does not depend on nu (in terms of E* = E/(1 − nu²)).

K(xi·h) is the ratio of the layer's surface compliance to the half-space's for a pressure
wave of wavenumber xi; both forms were re-derived here from the axisymmetric Navier equations
by a 4 × 4 transfer matrix (``tests/unit/test_layer.py`` checks them against it).

**The integral equation.**  With the contact pressure written through Copson's representation
P(xi) = ∫_0^a g(t)·cos(xi·t) dt, the mixed boundary-value problem reduces to a Fredholm
equation of the second kind on the contact radius a (Lebedev & Ufliand 1958; Hayes et al.
1972, eq. 11; the equation Dimitriadis et al. 2002 expand in powers of a/h)::

    phi(tau) + (lambda/pi)·∫_0^1 phi(s)·[k(lambda·(s − tau)) + k(lambda·(s + tau))] ds = r(tau),
    k(y) = ∫_0^∞ (K(u) − 1)·cos(u·y) du,          lambda = a/h,

with r = 1 for the punch's rigid displacement and r = tau^n for a profile c·r^n (Hess's
factor kappa_n absorbed; :mod:`palpbayes.contact.mdr`).  It is solved by Nyström's method on
Gauss–Legendre nodes (converged to 1e-10 at 16 nodes for lambda <= 1; the node count grows
with lambda).  For a flat punch of radius a the factor is ∫_0^1 phi (r = 1); for a curved
profile the pressure must vanish at the edge, which fixes the depth for each a, and
f(chi) follows with chi = a_hs(d)/h, a_hs the half-space contact radius at the same depth
(sqrt(R·d) for the paraboloid: Dimitriadis' chi).

**Checked against the literature** (``tests/unit/test_layer.py``): Hayes' bonded flat-punch
kappa at a/h = 0.2…1.0 for nu = 0.3 and 0.5 (design.md §1) to 4 digits; Garcia & Garcia's
(2018) bonded polynomials at nu = 0.5 (paraboloid within 0.2 % for chi <= 0.35, flat punch
within 3 %); Dimitriadis et al.'s (2002) series at small chi.  Where they part: Dimitriadis'
bonded series falls 2 % below the solution at chi = 0.27 (nu = 0.5) and 8 % at chi = 0.49,
and his non-bonded coefficients carry a nu-dependence that the frictionless kernel does not
have (first-order coefficient 0.884 at nu = 0.5 against 0.743 here, from
alpha0 = ∫(K − 1) du = −1.1676); Garcia's polynomials are fits at nu = 0.5 and do not apply
at other nu.  The closed forms stay available in :mod:`palpbayes.contact.thickness`.

**The sphere.**  A sphere's factor depends on a/R as well as a/h; evaluating the paraboloid's
factor at the sphere's own (Sneddon) half-space contact radius reproduces the direct sphere
solution within 0.3 % for d/R <= 0.35 (0.05 % at d/R = 0.04), where sqrt(R·d) would be
2.8 % off at d/R = 0.35.

**Validity.**  Linear elasticity with small strain, a frictionless tip, a layer of infinite
lateral extent.  The tables cover a/h <= :data:`LAMBDA_MAX`; beyond, the factor is
continued as a power law of chi; a fit whose contact is wider than :data:`LAMBDA_VALID`
times the layer carries a note (:func:`palpbayes.bayes.layer_fit.layer_notes`), one whose
indentation is deeper than the layer a warning.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
from numpy.polynomial.legendre import leggauss

__all__ = [
    "BASES",
    "LAMBDA_MAX",
    "LAMBDA_VALID",
    "kernel",
    "kernel_transform",
    "solve_layer",
    "flat_punch_factor",
    "profile_table",
    "ProfileTable",
    "profile_factor",
    "flat_table",
]

#: Base conditions: the layer bonded to the rigid base, or free to slip on it (frictionless).
BASES = ("bonded", "free")
#: Largest contact radius / thickness a/h of the tabulated solution.
LAMBDA_MAX = 8.0
#: a/h beyond which a fit carries a note: a contact much wider than the layer (thin-layer
#: regime: the answer hangs on compressibility and the base condition; strains are large).
LAMBDA_VALID = 2.0

# k(y) = ∫_0^∞ (K(u) − 1)·cos(u·y) du by Gauss–Legendre on [0, U_MAX] (K − 1 ~ e^(−2u):
# below 1e-20 past u = 25), tabulated on y in [0, 2·LAMBDA_MAX] and splined.
_U_MAX = 25.0
_U_PANELS, _U_ORDER = 200, 16   # composite Gauss–Legendre: 3,200 nodes, ~25 per period of
_Y_STEP = 0.005                 # cos(u·y) at the largest y
_Y_BLOCK = 64
# lambda grid of the profile tables: dense near 0 (chi ~ lambda), 241 points
_LAMBDA_GRID = LAMBDA_MAX * np.linspace(0.0, 1.0, 241) ** 2
# uniform chi grid of the lookup table (np.interp at run time)
_CHI_POINTS = 4097


def _check_base(base: str) -> str:
    if base not in BASES:
        raise ValueError(f"unknown base condition {base!r}; use one of {', '.join(BASES)}")
    return base


def kernel(t: np.ndarray, nu: float, base: str) -> np.ndarray:
    """K(t) [-]: the layer's surface compliance over the half-space's at t = xi·h.

    Written with e^(−2t) so that it neither overflows nor cancels for large t (K -> 1).

    Parameters
    ----------
    t
        Wavenumber times thickness [-], t >= 0.
    nu
        Poisson ratio [-] (bonded base only; the frictionless kernel does not depend on it).
    base
        ``"bonded"`` or ``"free"``.
    """
    t = np.asarray(t, dtype=float)
    e2, e4 = np.exp(-2.0 * t), np.exp(-4.0 * t)
    if _check_base(base) == "free":
        den = 1.0 - e4 + 4.0 * t * e2  # 0 only at t = 0, where K = 0
        return np.where(t > 0, (1.0 - e2) ** 2 / np.where(t > 0, den, 1.0), 0.0)
    k = 3.0 - 4.0 * nu
    return (2.0 * k * (1.0 - e4) - 8.0 * t * e2) / (
        2.0 * k * (1.0 + e4) + 2.0 * (1.0 + k * k + 4.0 * t * t) * e2)


@dataclass(frozen=True)
class _UniformCubic:
    """A cubic spline on the uniform knots 0, step, 2·step, ... (coefficients ``c`` of
    :class:`scipy.interpolate.CubicSpline`, shape (4, intervals)), evaluated by index
    arithmetic instead of a search: its values to 1 ulp, four times faster.  Beyond the last
    knot the last cubic is continued (below 0 the first), as scipy's default extrapolation;
    NaN gives NaN."""

    step: float
    c: np.ndarray

    def __call__(self, y: np.ndarray) -> np.ndarray:
        y = np.asarray(y, dtype=float)
        q = y * (1.0 / self.step)  # the interval's index, clipped before the cast (NaN, inf)
        i = np.minimum(np.where(q > 0, q, 0.0), self.c.shape[1] - 1).astype(np.intp)
        dx = y - i * self.step
        c = self.c
        return ((c[0, i] * dx + c[1, i]) * dx + c[2, i]) * dx + c[3, i]


@functools.lru_cache(maxsize=64)
def _transform_spline(nu: float, base: str) -> _UniformCubic:
    from scipy.interpolate import CubicSpline  # here: importing palpbayes stays quick

    x, w = leggauss(_U_ORDER)
    edges = np.linspace(0.0, _U_MAX, _U_PANELS + 1)
    half = 0.5 * np.diff(edges)[:, None]
    u = (edges[:-1, None] + half * (x[None, :] + 1.0)).ravel()
    g = (kernel(u, nu, base) - 1.0) * (half * w[None, :]).ravel()
    y = np.arange(0.0, 2.0 * LAMBDA_MAX + 4 * _Y_STEP, _Y_STEP)
    # cos(y·u) for y = start + b·step in blocks of _Y_BLOCK rows: Re(exp(i·start·u)·exp(i·b·
    # step·u)), two small tables of exponentials and one complex matrix product (the direct
    # cos of every (y, u) pair to 3e-15; ten times faster)
    starts = y[::_Y_BLOCK]
    rows = np.exp(1j * np.outer(np.arange(_Y_BLOCK) * _Y_STEP, u))
    vals = ((np.exp(1j * np.outer(starts, u)) * g) @ rows.T).real.ravel()[:y.size]
    return _UniformCubic(_Y_STEP, CubicSpline(y, vals).c)


def _key_nu(nu: float, base: str) -> float:
    """The cache key of nu: irrelevant for a free base, rounded to 1e-6 otherwise."""
    return 0.0 if base == "free" else round(float(nu), 6)


def kernel_transform(y: np.ndarray, nu: float, base: str) -> np.ndarray:
    """k(y) = ∫_0^∞ (K(u) − 1)·cos(u·y) du [-] for |y| <= 2·:data:`LAMBDA_MAX` (even in y)."""
    return _transform_spline(_key_nu(nu, base), _check_base(base))(np.abs(y))


def _nodes(lam: float) -> int:
    """Nyström nodes for a/h = lam: the kernel varies over 1/lam in tau."""
    return int(24 + 12 * math.ceil(lam))


def solve_layer(lam: float, nu: float, base: str, exponents: tuple[float, ...] = (0.0,)
                ) -> tuple[np.ndarray, np.ndarray]:
    """Solve the layer's Fredholm equation (module docstring) for right-hand sides tau^n.

    Parameters
    ----------
    lam
        Contact radius over thickness a/h [-], 0 <= lam <= :data:`LAMBDA_MAX` (the kernel
        transform is tabulated for the arguments up to 2·:data:`LAMBDA_MAX` that it takes).
    nu, base
        Poisson ratio [-] and base condition (:func:`kernel`).
    exponents
        n of each right-hand side r(tau) = tau^n (0: the rigid displacement).

    Returns
    -------
    edge, integral
        phi(1) and ∫_0^1 phi(tau) dtau for each right-hand side.
    """
    if not 0.0 <= lam <= LAMBDA_MAX:
        raise ValueError(f"a/h = {lam!r} is outside the layer solution's range "
                         f"[0, {LAMBDA_MAX:g}]; beyond it use the tables' power-law tail "
                         "(flat_punch_factor, profile_factor)")
    edge, integral = _solve_many(np.array([float(lam)]), nu, base, exponents)
    return edge[0], integral[0]


def _solve_many(lams: np.ndarray, nu: float, base: str, exponents: tuple[float, ...]
                ) -> tuple[np.ndarray, np.ndarray]:
    """:func:`solve_layer` at every a/h of ``lams``: edges and integrals, shape
    (lams, exponents).  The values of a/h that take the same Nyström nodes are solved as one
    stack (one spline evaluation and one batched solve per node count)."""
    lams = np.asarray(lams, dtype=float)
    edge = np.empty((lams.size, len(exponents)))
    integral = np.empty_like(edge)
    spline = _transform_spline(_key_nu(nu, base), _check_base(base))
    counts = np.array([_nodes(float(v)) for v in lams])
    for n in np.unique(counts):
        pick = np.flatnonzero(counts == n)
        lam = lams[pick, None, None]
        x, w = leggauss(int(n))
        t, wt = 0.5 * (x + 1.0), 0.5 * w
        rhs = np.column_stack([t ** e for e in exponents])
        km = spline(lam * np.abs(t[None, :] - t[:, None])) + spline(lam * (t[None, :] + t[:, None]))
        phi = np.linalg.solve(np.eye(int(n)) + (lam / np.pi) * km * wt[None, :],
                              np.broadcast_to(rhs, (pick.size,) + rhs.shape))
        k1 = spline(lam[:, :, 0] * (1.0 - t)) + spline(lam[:, :, 0] * (1.0 + t))  # (k, n)
        edge[pick] = 1.0 - (lam[:, :, 0] / np.pi) * np.einsum("kn,kne->ke", k1 * wt, phi)
        integral[pick] = np.einsum("n,kne->ke", wt, phi)
    return edge, integral


def flat_punch_factor(a_over_h, nu: float, base: str):
    """F_layer / F_half-space for a flat punch of radius a on a layer of thickness h [-].

    Hayes et al. (1972)'s kappa(a/h, nu) for the bonded base, the frictionless one for
    ``base="free"``; independent of depth.  Solved directly for a scalar a/h within the table
    (:data:`LAMBDA_MAX`); arrays are looked up in :func:`flat_table` (interpolation error
    below 1e-6).  Beyond :data:`LAMBDA_MAX` the solution is continued as a power law of a/h.
    """
    if np.ndim(a_over_h) == 0 and 0.0 <= float(a_over_h) <= LAMBDA_MAX:
        return float(solve_layer(float(a_over_h), nu, base)[1][0])
    return flat_table(nu, base).factor(a_over_h)


@dataclass(frozen=True)
class _LogTable:
    """ln f tabulated on a uniform grid of x, continued as a power law of x beyond it."""

    x: np.ndarray
    log_factor: np.ndarray
    tail_slope: float

    def factor(self, x: np.ndarray) -> np.ndarray:
        """f(x) [-] (1 at x <= 0)."""
        x = np.asarray(x, dtype=float)
        c = x.ravel()
        lf = np.interp(c, self.x, self.log_factor, left=0.0)  # ln f = 0 at x <= 0
        beyond = c > self.x[-1]
        if beyond.any():  # the power-law tail, on those points only
            lf[beyond] = self.log_factor[-1] + self.tail_slope * np.log(c[beyond] / self.x[-1])
        return np.exp(lf, out=lf).reshape(x.shape)[()]


def _log_table(x: np.ndarray, logf: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    from scipy.interpolate import PchipInterpolator  # here: importing palpbayes stays quick

    grid = np.linspace(0.0, x[-1], _CHI_POINTS)
    slope = (logf[-1] - logf[-6]) / math.log(x[-1] / x[-6])
    return grid, PchipInterpolator(x, logf)(grid), float(slope)


@functools.lru_cache(maxsize=64)
def _flat_table(nu: float, base: str) -> _LogTable:
    lams = _LAMBDA_GRID
    logf = np.log(_solve_many(lams, nu, base, (0.0,))[1][:, 0])
    return _LogTable(*_log_table(lams, logf))


def flat_table(nu: float, base: str) -> _LogTable:
    """The flat punch's factor tabulated in a/h (cached per process; ~0.1 s to build)."""
    base = _check_base(base)
    return _flat_table(_key_nu(nu, base), base)


@dataclass(frozen=True)
class ProfileTable:
    """The bottom-effect factor of a profile c·r^n as a function of chi = a_hs(d)/h.

    Attributes
    ----------
    n
        Profile exponent (2 paraboloid and sphere, 1 cone).
    nu, base
        Poisson ratio and base condition.
    chi, log_factor
        Uniform grid of chi [-] and ln f on it (looked up with :func:`numpy.interp`).
    lam
        a/h of the layer solution at each chi of the grid (the layer's own contact radius).
    tail_slope
        d ln f / d ln chi beyond the grid (power-law continuation).
    """

    n: float
    nu: float
    base: str
    chi: np.ndarray
    log_factor: np.ndarray
    lam: np.ndarray
    tail_slope: float

    def factor(self, chi: np.ndarray) -> np.ndarray:
        """f(chi) [-] (1 at chi <= 0)."""
        return _LogTable(self.chi, self.log_factor, self.tail_slope).factor(chi)

    def contact_ratio(self, chi: np.ndarray) -> np.ndarray:
        """The layer's contact radius over its thickness a/h at chi [-]."""
        return np.interp(np.clip(np.asarray(chi, dtype=float), 0.0, None), self.chi, self.lam,
                         right=np.nan)


@functools.lru_cache(maxsize=128)
def _profile_table(n: float, nu: float, base: str) -> ProfileTable:
    from scipy.interpolate import PchipInterpolator

    lams = _LAMBDA_GRID[1:]
    edge, integ = _solve_many(lams, nu, base, (0.0, n))
    rho = edge[:, 1] / edge[:, 0]          # depth = kappa_n·c·a^n·rho
    chi = lams * rho ** (1.0 / n)          # half-space contact radius at that depth, over h
    f = (n + 1) / n * lams ** (n + 1) * (rho * integ[:, 0] - integ[:, 1]) / chi ** (n + 1)
    chis, logf = np.r_[0.0, chi], np.r_[0.0, np.log(f)]
    grid, table, slope = _log_table(chis, logf)
    return ProfileTable(n=n, nu=nu, base=base, chi=grid, log_factor=table,
                        lam=PchipInterpolator(chis, np.r_[0.0, lams])(grid), tail_slope=slope)


def profile_table(n: float, nu: float, base: str) -> ProfileTable:
    """The :class:`ProfileTable` of profile exponent ``n`` (cached per process).

    Building one costs ~0.1 s (240 Nyström solves, stacked by node count), and the kernel
    transform of its nu and base ~0.02 s the first time; it is kept for the life of the
    process.
    """
    base = _check_base(base)
    if not (math.isfinite(n) and n > 0):
        raise ValueError(f"profile exponent n = {n!r} must be positive")
    return _profile_table(round(float(n), 9), _key_nu(nu, base), base)


def profile_factor(chi: np.ndarray, n: float, nu: float, base: str) -> np.ndarray:
    """Bottom-effect factor f(chi) of a profile c·r^n [-]; chi = a_hs(d)/h (module docstring).
    """
    return profile_table(n, nu, base).factor(chi)
