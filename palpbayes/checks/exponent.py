"""Exponent check: a free power law F = k·d_+^m + F0 (+ F1·(z - z_ref)) against the
law's own exponent on the same depths (:mod:`palpbayes.checks`)."""

from __future__ import annotations

import math

import numpy as np
from scipy import optimize

from ..contact import fixed_exponents
from ..errors import FitError
from ..fitdata import ModelSpec
from .core import (
    FINITE_THICKNESS,
    THRESHOLDS,
    CheckResult,
    contact_inputs,
    design_matrix,
    lstsq,
    residual_cov,
    validated_arrays,
)

#: scipy.optimize.least_squares settings of the free-exponent fit: tight enough to recover a
#: noise-free power law to 1e-6 in m (tests/unit/test_model_checks.py).
#: Bounds of the free exponent m.
_M_BOUNDS = (0.6, 4.0)

_LSQ_OPTIONS = {"ftol": 1e-12, "xtol": 1e-12, "gtol": 1e-12, "x_scale": "jac", "max_nfev": 200}


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
                      m_bounds: tuple[float, float] = _M_BOUNDS) -> dict:
    """Least-squares fit of a free power law F = k·d_+^m + F0 (+ F1·(z - z_ref)).

    d_+ = max(z_surf - z, 0).  Started from z_surf0 and m0 with k, F0 (and F1) solved
    linearly (variable projection, Golub & Pereyra 1973), then all parameters refined by
    :func:`scipy.optimize.least_squares` (trust-region reflective, z_surf and m bounded) with
    the analytic Jacobian in (z_surf, m, k, F0[, F1]) (a few ms for 16,000 samples).
    Standard errors from that Jacobian and the residual variance, multiplied by the AR(1)
    long-run factor (1+phi)/(1-phi) when ``noise_lag1`` is given.

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
    z, f, z_ref, dmax = contact_inputs(
        z, force, z_surf0, z_ref, "the starting surface lies below every sample: no contact to fit")
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
    beta0 = lstsq(design_matrix(zn, pw0, baseline, 0.0), y)[0]
    p0 = [0.0, m_start, beta0[0], beta0[1]] + ([beta0[2]] if linear else [])

    def resid_fn(q):
        return resid(q if linear else np.append(q, 0.0))

    def jac_fn(q):
        return jac(q if linear else np.append(q, 0.0))

    lo_u = (float(z.min()) - z_surf0) / dmax + 0.1
    hi_u = max((float(z.max()) - z_surf0) / dmax, 1e-3)
    lo = [lo_u, m_bounds[0]] + [-np.inf] * (len(p0) - 2)
    hi = [hi_u, m_bounds[1]] + [np.inf] * (len(p0) - 2)
    sol = optimize.least_squares(resid_fn, np.array(p0, dtype=float), jac=jac_fn,
                                 bounds=(lo, hi), method="trf", **_LSQ_OPTIONS)
    x, success = sol.x, bool(sol.success)
    p = np.append(x, 0.0) if not linear else x
    r = -resid(p) * fscale
    J = jac_fn(x) * fscale
    cov, rss, s2 = residual_cov(J, r, noise_lag1)
    m = float(p[1])
    return {
        "m": m, "m_se": float(math.sqrt(max(cov[1, 1], 0.0))),
        "z_surf": float(z_surf0 + p[0] * dmax),
        "z_surf_se": float(math.sqrt(max(cov[0, 0], 0.0)) * dmax),
        "k": float(p[2] * fscale / dmax**m), "F0": float(p[3] * fscale),
        "F1": float(p[4] * fscale / dmax) if linear else 0.0,
        "rss": rss, "s": math.sqrt(s2), "n": int(f.size), "residuals": r,
        "success": bool(success),
    }


def _wrong_tip_hint(model: ModelSpec, m: float) -> str:
    """'the cone's 2' when the fitted m is closer to another tip family's exponent."""
    kind = model.tip.kind
    best = min(fixed_exponents().items(), key=lambda kv: abs(kv[1] - m))
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
    z, f = validated_arrays(z, force)
    m_nom = model.exponent
    fit = free_exponent_fit(z, f, z_surf, baseline=baseline, z_ref=z_ref,
                            m0=m_nom if m_nom is not None else 1.5, noise_lag1=noise_lag1)
    m_law = law_exponent(model, z, z_surf, baseline=baseline, z_ref=z_ref)
    m, se = fit["m"], fit["m_se"]
    delta = m - m_law
    failed = abs(delta) > n_se * se and abs(delta) > rel_tol * m_law
    details = {"m": m, "m_se": se, "m_law": m_law, "delta_m": delta,
               "z_surf_free": fit["z_surf"], "k": fit["k"], "F0": fit["F0"], "F1": fit["F1"],
               "rel_tol": rel_tol, "n_se": n_se, "converged": fit["success"]}
    flag = ""
    if failed:
        at_limit = ""
        lo_m, hi_m = _M_BOUNDS
        if m >= hi_m - 1e-3 or m <= lo_m + 1e-3:
            at_limit = f" (at the free fit's limit {hi_m if m > 1 else lo_m:g}: steeper still)"
        head = (f"free-exponent fit m = {m:.3f} ± {se:.3f}{at_limit} vs {m_law:.3f} of the "
                f"{model.tip.kind} law")
        hint = _wrong_tip_hint(model, m)
        if delta > 0:
            causes = (f"{FINITE_THICKNESS}, strain-stiffening "
                      "material, a gradual onset before the surface (see residual_structure), "
                      "or wrong tip (sharper than the law)")
            if model.has_layer:
                causes = ("thickness under-corrected (check --thickness and --bonding), "
                          "strain-stiffening material, a gradual onset before the surface, or "
                          "wrong tip (sharper than the law)")
            if hint:
                causes = f"wrong tip ({hint}: check --tip), or " + causes.replace(
                    ", or wrong tip (sharper than the law)", "")
            flag = f"{head}: force stiffens with depth ({causes})"
        else:
            causes = ("wrong tip (blunter than the law), series compliance of robot/sensor, "
                      "a soft or non-linear start of contact (tilt, roughness, onset: skip "
                      "the start), or yielding")
            if hint:
                causes = f"wrong tip ({hint}: check --tip), or " + causes.replace(
                    "wrong tip (blunter than the law), ", "")
            flag = f"{head}: force softens with depth ({causes})"
    return CheckResult("exponent", float(m), not failed, flag, details)
