"""The stiff lump of a map: centre, size, depth and stiffness ratio with their intervals.

The per-point posteriors of log E (mean y_i, sd s_i at palpation position p_i) are explained
by one spherical inclusion in a homogeneous block, seen through the forward model of
:mod:`palpbayes.inclusion` (Boussinesq-weighted Reuss average):

    y_i ~ Normal(log E_b − log(1 − (1 − 1/rho)·V(|p_i − c|; R, D)), s_i² + tau²)

with background modulus E_b, centre c = (x_c, y_c), radius R, depth of the centre D = R + u
(u >= 0: buried, D + R <= H), stiffness ratio rho = E_inclusion/E_b and a nugget tau
(point-to-point heterogeneity of the material and what the forward model misses).  Priors:
flat on log E_b, uniform centre over the palpated area, log-uniform R, uniform cover u,
log-uniform rho on [1, :data:`RATIO_MAX`] (a stiff lump), half-normal tau (scale 0.2).
Sampled with emcee (differential-evolution moves, which follow the ridges of this posterior)
in the coordinates :data:`LUMP_PARAMS`, with the apparent peak ratio in place of rho (see
:class:`_Problem`), until the package's convergence test passes.

Derived per draw: the **apparent peak ratio** A = E_app(c)/E_b = 1/(1 − (1 − 1/rho)·V(0)) —
what palpation at the surface can see, and the quantity the data pin down best — and the
apparent full width at half maximum (the diameter where E_app/E_b − 1 falls to half of A − 1).

What the data cannot tell is reported, not hidden: a deep or very stiff inclusion's surface
signature saturates at 1/(1 − V(0)), so rho is bounded below but often not above (its
posterior then reaches the prior's upper end, and a flag says so); R and D trade off along a
ridge.  The inclusion's true ratio is identified only through the forward model, whose limits
are listed in :mod:`palpbayes.inclusion`.
"""

# Long module: one job, the lump model's posterior; issue 59 may replace its emcee loop by the
#   grid posterior of active/posterior.

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from scipy import optimize

from ..errors import InputError
from ..inclusion_table import SensitivityTable
from ..intervals import LEVEL, central

__all__ = ["RATIO_MAX", "LUMP_PARAMS", "LumpPosterior", "fit_lump", "lump_table"]

#: Upper end of the stiffness-ratio prior ("cancers can be up to 100 times stiffer").
RATIO_MAX = 100.0
#: Sampled parameters, in the order of the emcee state vector.
LUMP_PARAMS = ("log_Eb", "x_c", "y_c", "log_R", "cover", "log_A", "log_tau")
_ZERO = np.zeros(1)
#: The coordinates the data identify (background, centre, apparent peak ratio, nugget): the
#: convergence test is applied to them and to the log posterior.  Radius, cover and the
#: ratio itself lie on the size–depth–stiffness ridge (module docstring).
IDENTIFIED = (0, 1, 2, 5, 6)
_TAU_SCALE = 0.2
_WALKERS = 32


@dataclass
class LumpPosterior:
    """Posterior draws of the lump model.

    Attributes
    ----------
    draws
        DataFrame, one row per draw: ``E_background_pa``, ``x_m``, ``y_m``, ``radius_m``,
        ``depth_m`` (of the centre), ``ratio``, ``tau``, ``apparent_ratio``,
        ``apparent_fwhm_m``.
    chains
        (walkers, steps, 7) emcee chain after burn-in, in :data:`LUMP_PARAMS` (for arviz).
    log_prob
        (walkers, steps) log posterior.
    acceptance
        Mean acceptance fraction.
    n_steps
        Steps per walker run (the first half is burn-in).
    flags
        What the data cannot tell (parameters at a prior bound) and sampling problems.
    """

    draws: pd.DataFrame
    chains: np.ndarray
    log_prob: np.ndarray
    acceptance: float
    n_steps: int
    flags: list[str]
    table: SensitivityTable = field(repr=False)

    def excess(self, x: np.ndarray, y: np.ndarray, *, chunk: int = 64) -> np.ndarray:
        """The lump's log-excess log(E_app/E_b) = −log(1 − (1 − 1/rho)·V) at positions
        (``x``, ``y``) [m], one row per draw: shape (n_draws, n_points)."""
        x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
        d = self.draws
        cx, cy = d["x_m"].to_numpy(), d["y_m"].to_numpy()
        r, depth = d["radius_m"].to_numpy(), d["depth_m"].to_numpy()
        g = 1.0 - 1.0 / d["ratio"].to_numpy()
        out = np.empty((len(d), x.size))
        for k in range(0, len(d), chunk):
            sl = slice(k, k + chunk)
            s = np.hypot(x[None, :] - cx[sl, None], y[None, :] - cy[sl, None])
            out[sl] = -np.log1p(-g[sl, None] * self.table.batch(s, r[sl], depth[sl]))
        return out

    def p_apparent_above(self, k: float) -> float:
        """Posterior probability that the apparent peak ratio exceeds ``k``."""
        return float(np.mean(self.draws["apparent_ratio"].to_numpy() > k))

    @property
    def converged(self) -> bool:
        return not any(f.startswith("sampler") for f in self.flags)

    def summary(self, level: float = LEVEL) -> pd.DataFrame:
        """Mean, sd, median and central ``level`` interval of every reported quantity."""
        rows = []
        for name in self.draws.columns:
            x = self.draws[name].to_numpy()
            lo, hi = central(x, level)
            rows.append({"quantity": name, "mean": x.mean(), "sd": x.std(ddof=1),
                         "median": float(np.median(x)), "lo": lo, "hi": hi, "level": level})
        return pd.DataFrame(rows)


@dataclass(frozen=True)
class _Problem:
    """The lump model's log posterior in the sampled coordinates :data:`LUMP_PARAMS`.

    The stiffness ratio is sampled through the apparent peak ratio A (log_A), which the data
    pin down, instead of rho, which they often do not: rho follows from
    1 − 1/rho = (1 − 1/A)/V(0; R, D), and the log-uniform prior of rho becomes the density
    d log rho / d log A = 1/((1 − g)·A·V(0)), g = 1 − 1/rho, on log A.
    """

    x: np.ndarray
    y: np.ndarray
    obs: np.ndarray  # per-point log E means
    var: np.ndarray  # per-point variances s_i²
    table: SensitivityTable
    thickness: float
    box: tuple[float, float, float, float]  # x_lo, x_hi, y_lo, y_hi
    log_r: tuple[float, float]
    log_eb: tuple[float, float]

    def batch(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Log posterior and g = 1 − 1/rho of W states ``theta`` (W, 7) in one vectorised
        pass (emcee's ``vectorize=True``); -inf and NaN outside the prior's support."""
        theta = np.atleast_2d(np.asarray(theta, dtype=float))
        log_eb, xc, yc, log_r, cover, log_a, log_tau = theta.T
        r, tau = np.exp(log_r), np.exp(log_tau)
        x0, x1, y0, y1 = self.box
        ok = ((self.log_eb[0] < log_eb) & (log_eb < self.log_eb[1]) & (x0 <= xc) & (xc <= x1)
              & (y0 <= yc) & (yc <= y1) & (self.log_r[0] <= log_r) & (log_r <= self.log_r[1])
              & (0.0 <= cover) & (cover <= self.thickness - 2.0 * r) & (log_a >= 0.0)
              & (tau < 5.0))
        lp = np.full(theta.shape[0], -np.inf)
        g = np.full(theta.shape[0], np.nan)
        if not ok.any():
            return lp, g
        k = np.flatnonzero(ok)
        s = np.hypot(self.x[None, :] - xc[k, None], self.y[None, :] - yc[k, None])
        V = self.table.batch(np.hstack([np.zeros((k.size, 1)), s]), r[k], r[k] + cover[k])
        v0, V = V[:, 0], V[:, 1:]
        with np.errstate(divide="ignore", invalid="ignore"):
            gk = -np.expm1(-log_a[k]) / v0
        good = np.isfinite(gk) & (gk >= 0.0) & (gk <= 1.0 - 1.0 / RATIO_MAX) & (v0 > 0)
        k, gk, v0, V = k[good], gk[good], v0[good], V[good]
        var = self.var[None, :] + (tau[k] ** 2)[:, None]
        res = self.obs[None, :] - (log_eb[k, None] - np.log1p(-gk[:, None] * V))
        # uniform cover on [0, H − 2R]; log-uniform rho seen on log A; half-normal tau
        prior = (-np.log(self.thickness - 2.0 * r[k]) - np.log1p(-gk) - log_a[k] - np.log(v0)
                 - 0.5 * (tau[k] / _TAU_SCALE) ** 2 + log_tau[k])
        lp[k] = prior - 0.5 * np.sum(res * res / var + np.log(var), axis=1)
        g[k] = gk
        return lp, g

    def log_prob(self, theta: np.ndarray) -> float:
        """Log posterior of one state (7,)."""
        return float(self.batch(theta)[0][0])


def lump_table(contact_radius: float, thickness: float, step: float,
               extent: float) -> SensitivityTable:
    """The sensitivity table the lump model interpolates (radius from step/2 to the smaller
    of half the extent and half the thickness)."""
    r_hi = max(min(0.5 * extent, 0.5 * thickness), step)
    return SensitivityTable(contact_radius, thickness, radius_range=(0.5 * step, r_hi))


def _start(p: _Problem, guess: dict, rng: np.random.Generator) -> np.ndarray:
    """The best of a small grid of (radius, cover) around the map's guess, polished by
    Nelder–Mead, then a ball of walkers around it (each inside the prior)."""
    r_lo, r_hi = np.exp(p.log_r)
    log_a = math.log(max(guess.get("apparent", 1.1), 1.0 + 1e-3))
    best, best_lp = None, -np.inf
    for rf in (0.5, 0.75, 1.0, 1.5, 2.0):
        r = float(np.clip(rf * guess["radius"], r_lo, r_hi))
        for cf in (0.0, 0.1, 0.3, 0.6):
            th = np.array([guess["log_eb"], guess["x"], guess["y"], math.log(r),
                           cf * max(p.thickness - 2 * r, 0.0), log_a,
                           math.log(max(guess["tau"], 1e-3))])
            lp = p.log_prob(th)
            if lp > best_lp:
                best, best_lp = th, lp
    if best is None:
        raise InputError("lump model: no starting point inside the prior; the palpated area "
                         "or the thickness is too small for an inclusion")

    def nlp(t: np.ndarray) -> float:
        v = p.log_prob(t)
        return -v if np.isfinite(v) else 1e300

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        res = optimize.minimize(nlp, best, method="Nelder-Mead",
                                options={"maxiter": 4000, "xatol": 1e-7, "fatol": 1e-7})
    centre = res.x if np.isfinite(p.log_prob(res.x)) else best
    width = p.box[1] - p.box[0]
    scale = np.array([0.003, 0.01 * width, 0.01 * width, 0.05, 0.02 * p.thickness, 0.01, 0.05])
    walkers: list[np.ndarray] = []
    for _ in range(1000 * _WALKERS):
        th = centre + scale * rng.standard_normal(centre.size)
        if np.isfinite(p.log_prob(th)):
            walkers.append(th)
            if len(walkers) == _WALKERS:
                return np.array(walkers)
        scale = scale * 0.99
    raise InputError("lump model: could not place the walkers inside the prior")


def _fwhm(table: SensitivityTable, r: np.ndarray, d: np.ndarray,
          g: np.ndarray) -> np.ndarray:
    """Apparent full width at half maximum [m] per draw (the excess E_app/E_b − 1 on 256
    lateral distances out to the table's range, u_max·(D + a))."""
    out = np.full(r.size, np.nan)
    for k in range(r.size):
        s = np.linspace(0.0, table.u_max * (d[k] + table.contact_radius), 256)
        excess = 1.0 / (1.0 - g[k] * table(s, r[k], d[k])) - 1.0
        half = 0.5 * excess[0]
        below = np.nonzero(excess <= half)[0]
        if half <= 0 or below.size == 0:
            continue
        j = below[0]
        s0, s1, e0, e1 = s[j - 1], s[j], excess[j - 1], excess[j]
        out[k] = 2.0 * (s0 + (half - e0) * (s1 - s0) / (e1 - e0))
    return out


def _window(x: np.ndarray, y: np.ndarray, guess: dict, step: float, a: float,
            max_points: int) -> np.ndarray:
    """The points the lump model uses: all of them, or for a large map the disc around the
    guessed centre that holds the lump's signature and a ring of background."""
    if x.size <= max_points:
        return np.ones(x.size, dtype=bool)
    d = np.hypot(x - guess["x"], y - guess["y"])
    radius = max(6.0 * guess["radius"] + 4.0 * a, 10.0 * step)
    keep = d <= radius
    if keep.sum() > max_points:
        keep = d <= np.sort(d)[max_points - 1]
    return keep


# Many parameters: the points (x, y, mean, sd) and the specimen's geometry are the data; the rest
# is emcee's run (steps, checks, draws), each with a default.
def fit_lump(x: np.ndarray, y: np.ndarray, mean: np.ndarray, sd: np.ndarray, *,
             contact_radius: float, thickness: float, step: float, guess: dict,
             seed: int = 0, min_steps: int = 2000, max_steps: int = 20000,
             check_every: int = 1000, n_draws: int = 2000, max_points: int = 2500,
             table: SensitivityTable | None = None, progress: bool = False) -> LumpPosterior:
    """Posterior of the one-inclusion model (module docstring) from per-point summaries.

    The ensemble runs in blocks of ``check_every`` steps from ``min_steps`` on, and stops when
    the second half of the chain passes the package's convergence test (R-hat <= 1.05 and
    bulk/tail ESS >= 400, :func:`palpbayes.bayes.diagnostics.chain_passes`) for the identified
    coordinates (:data:`IDENTIFIED`) and the log posterior, or at ``max_steps`` (flagged); the
    first half is discarded as burn-in.  Radius, depth and ratio along the ridge are reported
    with a flag when their posterior is mostly the prior.

    Parameters
    ----------
    x, y
        [m] Palpation positions of the points with a fit.
    mean, sd
        Per-point posterior mean and sd of log(E/Pa).
    contact_radius
        [m] Contact radius of the tip at the indentation depth
        (:func:`palpbayes.inclusion.contact_radius`).
    thickness
        [m] Block thickness H.
    step
        [m] Grid step (smallest lump radius: step/2).
    guess
        Starting values from the spatial map: ``x``, ``y`` [m], ``radius`` [m], ``log_eb``,
        ``tau``, ``apparent`` (peak ratio).
    seed
        Seed of the walkers' start and of emcee.
    min_steps, max_steps, check_every
        Steps per walker: first check, cap, check interval.
    n_draws
        Draws kept (thinned evenly from the second half).
    max_points
        Larger maps use the points within a disc around the guessed centre (:func:`_window`).
    table
        A prebuilt :func:`lump_table` (built here when None).
    progress
        emcee's progress bar.
    """
    import emcee

    from ..bayes.diagnostics import chain_passes
    from ..bayes.sampler import seed_sampler

    x, y, mean, sd = (np.asarray(a, dtype=float) for a in (x, y, mean, sd))
    if not (x.size == y.size == mean.size == sd.size) or x.size < 10:
        raise InputError(f"the lump model needs at least 10 points with a fit, got {x.size}")
    if not (thickness > 0 and contact_radius > 0 and step > 0):
        raise InputError("the lump model needs a positive thickness, contact radius and step")
    if not 0 < min_steps <= max_steps:
        raise InputError(f"steps: need 0 < min_steps {min_steps} <= max_steps {max_steps}")
    keep = _window(x, y, guess, step, contact_radius, max_points)
    x, y, mean, sd = x[keep], y[keep], mean[keep], sd[keep]
    extent = float(max(np.ptp(x), np.ptp(y)) + step)
    table = table or lump_table(contact_radius, thickness, step, extent)
    r_lo, r_hi = table.radius_range
    half = 0.5 * step
    p = _Problem(x=x, y=y, obs=mean, var=sd ** 2, table=table, thickness=float(thickness),
                 box=(x.min() - half, x.max() + half, y.min() - half, y.max() + half),
                 log_r=(math.log(r_lo), math.log(min(r_hi, 0.5 * thickness * 0.999))),
                 log_eb=(float(mean.min()) - 2.0, float(mean.max()) + 2.0))
    rng = np.random.default_rng(seed)
    state = _start(p, guess, rng)
    moves = [(emcee.moves.DEMove(), 0.8), (emcee.moves.DESnookerMove(), 0.2)]
    sampler = emcee.EnsembleSampler(_WALKERS, len(LUMP_PARAMS), lambda t: p.batch(t)[0],
                                    moves=moves, vectorize=True)
    seed_sampler(sampler, seed)
    passed = False
    while sampler.iteration < max_steps:
        n = min_steps if sampler.iteration == 0 else check_every
        state = sampler.run_mcmc(state, min(n, max_steps - sampler.iteration),
                                 progress=progress)
        burn = sampler.iteration // 2
        chain = np.swapaxes(sampler.get_chain(discard=burn), 0, 1)  # (walkers, steps, ndim)
        lp = np.swapaxes(sampler.get_log_prob(discard=burn), 0, 1)
        if chain_passes(chain[..., IDENTIFIED], lp):
            passed = True
            break
    flat = chain.reshape(-1, chain.shape[-1])
    pick = np.linspace(0, flat.shape[0] - 1, min(n_draws, flat.shape[0])).astype(int)
    th = flat[pick]
    r, depth, A = np.exp(th[:, 3]), np.exp(th[:, 3]) + th[:, 4], np.exp(th[:, 5])
    g = p.batch(th)[1]
    draws = pd.DataFrame({
        "E_background_pa": np.exp(th[:, 0]), "x_m": th[:, 1], "y_m": th[:, 2],
        "radius_m": r, "depth_m": depth, "ratio": 1.0 / (1.0 - g), "tau": np.exp(th[:, 6]),
        "apparent_ratio": A, "apparent_fwhm_m": _fwhm(table, r, depth, g),
    })
    acc = float(np.mean(sampler.acceptance_fraction))
    flags = _lump_flags(draws, p)
    if not passed:
        flags.append(f"sampler: not converged after {sampler.iteration} steps per walker "
                     "(R-hat > 1.05 or ESS < 400); the intervals are rough")
    if not np.all(keep):
        flags.append(f"lump model used the {int(keep.sum())} points within "
                     f"{np.hypot(x - guess['x'], y - guess['y']).max() * 1e3:.3g} mm of the "
                     "map's guessed centre")
    return LumpPosterior(draws=draws, chains=chain, log_prob=lp, acceptance=acc,
                         n_steps=int(sampler.iteration), flags=flags, table=table)


def _lump_flags(d: pd.DataFrame, p: _Problem) -> list[str]:
    """What the data cannot tell: a quantity whose posterior piles up at a prior bound."""
    out = []
    lr = np.log(d["ratio"].to_numpy())
    top = math.log(RATIO_MAX)
    if np.quantile(lr, 0.95) > top - 0.1 * top:
        lo5 = float(np.quantile(d["ratio"], 0.05))
        out.append(f"stiffness ratio reaches the prior's upper end ({RATIO_MAX:g}): the data "
                   f"bound it below (>= {lo5:.3g} with 95 % probability) but not above — the "
                   "surface signature of a deep or very stiff inclusion saturates; the apparent "
                   "peak ratio is what palpation measures")
    prior_sd = top / math.sqrt(12.0)
    if np.std(lr) > 0.5 * prior_sd:
        out.append(f"stiffness ratio not identified (posterior sd of ln ratio {np.std(lr):.2f} "
                   f"against the prior's {prior_sd:.2f}): a smaller, stiffer inclusion and a "
                   "larger, softer or deeper one leave the same surface signature at one "
                   "indentation depth; the ratio's interval is mostly the prior — report the "
                   "apparent peak ratio, or give the depth from imaging")
    if np.median(d["apparent_ratio"]) - 1 < 2 * np.std(d["apparent_ratio"]):
        out.append("apparent peak ratio within two sd of 1: the data hardly show a stiff "
                   "inclusion")
    room = p.thickness - 2.0 * d["radius_m"].to_numpy()
    cover = (d["depth_m"] - d["radius_m"]).to_numpy()
    frac = cover / np.maximum(room, 1e-300)
    if np.median(frac) < 0.05:
        out.append("inclusion touching the surface: its cover is at the lower bound 0")
    if np.median(frac) > 0.95:
        out.append("inclusion at the bottom of the block: the depth is not resolved")
    log_r = np.log(d["radius_m"].to_numpy())
    w = p.log_r[1] - p.log_r[0]
    if np.median(log_r) - p.log_r[0] < 0.1 * w:
        out.append(f"radius at its lower bound ({math.exp(p.log_r[0]) * 1e3:.3g} mm, half a grid "
                   "step): the lump is smaller than the grid resolves")
    if p.log_r[1] - np.median(log_r) < 0.1 * w:
        out.append("radius at its upper bound: the lump is as large as the map or the block")
    return out
