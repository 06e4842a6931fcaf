"""Multi-palpation stiffening: E(t) = c1·e^(c2·t) + c3·e^(c4·t) versus rest time t (DESIGN §2).

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

Identifiability
---------------
A sum of two exponentials is notoriously ill-conditioned (Lanczos' example): the double law is
reported as *identifiable* only when all of these hold, otherwise ``identifiable`` is False and
``message`` says which failed, and the single exponential plus constant
E = c0 + c1·e^(c2·t) (same priors) is the preferred description:

1. at least six distinct rest times (five parameters);
2. the Bayesian information criterion prefers the double law by more than 2
   (BIC = k·ln n − 2·ln L_max, k = 5 vs 4; Kass & Raftery 1995 "positive evidence");
3. both amplitudes' 90 % intervals exclude zero;
4. the time scales are separated: the 5 % quantile of T4/T2 exceeds :data:`MIN_RATIO` (1.5);
5. the slow time scale is resolved: its 95 % quantile is below 10·max t (else the slow term
   is a constant over the data).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from scipy import optimize

from .bayes.diagnostics import compute_diagnostics, import_arviz
from .bayes.result import LEVEL
from .bayes.sampler import SamplerSettings, run_emcee
from .errors import InputError

__all__ = ["StiffeningResult", "fit_stiffening", "fit_stiffening_summary",
           "STIFFENING_SETTINGS", "MIN_RATIO", "double_exponential"]

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
    if model == "single":
        ex = np.concatenate([np.ones_like(ex[:, :1]), ex], axis=1)
    return np.swapaxes(ex, 1, 2)


def _split(model: str, theta: np.ndarray):
    if model == "double":
        return theta[:, [0, 2]], theta[:, [1, 3]], theta[:, 4]
    return theta[:, [0, 1]], theta[:, [2]], theta[:, 3]


def _log_like(model, theta, t, y, s):
    amp, logT, sx = _split(model, theta)
    f = np.einsum("wnk,wk->wn", _basis(model, logT, t), amp)
    v = s[None, :] ** 2 + sx[:, None] ** 2
    return -0.5 * np.sum(_LOG2PI + np.log(v) + (y[None, :] - f) ** 2 / v, axis=1)


def _log_post(model, theta, t, y, s, bounds):
    theta = np.atleast_2d(theta)
    amp, logT, sx = _split(model, theta)
    lo, hi = bounds
    ok = np.all(np.abs(amp) < _AMP, axis=1) & np.all((logT > lo) & (logT < hi), axis=1)
    ok &= sx >= 0
    if model == "double":
        ok &= logT[:, 0] < logT[:, 1]
    lp = np.full(theta.shape[0], -np.inf)
    if ok.any():
        th = theta[ok]
        lp[ok] = _log_like(model, th, t, y, s) - 0.5 * (_split(model, th)[2] / _SX) ** 2
    return lp


def _profile(model, logT, log_sx, t, y, s):
    """Max over amplitudes (weighted least squares) at fixed time scales and sigma_x."""
    sx = np.exp(log_sx)
    B = _basis(model, np.atleast_2d(logT), t)[0]
    w = 1.0 / np.sqrt(s**2 + sx**2)
    amp, *_ = np.linalg.lstsq(B * w[:, None], y * w, rcond=None)
    theta = np.concatenate([amp, logT, [sx]]) if model == "single" else \
        np.array([amp[0], logT[0], amp[1], logT[1], sx])
    return float(_log_like(model, theta[None, :], t, y, s)[0]), theta


def _mle(model, t, y, s, bounds) -> tuple[float, np.ndarray]:
    """Maximum likelihood (amplitudes profiled): grid over log T, then Nelder-Mead."""
    lo, hi = bounds
    grid = np.linspace(lo, hi, 25)
    sx_grid = np.log(np.array([1e-4, 0.003, 0.01, 0.03, 0.1, 0.3]))
    if model == "single":
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
    th[np.isin(np.arange(th.size), [0, 2] if model == "double" else [0, 1])] = np.clip(
        amp[0], -0.9 * _AMP, 0.9 * _AMP)
    lo, hi = bounds
    idx_T = [1, 3] if model == "double" else [2]
    th[idx_T] = np.clip(logT[0], lo + 0.05, hi - 0.05)
    th[-1] = max(th[-1], 1e-3)
    scale = np.full(th.size, 1e-3)
    scale[idx_T] = 1e-2
    p0 = th + scale * rng.standard_normal((nw, th.size))
    p0[:, -1] = np.abs(p0[:, -1])
    if model == "double":
        p0[:, idx_T] = np.sort(p0[:, idx_T], axis=1)

    def lp(x):
        return _log_post(model, x, t, y, s, bounds)

    bad = ~np.isfinite(lp(p0))
    if bad.any():  # pragma: no cover - the start is inside the support by construction
        raise InputError("stiffening fit: could not start the walkers inside the prior")
    ch = run_emcee(lp, p0, settings, int(np.random.SeedSequence(seed).generate_state(1)[0]))
    names = (["c1", "logT2", "c3", "logT4", "sigma_x"] if model == "double"
             else ["c0", "c1", "logT", "sigma_x"])
    post = {n: ch.samples[..., i] for i, n in enumerate(names)}
    with warnings.catch_warnings():  # short, heavily thinned chains: fewer draws than walkers
        warnings.filterwarnings("ignore", "More chains", UserWarning)
        idata = import_arviz().from_dict(posterior=post)
    diag = compute_diagnostics(idata, names, ch.tau, ch.acceptance, ch.n_steps, ch.hit_cap)
    return {n: v.ravel() for n, v in post.items()}, diag


# ----------------------------------------------------------------------------- result


def _q(x, level):
    a = (1 - level) / 2
    lo, hi = np.quantile(x, [a, 1 - a])
    return float(np.median(x)), float(np.std(x, ddof=1)), float(lo), float(hi)


@dataclass
class StiffeningResult:
    """Result of :func:`fit_stiffening`.

    Attributes
    ----------
    identifiable
        True when the two exponentials are resolved (module docstring, checks 1-5).
    message
        One paragraph: what was found and, if not identifiable, why.
    preferred
        ``"double"`` or ``"single"`` (the law to use for prediction).
    double, single
        Parameter tables (``parameter, unit, median, sd, lo, hi``; 90 % intervals) of the
        double law (c1 [Pa], c2 [1/s], c3 [Pa], c4 [1/s], sigma_x [Pa]) and of
        E = c0 + c1·e^(c2·t) (c0, c1 [Pa], c2 [1/s], sigma_x [Pa]).
    draws, single_draws
        Posterior draws in the same units (keys as the ``parameter`` column).
    bic_double, bic_single
        BIC of each law (lower is better).
    converged
        Both samplers passed R-hat/ESS.
    n_points, n_distinct
        Estimates used and distinct rest times.
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

    def row(self) -> dict:
        """One row of ``stiffening.csv``: verdict, BICs and the preferred law's medians."""
        tab = (self.double if self.preferred == "double" else self.single).set_index(
            "parameter")["median"]
        out = {"n_points": self.n_points, "n_distinct": self.n_distinct,
               "identifiable": self.identifiable, "preferred": self.preferred}
        for k in ("c0", "c1", "c2", "c3", "c4", "sigma_x"):
            out[k] = float(tab[k]) if k in tab.index else np.nan
        out.update({"bic_double": self.bic_double, "bic_single": self.bic_single,
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
        else:
            d = self.single_draws
            curves = d["c0"][:, None] + d["c1"][:, None] * np.exp(d["c2"][:, None] * t)
        a = (1 - level) / 2
        lo, med, hi = np.quantile(curves, [a, 0.5, 1 - a], axis=0)
        return pd.DataFrame({"t_s": t, "median_pa": med, "lo_pa": lo, "hi_pa": hi})


def _table(draws: dict, units: dict, level: float) -> pd.DataFrame:
    rows = []
    for k, x in draws.items():
        med, sd, lo, hi = _q(x, level)
        rows.append({"parameter": k, "unit": units[k], "median": med, "sd": sd, "lo": lo,
                     "hi": hi})
    return pd.DataFrame(rows)


def fit_stiffening(rest_time, E, E_sd=None, *, seed: int | None = 0,
                   settings: SamplerSettings | None = None, level: float = LEVEL
                   ) -> StiffeningResult:
    """Fit E(t) = c1·e^(c2·t) + c3·e^(c4·t) and the single exponential + constant.

    Parameters
    ----------
    rest_time
        [s] Rest time before each palpation (finite, >= 0; at least two positive values).
    E
        [Pa] Modulus estimate of each palpation.
    E_sd
        [Pa] Its standard uncertainty (None: zero, the extra scatter absorbs the noise).
    seed
        Seed of both samplers.
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
    t_max = float(t.max())
    bounds = (float(np.log(pos.min() / 5.0)), float(np.log(100.0 * t_max)))
    n, n_distinct = t.size, int(np.unique(t).size)
    ss_seed = np.random.SeedSequence(seed).spawn(2)
    seeds = [int(x.generate_state(1)[0]) for x in ss_seed]

    ll_d, th_d = _mle("double", t, ys, ss, bounds)
    ll_s, th_s = _mle("single", t, ys, ss, bounds)
    bic_d = 5 * np.log(n) - 2 * ll_d
    bic_s = 4 * np.log(n) - 2 * ll_s
    raw_d, diag_d = _sample("double", th_d, t, ys, ss, bounds, settings, seeds[0])
    raw_s, diag_s = _sample("single", th_s, t, ys, ss, bounds, settings, seeds[1])

    T2, T4 = np.exp(raw_d["logT2"]), np.exp(raw_d["logT4"])
    draws = {"c1": raw_d["c1"] * scale, "c2": -1.0 / T2, "c3": raw_d["c3"] * scale,
             "c4": -1.0 / T4, "sigma_x": raw_d["sigma_x"] * scale}
    single = {"c0": raw_s["c0"] * scale, "c1": raw_s["c1"] * scale,
              "c2": -1.0 / np.exp(raw_s["logT"]), "sigma_x": raw_s["sigma_x"] * scale}
    units = {"c0": "Pa", "c1": "Pa", "c2": "1/s", "c3": "Pa", "c4": "1/s", "sigma_x": "Pa"}

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
    ratio = np.quantile(T4 / T2, 0.05)
    if ratio < MIN_RATIO:
        reasons.append(f"the rates are not separated (5 % quantile of c2/c4 = {ratio:.2f} < "
                       f"{MIN_RATIO}, i.e. c2 ≈ c4)")
    slow = float(np.quantile(T4, 0.95))
    if slow > 10 * t_max:
        reasons.append(f"the slow term is indistinguishable from a constant over rest times up "
                       f"to {t_max:g} s (its time scale reaches {slow:.3g} s)")
    identifiable = not reasons
    converged = bool(diag_d.converged and diag_s.converged)
    if identifiable:
        med = {k: float(np.median(v)) for k, v in draws.items()}
        message = (f"two exponentials resolved from {n} estimates: time scales "
                   f"{-1 / med['c2']:.3g} s and {-1 / med['c4']:.3g} s, amplitudes "
                   f"{med['c1']:.4g} and {med['c3']:.4g} Pa (BIC favours them by {d_bic:.1f})")
    else:
        sm = {k: float(np.median(v)) for k, v in single.items()}
        message = ("E(t) = c1·e^(c2·t) + c3·e^(c4·t) is not identifiable from these data: "
                   + "; ".join(reasons) + ". Use the single exponential E = c0 + c1·e^(c2·t): "
                   f"c0 = {sm['c0']:.4g} Pa, c1 = {sm['c1']:.4g} Pa, time scale "
                   f"{-1 / sm['c2']:.3g} s.")
    if not converged:
        problems = diag_d.problems() + diag_s.problems()
        message += (" Sampler diagnostics failed (" + "; ".join(problems) + "), a usual "
                    "symptom of a degenerate double exponential.")
    return StiffeningResult(
        identifiable=identifiable, message=message,
        preferred="double" if identifiable else "single",
        double=_table(draws, units, level), single=_table(single, units, level),
        draws=draws, single_draws=single, bic_double=float(bic_d), bic_single=float(bic_s),
        converged=converged, n_points=n, n_distinct=n_distinct, reasons=reasons,
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
