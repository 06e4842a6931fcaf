"""Depth-consistency check: E* over the shallower half of the depth against E* over all of
it (Hausman 1978); see :mod:`palpbayes.checks`."""

from __future__ import annotations

import math

import numpy as np
from scipy import optimize

from ..errors import FitError
from ..fitdata import ModelSpec
from ..shapekernel import cross_sums
from .core import (
    FINITE_THICKNESS,
    THRESHOLDS,
    CheckResult,
    ShapeTable,
    contact_inputs,
    design_matrix,
    lstsq,
    residual_cov,
)


def profile_law_fit(z, f, model, z_surf0: float, half_width: float,
                     baseline: str, z_ref: float, phi: float | None) -> dict:
    """F = E*·s(z_surf - z) + F0 (+F1·(z - z_ref)): Brent over z_surf, E*/F0/F1 linear.

    ``model`` is the contact model or its :class:`~.core.ShapeTable` (the same compiled law).
    Brent's objective, the residual sum of squares at a trial surface, comes from the compiled
    loop's sums (:func:`palpbayes.shapekernel.cross_sums`: Σ s², Σ s·c over the columns
    c = 1[, u], F less its mean) and the normal equations (F centred: no offset to cancel);
    the fit at the optimum is the least squares of :func:`~.core.lstsq`."""
    law = getattr(model, "model", model)

    def fit_at(zs):
        s = model.shape(zs - z)
        X = design_matrix(z, s, baseline, z_ref)
        beta, r = lstsq(X, f)
        return beta, r, X

    fixed = [np.ones(z.size)] + ([z - z_ref] if baseline == "linear" else [])
    C = np.column_stack(fixed + [f - float(np.mean(f))])
    CC = C.T @ C
    p = C.shape[1]  # parameters: E*, F0[, F1]

    def rss(zs):
        ss, sc = cross_sums(np.array([zs]), z, C, law, False)[:2]
        A = np.empty((p, p))
        A[0, 0], A[0, 1:], A[1:, 0] = ss[0], sc[0, :-1], sc[0, :-1]
        A[1:, 1:] = CC[:-1, :-1]
        b = np.r_[sc[0, -1], CC[:-1, -1]]
        if not ss[0] > 0:  # no sample in contact: the fit of the fixed columns alone
            A, b = A[1:, 1:], b[1:]
        d = 1.0 / np.sqrt(np.where(np.diag(A) > 0, np.diag(A), 1.0))  # equilibrated
        try:
            beta = np.linalg.solve(A * d[:, None] * d[None, :], b * d) * d
        except np.linalg.LinAlgError:
            return float(CC[-1, -1])
        return float(CC[-1, -1] - b @ beta)

    res = optimize.minimize_scalar(rss, bounds=(z_surf0 - half_width, z_surf0 + half_width),
                                   method="bounded", options={"xatol": 1e-6 * half_width})
    zs = float(res.x)
    beta, r, X = fit_at(zs)
    dsdz = model.shape_derivative(zs - z)
    J = np.column_stack([beta[0] * dsdz, X])
    cov, rs, _ = residual_cov(J, r, phi)
    return {"z_surf": zs, "estar": float(beta[0]), "estar_se": math.sqrt(max(cov[1, 1], 0.0)),
            "F0": float(beta[1]), "F1": float(beta[2]) if beta.size > 2 else 0.0, "rss": rs,
            "n": int(f.size)}


def _deep_window(z, f, table, full: dict, d_half: float, baseline: str, z_ref: float,
                 phi: float | None) -> tuple[float, float]:
    """E* [Pa] and its se over the deeper half of the depth, with the surface and a force
    offset of its own (the full fit's drift slope kept): what the law gives when whatever
    happens near the surface (a soft skin, a gradual onset, a blunted apex) is left out.
    (NaN, NaN) with fewer than 10 samples there, or when its surface sits at the search
    bound (±d_half/2 around the full fit's: e.g. strain stiffening, where the deep half
    has no interior optimum and its E* would be the bound's)."""
    sel = z <= full["z_surf"] - d_half
    if np.count_nonzero(sel) < 10:
        return float("nan"), float("nan")
    fd = f[sel] - (full["F1"] * (z[sel] - z_ref) if baseline == "linear" else 0.0)
    hw = 0.5 * d_half
    try:
        deep = profile_law_fit(z[sel], fd, table, full["z_surf"], hw, "constant", z_ref, phi)
    except (FitError, np.linalg.LinAlgError):
        return float("nan"), float("nan")
    if abs(deep["z_surf"] - full["z_surf"]) > 0.99 * hw:  # at its search bound: no optimum
        return float("nan"), float("nan")
    return deep["estar"], deep["estar_se"]


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
        [Pa], their se, ``estar_deep`` [Pa] and its se (the deeper half with its own surface
        and force offset: not part of the test, an alternative for the model-form interval,
        :mod:`palpbayes.bayes.modelform`), ``ratio``, ``ratio_se``, ``z_surf_all``,
        ``z_surf_shallow``, ``d_half`` [m].
    """
    z, f, z_ref, dmax = contact_inputs(z, force, z_surf, z_ref,
                                        "the surface lies below every sample: no contact to check")
    hw = 0.25 * dmax
    table = ShapeTable(model, 1.5 * dmax)
    full = profile_law_fit(z, f, table, z_surf, hw, baseline, z_ref, noise_lag1)
    d_half = 0.5 * (full["z_surf"] - float(z.min()))
    sel = z >= full["z_surf"] - d_half
    if np.count_nonzero(sel & (z < full["z_surf"])) < 10:
        raise FitError("too few samples in the shallow half of the contact")
    shallow = profile_law_fit(z[sel], f[sel], table, full["z_surf"], 0.5 * d_half, baseline,
                               z_ref, noise_lag1)
    estar_deep, estar_deep_se = _deep_window(z, f, table, full, d_half, baseline, z_ref,
                                             noise_lag1)
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
               "estar_deep": estar_deep, "estar_deep_se": estar_deep_se,
               "n_se": n_se}
    flag = ""
    if failed:
        head = (f"E* over the shallow half = {ratio:.3f} ± {ratio_se:.3f} × E* over all "
                "depths")
        if dev < 0:
            cause = (FINITE_THICKNESS if not model.has_layer
                     else "thickness under-corrected (check --thickness and --bonding)")
            flag = (f"{head}: apparent modulus rises with depth ({cause}, strain-stiffening "
                    "material, a gradual onset before the surface, or wrong tip sharper than "
                    "the law)")
        else:
            flag = (f"{head}: apparent modulus falls with depth (wrong tip blunter than the "
                    "law, series compliance of robot/sensor, or yielding)")
    return CheckResult("depth_consistency", float(ratio), not failed, flag, details)
