"""Posterior-predictive check of the binned-residual chi² (Gelman, Meng & Stern 1996);
see :mod:`palpbayes.checks`."""

from __future__ import annotations

import math

import numpy as np

from ..errors import InputError
from .core import THRESHOLDS, CheckResult, clip_phi, validated_arrays
from .residuals import binned_residuals


# Many parameters: the data, the posterior's curves and noise draws, and the check's bins and
# level.
def posterior_predictive_check(z, force, mean_curves, sigmas, *, phi=None,
                               rng: np.random.Generator | int | None = None,
                               z_surf: float | None = None, n_bins: int = 10,
                               max_draws: int = 200,
                               alpha: float = THRESHOLDS["ppc_alpha"]) -> CheckResult:
    """Posterior-predictive p-value of the binned-residual chi² (Gelman, Meng & Stern 1996).

    For each posterior draw i with model curve mu_i, noise sd sigma_i (and AR(1) phi_i):
    T_obs,i = chi² of the binned y - mu_i; T_rep,i = the same for y_rep = mu_i + e_i, e_i
    drawn from the noise model (iid N(0, sigma_i²), or stationary AR(1)).  For iid noise
    T_rep,i is exactly chi² with as many degrees of freedom as bins (independent bin means of
    variance sigma_i²/n_b) and is drawn as such.  The discrepancy
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
    z, y = validated_arrays(z, force)
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
    t_obs = binned_residuals(z, y[None, :] - mu, z_surf, sig, phi=ph, n_bins=n_bins)
    if not np.any(ph):
        # iid noise: the bin means of e_i ~ N(0, sigma_i²) are independent N(0, sigma_i²/n_b),
        # so T_rep,i is exactly chi²(B) (B bins): drawn as such, not from n·n_draws normals
        t_rep = {"chi2": gen.chisquare(t_obs["dof"], nd)}
    else:
        from scipy.signal import lfilter  # AR(1) only (scipy.signal is slow to import)

        w = gen.standard_normal((nd, n))
        e = np.empty_like(w)
        for i in range(nd):
            p_i = clip_phi(ph[i])
            if p_i == 0:
                e[i] = sig[i] * w[i]
            else:
                e[i, 0] = sig[i] * w[i, 0]
                e[i, 1:] = lfilter([math.sqrt(1 - p_i * p_i) * sig[i]], [1.0, -p_i], w[i, 1:],
                                   zi=[p_i * e[i, 0]])[0]
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
