"""Where the walkers start: every mode of the surface posterior.

For Gaussian and AR(1) noise the modes and their masses come from the exact engine
(:func:`modes_from_exact`, :mod:`palpbayes.bayes.exact`); otherwise (Student-t noise, the soft
surface prior) from the profile scan below.

For a trial surface z_s the mean force E*·s(z_s − z) + F0 (+ F1·(z − z_ref)) is linear in
β = (E*, F0[, F1]), so the least-squares β(z_s) and the residual sum of squares RSS(z_s) have a
closed form (normal equations, with E* >= 0). The Gaussian priors of F0 (and F1) enter as
pseudo-observations weighted by (sigma0/sd)², sigma0 the prior's noise scale — without them a
flat punch whose window lies wholly in contact has no optimum along its z_surf–F0 ridge. The
profile log-likelihood of iid Gaussian noise, ℓ(z_s) = −(n/2)·ln RSS(z_s), is scanned on
:data:`SCAN_POINTS` heights over the whole loading range (the surface prior's support), every
local maximum is refined with bounded Brent (:func:`scipy.optimize.minimize_scalar`), and each
becomes a :class:`Mode` with its Gauss–Newton covariance. The modes are weighted by their
Laplace evidence, exp(ℓ)·sqrt(det cov), and the walkers are shared among those holding at least
:data:`MIN_WEIGHT` of it, so a second surface that fits almost as well is sampled instead of
missed — and then flagged as bimodal. The others are kept in the fit's record
(``other_modes``).

Walkers start in a small Gaussian ball shaped by each mode's covariance (0.1 of its sd), so
they lie along a long thin ridge rather than across it; emcee's moves then spread them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import optimize

from ..fitdata import FitData
from ..sensor_noise import acf1
from ..shapekernel import cross_sums
from .priors import TracePrior

__all__ = ["Mode", "find_modes", "modes_from_exact", "initial_ensemble", "SCAN_POINTS",
           "MIN_WEIGHT", "BALL"]

#: Heights of the coarse profile scan over the loading range.
SCAN_POINTS = 256
#: Smallest Laplace weight of a mode that gets walkers.
MIN_WEIGHT = 0.02
#: Start ball: this fraction of each mode's standard deviations.
BALL = 0.1


@dataclass(frozen=True)
class Mode:
    """A local optimum of the surface profile.

    Attributes
    ----------
    z_surf
        [m] Surface height.
    beta
        (E* [Pa], F0 [N][, F1 [N/m]]) least-squares values at ``z_surf``.
    rss
        [N²] Residual sum of squares.
    loglik
        Profile log-likelihood −(n/2)·ln(RSS/n) − n/2.
    cov
        Gauss–Newton covariance of (E*, z_s, F0[, F1]), the θ order (NaN when singular).
    lag1
        Lag-one autocorrelation of the residuals (time order).
    weight
        Laplace weight among all modes found (sums to 1).
    """

    z_surf: float
    beta: np.ndarray
    rss: float
    loglik: float
    cov: np.ndarray
    lag1: float
    weight: float = 1.0


@dataclass(frozen=True)
class _Penalty:
    """Gaussian priors of the linear baseline terms as pseudo-observations: rows
    sqrt(w_k)·(β_k − c_k) with w_k = (sigma0/sd_k)², for β_k = F0 (and F1)."""

    centers: np.ndarray
    weights: np.ndarray

    def rows(self, p: int) -> tuple[np.ndarray, np.ndarray]:
        """Extra design rows (k, p) and targets (k,) for p linear coefficients."""
        k = self.centers.size
        X = np.zeros((k, p))
        X[np.arange(k), 1 + np.arange(k)] = np.sqrt(self.weights)
        return X, np.sqrt(self.weights) * self.centers


def _design(data: FitData, z_s: float, u: np.ndarray | None) -> np.ndarray:
    cols = [data.shape(z_s - data.z), np.ones(data.n_points)]
    if u is not None:
        cols.append(u)
    return np.column_stack(cols)


def _solve(X: np.ndarray, F: np.ndarray, pen: _Penalty) -> tuple[np.ndarray, float]:
    """Penalised least squares of F on the columns of X with the first coefficient (E*) >= 0.

    Returns β and the residual sum of squares of the data (without the pseudo-observations).
    """
    Xp, Fp = pen.rows(X.shape[1])
    beta, *_ = np.linalg.lstsq(np.vstack([X, Xp]), np.concatenate([F, Fp]), rcond=None)
    if not beta[0] > 0:
        sub, *_ = np.linalg.lstsq(np.vstack([X, Xp])[:, 1:], np.concatenate([F, Fp]),
                                  rcond=None)
        beta = np.concatenate([[0.0], sub])
    r = F - X @ beta
    rp = Fp - Xp @ beta
    return beta, float(r @ r + rp @ rp)


def _profile_grid(data: FitData, zs: np.ndarray, u: np.ndarray | None,
                  pen: _Penalty) -> np.ndarray:
    """Penalised RSS(z_s) on a grid from the normal equations."""
    F = data.force
    n = data.n_points
    one = np.ones(n)
    cols_const = [one] + ([u] if u is not None else [])
    C = np.array([[a @ b for b in cols_const] for a in cols_const])  # constant block
    cF = np.array([a @ F for a in cols_const])
    FF = float(F @ F)
    # pseudo-observations of the priors
    C = C + np.diag(pen.weights)
    cF = cF + pen.weights * pen.centers
    FF += float(pen.weights @ pen.centers**2)
    # Σ s², Σ s·c and Σ s·F at every trial surface: the compiled loop, no (z_s × sample) array
    ss, sums = cross_sums(zs, data.z, np.column_stack(cols_const + [F]), data.model, False)[:2]
    sc, sF = sums[:, :-1], sums[:, -1]
    k = 1 + len(cols_const)
    A = np.empty((ss.size, k, k))
    A[:, 0, 0] = ss
    A[:, 0, 1:] = sc
    A[:, 1:, 0] = sc
    A[:, 1:, 1:] = C
    b = np.concatenate([sF[:, None], np.broadcast_to(cF, (ss.size, cF.size))], axis=1)
    with np.errstate(all="ignore"):
        beta = np.linalg.solve(A + np.eye(k) * 1e-300, b[..., None])[..., 0]
        full = FF - np.einsum("ij,ij->i", beta, b)
        base = FF - cF @ np.linalg.solve(C, cF)
    bad = ~(beta[:, 0] > 0) | ~np.isfinite(full) | (ss <= 0)
    return np.where(bad, base, full)


def _gauss_newton_cov(data: FitData, z_s: float, beta: np.ndarray, rss: float,
                      u: np.ndarray | None, pen: _Penalty) -> np.ndarray:
    """Covariance s²·(JᵀJ + P)⁻¹ of (E*, z_s, F0[, F1]), P the priors' pseudo-rows."""
    d = z_s - data.z
    cols = [data.shape(d), beta[0] * data.model.shape_derivative(d), np.ones(data.n_points)]
    if u is not None:
        cols.append(u)
    J = np.column_stack(cols)
    H = J.T @ J
    k = pen.weights.size
    H[2 + np.arange(k), 2 + np.arange(k)] += pen.weights
    s2 = rss / max(data.n_points - J.shape[1], 1)
    try:
        cov = s2 * np.linalg.inv(H)
    except np.linalg.LinAlgError:
        return np.full(H.shape, np.nan)
    return cov if np.all(np.diag(cov) > 0) else np.full(H.shape, np.nan)


def find_modes(data: FitData, prior: TracePrior, max_drop: float = 20.0) -> list[Mode]:
    """Local optima of the surface profile over the surface prior's support.

    Parameters
    ----------
    data
        Prepared fit data.
    prior
        The trace's prior: baseline model and its reference height, the F0 (F1) priors that
        enter as pseudo-observations, the noise scale and the surface support.
    max_drop
        Modes whose profile log-likelihood is more than this below the best are dropped.

    Returns
    -------
    list of Mode
        Best first, with Laplace weights summing to 1.
    """
    lo, hi = prior.z_bounds
    linear = prior.baseline == "linear"
    u = (data.z - prior.z_ref) if linear else None
    s0 = prior.sigma_center
    pen = _Penalty(
        centers=np.array([prior.f0_center] + ([0.0] if linear else [])),
        weights=np.array([(s0 / prior.f0_sd) ** 2] + ([(s0 / prior.f1_sd) ** 2] if linear
                                                      else [])))
    grid = np.linspace(lo, hi, SCAN_POINTS)
    rss = _profile_grid(data, grid, u, pen)
    n = data.n_points
    is_min = np.r_[rss[0] < rss[1], (rss[1:-1] <= rss[:-2]) & (rss[1:-1] <= rss[2:]),
                   rss[-1] < rss[-2]]
    cand = np.flatnonzero(is_min)
    best_grid = float(rss[cand].min())
    cand = [i for i in cand if -0.5 * n * np.log(rss[i] / best_grid) > -2 * max_drop]

    def scalar(z: float) -> float:
        return _solve(_design(data, z, u), data.force, pen)[1]

    found: list[tuple[float, np.ndarray, float]] = []
    for i in cand:
        a, b = grid[max(i - 1, 0)], grid[min(i + 1, grid.size - 1)]
        width = b - a
        res = optimize.minimize_scalar(lambda x, a=a, w=width: scalar(a + x * w),
                                       bounds=(0.0, 1.0), method="bounded",
                                       options={"xatol": 1e-10})
        z = a + float(res.x) * width
        if scalar(grid[i]) < res.fun:
            z = float(grid[i])
        beta, r = _solve(_design(data, z, u), data.force, pen)
        if beta[0] > 0 and not any(abs(z - f[0]) <= width for f in found):
            found.append((z, beta, r))
    if not found:  # fall back on the best grid point
        i = int(np.argmin(rss))
        beta, r = _solve(_design(data, grid[i], u), data.force, pen)
        found.append((float(grid[i]), beta, r))
    modes = []
    for z, beta, r in found:
        ll = -0.5 * n * np.log(r / n) - 0.5 * n
        cov = (_gauss_newton_cov(data, z, beta, r, u, pen) if beta[0] > 0
               else np.full((3 + linear,) * 2, np.nan))
        X = _design(data, z, u)
        res = data.force - X @ beta
        lag1 = acf1(res)
        modes.append(Mode(z_surf=z, beta=beta, rss=r, loglik=float(ll), cov=cov, lag1=lag1))
    best = max(m.loglik for m in modes)
    modes = [m for m in modes if m.loglik > best - max_drop]
    logw = np.array([m.loglik + 0.5 * _logdet(m.cov) for m in modes])
    w = np.exp(logw - logw.max())
    w /= w.sum()
    modes = [Mode(m.z_surf, m.beta, m.rss, m.loglik, m.cov, m.lag1, float(wi))
             for m, wi in zip(modes, w, strict=True)]
    return sorted(modes, key=lambda m: -m.weight)


def modes_from_exact(post, rng: np.random.Generator, n_draws: int = 4000) -> list[Mode]:
    """Modes of the exact posterior (:class:`palpbayes.bayes.exact.ExactPosterior`), with
    their exact masses and the mean and covariance of the draws in each one's basin.

    Used instead of :func:`find_modes` for Gaussian and AR(1) noise: the walkers then start
    at every mode in proportion to its posterior mass, not to a Laplace approximation of it.
    """
    found = post.basins()
    d = post.draws(rng, n_draws)
    z = d["z_surf"]
    owner = np.full(z.size, -1)
    for k, (_, _, lo, hi) in enumerate(found):  # each draw to the basin it lies in
        owner[(z >= lo) & (z < hi)] = k
    cols = ["E_star", "z_surf", "F0"] + (["F1"] if "F1" in d else [])
    out = []
    for k, (_, mass, _, _) in enumerate(found):
        sel = owner == k
        if sel.sum() < 10:
            continue
        X = np.column_stack([d[c][sel] for c in cols])
        mean = X.mean(axis=0)
        sigma = float(np.median(d["sigma"][sel]))
        n = post.post.nu
        out.append(Mode(z_surf=float(mean[1]), beta=np.r_[mean[0], mean[2:]],
                        rss=n * sigma**2, loglik=np.nan, cov=np.cov(X, rowvar=False),
                        lag1=float(np.median(d["phi"][sel])) if "phi" in d else 0.0,
                        weight=float(mass)))
    total = sum(m.weight for m in out)
    return sorted([Mode(m.z_surf, m.beta, m.rss, m.loglik, m.cov, m.lag1, m.weight / total)
                   for m in out], key=lambda m: -m.weight)


def _logdet(cov: np.ndarray) -> float:
    sign, ld = np.linalg.slogdet(cov) if np.all(np.isfinite(cov)) else (0.0, 0.0)
    return float(ld) if sign > 0 else 0.0


def initial_ensemble(modes: list[Mode], names: list[str] | tuple[str, ...], n_walkers: int,
                     rng: np.random.Generator, z_bounds: tuple[float, float],
                     log_estar_bounds: tuple[float, float] = (-np.inf, np.inf),
                     n: int = 1) -> tuple[np.ndarray, list[Mode]]:
    """Walkers around every mode of weight >= :data:`MIN_WEIGHT`, in proportion to weight.

    Parameters
    ----------
    modes
        From :func:`find_modes`.
    names
        Sampled parameter names (θ order, :func:`palpbayes.bayes.priors.param_names`).
    n_walkers
        Ensemble size.
    rng
        Random generator.
    z_bounds
        [m] Surface prior support (walkers are reflected into it).
    log_estar_bounds
        Bounds of log E* (walkers are kept 5 ball widths inside).
    n
        Number of fitted points (scale of log sigma: 1/sqrt(2n)).

    Returns
    -------
    p0, used
        (n_walkers, ndim) start and the modes that got walkers.
    """
    used = [m for m in modes if m.weight >= MIN_WEIGHT] or modes[:1]
    w = np.array([m.weight for m in used])
    counts = np.floor(w / w.sum() * n_walkers).astype(int)
    counts[0] += n_walkers - counts.sum()
    blocks = []
    for m, k in zip(used, counts, strict=True):
        if k <= 0:
            continue
        blocks.append(_ball(m, names, k, rng, n))
    p0 = np.concatenate(blocks, axis=0)
    lo, hi = z_bounds
    j = list(names).index("z_surf")
    z = p0[:, j]
    z = np.where(z < lo, 2 * lo - z, z)
    z = np.where(z > hi, 2 * hi - z, z)
    p0[:, j] = np.clip(z, lo, hi)
    e_lo, e_hi = log_estar_bounds
    p0[:, 0] = np.clip(p0[:, 0], e_lo + 1e-6 * abs(e_lo) + 1e-9, e_hi - 1e-6 * abs(e_hi) - 1e-9)
    return p0, [m for m, k in zip(used, counts, strict=True) if k > 0]


def _ball(m: Mode, names, k: int, rng: np.random.Generator, n: int) -> np.ndarray:
    """k walkers in a ball of BALL sd around mode ``m`` (sampler coordinates)."""
    estar = float(m.beta[0])
    sigma = float(np.sqrt(m.rss / max(n, 1)))
    # (E*, z_s, F0[, F1]) -> (log E*, z_s, F0[, F1]) by the Jacobian diag(1/E*, 1, 1, 1)
    cov = np.array(m.cov, dtype=float)
    lin_names = ["log_Estar", "z_surf", "F0"] + (["F1"] if "F1" in names else [])
    p = len(lin_names)
    ok = cov.shape == (p, p) and np.all(np.isfinite(cov))
    if ok:
        jac = np.diag([1.0 / estar] + [1.0] * (p - 1))
        cov = jac @ cov @ jac
        try:
            L = np.linalg.cholesky(cov + np.eye(p) * 1e-30)
        except np.linalg.LinAlgError:
            ok = False
    if not ok:
        scale = np.array([1e-3, 1e-7, sigma / np.sqrt(max(n, 1))] + [1e-9] * (p - 3))
        L = np.diag(scale)
    centre = [np.log(estar), m.z_surf, float(m.beta[1])] + (
        [float(m.beta[2])] if p == 4 else [])
    lin = np.asarray(centre) + BALL * rng.standard_normal((k, p)) @ L.T
    cols = {name: lin[:, i] for i, name in enumerate(lin_names)}
    cols["log_sigma"] = np.log(max(sigma, 1e-300)) + BALL * rng.standard_normal(k) / np.sqrt(
        2 * max(n, 1))
    cols["phi"] = np.clip(m.lag1, -0.9, 0.9) + 0.02 * rng.standard_normal(k)
    cols["log_nu_t"] = np.log(20.0) + 0.2 * rng.standard_normal(k)
    return np.column_stack([cols[name] for name in names])
