"""Multi-palpation stiffening: E(t) = c1·e^(c2·t) + c3·e^(c4·t) versus rest time t.

The law and its numbers: docs/design.md §2.

Repeated palpation of foam without rest stiffens it; the paper describes the modulus measured
after a rest t [s] since the previous excitation by a sum of two exponentials.  This module fits
that law to per-trace estimates E_i ± s_i, Bayesian with emcee, and says whether the data can
tell the two exponentials apart.

Model and priors
----------------
    E_i ~ Normal(c1·e^(c2·t_i) + c3·e^(c4·t_i),  s_i² + sigma_x²)

* Rates are decays, c = −1/T with the time scale T log-uniform on [T_lo, T_hi] =
  [min positive t / 5, 100·max t]: a faster decay is over before the first rest time, a slower
  one varies by less than 1 % over the data (a constant; the simulator's default law has
  c2 = 0).  Recovery after an excitation makes E fall with rest, so growth (c > 0) is excluded.
* Label switching is broken by the ordering c2 < c4 (T2 < T4): (c1, c2) is the fast term.
* Amplitudes c1, c3 are uniform on ±10·median(E) (flat over every plausible value).
* sigma_x ≥ 0, an extra scatter beyond the per-trace uncertainties s_i (location-to-location
  variation, unmodelled drift), is half-normal with scale 0.1·median(E).

Identifiability and the three outcomes
--------------------------------------
Three laws are fitted (same priors): the double law, the single exponential plus constant
E = c0 + c1·e^(c2·t) and a constant E = c0 (no stiffening).  The *simplest law that passes its
checks* is reported (``preferred``), starting from the double law.

A sum of two exponentials is notoriously ill-conditioned (Lanczos' example): the double law is
reported as *identifiable* only when all of these hold, otherwise ``identifiable`` is False and
``message`` says which failed:

1. at least six distinct rest times (five parameters);
2. the Bayesian information criterion prefers the double law by more than 2
   (BIC = k·ln n − 2·ln L_max, k = 5 vs 4; Kass & Raftery 1995 "positive evidence");
3. both amplitudes' 90 % intervals exclude zero;
4. the time scales are separated: the 5 % quantile of T4/T2 exceeds :data:`MIN_RATIO` (1.5);
5. the slow time scale is resolved: its 95 % quantile is below 10·max t (else the slow term
   is a constant over the data);
6. its sampler converged (R-hat, ESS; :mod:`palpbayes.bayes.diagnostics`).

The single exponential is the fallback only when it passes the same kind of checks
(``single_identifiable``):

1. at least four distinct rest times (four parameters);
2. BIC prefers it over the constant by more than 2 (k = 4 vs 2);
3. the 90 % interval of its amplitude c1 excludes zero;
4. its time scale T = −1/c2 is resolved within the observed rest times: its 90 % interval lies
   inside [smallest positive t, largest t] (a faster decay is over before the first rest
   time, a slower one is a straight line or a constant over the data);
5. its sampler converged.

Otherwise the outcome is **no stiffening detected**: ``preferred = "constant"``, and the
message gives E = mean ± sd of the estimates (with the 90 % interval of the constant law's
c0).  Before the single law was checked it was recommended whenever the double law failed:
on constant data (100 kPa, 10 % scatter, eight rest times) an audit got c0 = 183 kPa,
c1 = −97 kPa and a 20,500 s time scale, far beyond the data.

Every sampler runs until R-hat and ESS pass (or the step cap), since convergence is a check.

Sampling: sigma_x is sampled as log sigma_x (prior plus Jacobian: no wall at 0); the walkers
start from a Laplace approximation at the maximum (Fisher information), scaled to the posterior
however precise the estimates are; the single and constant laws, linear in their amplitudes,
are sampled over (log T, log sigma_x) with the amplitudes integrated out and drawn afterwards
from their Gaussian conditional.  With all four parameters sampled, the single law's
log-posterior autocorrelation time was ~30 steps and R-hat <= 1.01 at 3,000 steps a matter of
luck: on least-squares estimates of a simulated series (0.03 % sd) 3 of 30 seeds hit the step
cap and the outcome fell to "constant" (issue 13).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from scipy import optimize

from .bayes.diagnostics import chain_passes, compute_diagnostics, import_arviz
from .bayes.sampler import SamplerSettings, run_emcee
from .errors import InputError
from .intervals import LEVEL, central, central_band
from .units import format_pressure

__all__ = ["StiffeningResult", "fit_stiffening", "fit_stiffening_summary",
           "STIFFENING_SETTINGS", "MIN_RATIO", "double_exponential", "LAW_TEXT"]

#: Minimum ratio T4/T2 (5 % quantile) for the two time scales to count as distinct.
MIN_RATIO = 1.5
#: emcee settings (5 parameters; degenerate posteriors need the DE moves).
STIFFENING_SETTINGS = SamplerSettings(n_walkers=40, max_steps=20000, min_steps=2000,
                                      check_every=500, moves="de", progress=False)
_AMP = 10.0  # amplitude bound in units of median(E)
_SX = 0.1    # half-normal scale of sigma_x in units of median(E)
_LOG2PI = np.log(2 * np.pi)


def double_exponential(t, c) -> np.ndarray:
    """E(t) = c1·e^(c2·t) + c3·e^(c4·t) [Pa] for rest time t [s], c = (c1, c2, c3, c4)."""
    c1, c2, c3, c4 = c
    t = np.asarray(t, dtype=float)
    return c1 * np.exp(c2 * t) + c3 * np.exp(c4 * t)


# ----------------------------------------------------------------------------- models
# θ in scaled units: amplitudes and sigma_x / E_s, time scales as log T [log s].


def _basis(model: str, logT: np.ndarray, t: np.ndarray) -> np.ndarray:
    """(W, n, k) basis functions; amplitudes multiply them linearly."""
    ex = np.exp(-t[None, None, :] / np.exp(logT)[:, :, None])  # (W, nT, n)
    if model in ("single", "constant"):
        ones = np.ones((ex.shape[0], 1, t.size))
        ex = np.concatenate([ones, ex], axis=1)
    return np.swapaxes(ex, 1, 2)


def _split(model: str, theta: np.ndarray):
    if model == "double":
        return theta[:, [0, 2]], theta[:, [1, 3]], theta[:, 4]
    if model == "constant":
        return theta[:, [0]], theta[:, 1:1], theta[:, 1]
    return theta[:, [0, 1]], theta[:, [2]], theta[:, 3]


#: Number of parameters (amplitudes, time scales, sigma_x) of each law.
_N_PARAMS = {"double": 5, "single": 4, "constant": 2}
_NAMES = {"double": ["c1", "logT2", "c3", "logT4", "sigma_x"],
          "single": ["c0", "c1", "logT", "sigma_x"], "constant": ["c0", "sigma_x"]}
_AMP_IDX = {"double": [0, 2], "single": [0, 1], "constant": [0]}
_T_IDX = {"double": [1, 3], "single": [2], "constant": []}


def _log_like(model, theta, t, y, s):
    amp, logT, sx = _split(model, theta)
    f = np.einsum("wnk,wk->wn", _basis(model, logT, t), amp)
    v = s[None, :] ** 2 + sx[:, None] ** 2
    return -0.5 * np.sum(_LOG2PI + np.log(v) + (y[None, :] - f) ** 2 / v, axis=1)


def _log_post(model, theta, t, y, s, bounds):
    """Log posterior in the *sampled* coordinates: θ with its last entry log sigma_x.

    sigma_x is sampled on the log scale (half-normal prior plus the Jacobian log sigma_x): the
    posterior then has no wall at sigma_x = 0, where precise estimates (least-squares sd's of
    0.03 %) pile it up and a linear sigma_x mixes slowest of all parameters.
    """
    theta = np.atleast_2d(theta)
    amp, logT, log_sx = _split(model, theta)
    lo, hi = bounds
    ok = np.all(np.abs(amp) < _AMP, axis=1) & np.all((logT > lo) & (logT < hi), axis=1)
    ok &= np.isfinite(log_sx) & (log_sx < np.log(_AMP))
    if model == "double":
        ok &= logT[:, 0] < logT[:, 1]
    lp = np.full(theta.shape[0], -np.inf)
    if ok.any():
        th = theta[ok].copy()
        th[:, -1] = np.exp(th[:, -1])
        sx = th[:, -1]
        lp[ok] = _log_like(model, th, t, y, s) - 0.5 * (sx / _SX) ** 2 + np.log(sx)
    return lp


def _linear_fit(model, x, t, y, s):
    """Amplitudes' conditional posterior at sampled (log T, log sigma_x) rows ``x``.

    For fixed time scales and sigma_x the amplitudes enter linearly, so with their flat prior
    they are Gaussian: mean â (weighted least squares) and precision G = Bᵀ·V⁻¹·B.  Returns
    (â, G, log L(â)), vectorised over rows.
    """
    sx = np.exp(x[:, -1])
    B = _basis(model, x[:, :-1], t)                                   # (W, n, k)
    v = s[None, :] ** 2 + sx[:, None] ** 2                            # (W, n)
    G = np.einsum("wnk,wn,wnj->wkj", B, 1.0 / v, B)
    h = np.einsum("wnk,wn,n->wk", B, 1.0 / v, y)
    a = np.linalg.solve(G, h[..., None])[..., 0]
    r = y[None, :] - np.einsum("wnk,wk->wn", B, a)
    ll = -0.5 * np.sum(_LOG2PI + np.log(v) + r**2 / v, axis=1)
    return a, G, ll


def _log_post_collapsed(model, x, t, y, s, bounds):
    """Log posterior of (log T, log sigma_x) with the amplitudes integrated out (single and
    constant laws): log L(â) + (k/2)·log 2π − ½·log det G, plus the sigma_x prior and its
    Jacobian.  The amplitudes' flat prior is treated as unbounded here; draws outside ±10·median
    are redrawn (:func:`_draw_amplitudes`), which matters only far outside the data's reach.
    """
    x = np.atleast_2d(x)
    lo, hi = bounds
    logT, log_sx = x[:, :-1], x[:, -1]
    ok = np.all((logT > lo) & (logT < hi), axis=1) & np.isfinite(log_sx)
    ok &= log_sx < np.log(_AMP)
    lp = np.full(x.shape[0], -np.inf)
    if ok.any():
        xo = x[ok]
        _, G, ll = _linear_fit(model, xo, t, y, s)
        k = G.shape[-1]
        sign, logdet = np.linalg.slogdet(G)
        sx = np.exp(xo[:, -1])
        val = ll + 0.5 * k * _LOG2PI - 0.5 * logdet - 0.5 * (sx / _SX) ** 2 + np.log(sx)
        lp[ok] = np.where(sign > 0, val, -np.inf)
    return lp


def _draw_amplitudes(model, x, t, y, s, rng) -> np.ndarray:
    """One draw of the amplitudes from their conditional posterior at each row of ``x``."""
    a, G, _ = _linear_fit(model, x, t, y, s)
    L = np.linalg.cholesky(np.linalg.inv(G))
    out = a + np.einsum("wkj,wj->wk", L, rng.standard_normal(a.shape))
    for _ in range(20):  # the flat prior's bounds
        bad = np.any(np.abs(out) >= _AMP, axis=1)
        if not bad.any():
            break
        out[bad] = a[bad] + np.einsum("wkj,wj->wk", L[bad],
                                      rng.standard_normal((int(bad.sum()), a.shape[1])))
    return np.clip(out, -0.999 * _AMP, 0.999 * _AMP)


def _start(model, theta0, t, y, s, bounds, n_walkers, rng) -> np.ndarray:
    """Initial ensemble (sampled coordinates) drawn around the maximum ``theta0``.

    Walkers are drawn from a Laplace approximation whose covariance is the inverse Fisher
    information (Gauss-Newton: exact Jacobian of the mean law and of the variance), plus a
    weak ridge that caps each parameter's spread (amplitudes 0.3, log T 1, log sigma_x 1).
    The start is thus scaled to the posterior however precise the estimates are (a fixed ball
    was 4 sd wide for 0.03 % least-squares estimates, and a burn-in of 2·tau was too short to
    forget it).  Draws outside the support are redrawn closer to ``theta0``.
    """
    th = np.asarray(theta0, dtype=float)
    amp, logT, log_sx = _split(model, th[None, :])
    amp, logT, sx = amp[0], logT[0], float(np.exp(log_sx[0]))
    B = _basis(model, logT[None, :], t)[0]                      # (n, k)
    v = s**2 + sx**2
    n_amp = amp.size
    # d f / d amplitude = basis; d f / d logT_j = amp_j·e^(-t/T_j)·t/T_j
    J = [B[:, k] for k in range(n_amp)]
    ex = np.exp(-t[:, None] / np.exp(logT)[None, :])
    off = n_amp - logT.size  # the single law's constant has no time scale
    dT = [amp[off + j] * ex[:, j] * t / np.exp(logT[j]) for j in range(logT.size)]
    amp_i, T_i = _AMP_IDX[model], _T_IDX[model]
    cols = np.zeros((t.size, th.size))
    for k, col in zip(amp_i, J, strict=True):
        cols[:, k] = col
    for k, col in zip(T_i, dT, strict=True):
        cols[:, k] = col
    fisher = (cols / v[:, None]).T @ cols
    fisher[-1, -1] = 0.5 * np.sum((2 * sx**2 / v) ** 2) + 1.0  # + the prior's curvature
    cap = np.full(th.size, 0.3)
    cap[T_i] = 1.0
    cap[-1] = 1.0
    cov = np.linalg.pinv(fisher + np.diag(1.0 / cap**2), hermitian=True)
    chol = np.linalg.cholesky(cov + 1e-14 * np.eye(th.size))
    p0 = th + rng.standard_normal((n_walkers, th.size)) @ chol.T
    for _ in range(30):
        bad = ~np.isfinite(_log_post(model, p0, t, y, s, bounds))
        if not bad.any():
            break
        p0[bad] = th + 0.5 * (p0[bad] - th)  # shrink toward the maximum
    return p0


def _profile(model, logT, log_sx, t, y, s):
    """Max over amplitudes (weighted least squares) at fixed time scales and sigma_x."""
    sx = np.exp(log_sx)
    B = _basis(model, np.asarray(logT, dtype=float).reshape(1, -1), t)[0]
    w = 1.0 / np.sqrt(s**2 + sx**2)
    amp, *_ = np.linalg.lstsq(B * w[:, None], y * w, rcond=None)
    theta = np.concatenate([amp, logT, [sx]]) if model != "double" else \
        np.array([amp[0], logT[0], amp[1], logT[1], sx])
    return float(_log_like(model, theta[None, :], t, y, s)[0]), theta


def _mle(model, t, y, s, bounds) -> tuple[float, np.ndarray]:
    """Maximum likelihood (amplitudes profiled): grid over log T, then Nelder-Mead."""
    lo, hi = bounds
    grid = np.linspace(lo, hi, 25)
    sx_grid = np.log(np.array([1e-4, 0.003, 0.01, 0.03, 0.1, 0.3]))
    if model == "constant":
        starts = [(np.zeros(0), q) for q in sx_grid]
    elif model == "single":
        starts = [(np.array([g]), q) for g in grid for q in sx_grid]
    else:
        starts = [(np.array([a, b]), q) for i, a in enumerate(grid) for b in grid[i + 1:]
                  for q in sx_grid]
    best = max(starts, key=lambda st: _profile(model, st[0], st[1], t, y, s)[0])
    nT = best[0].size

    def neg(x):
        logT = np.clip(x[:nT], lo, hi)
        if model == "double":
            logT = np.sort(logT)
        return -_profile(model, logT, np.clip(x[nT], np.log(1e-8), np.log(10.0)), t, y, s)[0]

    res = optimize.minimize(neg, np.concatenate([best[0], [best[1]]]), method="Nelder-Mead",
                            options={"xatol": 1e-6, "fatol": 1e-9, "maxiter": 4000})
    logT = np.clip(res.x[:nT], lo, hi)
    logT = np.sort(logT) if model == "double" else logT
    ll, theta = _profile(model, logT, np.clip(res.x[nT], np.log(1e-8), np.log(10.0)), t, y, s)
    return ll, theta


def _sample(model, theta0, t, y, s, bounds, settings, seed):
    rng = np.random.default_rng(np.random.SeedSequence(seed).spawn(1)[0])
    nw = max(settings.n_walkers, 2 * theta0.size + 2)
    th = np.array(theta0, dtype=float)
    amp, logT, _ = _split(model, th[None, :])
    th[_AMP_IDX[model]] = np.clip(amp[0], -0.9 * _AMP, 0.9 * _AMP)
    lo, hi = bounds
    idx_T = _T_IDX[model]
    th[idx_T] = np.clip(logT[0], lo + 0.05, hi - 0.05)
    if model == "double" and th[idx_T[0]] >= th[idx_T[1]]:
        th[idx_T[1]] = th[idx_T[0]] + 1e-3
    th[-1] = np.log(np.clip(th[-1], 1e-8, 0.9 * _AMP))  # sampled as log sigma_x
    p0 = _start(model, th, t, y, s, bounds, nw, rng)
    names = _NAMES[model][:-1] + ["log_sigma_x"]  # the sampled coordinates
    # The single and constant laws are linear in their amplitudes: sample (log T, log sigma_x)
    # with the amplitudes integrated out and draw the amplitudes afterwards (2 and 1 sampled
    # dimensions instead of 4 and 2: an ensemble's autocorrelation time grows with the
    # dimension, and with 4 the log posterior's tau of ~30 steps left R-hat <= 1.01 to chance
    # at a few thousand steps).  The double law keeps its amplitudes, whose bounds shape its
    # degenerate posteriors.
    collapsed = model in ("single", "constant")
    if collapsed:
        keep = [i for i in range(th.size) if i not in _AMP_IDX[model]]
        p0 = p0[:, keep]

        def lp(x):
            return _log_post_collapsed(model, x, t, y, s, bounds)
    else:
        def lp(x):
            return _log_post(model, x, t, y, s, bounds)

    bad = ~np.isfinite(lp(p0))
    if bad.any():  # pragma: no cover - the start is inside the support by construction
        raise InputError("stiffening fit: could not start the walkers inside the prior")
    # run until R-hat and ESS pass (or the step cap): convergence is one of the checks
    ch = run_emcee(lp, p0, settings, int(np.random.SeedSequence(seed).generate_state(1)[0]),
                   accept=chain_passes)
    samples, tau = ch.samples, ch.tau
    if collapsed:
        W, D, _ = samples.shape
        flat = samples.reshape(W * D, -1)
        amp = _draw_amplitudes(model, flat, t, y, s, rng).reshape(W, D, -1)
        full = np.empty((W, D, th.size))
        full[..., keep] = samples
        full[..., _AMP_IDX[model]] = amp
        samples = full
        # amplitudes are drawn afresh at each draw: no slower than the sampled coordinates
        tau_full = np.full(th.size, float(np.max(tau)))
        tau_full[keep] = tau
        tau = tau_full
    # diagnostics on the sampled coordinates (log sigma_x) and the log posterior, as the
    # stop test saw them
    post = {n: samples[..., i] for i, n in enumerate(names)}
    with warnings.catch_warnings():  # short, heavily thinned chains: fewer draws than walkers
        warnings.filterwarnings("ignore", "More chains", UserWarning)
        idata = import_arviz().from_dict(posterior=post, sample_stats={"lp": ch.log_prob})
    diag = compute_diagnostics(idata, names, tau, ch.acceptance, ch.n_steps, ch.hit_cap)
    out = {n: v.ravel() for n, v in post.items()}
    out["sigma_x"] = np.exp(out.pop("log_sigma_x"))
    return out, diag


# ----------------------------------------------------------------------------- result


def _q(x, level):
    lo, hi = central(x, level)
    return float(np.median(x)), float(np.std(x, ddof=1)), float(lo), float(hi)


#: Equation of each law, by the names used in :attr:`StiffeningResult.preferred`.
LAW_TEXT = {
    "double": "E(t) = c1·exp(c2·t) + c3·exp(c4·t)",
    "single": "E(t) = c0 + c1·exp(c2·t)",
    "constant": "E(t) = c0 (no stiffening detected)",
}


@dataclass
class StiffeningResult:
    """Result of :func:`fit_stiffening`.

    Attributes
    ----------
    identifiable
        True when the two exponentials are resolved (module docstring, double-law checks 1-6,
        convergence included).
    message
        One paragraph: what was found and, for a simpler law, why the richer ones failed.
    preferred
        ``"double"``, ``"single"`` or ``"constant"`` (no stiffening detected): the law to use
        for prediction.
    double, single, constant
        Parameter tables (``parameter, unit, median, sd, lo, hi``; 90 % intervals) of the
        double law (c1 [Pa], c2 [1/s], c3 [Pa], c4 [1/s], sigma_x [Pa]), of
        E = c0 + c1·e^(c2·t) (c0, c1 [Pa], c2 [1/s], sigma_x [Pa]) and of E = c0 (c0,
        sigma_x [Pa]).
    draws, single_draws, constant_draws
        Posterior draws in the same units (keys as the ``parameter`` column).
    bic_double, bic_single, bic_constant
        BIC of each law (lower is better).
    converged
        The preferred law's sampler passed R-hat/ESS (``converged_laws`` has all three).
    n_points, n_distinct
        Estimates used and distinct rest times.
    reasons, single_reasons
        Failed checks of the double and of the single law.
    single_identifiable
        The single exponential passes its checks (module docstring).
    E_mean_pa, E_sd_pa
        [Pa] Mean and sd (ddof 1) of the estimates.
    """

    identifiable: bool
    message: str
    preferred: str
    double: pd.DataFrame
    single: pd.DataFrame
    draws: dict[str, np.ndarray]
    single_draws: dict[str, np.ndarray]
    bic_double: float
    bic_single: float
    converged: bool
    n_points: int
    n_distinct: int
    reasons: list[str] = field(default_factory=list)
    single_identifiable: bool = False
    single_reasons: list[str] = field(default_factory=list)
    constant: pd.DataFrame | None = None
    constant_draws: dict[str, np.ndarray] = field(default_factory=dict)
    bic_constant: float = np.nan
    converged_laws: dict[str, bool] = field(default_factory=dict)
    E_mean_pa: float = np.nan
    E_sd_pa: float = np.nan

    @property
    def stiffening_detected(self) -> bool:
        """False when the outcome is a constant modulus (no stiffening law passed its checks)."""
        return self.preferred != "constant"

    def table_of(self, model: str | None = None) -> pd.DataFrame:
        """Parameter table of ``model`` ("double", "single", "constant"; default: preferred)."""
        model = model or self.preferred
        return {"double": self.double, "single": self.single, "constant": self.constant}[model]

    @property
    def law(self) -> str:
        """The preferred law as an equation, e.g. ``E(t) = c0 + c1·exp(c2·t)``."""
        return LAW_TEXT[self.preferred]

    def row(self) -> dict:
        """One row of ``stiffening.csv``: verdict, BICs and the preferred law's medians."""
        tab = self.table_of().set_index("parameter")["median"]
        out = {"n_points": self.n_points, "n_distinct": self.n_distinct,
               "identifiable": self.identifiable, "preferred": self.preferred}
        for k in ("c0", "c1", "c2", "c3", "c4", "sigma_x"):
            out[k] = float(tab[k]) if k in tab.index else np.nan
        out.update({"bic_double": self.bic_double, "bic_single": self.bic_single,
                    "bic_constant": self.bic_constant,
                    "stiffening_detected": self.stiffening_detected,
                    "single_identifiable": self.single_identifiable,
                    "E_mean_pa": self.E_mean_pa, "E_sd_pa": self.E_sd_pa,
                    "converged": self.converged, "message": self.message})
        return out

    def predict(self, t, level: float = LEVEL, model: str | None = None) -> pd.DataFrame:
        """Posterior of the mean curve E(t) [Pa] on rest times ``t`` [s] (preferred law)."""
        model = model or self.preferred
        t = np.atleast_1d(np.asarray(t, dtype=float))
        if model == "double":
            d = self.draws
            curves = (d["c1"][:, None] * np.exp(d["c2"][:, None] * t)
                      + d["c3"][:, None] * np.exp(d["c4"][:, None] * t))
        elif model == "constant":
            curves = np.repeat(self.constant_draws["c0"][:, None], t.size, axis=1)
        else:
            d = self.single_draws
            curves = d["c0"][:, None] + d["c1"][:, None] * np.exp(d["c2"][:, None] * t)
        lo, med, hi = central_band(curves, level)
        return pd.DataFrame({"t_s": t, "median_pa": med, "lo_pa": lo, "hi_pa": hi})


def _table(draws: dict, units: dict, level: float) -> pd.DataFrame:
    rows = []
    for k, x in draws.items():
        med, sd, lo, hi = _q(x, level)
        rows.append({"parameter": k, "unit": units[k], "median": med, "sd": sd, "lo": lo,
                     "hi": hi})
    return pd.DataFrame(rows)


def _double_reasons(draws, bic_d, bic_s, n_distinct, t_max, diag, level) -> list[str]:
    reasons = []
    if n_distinct < 6:
        reasons.append(f"only {n_distinct} distinct rest times; five parameters need six or more")
    d_bic = float(bic_s - bic_d)
    if d_bic <= 2:
        reasons.append(f"BIC does not prefer two exponentials over one plus a constant "
                       f"(BIC_single - BIC_double = {d_bic:.1f} <= 2)")
    for name in ("c1", "c3"):
        _, _, lo, hi = _q(draws[name], level)
        if lo <= 0 <= hi:
            reasons.append(f"the {int(level * 100)} % interval of amplitude {name} includes 0")
    T2, T4 = -1.0 / draws["c2"], -1.0 / draws["c4"]
    ratio = np.quantile(T4 / T2, 0.05)
    if ratio < MIN_RATIO:
        reasons.append(f"the rates are not separated (5 % quantile of c2/c4 = {ratio:.2f} < "
                       f"{MIN_RATIO}, i.e. c2 ≈ c4)")
    slow = float(np.quantile(T4, 0.95))
    if slow > 10 * t_max:
        reasons.append(f"the slow term is indistinguishable from a constant over rest times up "
                       f"to {t_max:g} s (its time scale reaches {slow:.3g} s)")
    if not diag.converged:
        reasons.append("its sampler did not converge (" + "; ".join(diag.problems()) + "), a "
                       "usual symptom of a degenerate double exponential")
    return reasons


def _single_reasons(draws, bic_s, bic_c, n_distinct, t_min, t_max, diag, level) -> list[str]:
    reasons = []
    if n_distinct < 4:
        reasons.append(f"only {n_distinct} distinct rest times; four parameters need four or "
                       "more")
    d_bic = float(bic_c - bic_s)
    if d_bic <= 2:
        reasons.append(f"BIC does not prefer one exponential over a constant "
                       f"(BIC_constant - BIC_single = {d_bic:.1f} <= 2)")
    _, _, lo, hi = _q(draws["c1"], level)
    if lo <= 0 <= hi:
        reasons.append(f"the {int(level * 100)} % interval of amplitude c1 includes 0")
    T_lo, T_hi = central(-1.0 / draws["c2"], level)
    if T_lo < t_min or T_hi > t_max:
        reasons.append(f"its time scale is not resolved within the rest times {t_min:g}-{t_max:g}"
                       f" s (its {int(level * 100)} % interval is {T_lo:.3g}-{T_hi:.3g} s)")
    if not diag.converged:
        reasons.append("its sampler did not converge (" + "; ".join(diag.problems()) + ")")
    return reasons


def fit_stiffening(rest_time, E, E_sd=None, *, seed: int | None = 0,
                   settings: SamplerSettings | None = None, level: float = LEVEL
                   ) -> StiffeningResult:
    """Fit E(t) = c1·e^(c2·t) + c3·e^(c4·t), the single exponential + constant and a constant.

    The preferred law is the double law if it is identifiable, else the single law if it
    passes its checks, else the constant ("no stiffening detected"); module docstring.

    Parameters
    ----------
    rest_time
        [s] Rest time before each palpation (finite, >= 0; at least two positive values).
    E
        [Pa] Modulus estimate of each palpation.
    E_sd
        [Pa] Its standard uncertainty (None: zero, the extra scatter absorbs the noise).
    seed
        Seed of the samplers.
    settings
        emcee settings (default :data:`STIFFENING_SETTINGS`).
    level
        Probability content of the reported intervals.

    Returns
    -------
    StiffeningResult
    """
    t = np.asarray(rest_time, dtype=float).ravel()
    y = np.asarray(E, dtype=float).ravel()
    s = np.zeros_like(y) if E_sd is None else np.asarray(E_sd, dtype=float).ravel()
    if not (t.size == y.size == s.size) or t.size < 3:
        raise InputError("rest_time, E and E_sd must have the same length, at least 3")
    if not (np.all(np.isfinite(t)) and np.all(t >= 0) and np.all(np.isfinite(y))
            and np.all(np.isfinite(s)) and np.all(s >= 0)):
        raise InputError("rest times must be finite and >= 0, E finite and E_sd finite >= 0")
    pos = t[t > 0]
    if np.unique(pos).size < 2:
        raise InputError("the stiffening law needs at least two distinct positive rest times")
    settings = settings or STIFFENING_SETTINGS
    scale = float(np.median(np.abs(y)))
    if not scale > 0:
        raise InputError("the modulus estimates are all zero")
    ys, ss = y / scale, s / scale
    t_min, t_max = float(pos.min()), float(t.max())
    bounds = (float(np.log(t_min / 5.0)), float(np.log(100.0 * t_max)))
    n, n_distinct = t.size, int(np.unique(t).size)
    # seeds: the first two children as before (double, single), a third for the constant
    ss_seed = np.random.SeedSequence(seed).spawn(3)
    seeds = [int(x.generate_state(1)[0]) for x in ss_seed]

    fits = {}
    for model, seed_k in zip(("double", "single", "constant"), seeds, strict=True):
        ll, theta = _mle(model, t, ys, ss, bounds)
        raw, diag = _sample(model, theta, t, ys, ss, bounds, settings, seed_k)
        fits[model] = (_N_PARAMS[model] * np.log(n) - 2 * ll, raw, diag)
    bic_d, raw_d, diag_d = fits["double"]
    bic_s, raw_s, diag_s = fits["single"]
    bic_c, raw_c, diag_c = fits["constant"]

    draws = {"c1": raw_d["c1"] * scale, "c2": -1.0 / np.exp(raw_d["logT2"]),
             "c3": raw_d["c3"] * scale, "c4": -1.0 / np.exp(raw_d["logT4"]),
             "sigma_x": raw_d["sigma_x"] * scale}
    single = {"c0": raw_s["c0"] * scale, "c1": raw_s["c1"] * scale,
              "c2": -1.0 / np.exp(raw_s["logT"]), "sigma_x": raw_s["sigma_x"] * scale}
    constant = {"c0": raw_c["c0"] * scale, "sigma_x": raw_c["sigma_x"] * scale}
    units = {"c0": "Pa", "c1": "Pa", "c2": "1/s", "c3": "Pa", "c4": "1/s", "sigma_x": "Pa"}

    reasons = _double_reasons(draws, bic_d, bic_s, n_distinct, t_max, diag_d, level)
    single_reasons = _single_reasons(single, bic_s, bic_c, n_distinct, t_min, t_max, diag_s,
                                     level)
    identifiable = not reasons
    single_ok = not single_reasons
    preferred = "double" if identifiable else ("single" if single_ok else "constant")
    pct = f"{int(level * 100)} %"
    mean, sd = float(y.mean()), float(y.std(ddof=1))
    if identifiable:
        med = {k: float(np.median(v)) for k, v in draws.items()}
        message = (f"two exponentials resolved from {n} estimates: time scales "
                   f"{-1 / med['c2']:.3g} s and {-1 / med['c4']:.3g} s, amplitudes "
                   f"{format_pressure(med['c1'], 4)} and {format_pressure(med['c3'], 4)} (BIC "
                   "favours them by "
                   f"{float(bic_s - bic_d):.1f})")
    else:
        message = ("E(t) = c1·e^(c2·t) + c3·e^(c4·t) is not identifiable from these data: "
                   + "; ".join(reasons) + ".")
        if single_ok:
            q = {k: _q(v, level) for k, v in single.items()}
            T = -1.0 / single["c2"]
            T_lo, T_hi = central(T, level)
            message += (f" Use the single exponential E = c0 + c1·e^(c2·t): c0 = "
                        f"{format_pressure(q['c0'][0], 4)}, c1 = {format_pressure(q['c1'][0], 4)} "
                        f"({pct} interval {format_pressure(q['c1'][2], 4)} to "
                        f"{format_pressure(q['c1'][3], 4)}), time scale "
                        f"{float(np.median(T)):.3g} s ({pct} interval {T_lo:.3g}-{T_hi:.3g} s); "
                        f"BIC favours it over a constant by {float(bic_c - bic_s):.1f}.")
        else:
            _, _, c_lo, c_hi = _q(constant["c0"], level)
            message += (" A single exponential E = c0 + c1·e^(c2·t) is not supported either: "
                        + "; ".join(single_reasons) + f". No stiffening detected: E = "
                        f"{format_pressure(mean, 4)} ± {format_pressure(sd)} (mean ± sd of {n} "
                        f"estimates; {pct} interval of the constant {format_pressure(c_lo, 4)} to "
                        f"{format_pressure(c_hi, 4)}).")
    converged_laws = {"double": bool(diag_d.converged), "single": bool(diag_s.converged),
                      "constant": bool(diag_c.converged)}
    return StiffeningResult(
        identifiable=identifiable, message=message, preferred=preferred,
        double=_table(draws, units, level), single=_table(single, units, level),
        draws=draws, single_draws=single, bic_double=float(bic_d), bic_single=float(bic_s),
        converged=converged_laws[preferred], n_points=n, n_distinct=n_distinct,
        reasons=reasons, single_identifiable=single_ok, single_reasons=single_reasons,
        constant=_table(constant, units, level), constant_draws=constant,
        bic_constant=float(bic_c), converged_laws=converged_laws, E_mean_pa=mean, E_sd_pa=sd,
    )


def fit_stiffening_summary(summary: pd.DataFrame, *, method: str = "bayes",
                           seed: int | None = 0, settings: SamplerSettings | None = None,
                           **select) -> StiffeningResult:
    """:func:`fit_stiffening` on the rows of a ``summary.csv`` table with a rest time.

    Bayesian rows use the *statistical* estimate (``E_stat_pa`` ± ``E_stat_sd_pa``): the budget's
    systematic inputs are common to every palpation of a specimen and scale the whole curve,
    not its shape.  Least-squares rows use ``E_pa`` ± ``E_sd_pa``.  ``select`` filters rows by
    column value (e.g. ``material="White", tip="sphere"``).
    """
    e_col, s_col = ("E_stat_pa", "E_stat_sd_pa") if method == "bayes" else ("E_pa", "E_sd_pa")
    missing = {"method", "rest_time_s", e_col, s_col} - set(summary.columns)
    if missing:
        raise InputError(f"summary lacks column(s) {', '.join(sorted(missing))} for {method} "
                         "rows")
    df = summary[summary["method"] == method]
    for col, value in select.items():
        if col not in df.columns:
            raise InputError(f"summary has no column {col!r} to select on")
        df = df[df[col] == value]
    df = df[np.isfinite(df["rest_time_s"].astype(float))]
    df = df[np.isfinite(df[e_col].astype(float))]
    if df.empty:
        raise InputError(f"no {method} rows with a rest time to fit")
    return fit_stiffening(df["rest_time_s"].to_numpy(float), df[e_col].to_numpy(float),
                          df[s_col].to_numpy(float), seed=seed, settings=settings)
