"""Residual-structure check: binned mean residuals against depth, their AR(1)-aware chi²
and the pattern they show (drift, onset/adhesion, law shape); :mod:`palpbayes.checks`."""

from __future__ import annotations

import math

import numpy as np
from scipy import stats

from ..errors import FitError, InputError
from ..sensor_noise import acf1
from .core import (
    MIN_BIN,
    THRESHOLDS,
    CheckResult,
    ar1_mean_variance_factor,
    clip_phi,
    phi_from_differences,
    validated_arrays,
)


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
    nb_c = int(min(n_bins, idx_c.size // MIN_BIN))
    if n_pre_bins is None:
        n_pre_bins = max(2, n_bins // 2)
    nb_p = int(min(n_pre_bins, idx_p.size // MIN_BIN))
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
    """Name the residual pattern of failed bins: ('drift' | 'offset' | 'onset' | 'shape', text,
    scores).

    Scores (chi² shares of the standardized bin means z_b):
    ``pre_line``, the part of the pre-contact bins' spread about their mean that a straight
    line in depth explains (a drift or tilt of the baseline is a ramp before contact, which the
    contact fit mostly absorbs further on); ``near``, the bin just above the surface and the
    first two contact bins; ``deep``, the remaining contact bins; ``near_excess``, the
    standardized step of the bin just above the surface over the mean of the farther
    pre-contact bins.  Drift: ``pre_line`` > half of chi² and > ``deep``.  Onset: |near_excess|
    > 3 with the sign of the first contact bin and ``deep`` < 0.9·``near``.  ``pre_level``, the
    chi² of the pre-contact bins' common (weighted mean) level: offset, when it is over 30 % of
    chi² and above ``pre_line`` — a force offset the model lacks (an untared sensor fitted by
    the paper's least squares, which has no offset term).  Else a shape misfit of the contact
    law.
    """
    zb = b["means"] / b["sd"]
    kinds = b["contact"]
    pre = np.flatnonzero(~kinds)
    con = np.flatnonzero(kinds)
    total = float(np.sum(zb**2))
    scores = {"pre_line": 0.0, "near": 0.0, "deep": float(np.sum(zb[con[2:]] ** 2)),
              "near_excess": 0.0, "pre_level": 0.0}
    if pre.size >= 3:
        w = 1.0 / b["sd"][pre] ** 2
        x = b["depth"][pre]
        y = b["means"][pre]
        xm = np.sum(w * x) / np.sum(w)
        ym = np.sum(w * y) / np.sum(w)
        sxx = np.sum(w * (x - xm) ** 2)
        scores["pre_line"] = float(np.sum(w * (x - xm) * (y - ym)) ** 2 / sxx) if sxx > 0 else 0.0
    if pre.size >= 2:
        w = 1.0 / b["sd"][pre] ** 2
        scores["pre_level"] = float(np.sum(w * b["means"][pre]) ** 2 / np.sum(w))
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
    if scores["pre_level"] > 0.3 * total and scores["pre_level"] > scores["pre_line"]:
        return "offset", ("pre-contact residuals sit at a constant offset: a force offset the "
                          "model lacks (an untared sensor, or the paper's least squares, which "
                          "has no offset term) -> --tare, or the Bayesian fit's F0"), scores
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
    z, r = validated_arrays(z, residuals)
    sigma = float(sigma)
    if not sigma > 0:
        raise InputError(f"sigma must be positive, got {sigma!r}")
    order = np.argsort(z_surf - z, kind="stable")
    rd = r[order]
    if baseline_lag1 is None:
        phi, source = phi_from_differences(r), "residual differences"
    else:
        phi, source = clip_phi(float(baseline_lag1)), "given"
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
               "phi_source": source, "durbin_watson": dw, "lag1": acf1(rd),
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
