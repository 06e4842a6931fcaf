"""Model-adequacy checks of a contact fit (DESIGN §3 point 7).

A 3,840-point trace pins E* to a fraction of a percent, so a fit can be statistically tight and
physically wrong.  Each check here compares the data with what the fitted contact law
F = E*·s(d) + F0 (+ F1·(z - z_ref)), d = z_surf - z, implies, and returns a
:class:`CheckResult` whose ``flag`` names the likely cause and the fix when it fails:

``exponent``
    Free power law F = k·d_+^m + F0 (+ F1·(z - z_ref)) fitted with z_surf and m free
    (:func:`free_exponent_fit`) against the law's own exponent on the same depths (1 flat,
    1.5 paraboloid, 2 cone; the local log-slope for the exact sphere or a thickness-corrected
    law).  Stiffening with depth (m too high) points at finite thickness, strain-stiffening
    or a sharper tip; softening at a blunter tip, series compliance or a soft start.
``residual_structure``
    Mean residual in depth bins (pre-contact and contact), chi² against the AR(1)-aware
    variance of a bin mean; the pattern names drift/tilt, a gradual onset/adhesion, or a
    wrong law shape.  Durbin-Watson and lag-1 autocorrelation of the residuals in depth order
    are reported.
``ppc``
    Posterior-predictive check (Gelman, Meng & Stern 1996): the same binned chi² as the
    discrepancy T(y, theta), replicated data drawn from the fitted noise model (iid or AR(1))
    at each posterior draw; p = P(T(y_rep) >= T(y)).
``depth_consistency``
    E* refitted on the shallower half of the depth (z_surf, E*, F0 free) against E* over
    all points; the standard error of the difference is the Hausman form
    sqrt(se_shallow² - se_all²) for nested efficient estimators (Hausman 1978).

**Thresholds.**  Standard errors of a long trace are tiny, so every check fails only when a
statistical test *and* a physical effect size agree (:data:`THRESHOLDS`): exponent
|m - m_law| > 3 se and > 3 % of m_law; binned residual chi² p < 0.01 and the largest bin mean
> 0.2 sigma; posterior-predictive p < 0.01; depth consistency |E*_shallow/E*_all - 1| > 3 se
and > 5 %.  They were calibrated on simulated traces (``tests/test_model_checks.py``).

**Correlated noise.**  800 Hz force noise is autocorrelated.  The variance of the mean of n
consecutive AR(1) samples with lag-1 coefficient phi and marginal sd sigma is
(sigma²/n)·[(1+phi)/(1-phi) - 2·phi·(1-phi^n)/(n·(1-phi)²)] (e.g. Box & Jenkins); standard
errors of fitted parameters are inflated by the long-run factor sqrt((1+phi)/(1-phi)).  phi is
the noise's own lag-1 autocorrelation, best taken from the pre-contact baseline
(:func:`noise_lag1`); without it, it is estimated from the residuals' first differences,
phi = 1 + 2·corr(Δr_t, Δr_(t-1)) (exact for AR(1), and blind to smooth misfit).

**Baseline reference.**  A linear baseline is F0 + F1·(z - z_ref) with z_ref = the highest z of
the fitted samples (the start of the approach) unless ``z_ref`` is given: F0 is then the force
where the approach starts.

Pure numpy/scipy, no plotting.  Inputs are the fitted samples in time order (loading segment).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy import optimize, stats
from scipy.signal import lfilter

from .errors import FitError, InputError
from .fitdata import ModelSpec

__all__ = [
    "CheckResult",
    "THRESHOLDS",
    "TIP_EXPONENTS",
    "ar1_mean_variance_factor",
    "noise_lag1",
    "law_exponent",
    "free_exponent_fit",
    "exponent_check",
    "binned_residuals",
    "residual_structure_check",
    "posterior_predictive_check",
    "depth_consistency_check",
    "run_checks",
]

#: Pass/fail thresholds (statistical and physical) of the checks; see the module docstring.
THRESHOLDS: dict[str, float] = {
    "exponent_n_se": 3.0,        # |m - m_law| > 3 standard errors ...
    "exponent_rel": 0.03,        # ... and > 3 % of m_law
    "residual_alpha": 0.01,      # binned chi² p-value below 1 % ...
    "residual_amp": 0.2,         # ... and the largest |bin mean| above 0.2 sigma
    "ppc_alpha": 0.01,           # posterior-predictive p below 1 %
    "depth_n_se": 3.0,           # |E*_shallow/E*_all - 1| > 3 standard errors ...
    "depth_rel": 0.05,           # ... and > 5 %
}

#: Exponent m of each power-law tip family (for naming a wrong tip).
TIP_EXPONENTS: dict[str, float] = {"flat": 1.0, "paraboloid": 1.5, "cone": 2.0}

_MIN_BIN = 8  # fewest samples in a bin


@dataclass(frozen=True)
class CheckResult:
    """Outcome of one adequacy check.

    Attributes
    ----------
    name
        ``"exponent"``, ``"residual_structure"``, ``"ppc"`` or ``"depth_consistency"``.
    statistic
        The check's number: fitted m, binned chi², posterior-predictive p-value, or
        E*_shallow/E*_all.
    passed
        False when the check flags the model.
    flag
        ``""`` when passed, else one line naming the likely cause and the fix.
    details
        Numbers for tables (all SI).
    """

    name: str
    statistic: float
    passed: bool
    flag: str
    details: dict = field(default_factory=dict)


# ----------------------------------------------------------------------------- helpers


def _arrays(z, force) -> tuple[np.ndarray, np.ndarray]:
    z = np.asarray(z, dtype=float).ravel()
    f = np.asarray(force, dtype=float).ravel()
    if z.shape != f.shape:
        raise InputError(f"z ({z.size}) and force ({f.size}) differ in length")
    if z.size < 20:
        raise InputError(f"a model check needs at least 20 samples, got {z.size}")
    if not (np.all(np.isfinite(z)) and np.all(np.isfinite(f))):
        raise InputError("z and force must be finite")
    return z, f


def _acf1(x: np.ndarray) -> float:
    x = np.asarray(x, dtype=float) - np.mean(x)
    den = float(np.dot(x, x))
    return float(np.dot(x[1:], x[:-1]) / den) if den > 0 else 0.0


def _clip_phi(phi: float) -> float:
    return float(np.clip(phi, -0.99, 0.999))


def ar1_mean_variance_factor(n, phi: float) -> np.ndarray:
    """Variance of the mean of n consecutive AR(1) samples, in units of sigma²/n [-].

    g(n, phi) = (1+phi)/(1-phi) - 2·phi·(1-phi^n)/(n·(1-phi)²): 1 for white noise, tending to
    the long-run factor (1+phi)/(1-phi) for n >> 1/(1-phi) (Box & Jenkins, AR(1) sample mean).

    Parameters
    ----------
    n
        Number of samples per mean (array or scalar, >= 1).
    phi
        Lag-1 autocorrelation, |phi| < 1.
    """
    n = np.asarray(n, dtype=float)
    phi = _clip_phi(phi)
    if phi == 0:
        return np.ones_like(n)
    return (1 + phi) / (1 - phi) - 2 * phi * (1 - phi**n) / (n * (1 - phi) ** 2)


def _phi_from_differences(r: np.ndarray) -> float:
    """AR(1) coefficient from the lag-1 correlation of first differences: phi = 1 + 2·rho_Δ."""
    dr = np.diff(r)
    if dr.size < 3:
        return 0.0
    return _clip_phi(1.0 + 2.0 * _acf1(dr))


def noise_lag1(z, force, z_surf: float, *, margin: float = 0.05) -> float | None:
    """Lag-1 autocorrelation [-] of the force noise from the pre-contact baseline.

    Uses the samples above z_surf + margin·(z_surf - min z) (clear of a gradual onset), in time
    order, after removing a straight line in time (drift); None with fewer than 32 of them.

    Parameters
    ----------
    z, force
        [m], [N] samples in time order.
    z_surf
        [m] Fitted surface height.
    margin
        Fraction of the contact depth kept clear above the surface.
    """
    z, f = _arrays(z, force)
    dmax = max(z_surf - float(z.min()), 0.0)
    sel = z > z_surf + margin * dmax
    if sel.sum() < 32:
        return None
    y = f[sel]
    t = np.arange(y.size, dtype=float)
    y = y - np.polyval(np.polyfit(t, y, 1), t)
    return _clip_phi(_acf1(y))


def _design(z, dp_term, baseline: str, z_ref: float) -> np.ndarray:
    cols = [dp_term, np.ones_like(z)]
    if baseline == "linear":
        cols.append(z - z_ref)
    elif baseline != "constant":
        raise InputError(f"baseline must be 'constant' or 'linear', got {baseline!r}")
    return np.column_stack(cols)


# Tall-skinny products go through einsum, not BLAS: a threaded BLAS on a loaded machine makes
# a (16000 x 5)ᵀ(16000 x 5) product 100x slower than the arithmetic needs.
def _gram(J: np.ndarray) -> np.ndarray:
    return np.einsum("ij,ik->jk", J, J)


def _tdot(J: np.ndarray, r: np.ndarray) -> np.ndarray:
    return np.einsum("ij,i->j", J, r)


def _lstsq(X: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Linear least squares (scaled normal equations; few columns); (coefficients, residuals)."""
    scale = np.sqrt(np.einsum("ij,ij->j", X, X))
    scale[scale == 0] = 1.0
    Xs = X / scale
    beta = np.linalg.lstsq(_gram(Xs), _tdot(Xs, y), rcond=None)[0] / scale
    return beta, y - np.einsum("ij,j->i", X, beta)


def _cov(J: np.ndarray, s2: float, infl: float) -> np.ndarray:
    scale = np.sqrt(np.einsum("ij,ij->j", J, J))
    scale[scale == 0] = 1.0
    Js = J / scale
    cov = np.linalg.pinv(_gram(Js)) / np.outer(scale, scale)
    return cov * s2 * infl


class _ShapeTable:
    """s(d) and ds/dd of a model tabulated on d_i = d_top·(i/N)², linearly interpolated.

    The exact shape function (e.g. Sneddon's sphere, solved by Halley iterations) is too slow
    to call for every posterior draw and every step of a search; the table is exact at its
    4097 nodes (denser near d = 0 where s is least smooth) and its interpolation error is below
    1e-6·s(d_top) for the laws of :mod:`palpbayes.contact`.  Depths beyond d_top fall back to
    the exact law.
    """

    def __init__(self, model: ModelSpec, d_top: float, n: int = 4096):
        self.model = model
        self.d_top = float(d_top)
        self.grid = self.d_top * (np.arange(n + 1) / n) ** 2
        self.s = model.shape(self.grid)
        self.ds = model.shape_derivative(self.grid)

    def shape(self, d) -> np.ndarray:
        d = np.asarray(d, dtype=float)
        out = np.interp(d, self.grid, self.s, left=0.0)
        far = d > self.d_top
        if np.any(far):
            out[far] = self.model.shape(d[far])
        return out

    def shape_derivative(self, d) -> np.ndarray:
        d = np.asarray(d, dtype=float)
        out = np.interp(d, self.grid, self.ds, left=0.0)
        far = d > self.d_top
        if np.any(far):
            out[far] = self.model.shape_derivative(d[far])
        return out


def _long_run(phi: float | None) -> float:
    phi = 0.0 if phi is None else _clip_phi(phi)
    return (1 + phi) / (1 - phi)


def _levenberg_marquardt(resid, jac, x0: np.ndarray, lo: np.ndarray, hi: np.ndarray,
                         max_iter: int = 100, tol: float = 1e-10) -> tuple[np.ndarray, bool]:
    """Minimise |resid(x)|² by Levenberg-Marquardt with Marquardt scaling, x clipped to
    [lo, hi] (projected steps).  Few parameters, many residuals: each step solves the p×p
    normal equations.  Returns (x, converged)."""
    x = np.clip(x0, lo, hi)
    r = resid(x)
    cost = float(np.dot(r, r))
    lam = 1e-3
    for _ in range(max_iter):
        J = jac(x)
        A = _gram(J)
        g = _tdot(J, r)
        dA = np.diag(A).copy()
        dA[dA <= 0] = 1.0
        improved = False
        for _ in range(30):
            try:
                step = -np.linalg.solve(A + lam * np.diag(dA), g)
            except np.linalg.LinAlgError:
                lam *= 10.0
                continue
            xn = np.clip(x + step, lo, hi)
            rn = resid(xn)
            cn = float(np.dot(rn, rn))
            if cn <= cost:
                improved = True
                break
            lam *= 10.0
        if not improved:
            return x, True  # no downhill step at any damping: at a (bounded) minimum
        rel = (cost - cn) / max(cost, 1e-300)
        dx = float(np.max(np.abs(xn - x) / (np.abs(xn) + 1e-12)))
        x, r, cost = xn, rn, cn
        lam = max(lam / 10.0, 1e-12)
        if rel < tol and dx < 1e-8:
            return x, True
    return x, False


# ----------------------------------------------------------------------------- exponent


def law_exponent(model: ModelSpec, z, z_surf: float, *, baseline: str = "constant",
                 z_ref: float | None = None) -> float:
    """Exponent m [-] that a free power-law fit finds on noise-free data of the model's law.

    The exponent of the tip's law when it is a power law on a half-space (1 flat, 1.5
    paraboloid, 2 cone, (n+1)/n power).  Otherwise (exact Sneddon sphere, finite-thickness
    correction) :func:`free_exponent_fit` is run on the noise-free curve s(z_surf - z) at the
    same heights z, baseline and free surface as the data's fit, so that m_law and the data's
    m carry the same trade-off between m and z_surf (for the sphere at small d/R it tends to
    Hertz's 1.5; at d/R = 0.3 it is about 1.47).

    Parameters
    ----------
    model
        The contact model.
    z
        [m] Heights of the fitted samples.
    z_surf
        [m] Fitted surface height.
    baseline, z_ref
        As in :func:`free_exponent_fit`.
    """
    m0 = model.exponent
    if m0 is not None:
        return float(m0)
    z = np.asarray(z, dtype=float)
    s = model.shape(z_surf - z)
    if np.count_nonzero(s > 0) < 3:
        raise FitError("too few contact samples to compute the law's effective exponent")
    s = s / s.max()
    return free_exponent_fit(z, s, z_surf, baseline=baseline, z_ref=z_ref)["m"]


def free_exponent_fit(z, force, z_surf0: float, *, baseline: str = "constant",
                      z_ref: float | None = None, m0: float = 1.5,
                      noise_lag1: float | None = None,
                      m_bounds: tuple[float, float] = (0.6, 4.0)) -> dict:
    """Least-squares fit of a free power law F = k·d_+^m + F0 (+ F1·(z - z_ref)).

    d_+ = max(z_surf - z, 0).  Started from z_surf0 and m0 with k, F0 (and F1) solved
    linearly (variable projection, Golub & Pereyra 1973), then all parameters refined by a
    bounded Levenberg-Marquardt (Marquardt 1963) with the analytic Jacobian in
    (z_surf, m, k, F0[, F1]) (a few ms for 16,000 samples).  Standard errors from that
    Jacobian and the residual variance, multiplied by the AR(1) long-run factor
    (1+phi)/(1-phi) when ``noise_lag1`` is given.

    Parameters
    ----------
    z, force
        [m], [N] fitted samples (pre-contact samples help pin F0).
    z_surf0
        [m] Starting surface height (e.g. the law fit's z_surf).
    baseline
        ``"constant"`` (F0) or ``"linear"`` (F0 + F1·(z - z_ref)).
    z_ref
        [m] Reference height of the linear baseline; default the highest z.
    m0
        Starting exponent.
    noise_lag1
        Lag-1 autocorrelation phi of the noise, for the standard errors.
    m_bounds
        Bounds of m.

    Returns
    -------
    dict
        ``m``, ``m_se``, ``z_surf`` [m], ``z_surf_se`` [m], ``k`` [N/m^m], ``F0`` [N], ``F1``
        [N/m] (0 for a constant baseline), ``rss`` [N²], ``s`` [N] residual sd, ``n``,
        ``residuals`` [N], ``success``.
    """
    z, f = _arrays(z, force)
    z_ref = float(z.max()) if z_ref is None else float(z_ref)
    dmax = z_surf0 - float(z.min())
    if not dmax > 0:
        raise FitError("the starting surface lies below every sample: no contact to fit")
    linear = baseline == "linear"
    zn = (z - z_ref) / dmax  # scaled baseline regressor
    fscale = float(np.max(np.abs(f))) or 1.0
    y = f / fscale

    def parts(p):
        dpn = np.maximum(p[0] - (z - z_surf0) / dmax, 0.0)  # depth / dmax
        with np.errstate(divide="ignore", invalid="ignore"):
            pw = np.where(dpn > 0, dpn ** p[1], 0.0)
        return dpn, pw

    def resid(p):
        _, pw = parts(p)
        mu = p[2] * pw + p[3] + (p[4] * zn if linear else 0.0)
        return mu - y

    def jac(p):
        dpn, pw = parts(p)
        pos = dpn > 0
        safe = np.where(pos, dpn, 1.0)
        cols = [np.where(pos, p[2] * p[1] * pw / safe, 0.0),
                np.where(pos, p[2] * pw * np.log(safe), 0.0), pw, np.ones_like(z)]
        if linear:
            cols.append(zn)
        return np.column_stack(cols)

    m_start = float(np.clip(m0, m_bounds[0] + 1e-6, m_bounds[1] - 1e-6))
    _, pw0 = parts([0.0, m_start])
    beta0 = _lstsq(_design(zn, pw0, baseline, 0.0), y)[0]
    p0 = [0.0, m_start, beta0[0], beta0[1]] + ([beta0[2]] if linear else [])

    def resid_fn(q):
        return resid(q if linear else np.append(q, 0.0))

    def jac_fn(q):
        return jac(q if linear else np.append(q, 0.0))

    lo_u = (float(z.min()) - z_surf0) / dmax + 0.1
    hi_u = max((float(z.max()) - z_surf0) / dmax, 1e-3)
    lo = [lo_u, m_bounds[0]] + [-np.inf] * (len(p0) - 2)
    hi = [hi_u, m_bounds[1]] + [np.inf] * (len(p0) - 2)
    x, success = _levenberg_marquardt(resid_fn, jac_fn, np.array(p0, dtype=float),
                                      np.array(lo), np.array(hi))
    p = np.append(x, 0.0) if not linear else x
    r = -resid(p) * fscale
    J = jac_fn(x) * fscale
    n, npar = f.size, J.shape[1]
    rss = float(np.dot(r, r))
    cov = _cov(J, rss / max(n - npar, 1), _long_run(noise_lag1))
    m = float(p[1])
    return {
        "m": m, "m_se": float(math.sqrt(max(cov[1, 1], 0.0))),
        "z_surf": float(z_surf0 + p[0] * dmax),
        "z_surf_se": float(math.sqrt(max(cov[0, 0], 0.0)) * dmax),
        "k": float(p[2] * fscale / dmax**m), "F0": float(p[3] * fscale),
        "F1": float(p[4] * fscale / dmax) if linear else 0.0,
        "rss": rss, "s": math.sqrt(rss / max(n - npar, 1)), "n": int(n), "residuals": r,
        "success": bool(success),
    }


def _wrong_tip_hint(model: ModelSpec, m: float) -> str:
    """'the cone's 2' when the fitted m is closer to another tip family's exponent."""
    kind = model.tip.kind
    best = min(TIP_EXPONENTS.items(), key=lambda kv: abs(kv[1] - m))
    if best[0] != kind and abs(best[1] - m) < 0.15:
        return f"m is near the {best[0]} law's {best[1]:g}"
    return ""


def exponent_check(z, force, model: ModelSpec, z_surf: float, *, baseline: str = "constant",
                   z_ref: float | None = None, noise_lag1: float | None = None,
                   n_se: float = THRESHOLDS["exponent_n_se"],
                   rel_tol: float = THRESHOLDS["exponent_rel"]) -> CheckResult:
    """Free-exponent fit against the law's exponent on the same depths.

    Fails when |m - m_law| > ``n_se``·se(m) **and** > ``rel_tol``·m_law, with m from
    :func:`free_exponent_fit` and m_law from :func:`law_exponent` (evaluated at the contact
    depths of the fit).

    Parameters
    ----------
    z, force
        [m], [N] fitted samples.
    model
        The fitted contact model.
    z_surf
        [m] Fitted surface height (start of the free fit).
    baseline, z_ref
        Baseline of the fit (``"constant"`` or ``"linear"``) and its reference height [m].
    noise_lag1
        Noise lag-1 autocorrelation (inflates se(m)).
    n_se, rel_tol
        Statistical and physical thresholds.

    Returns
    -------
    CheckResult
        ``statistic`` = free m; ``details``: ``m``, ``m_se``, ``m_law``, ``delta_m``,
        ``z_surf_free`` [m], ``k``, ``F0`` [N], ``rel_tol``, ``n_se``.
    """
    z, f = _arrays(z, force)
    m_nom = model.exponent
    fit = free_exponent_fit(z, f, z_surf, baseline=baseline, z_ref=z_ref,
                            m0=m_nom if m_nom is not None else 1.5, noise_lag1=noise_lag1)
    m_law = law_exponent(model, z, z_surf, baseline=baseline, z_ref=z_ref)
    m, se = fit["m"], fit["m_se"]
    delta = m - m_law
    failed = abs(delta) > n_se * se and abs(delta) > rel_tol * m_law
    details = {"m": m, "m_se": se, "m_law": m_law, "delta_m": delta,
               "z_surf_free": fit["z_surf"], "k": fit["k"], "F0": fit["F0"],
               "rel_tol": rel_tol, "n_se": n_se, "converged": fit["success"]}
    flag = ""
    if failed:
        head = (f"free-exponent fit m = {m:.3f} ± {se:.3f} vs {m_law:.3f} of the "
                f"{model.tip.kind} law")
        hint = _wrong_tip_hint(model, m)
        if delta > 0:
            causes = ("finite thickness -> --thickness/--finite-thickness, strain-stiffening "
                      "material, a gradual onset before the surface (see residual_structure), "
                      "or wrong tip (sharper than the law)")
            if model.thickness is not None:
                causes = ("thickness under-corrected (check --thickness, bonded or not), "
                          "strain-stiffening material, a gradual onset before the surface, or "
                          "wrong tip (sharper than the law)")
            if hint:
                causes = f"wrong tip ({hint}; check --tip), or " + causes.replace(
                    ", or wrong tip (sharper than the law)", "")
            flag = f"{head}: force stiffens with depth ({causes})"
        else:
            causes = ("wrong tip (blunter than the law), series compliance of robot/sensor, "
                      "a soft or non-linear start of contact (tilt, roughness, onset: skip "
                      "the start), or yielding")
            if hint:
                causes = f"wrong tip ({hint}; check --tip), or " + causes.replace(
                    "wrong tip (blunter than the law), ", "")
            flag = f"{head}: force softens with depth ({causes})"
    return CheckResult("exponent", float(m), not failed, flag, details)


# ----------------------------------------------------------------------------- residual bins


def _bin_labels(z: np.ndarray, z_surf: float | None, n_bins: int,
                n_pre_bins: int | None) -> tuple[np.ndarray, np.ndarray, int]:
    """Bin index of every sample: pre-contact bins first (far -> near the surface), then
    contact bins (shallow -> deep), equal counts by depth.  Returns (labels, is_contact per
    bin, number of bins)."""
    n = z.size
    d = (z_surf - z) if z_surf is not None else (z.max() - z)
    contact = d > 0 if z_surf is not None else np.ones(n, bool)
    labels = np.empty(n, dtype=np.intp)
    idx_c = np.flatnonzero(contact)
    idx_p = np.flatnonzero(~contact)
    nb_c = int(min(n_bins, idx_c.size // _MIN_BIN))
    if n_pre_bins is None:
        n_pre_bins = max(2, n_bins // 2)
    nb_p = int(min(n_pre_bins, idx_p.size // _MIN_BIN))
    if nb_c < 1:
        raise FitError("too few contact samples for binned residuals")
    off = 0
    kinds = []
    if idx_p.size:
        if nb_p >= 1:
            order = idx_p[np.argsort(d[idx_p], kind="stable")]  # far (most negative) first
            labels[order] = np.arange(order.size) * nb_p // order.size
            off = nb_p
            kinds += [False] * nb_p
        else:  # a handful of pre-contact samples: join the first contact bin
            labels[idx_p] = 0
    order = idx_c[np.argsort(d[idx_c], kind="stable")]
    labels[order] = off + np.arange(order.size) * nb_c // order.size
    kinds += [True] * nb_c
    return labels, np.array(kinds, bool), off + nb_c


def binned_residuals(z, residuals, z_surf: float | None, sigma, *, phi: float = 0.0,
                     n_bins: int = 10, n_pre_bins: int | None = None) -> dict:
    """Mean residual in depth bins and its chi² (AR(1)-aware bin-mean variance).

    Contact samples (d = z_surf - z > 0) are split into ``n_bins`` equal-count depth bins,
    pre-contact samples into ``n_pre_bins`` (default n_bins/2, at least 2).  With bin mean
    r_b over n_b samples, var(r_b) = sigma²/n_b·g(n_b, phi) (:func:`ar1_mean_variance_factor`)
    and chi² = Σ_b r_b²/var(r_b) ~ chi²(B) for a correct model (slightly fewer degrees of
    freedom once parameters are fitted, which makes the test conservative).

    Parameters
    ----------
    z
        [m] Heights of the samples.
    residuals
        [N] Data minus model, shape (n,) or (n_draws, n).
    z_surf
        [m] Surface height; None bins by z alone (all samples as "contact").
    sigma
        [N] Noise sd, scalar or (n_draws,).
    phi
        Lag-1 autocorrelation of the noise, scalar or (n_draws,).
    n_bins, n_pre_bins
        Number of contact / pre-contact bins.

    Returns
    -------
    dict
        ``chi2`` (scalar or (n_draws,)), ``dof``, ``means`` [N], ``sd`` [N], ``counts``,
        ``contact`` (bool per bin), ``depth`` [m] (mean depth per bin), ``labels``.
    """
    z = np.asarray(z, dtype=float)
    r = np.asarray(residuals, dtype=float)
    labels, kinds, nb = _bin_labels(z, z_surf, n_bins, n_pre_bins)
    counts = np.bincount(labels, minlength=nb).astype(float)
    order = np.argsort(labels, kind="stable")
    starts = np.concatenate([[0], np.cumsum(counts[:-1])]).astype(np.intp)

    def bin_sum(x):
        return np.add.reduceat(x[..., order], starts, axis=-1)

    means = bin_sum(r) / counts
    sig = np.asarray(sigma, dtype=float)
    ph = np.atleast_1d(np.asarray(phi, dtype=float))
    g = np.array([ar1_mean_variance_factor(counts, p) for p in ph])
    if r.ndim == 1:
        g = g[0]
        var = sig**2 * g / counts
    else:
        g = g if g.shape[0] == r.shape[0] else np.broadcast_to(g, (r.shape[0], nb))
        var = (np.broadcast_to(sig, (r.shape[0],))[:, None] ** 2) * g / counts
    chi2 = np.sum(means**2 / var, axis=-1)
    zb = z_surf if z_surf is not None else z.max()
    depth = bin_sum(zb - z) / counts
    return {"chi2": chi2, "dof": nb, "means": means, "sd": np.sqrt(var), "counts": counts,
            "contact": kinds, "depth": depth, "labels": labels}


def _pattern(b: dict) -> tuple[str, str, dict]:
    """Name the residual pattern of failed bins: ('drift' | 'onset' | 'shape', text, scores).

    Scores (chi² shares of the standardized bin means z_b):
    ``pre_line``, the part of the pre-contact bins' spread about their mean that a straight
    line in depth explains (a drift or tilt of the baseline is a ramp before contact, which the
    contact fit mostly absorbs further on); ``near``, the bin just above the surface and the
    first two contact bins; ``deep``, the remaining contact bins; ``near_excess``, the
    standardized step of the bin just above the surface over the mean of the farther
    pre-contact bins.  Drift: ``pre_line`` > half of chi² and > ``deep``.  Onset: |near_excess|
    > 3 with the sign of the first contact bin and ``deep`` < 0.9·``near``.  Else a shape misfit
    of the contact law.
    """
    zb = b["means"] / b["sd"]
    kinds = b["contact"]
    pre = np.flatnonzero(~kinds)
    con = np.flatnonzero(kinds)
    total = float(np.sum(zb**2))
    scores = {"pre_line": 0.0, "near": 0.0, "deep": float(np.sum(zb[con[2:]] ** 2)),
              "near_excess": 0.0}
    if pre.size >= 3:
        w = 1.0 / b["sd"][pre] ** 2
        x = b["depth"][pre]
        y = b["means"][pre]
        xm = np.sum(w * x) / np.sum(w)
        ym = np.sum(w * y) / np.sum(w)
        sxx = np.sum(w * (x - xm) ** 2)
        scores["pre_line"] = float(np.sum(w * (x - xm) * (y - ym)) ** 2 / sxx) if sxx > 0 else 0.0
    if pre.size >= 2:
        near, far = pre[-1], pre[:-1]
        w = 1.0 / b["sd"][far] ** 2
        far_level = float(np.sum(w * b["means"][far]) / np.sum(w))
        far_sd = float(1.0 / np.sqrt(np.sum(w)))
        step = b["means"][near] - far_level
        scores["near_excess"] = float(step / math.hypot(b["sd"][near], far_sd))
        scores["near"] = float(zb[near] ** 2 + np.sum(zb[con[:2]] ** 2))
    else:
        scores["near"] = float(np.sum(zb[con[:2]] ** 2))
    if scores["pre_line"] > 0.5 * total and scores["pre_line"] > scores["deep"]:
        return "drift", ("pre-contact residuals ramp linearly with height: baseline drift or "
                         "tilt -> linear baseline (F1) or re-tare"), scores
    ex = scores["near_excess"]
    if (abs(ex) > 3 and con.size and np.sign(ex) == np.sign(zb[con[0]])
            and scores["deep"] < 0.9 * scores["near"]):
        if ex > 0:
            what = ("force rises before the fitted surface: gradual onset (soft skin/coating, "
                    "roughness, long-range repulsion)")
        else:
            what = ("force falls before the fitted surface: adhesion or long-range attraction "
                    "(snap-in)")
        return "onset", f"{what} -> fit past the onset or model it", scores
    return "shape", ("systematic misfit through the contact: the force's shape with depth "
                     "differs from the law (see the exponent check: finite thickness, wrong "
                     "tip, nonlinear material)"), scores


def residual_structure_check(z, residuals, z_surf: float, sigma: float, *,
                             baseline_lag1: float | None = None, n_bins: int = 10,
                             n_pre_bins: int | None = None,
                             alpha: float = THRESHOLDS["residual_alpha"],
                             amp_tol: float = THRESHOLDS["residual_amp"]) -> CheckResult:
    """Binned mean residual against depth: is there structure the noise cannot explain?

    chi² of the bin means (:func:`binned_residuals`) with the noise's lag-1 autocorrelation
    ``baseline_lag1`` (else estimated from the residuals' first differences); fails when
    p = P(chi²(B) >= chi²) < ``alpha`` **and** the largest |bin mean| > ``amp_tol``·sigma.
    Durbin-Watson DW = Σ(Δr)²/Σr² (Durbin & Watson 1950; about 2·(1 - rho1)) and the lag-1
    autocorrelation of the residuals in depth order are reported, not tested (they mix
    structure and correlated noise).

    Parameters
    ----------
    z
        [m] Heights of the fitted samples (time order).
    residuals
        [N] Data minus fitted model.
    z_surf
        [m] Fitted surface height.
    sigma
        [N] Fitted noise sd.
    baseline_lag1
        Lag-1 autocorrelation of the noise (e.g. :func:`noise_lag1` of the baseline, or the
        fit's AR(1) phi).
    n_bins, n_pre_bins
        Contact and pre-contact bins.
    alpha, amp_tol
        Statistical and physical thresholds.

    Returns
    -------
    CheckResult
        ``statistic`` = chi²; ``details``: ``chi2``, ``dof``, ``p``, ``max_abs_bin_sigma``,
        ``phi``, ``phi_source``, ``durbin_watson``, ``lag1``, ``chi2_pre``, ``chi2_contact``,
        ``pattern``, ``bin_depth`` [m], ``bin_mean`` [N], ``bin_sd`` [N], ``bin_count``.
    """
    z, r = _arrays(z, residuals)
    sigma = float(sigma)
    if not sigma > 0:
        raise InputError(f"sigma must be positive, got {sigma!r}")
    order = np.argsort(z_surf - z, kind="stable")
    rd = r[order]
    if baseline_lag1 is None:
        phi, source = _phi_from_differences(r), "residual differences"
    else:
        phi, source = _clip_phi(float(baseline_lag1)), "given"
    b = binned_residuals(z, r, z_surf, sigma, phi=phi, n_bins=n_bins, n_pre_bins=n_pre_bins)
    chi2, dof = float(b["chi2"]), int(b["dof"])
    p = float(stats.chi2.sf(chi2, dof))
    amp = float(np.max(np.abs(b["means"])) / sigma)
    dw = float(np.sum(np.diff(rd) ** 2) / np.sum(rd**2)) if np.any(rd) else 2.0
    failed = p < alpha and amp > amp_tol
    pattern, text, scores = _pattern(b) if failed else ("", "", {})
    pre = ~b["contact"]
    zb2 = (b["means"] / b["sd"]) ** 2
    details = {"chi2": chi2, "dof": dof, "p": p, "max_abs_bin_sigma": amp, "phi": phi,
               "phi_source": source, "durbin_watson": dw, "lag1": _acf1(rd),
               "chi2_pre": float(np.sum(zb2[pre])), "chi2_contact": float(np.sum(zb2[~pre])),
               "pattern": pattern, "pattern_scores": scores, "bin_depth": b["depth"],
               "bin_mean": b["means"],
               "bin_sd": b["sd"], "bin_count": b["counts"], "alpha": alpha,
               "amp_tol": amp_tol}
    flag = ""
    if failed:
        flag = (f"binned residuals chi² = {chi2:.1f} on {dof} bins (p = {p:.2g}), largest bin "
                f"mean {amp:.2f} sigma: {text}")
    return CheckResult("residual_structure", chi2, not failed, flag, details)


# ----------------------------------------------------------------------------- PPC


def posterior_predictive_check(z, force, mean_curves, sigmas, *, phi=None,
                               rng: np.random.Generator | int | None = None,
                               z_surf: float | None = None, n_bins: int = 10,
                               max_draws: int = 200,
                               alpha: float = THRESHOLDS["ppc_alpha"]) -> CheckResult:
    """Posterior-predictive p-value of the binned-residual chi² (Gelman, Meng & Stern 1996).

    For each posterior draw i with model curve mu_i, noise sd sigma_i (and AR(1) phi_i):
    T_obs,i = chi² of the binned y - mu_i; T_rep,i = the same for y_rep = mu_i + e_i, e_i
    drawn from the noise model (iid N(0, sigma_i²), or stationary AR(1)).  The discrepancy
    uses the draw's own sigma_i and phi_i (:func:`binned_residuals`).  p = mean(T_rep >=
    T_obs); the check fails when p < ``alpha``.

    Parameters
    ----------
    z, force
        [m], [N] fitted samples in time order.
    mean_curves
        [N] (n_draws, n) model force at the posterior draws (baseline included).
    sigmas
        [N] (n_draws,) noise sd per draw.
    phi
        None (iid noise) or (n_draws,) / scalar AR(1) coefficients.
    rng
        numpy Generator or seed for the replicated noise.
    z_surf
        [m] Posterior median surface, to split pre-contact and contact bins (None: bins by z).
    n_bins
        Contact bins.
    max_draws
        At most this many draws are used (evenly thinned).
    alpha
        Threshold on p.

    Returns
    -------
    CheckResult
        ``statistic`` = p; ``details``: ``p``, ``T_obs_median``, ``T_rep_median``,
        ``n_draws``, ``dof``.
    """
    z, y = _arrays(z, force)
    mu = np.atleast_2d(np.asarray(mean_curves, dtype=float))
    if mu.shape[1] != y.size:
        raise InputError(f"mean_curves has {mu.shape[1]} columns for {y.size} samples")
    sig = np.broadcast_to(np.asarray(sigmas, dtype=float), (mu.shape[0],))
    ph = (np.zeros(mu.shape[0]) if phi is None
          else np.broadcast_to(np.asarray(phi, dtype=float), (mu.shape[0],)))
    if mu.shape[0] > max_draws:
        keep = np.linspace(0, mu.shape[0] - 1, max_draws).round().astype(int)
        mu, sig, ph = mu[keep], sig[keep], ph[keep]
    nd, n = mu.shape
    gen = np.random.default_rng(rng)
    w = gen.standard_normal((nd, n))
    e = np.empty_like(w)
    for i in range(nd):
        p_i = _clip_phi(ph[i])
        if p_i == 0:
            e[i] = sig[i] * w[i]
        else:
            e[i, 0] = sig[i] * w[i, 0]
            e[i, 1:] = lfilter([math.sqrt(1 - p_i * p_i) * sig[i]], [1.0, -p_i], w[i, 1:],
                               zi=[p_i * e[i, 0]])[0]
    t_obs = binned_residuals(z, y[None, :] - mu, z_surf, sig, phi=ph, n_bins=n_bins)
    t_rep = binned_residuals(z, e, z_surf, sig, phi=ph, n_bins=n_bins)
    p = float(np.mean(t_rep["chi2"] >= t_obs["chi2"]))
    failed = p < alpha
    details = {"p": p, "T_obs_median": float(np.median(t_obs["chi2"])),
               "T_rep_median": float(np.median(t_rep["chi2"])), "n_draws": int(nd),
               "dof": int(t_obs["dof"]), "noise": "iid" if not np.any(ph) else "ar1",
               "alpha": alpha}
    flag = ""
    if failed:
        flag = (f"posterior-predictive p = {p:.3g} (binned chi² {details['T_obs_median']:.1f} "
                f"vs {details['T_rep_median']:.1f} replicated): the fitted model and noise "
                "cannot reproduce the data's residual structure (model misfit, see the other "
                "checks, or correlated noise -> --noise ar1)")
    return CheckResult("ppc", p, not failed, flag, details)


# ----------------------------------------------------------------------------- depth


def _profile_law_fit(z, f, model, z_surf0: float, half_width: float,
                     baseline: str, z_ref: float, phi: float | None) -> dict:
    """F = E*·s(z_surf - z) + F0 (+F1·(z - z_ref)): Brent over z_surf, E*/F0/F1 linear."""
    def fit_at(zs):
        s = model.shape(zs - z)
        X = _design(z, s, baseline, z_ref)
        beta, r = _lstsq(X, f)
        return beta, r, X

    def rss(zs):
        r = fit_at(zs)[1]
        return float(np.dot(r, r))

    res = optimize.minimize_scalar(rss, bounds=(z_surf0 - half_width, z_surf0 + half_width),
                                   method="bounded", options={"xatol": 1e-6 * half_width})
    zs = float(res.x)
    beta, r, X = fit_at(zs)
    dsdz = model.shape_derivative(zs - z)
    J = np.column_stack([beta[0] * dsdz, X])
    n, p = f.size, J.shape[1]
    rs = float(np.dot(r, r))
    cov = _cov(J, rs / max(n - p, 1), _long_run(phi))
    return {"z_surf": zs, "estar": float(beta[0]), "estar_se": math.sqrt(max(cov[1, 1], 0.0)),
            "F0": float(beta[1]), "rss": rs, "n": int(n)}


def depth_consistency_check(z, force, model: ModelSpec, z_surf: float, *,
                            baseline: str = "constant", z_ref: float | None = None,
                            noise_lag1: float | None = None,
                            n_se: float = THRESHOLDS["depth_n_se"],
                            rel_tol: float = THRESHOLDS["depth_rel"]) -> CheckResult:
    """E* over the shallower half of the depth against E* over all the depth.

    Both fits are F = E*·s(z_surf - z) + F0 (+ F1·(z - z_ref)) with z_surf free (bounded
    Brent search around the given one), E*, F0, F1 profiled linearly.  The shallow fit keeps
    every sample above z_surf - d_max/2 (pre-contact included).  A law that describes the
    material and geometry gives the same E* at all depths; finite thickness (substrate
    effect), strain stiffening, a sharper tip or a gradual onset make the shallow E* lower
    (simulated: 0.94 for the 30 mm layer, 0.76 for a cone fitted as a paraboloid, 0.96-0.98 for
    a 20-50 mN onset), a blunter tip, series compliance or yielding make it higher.  se of
    the difference (Hausman 1978, nested efficient estimators): sqrt(se_shallow² - se_all²)
    (floored at se_shallow/2), AR(1)-inflated with ``noise_lag1``.  Fails when |ratio - 1| >
    ``n_se``·se **and** > ``rel_tol``.  A flat punch on a finite layer keeps F ∝ d (the Hayes
    factor does not depend on depth), so neither this check nor the exponent can see it.

    Parameters
    ----------
    z, force
        [m], [N] fitted samples.
    model
        The fitted contact model.
    z_surf
        [m] Fitted surface height.
    baseline, z_ref
        Baseline of the fit and its reference height [m] (default highest z).
    noise_lag1
        Noise lag-1 autocorrelation.
    n_se, rel_tol
        Statistical and physical thresholds.

    Returns
    -------
    CheckResult
        ``statistic`` = E*_shallow/E*_all; ``details``: ``estar_all``, ``estar_shallow``
        [Pa], their se, ``ratio``, ``ratio_se``, ``z_surf_all``, ``z_surf_shallow`` [m],
        ``d_half`` [m].
    """
    z, f = _arrays(z, force)
    z_ref = float(z.max()) if z_ref is None else float(z_ref)
    dmax = z_surf - float(z.min())
    if not dmax > 0:
        raise FitError("the surface lies below every sample: no contact to check")
    hw = 0.25 * dmax
    table = _ShapeTable(model, 1.5 * dmax)
    full = _profile_law_fit(z, f, table, z_surf, hw, baseline, z_ref, noise_lag1)
    d_half = 0.5 * (full["z_surf"] - float(z.min()))
    sel = z >= full["z_surf"] - d_half
    if np.count_nonzero(sel & (z < full["z_surf"])) < 10:
        raise FitError("too few samples in the shallow half of the contact")
    shallow = _profile_law_fit(z[sel], f[sel], table, full["z_surf"], 0.5 * d_half, baseline,
                               z_ref, noise_lag1)
    ratio = shallow["estar"] / full["estar"]
    se_diff = math.sqrt(max(shallow["estar_se"] ** 2 - full["estar_se"] ** 2,
                            0.25 * shallow["estar_se"] ** 2))
    ratio_se = se_diff / full["estar"]
    dev = ratio - 1.0
    failed = abs(dev) > n_se * ratio_se and abs(dev) > rel_tol
    details = {"estar_all": full["estar"], "estar_all_se": full["estar_se"],
               "estar_shallow": shallow["estar"], "estar_shallow_se": shallow["estar_se"],
               "ratio": ratio, "ratio_se": ratio_se, "z_surf_all": full["z_surf"],
               "z_surf_shallow": shallow["z_surf"], "d_half": d_half, "rel_tol": rel_tol,
               "n_se": n_se}
    flag = ""
    if failed:
        head = (f"E* over the shallow half = {ratio:.3f} ± {ratio_se:.3f} × E* over all "
                "depths")
        if dev < 0:
            cause = ("finite thickness -> --thickness/--finite-thickness" if model.thickness
                     is None else "thickness under-corrected (check --thickness, bonded)")
            flag = (f"{head}: apparent modulus rises with depth ({cause}, strain-stiffening "
                    "material, a gradual onset before the surface, or wrong tip sharper than "
                    "the law)")
        else:
            flag = (f"{head}: apparent modulus falls with depth (wrong tip blunter than the "
                    "law, series compliance of robot/sensor, or yielding)")
    return CheckResult("depth_consistency", float(ratio), not failed, flag, details)


# ----------------------------------------------------------------------------- all


def run_checks(z, force, model: ModelSpec, *, z_surf: float, estar: float, f0: float,
               f1: float = 0.0, sigma: float, draws: dict | None = None,
               baseline_lag1: float | None = None, baseline: str | None = None,
               z_ref: float | None = None,
               rng: np.random.Generator | int | None = None) -> list[CheckResult]:
    """Run every adequacy check on one fit.

    Model force: mu(z) = E*·s(z_surf - z) + F0 + F1·(z - z_ref), z_ref = highest z unless
    given.  Runs the exponent, residual-structure and depth-consistency checks, and the
    posterior-predictive check when ``draws`` are given.

    Parameters
    ----------
    z, force
        [m], [N] fitted samples in time order.
    model
        The fitted contact model.
    z_surf, estar, f0, f1, sigma
        Point estimates (posterior medians): [m], [Pa], [N], [N/m], [N].
    draws
        Optional posterior draws: dict of equal-length arrays ``E_star`` [Pa], ``z_surf``
        [m], ``F0`` [N], ``sigma`` [N], optional ``F1`` [N/m] and ``phi``.
    baseline_lag1
        Lag-1 autocorrelation of the noise; default the fit's median ``phi`` if drawn, else
        :func:`noise_lag1` of the pre-contact samples, else estimated from the residuals.
    baseline
        ``"constant"`` or ``"linear"``; default linear when f1 != 0 or ``F1`` is drawn.
    z_ref
        [m] Linear-baseline reference height.
    rng
        Generator or seed for the posterior-predictive replicates.

    Returns
    -------
    list of CheckResult
        In the order exponent, residual_structure, depth_consistency[, ppc].
    """
    z, f = _arrays(z, force)
    z_ref = float(z.max()) if z_ref is None else float(z_ref)
    if baseline is None:
        baseline = "linear" if (f1 != 0 or (draws is not None and "F1" in draws)) else "constant"
    phi = baseline_lag1
    if phi is None and draws is not None and "phi" in draws:
        phi = float(np.median(draws["phi"]))
    if phi is None:
        phi = noise_lag1(z, f, z_surf)
    mu = estar * model.shape(z_surf - z) + f0 + f1 * (z - z_ref)
    out = [
        exponent_check(z, f, model, z_surf, baseline=baseline, z_ref=z_ref, noise_lag1=phi),
        residual_structure_check(z, f - mu, z_surf, sigma, baseline_lag1=phi),
        depth_consistency_check(z, f, model, z_surf, baseline=baseline, z_ref=z_ref,
                                noise_lag1=phi),
    ]
    if draws is not None:
        es = np.asarray(draws["E_star"], dtype=float)
        zs = np.asarray(draws["z_surf"], dtype=float)
        f0s = np.asarray(draws["F0"], dtype=float)
        f1s = np.asarray(draws.get("F1", np.zeros_like(es)), dtype=float)
        keep = np.linspace(0, es.size - 1, min(es.size, 200)).round().astype(int)
        table = _ShapeTable(model, 1.5 * (float(np.max(zs[keep])) - float(z.min())))
        curves = (es[keep, None] * table.shape(zs[keep, None] - z[None, :])
                  + f0s[keep, None] + f1s[keep, None] * (z - z_ref)[None, :])
        sig = np.asarray(draws["sigma"], dtype=float)[keep]
        ph = np.asarray(draws["phi"], dtype=float)[keep] if "phi" in draws else None
        out.append(posterior_predictive_check(z, f, curves, sig, phi=ph, rng=rng,
                                              z_surf=z_surf))
    return out
