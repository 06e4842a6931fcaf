"""Hyperparameters of the stiffness map: PC priors and the INLA-style integration grid.

theta = (sigma_f, range, tau) — the field's marginal sd [log E], its range [m] and the nugget
sd [log E] — is handled on the log scale, t = log theta, and every density here is a density
of t (it includes the Jacobian theta).

Priors (penalised-complexity, Simpson et al. 2017; Fuglstad et al. 2019 for the Matérn field in
d = 2)::

    pi(range)   = lam_r · range^-2 · exp(-lam_r / range),  lam_r = -log(alpha) · range_0
    pi(sigma_f) = lam_s · exp(-lam_s · sigma_f),           lam_s = -log(alpha) / sigma_0
    pi(tau)     = lam_t · exp(-lam_t · tau),               lam_t = -log(alpha) / tau_0

so that P(range < range_0) = P(sigma_f > sigma_0) = P(tau > tau_0) = alpha.

Integration (Rue, Martino & Chopin 2009, the "grid" strategy): the mode t* of log p(t | y) is
found with L-BFGS-B (central-difference gradients); the Hessian H of −log p there (central
differences) gives principal axes t = t* + V·diag(eig(H))^-1/2·z.  Each half-axis is stretched
by the skewness correction of Rue et al. (INLA's "stdev.corr"): the factor
sqrt(SKEW_Z² / 2δ), δ the drop of log p at z = ±SKEW_Z, so that a heavy tail (e.g. log tau
when the nugget is not much larger than the trace sd s_i) gets a wider spacing on its side.
z is gridded with spacing ``Z_MAX / K`` (``2K + 1`` points from −Z_MAX to +Z_MAX corrected sd
per axis) and explored outward from the mode, a point being expanded while its log posterior
is within :data:`DROP` of the best (at most :data:`MAX_POINTS` points, flagged when reached).
Exploration may run past ±Z_MAX up to :data:`REACH` times as far (a curved, "banana"
posterior drifts many sd off its narrow principal axes in the tails); a point of
non-negligible weight (more than :data:`EDGE` of the largest) whose neighbour could not be
explored (past that cap or outside the search box) is reported in the flags: the posterior
then piles up at the edge of its grid or at a bound.  A point's weight is exp(log posterior)
times the volume of its cell (the product of the stretch factors of its half-axes; the mean
of both on an axis through the mode).

References
----------
Rue, H., Martino, S. & Chopin, N. (2009). JRSS-B 71:319–392.
Simpson, D., Rue, H., Riebler, A., Martins, T. & Sørbye, S. (2017). Statistical Science 32:1–28.
Fuglstad, G.-A., Simpson, D., Lindgren, F. & Rue, H. (2019). JASA 114:445–452.
"""

from __future__ import annotations

from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from itertools import product

import numpy as np
import pandas as pd
from scipy import optimize, stats

from ..errors import InputError

__all__ = ["HYPER_NAMES", "log_pc_prior", "explore", "weighted_summary"]

#: Hyperparameter names, in the order of t.
HYPER_NAMES = ("sigma_f", "range_m", "tau")
#: Half-width of the nominal grid along each principal axis [posterior sd].
Z_MAX = 3.5
#: Points whose log posterior is more than DROP below the best are evaluated but not expanded.
DROP = 6.0
#: Where the skewness correction probes each half-axis [Hessian sd], and its largest factor.
SKEW_Z, CORR_MAX = 2.0, 4.0
#: How many times ±Z_MAX the exploration may reach along each axis.
REACH = 5
#: Most theta points the exploration evaluates.
MAX_POINTS = 1200
#: Relative weight above which a point at the edge of the explored grid is flagged.
EDGE = 0.01


def log_pc_prior(t: np.ndarray, range_0: float, sigma_0: float, tau_0: float,
              alpha: float) -> float:
    """Log PC-prior density of t = (log sigma_f, log range, log tau), Jacobian included."""
    ls, lr, lt = (float(v) for v in t)
    c = -np.log(alpha)
    lam_s, lam_r, lam_t = c / sigma_0, c * range_0, c / tau_0
    return float(np.log(lam_s) - lam_s * np.exp(ls) + ls
                 + np.log(lam_r) - lam_r * np.exp(-lr) - lr
                 + np.log(lam_t) - lam_t * np.exp(lt) + lt)


def _hessian(F: Callable[[list], list], t: np.ndarray, f0: float, d: float = 0.05
             ) -> np.ndarray:
    """Central-difference Hessian of f at t (``F`` evaluates f at a list of points)."""
    n = t.size
    e = np.eye(n) * d
    pts = [t + e[i] for i in range(n)] + [t - e[i] for i in range(n)]
    pairs = [(i, j) for i in range(n) for j in range(i)]
    for i, j in pairs:
        pts += [t + e[i] + e[j], t + e[i] - e[j], t - e[i] + e[j], t - e[i] - e[j]]
    v = F(pts)
    H = np.empty((n, n))
    for i in range(n):
        H[i, i] = (v[i] - 2 * f0 + v[n + i]) / d**2
    for p, (i, j) in enumerate(pairs):
        a, b, c, g = v[2 * n + 4 * p: 2 * n + 4 * p + 4]
        H[i, j] = H[j, i] = (a - b - c + g) / (4 * d**2)
    return H


def _axis_names(V: np.ndarray) -> list[str]:
    return [HYPER_NAMES[int(np.argmax(np.abs(V[:, j])))] for j in range(V.shape[1])]


def _mode(F, t0, bounds, flags, d: float = 1e-3):
    """L-BFGS-B on −f with central-difference gradients (7 points per call, batched)."""
    def fun(t):
        pts = [t] + [t + d * e for e in np.eye(3)] + [t - d * e for e in np.eye(3)]
        v = np.array(F(pts))
        if not np.all(np.isfinite(v)):
            return 1e300, np.zeros(3)
        return -v[0], -(v[1:4] - v[4:7]) / (2 * d)

    res = optimize.minimize(fun, np.clip(t0, bounds[:, 0], bounds[:, 1]), jac=True,
                            method="L-BFGS-B", bounds=bounds,
                            options={"maxiter": 100, "gtol": 1e-3, "ftol": 1e-12})
    t_star = res.x
    if not res.success or not np.isfinite(res.fun):
        # a line search that stalls at the mode (finite-difference noise) is no failure
        free = (t_star > bounds[:, 0] + 1e-3) & (t_star < bounds[:, 1] - 1e-3)
        if not (np.isfinite(res.fun) and np.max(np.abs(res.jac[free]), initial=0.0) < 0.05):
            flags.append(f"hyperparameter optimiser did not converge ({res.message}); the "
                         "theta grid is centred on its last point")
    at_bound = [HYPER_NAMES[i] for i in range(3)
                if min(abs(t_star[i] - bounds[i, 0]), abs(t_star[i] - bounds[i, 1])) < 1e-3]
    if at_bound:
        flags.append("theta mode at the edge of its search box for " + ", ".join(at_bound)
                     + ": the posterior piles up at a bound (e.g. tau -> 0 or range -> infinity)")
    return t_star, -float(res.fun), res.nit


def explore(log_post: Callable[[np.ndarray], float], t0: np.ndarray, bounds: np.ndarray, *,
            grid_points: int = 7, workers: int = 1, bound_notes: dict | None = None,
            progress: Callable[[str], None] | None = None) -> tuple[pd.DataFrame, list[str]]:
    """Mode, Hessian and grid exploration of ``log_post`` over t = log theta.

    Parameters
    ----------
    log_post
        Log posterior density of t (up to a constant); ``-inf`` or NaN where it fails.  Called
        from ``workers`` threads at once, so it must be thread-safe.
    t0
        Starting point of the optimiser.
    bounds
        ``(3, 2)`` search box for t (lower, upper); the grid never leaves it.
    grid_points
        Odd number of grid points per principal axis between −Z_MAX and +Z_MAX sd.
    workers
        Threads evaluating ``log_post`` (sparse factorisations release the GIL).
    bound_notes
        ``{(parameter index, 0 lower | 1 upper): sentence}``: the plain-word meaning of an
        end of the search box that is expected (no spatial variation, a field smooth across
        the map).  When the posterior piles up at such an end its flag is information
        (``"info: <sentence> (<the technical detail>)"``); at an end without a note it is a
        warning.
    progress
        Called with a one-line message after each stage.

    Returns
    -------
    grid
        One row per evaluated point: ``t_sigma_f``, ``t_range_m``, ``t_tau`` (log values),
        ``log_post`` and ``weight`` (normalised to sum to 1), plus the integer grid
        coordinates ``k0, k1, k2``.
    flags
        Sentences naming an optimiser failure, a mode at the search box, a Hessian that is not
        positive definite, or a posterior reaching the edge of its grid.
    """
    if grid_points < 3 or grid_points % 2 == 0:
        raise InputError(f"grid_points must be odd and at least 3, got {grid_points!r}")
    say = progress or (lambda msg: None)
    flags: list[str] = []
    with ThreadPoolExecutor(max(1, int(workers))) as pool:
        def F(points):
            v = np.array(list(pool.map(lambda t: log_post(np.asarray(t, dtype=float)), points)))
            return np.where(np.isfinite(v), v, -np.inf)

        t_star, f_star, nit = _mode(F, np.asarray(t0, dtype=float), bounds, flags)
        say(f"theta mode after {nit} iterations: {np.round(np.exp(t_star), 6)}")
        H = _hessian(lambda pts: -F(pts), t_star, -f_star)
        evals, V = np.linalg.eigh(0.5 * (H + H.T))
        if np.any(~np.isfinite(evals)) or np.any(evals <= 0):
            flags.append("the Hessian of log p(theta | y) at the mode is not positive definite; "
                         "the grid uses a unit scale in log theta along those directions")
            evals = np.where(np.isfinite(evals) & (evals > 0), evals, 1.0)
        scale = V / np.sqrt(evals)
        # skewness correction (Rue et al. 2009; INLA's stdev.corr): per half-axis, the sd
        # that matches the drop of log p at z = ±SKEW_Z (heavier tail -> wider spacing)
        signs = (-1.0, 1.0)
        drops = f_star - F([t_star + scale[:, j] * sg * SKEW_Z
                            for j in range(3) for sg in signs])
        corr = np.sqrt(SKEW_Z**2 / (2 * np.maximum(drops, 1e-12))).reshape(3, 2)
        corr = np.clip(corr, 1 / CORR_MAX, CORR_MAX)
        K = (grid_points - 1) // 2
        dz, cap = Z_MAX / K, REACH * K

        def zvec(k):
            return np.array([c * dz * corr[j, int(c > 0)] for j, c in enumerate(k)])

        def volume(k):
            return float(np.prod([corr[j, int(c > 0)] if c else corr[j].mean()
                                  for j, c in enumerate(k)]))

        def point(k):
            return t_star + scale @ zvec(k)

        def outside(k) -> tuple | None:
            """Why grid point k cannot be explored: ``(parameter, side)`` past the box, or
            ``("cap",)``; None when it can."""
            t = point(k)
            off = np.flatnonzero((t < bounds[:, 0]) | (t > bounds[:, 1]))
            if off.size:
                i = int(off[0])
                return (i, int(t[i] > bounds[i, 1]))
            return None if max(abs(c) for c in k) <= cap else ("cap",)

        values: dict[tuple, float] = {}
        best = -np.inf
        level, seen, blocked = [(0, 0, 0)], {(0, 0, 0)}, set()
        while level:
            if len(values) + len(level) > MAX_POINTS:
                level = level[:max(0, MAX_POINTS - len(values))]
                flags.append(f"the theta grid exploration stopped at its budget of {MAX_POINTS} "
                             "points: the posterior is far from Gaussian and may be truncated")
                if not level:
                    break
            for k, v in zip(level, F([point(k) for k in level]), strict=True):
                values[k] = float(v)
            best = max(best, max(values[k] for k in level))
            nxt = []
            for k in level:
                if values[k] < best - DROP:
                    continue
                for j, sgn in product(range(3), (-1, 1)):
                    nb = tuple(k[i] + (sgn if i == j else 0) for i in range(3))
                    if nb in seen:
                        continue
                    why = outside(nb)
                    if why is not None:
                        blocked.add((k, j, why))
                        continue
                    seen.add(nb)
                    nxt.append(nb)
            level = nxt
    say(f"theta grid: {len(values)} points evaluated")
    ks = np.array(list(values))
    lp = np.array(list(values.values()))
    mass = np.exp(lp - lp.max()) * np.array([volume(k) for k in values])
    rel = mass / mass.max()
    row = {k: i for i, k in enumerate(values)}
    names = _axis_names(V)
    heavy = [(j, why) for k, j, why in blocked if rel[row[k]] > EDGE]
    capped = sorted({names[j] for j, why in heavy if why == ("cap",)})
    if capped:
        flags.append("the theta posterior reaches the edge of its integration grid "
                     f"(±{REACH * Z_MAX:g} corrected sd) along the axis dominated by "
                     + ", ".join(capped) + ": it is far from Gaussian there and is truncated")
    for i, side in sorted({why for j, why in heavy if why != ("cap",)}):
        end = ("lower", "upper")[side]
        note = (bound_notes or {}).get((i, side))
        detail = (f"the theta posterior piles up at the {end} end of the search interval of "
                  f"{HYPER_NAMES[i]} ({np.exp(bounds[i, side]):.3g}): the data do not bound "
                  f"{HYPER_NAMES[i]} and its posterior follows the prior there, truncated")
        # an end with a note is an expected one (a flat map, a smooth field): information
        flags.append(f"info: {note} ({detail})" if note else detail)
    if lp.max() > f_star + 1.0:
        flags.append(f"a grid point beats the optimiser's mode by {lp.max() - f_star:.2f} in "
                     "log posterior: the mode search stopped early")
    T = np.array([point(k) for k in ks])
    grid = pd.DataFrame({f"t_{n}": T[:, i] for i, n in enumerate(HYPER_NAMES)})
    grid["log_post"] = lp
    grid["weight"] = mass / mass.sum()
    for i in range(3):
        grid[f"k{i}"] = ks[:, i]
    return grid, flags


#: Kernel sd of the quantile smoothing, in posterior sd (see :func:`weighted_summary`).
KERNEL = 0.5


def _smoothed_quantiles(v: np.ndarray, w: np.ndarray, qs) -> list[float]:
    m = float(w @ v)
    sd = float(np.sqrt(w @ (v - m) ** 2))
    if not sd > 0:
        return [m for _ in qs]
    h = KERNEL * sd
    c = m + np.sqrt(1.0 - KERNEL**2) * (v - m)  # shrunk so that the mixture keeps the variance
    lo, hi = float(c.min() - 10 * h), float(c.max() + 10 * h)
    return [optimize.brentq(lambda x, q=q: float(w @ stats.norm.cdf((x - c) / h)) - q, lo, hi,
                            xtol=1e-10 * max(1.0, abs(m))) for q in qs]


def weighted_summary(values: pd.DataFrame, weight: np.ndarray, *, log: bool = False
                     ) -> pd.DataFrame:
    """Mean, sd, 5 % and 95 % quantiles of each column of ``values`` under grid ``weight``:
    one row per column, columns ``parameter, mean, sd, q05, q95``.

    The grid's levels are about one posterior sd apart, too coarse for quantiles read off the
    cumulative weights; the quantiles are those of the grid smoothed by a Gaussian kernel of
    :data:`KERNEL` sd, the points first shrunk towards the mean so that the smoothed
    distribution keeps the grid's mean and variance.  With ``log=True`` ``values`` hold
    log-parameters (on whose scale the grid is regular): the quantiles are smoothed there and
    exponentiated, the mean and sd are those of the exponentiated values.
    """
    w = np.asarray(weight, dtype=float) / np.sum(weight)
    rows = []
    for c in values.columns:
        v = values[c].to_numpy(dtype=float)
        q05, q95 = _smoothed_quantiles(v, w, (0.05, 0.95))
        if log:
            v, q05, q95 = np.exp(v), float(np.exp(q05)), float(np.exp(q95))
        m = float(w @ v)
        rows.append({"parameter": c, "mean": m, "sd": float(np.sqrt(w @ (v - m) ** 2)),
                     "q05": q05, "q95": q95})
    return pd.DataFrame(rows)
