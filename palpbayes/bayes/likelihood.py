"""Log-likelihood of one trace, vectorised over walkers.

Model: F_j = E*·s(z_s − z_j) + F0 + e_j with s the tip's shape function and the noise e
iid Gaussian (sd sigma), stationary AR(1) (marginal sd sigma, lag-one correlation phi) or
Student-t (scale sigma, nu_t degrees of freedom).

**Tabulated sufficient statistics (Gaussian and AR(1)).**  For fixed z_s the residual
r = F − E*·s − F0·1 is linear in (E*, F0), so every quadratic form r'·M·r the likelihood needs
(M = identity; the lag-one and interior matrices of AR(1)) is a polynomial in (E*, F0) whose
coefficients s'Ms, s'MF, s'M1 depend on z_s only.  Those coefficients are tabulated once per
trace on a grid of z_s — 128 points over the whole admissible range plus 384 points within ±40
least-squares standard errors of the least-squares surface — and interpolated by a cubic spline.
A likelihood evaluation then costs O(1) instead of O(n_points).  The approximation is checked
against the direct sum in the tests (|Δ log L| < 1e-3 at posterior draws; measured <= 7e-5 on
paper-like flat, sphere, paraboloid and cone traces, iid and AR(1), where the error is set by
floating-point cancellation in the quadratic forms rather than by the grid: 256 + 768 points
gave up to 7e-4); ``tabulate=False`` uses the direct sum everywhere.  Student-t has no such
statistics and is always direct.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.interpolate import CubicSpline
from scipy.special import gammaln

from ..fitdata import FitData
from ..shapekernel import cross_sums
from .noisemodels import EXACT_NOISE_MODELS

__all__ = ["TraceLikelihood", "COARSE_POINTS", "FINE_POINTS", "FINE_HALF_WIDTH"]

COARSE_POINTS = 128
FINE_POINTS = 384
#: Half-width of the fine grid in least-squares standard errors of z_surf.
FINE_HALF_WIDTH = 40.0
_LOG2PI = np.log(2.0 * np.pi)


def _pair(a: np.ndarray, b: np.ndarray, ar1: bool) -> np.ndarray:
    """a'M_k b for each matrix M_k, shape (…, K): identity, and for AR(1) also the symmetric
    lag-one matrix L (r'Lr = Σ r_t r_{t-1}) and the interior diagonal D (Σ_{t=2}^{N-1} r_t²).
    ``a`` may be (…, N) and ``b`` (N,) or (…, N)."""
    out = [np.einsum("...j,...j->...", a, b)]
    if ar1:
        out.append(0.5 * (np.einsum("...j,...j->...", a[..., 1:], b[..., :-1])
                          + np.einsum("...j,...j->...", a[..., :-1], b[..., 1:])))
        out.append(np.einsum("...j,...j->...", a[..., 1:-1], b[..., 1:-1]))
    return np.stack(np.broadcast_arrays(*out), axis=-1)


def _quad_forms(s: np.ndarray, F: np.ndarray, u: np.ndarray | None, ar1: bool) -> np.ndarray:
    """Statistics (…, P·K) of shape rows ``s`` (…, N): [sMs, sMF, sM1(, sMu)] for each M."""
    one = np.ones(F.size)
    parts = [_pair(s, s, ar1), _pair(s, F, ar1), _pair(s, one, ar1)]
    if u is not None:
        parts.append(_pair(s, u, ar1))
    return np.concatenate(parts, axis=-1)


def _const_forms(F: np.ndarray, u: np.ndarray | None, ar1: bool) -> dict[str, np.ndarray]:
    """Data-only forms for each matrix M: FMF, 1MF, 1M1 (and uMF, 1Mu, uMu), each (K,)."""
    one = np.ones(F.size)
    out = {"FF": _pair(F, F, ar1), "1F": _pair(one, F, ar1), "11": _pair(one, one, ar1)}
    if u is not None:
        out.update({"uF": _pair(u, F, ar1), "1u": _pair(one, u, ar1), "uu": _pair(u, u, ar1)})
    return out


def _form_value(stats: np.ndarray, const: dict, estar: np.ndarray, f0: np.ndarray,
                f1: np.ndarray | None, k: int, n_m: int) -> np.ndarray:
    """r'M_k r for r = F − E*·s − F0 − F1·u from the statistics of matrix k."""
    sMs, sMF, sM1 = stats[..., k], stats[..., n_m + k], stats[..., 2 * n_m + k]
    q = (const["FF"][k] - 2.0 * estar * sMF - 2.0 * f0 * const["1F"][k] + estar**2 * sMs
         + 2.0 * estar * f0 * sM1 + f0**2 * const["11"][k])
    if f1 is not None:
        sMu = stats[..., 3 * n_m + k]
        q = q + (f1**2 * const["uu"][k] - 2.0 * f1 * const["uF"][k] + 2.0 * estar * f1 * sMu
                 + 2.0 * f0 * f1 * const["1u"][k])
    return q


@dataclass
class TraceLikelihood:
    """Log-likelihood of θ = (log E*, z_s, log sigma, F0[, F1][, phi | log nu_t]) for one trace.

    The mean force is E*·s(z_s − z) + F0 (+ F1·(z − z_ref) with a linear baseline).

    Parameters
    ----------
    data
        Prepared fit data (points in time order).
    noise
        ``"gaussian"``, ``"ar1"`` or ``"student"``.
    tabulate
        Use the tabulated sufficient statistics (Gaussian/AR(1) only).
    z_center, z_scale
        [m] Centre and scale (a surface estimate and its standard error) of a fine grid.
    baseline
        ``"constant"`` (F0) or ``"linear"`` (F0 + F1·(z − z_ref)).
    z_ref
        [m] Reference height of the linear baseline (default: the top of the loading range).
    centers
        More (centre, scale) pairs [m], one fine grid each: every local optimum of the
        surface profile (:mod:`palpbayes.bayes.start`).
    """

    data: FitData
    noise: str = "gaussian"
    tabulate: bool = True
    z_center: float | None = None
    z_scale: float | None = None
    baseline: str = "constant"
    z_ref: float | None = None
    centers: tuple[tuple[float, float], ...] = ()

    def __post_init__(self) -> None:
        self._F = self.data.force
        self._z = self.data.z
        self._ar1 = self.noise == "ar1"
        self._n_m = 3 if self._ar1 else 1
        self._linear = self.baseline == "linear"
        if self.z_ref is None:
            self.z_ref = float(self.data.z_top)
        self._u = (self._z - self.z_ref) if self._linear else None
        self._const = _const_forms(self._F, self._u, self._ar1)
        self._n_stats = self._n_m * (4 if self._linear else 3)
        self._spline = None
        if self.tabulate and self.noise in EXACT_NOISE_MODELS:
            self._spline = self._build_table()

    @property
    def z_bounds(self) -> tuple[float, float]:
        """[m] Support of the z_surf prior: the whole loading range (docs/design.md §3.6)."""
        return self.data.z_prior

    def grid(self) -> np.ndarray:
        """The z_s grid of the tabulation [m]."""
        lo, hi = self.z_bounds
        parts = [np.linspace(lo, hi, COARSE_POINTS)]
        centers = list(self.centers)
        if self.z_center is not None:
            centers.append((self.z_center, self.z_scale))
        for c, scale in centers:
            if not (scale and np.isfinite(scale) and np.isfinite(c)):
                continue
            half = FINE_HALF_WIDTH * max(scale, 1e-9 * (hi - lo), 1e-15)
            a, b = max(lo, c - half), min(hi, c + half)
            if b > a:
                parts.append(np.linspace(a, b, FINE_POINTS))
        return np.unique(np.concatenate(parts))

    def _direct_stats(self, z_surf: np.ndarray) -> np.ndarray:
        """The statistics of :func:`_quad_forms` at each z_s, from the compiled loop's sums
        (:func:`palpbayes.shapekernel.cross_sums`, no (z_s × sample) array): with the columns
        c = (F, 1[, u]), s'c is Σ s·c; for AR(1) the lag-one form is half of
        Σ s_t·c_(t−1) + Σ s_(t−1)·c_t and the interior one Σ s·c less the first and last
        samples' terms."""
        z_surf = np.ascontiguousarray(z_surf, dtype=float)
        cols = [self._F, np.ones(self._F.size)] + ([self._u] if self._linear else [])
        C = np.column_stack(cols)
        ss, sc, l00, l0c, lc0, s0, s1, _ = cross_sums(z_surf, self._z, C, self.data.model,
                                                      self._ar1)
        # rows: s, then each column of C (F, 1, u), as _quad_forms orders them
        plain = [ss] + [sc[:, j] for j in range(C.shape[1])]
        if not self._ar1:
            return np.column_stack(plain)
        lag = [l00] + [0.5 * (l0c[:, j] + lc0[:, j]) for j in range(C.shape[1])]
        inner = [ss - s0 * s0 - s1 * s1] + [sc[:, j] - s0 * C[0, j] - s1 * C[-1, j]
                                             for j in range(C.shape[1])]
        return np.column_stack([x for trio in zip(plain, lag, inner, strict=True)
                                for x in trio])

    def _build_table(self) -> CubicSpline:
        grid = self.grid()
        return CubicSpline(grid, self._direct_stats(grid), axis=0)

    def statistics(self, z_surf: np.ndarray, direct: bool = False) -> np.ndarray:
        """Quadratic-form statistics at each z_s, shape (W, K)."""
        z_surf = np.atleast_1d(np.asarray(z_surf, dtype=float))
        if self._spline is not None and not direct:
            return self._spline(z_surf)
        return self._direct_stats(z_surf)

    def _split(self, theta: np.ndarray):
        estar = np.exp(theta[:, 0])
        f1 = theta[:, 4] if self._linear else None
        extra = theta[:, 5 if self._linear else 4] if self.noise != "gaussian" else None
        return estar, theta[:, 1], np.exp(theta[:, 2]), theta[:, 3], f1, extra

    def __call__(self, theta: np.ndarray, direct: bool = False) -> np.ndarray:
        """Log-likelihood for θ of shape (W, ndim) (or (ndim,)); returns shape (W,)."""
        theta = np.atleast_2d(theta)
        estar, zs, sigma, f0, f1, extra = self._split(theta)
        if self.noise == "student":
            return self._student(estar, zs, sigma, f0, f1, np.exp(extra))
        return self.from_statistics(self.statistics(zs, direct=direct), theta)

    def stats_of_rows(self, s: np.ndarray) -> np.ndarray:
        """Quadratic-form statistics (W, K) of given shape rows ``s`` (W, N) [m²]: for models
        whose shape differs per walker (:mod:`palpbayes.bayes.layer_likelihood`)."""
        return _quad_forms(s, self._F, self._u, self._ar1)

    def from_statistics(self, stats: np.ndarray, theta: np.ndarray) -> np.ndarray:
        """Gaussian or AR(1) log-likelihood (W,) from the statistics of each walker's shape."""
        estar, _, sigma, f0, f1, extra = self._split(np.atleast_2d(theta))
        n = self._F.size
        q0 = _form_value(stats, self._const, estar, f0, f1, 0, self._n_m)
        if not self._ar1:
            return -n * np.log(sigma) - 0.5 * n * _LOG2PI - 0.5 * q0 / sigma**2
        phi = extra
        q1 = _form_value(stats, self._const, estar, f0, f1, 1, self._n_m)
        q2 = _form_value(stats, self._const, estar, f0, f1, 2, self._n_m)
        one_m = 1.0 - phi**2
        quad = (q0 - 2.0 * phi * q1 + phi**2 * q2) / one_m
        return (-n * np.log(sigma) - 0.5 * (n - 1) * np.log(one_m) - 0.5 * n * _LOG2PI
                - 0.5 * quad / sigma**2)

    def _student(self, estar, zs, sigma, f0, f1, nu_t, shape_rows=None) -> np.ndarray:
        n = self._F.size
        nu = nu_t
        tail = np.empty(zs.size)
        for rows in self.data.blocks(zs.size):
            s = (self.data.shape(zs[rows, None] - self._z[None, :]) if shape_rows is None
                 else shape_rows(rows))
            mean = estar[rows, None] * s + f0[rows, None]
            if f1 is not None:
                mean = mean + f1[rows, None] * self._u[None, :]
            r = (self._F[None, :] - mean) / sigma[rows, None]
            tail[rows] = np.log1p(r * r / nu[rows, None]).sum(axis=1)
        return (n * (gammaln((nu + 1) / 2) - gammaln(nu / 2) - 0.5 * np.log(nu * np.pi))
                - n * np.log(sigma) - 0.5 * (nu + 1) * tail)

    def student_rows(self, theta: np.ndarray, shape_rows) -> np.ndarray:
        """Student-t log-likelihood (W,) with each walker's shape row from
        ``shape_rows(rows) -> (len(rows), N)``."""
        estar, zs, sigma, f0, f1, extra = self._split(np.atleast_2d(theta))
        return self._student(estar, zs, sigma, f0, f1, np.exp(extra), shape_rows)

    def mean_force(self, theta: np.ndarray, z: np.ndarray | None = None) -> np.ndarray:
        """Model force [N] at heights ``z`` (default: the fitted samples) for one θ."""
        theta = np.asarray(theta, dtype=float)
        z = self._z if z is None else np.asarray(z, dtype=float)
        out = np.exp(theta[0]) * self.data.shape(theta[1] - z) + theta[3]
        if self._linear:
            out = out + theta[4] * (z - self.z_ref)
        return out

    def residuals(self, theta: np.ndarray) -> np.ndarray:
        """Residuals F − model [N] for one parameter vector."""
        return self._F - self.mean_force(theta)
