"""Fitting one stiffening law: maximum likelihood, then emcee from a Laplace-scaled start.

:func:`mle` maximises the likelihood (amplitudes profiled; a grid over log T, then
Nelder-Mead), :func:`sample_law` runs the ensemble from there until R-hat and ESS pass and
returns the draws with their diagnostics (:mod:`palpbayes.bayes.diagnostics`).  The laws and their
posterior are :mod:`palpbayes.stiffening.model`.

Sampling
--------
Every sampler runs until R-hat and ESS pass (or the step cap), since convergence is a check.

Sampling: sigma_x is sampled as log sigma_x (prior plus Jacobian: no wall at 0); the walkers
start from a Laplace approximation at the maximum (Fisher information), scaled to the posterior
however precise the estimates are; the single and constant laws, linear in their amplitudes,
are sampled over (log T, log sigma_x) with the amplitudes integrated out and drawn afterwards
from their Gaussian conditional.  With all four parameters sampled, the single law's
log-posterior autocorrelation time was ~30 steps and R-hat <= 1.01 at 3,000 steps a matter of
luck: on least-squares estimates of a simulated series (0.03 % sd) 3 of 30 seeds hit the step
cap and the outcome fell to "constant".
"""

from __future__ import annotations

import warnings

import numpy as np
from scipy import optimize

from ..bayes.diagnostics import chain_passes, compute_diagnostics, import_arviz
from ..bayes.sampler import run_emcee
from ..errors import InputError
from .model import (
    AMP_BOUND,
    AMP_IDX,
    PARAM_NAMES,
    T_IDX,
    law_basis,
    linear_fit,
    log_like,
    log_post,
    log_post_collapsed,
    split_theta,
)

__all__ = ["mle", "sample_law"]


def _draw_amplitudes(model, x, t, y, s, rng) -> np.ndarray:
    """One draw of the amplitudes from their conditional posterior at each row of ``x``."""
    a, G, _ = linear_fit(model, x, t, y, s)
    L = np.linalg.cholesky(np.linalg.inv(G))
    out = a + np.einsum("wkj,wj->wk", L, rng.standard_normal(a.shape))
    for _ in range(20):  # the flat prior's bounds
        bad = np.any(np.abs(out) >= AMP_BOUND, axis=1)
        if not bad.any():
            break
        out[bad] = a[bad] + np.einsum("wkj,wj->wk", L[bad],
                                      rng.standard_normal((int(bad.sum()), a.shape[1])))
    return np.clip(out, -0.999 * AMP_BOUND, 0.999 * AMP_BOUND)


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
    amp, logT, log_sx = split_theta(model, th[None, :])
    amp, logT, sx = amp[0], logT[0], float(np.exp(log_sx[0]))
    B = law_basis(model, logT[None, :], t)[0]                   # (n, k)
    v = s**2 + sx**2
    n_amp = amp.size
    # d f / d amplitude = basis; d f / d logT_j = amp_j·e^(-t/T_j)·t/T_j
    J = [B[:, k] for k in range(n_amp)]
    ex = np.exp(-t[:, None] / np.exp(logT)[None, :])
    off = n_amp - logT.size  # the single law's constant has no time scale
    dT = [amp[off + j] * ex[:, j] * t / np.exp(logT[j]) for j in range(logT.size)]
    amp_i, T_i = AMP_IDX[model], T_IDX[model]
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
        bad = ~np.isfinite(log_post(model, p0, t, y, s, bounds))
        if not bad.any():
            break
        p0[bad] = th + 0.5 * (p0[bad] - th)  # shrink toward the maximum
    return p0


def _profile(model, logT, log_sx, t, y, s):
    """Max over amplitudes (weighted least squares) at fixed time scales and sigma_x."""
    sx = np.exp(log_sx)
    B = law_basis(model, np.asarray(logT, dtype=float).reshape(1, -1), t)[0]
    w = 1.0 / np.sqrt(s**2 + sx**2)
    amp, *_ = np.linalg.lstsq(B * w[:, None], y * w, rcond=None)
    theta = np.concatenate([amp, logT, [sx]]) if model != "double" else \
        np.array([amp[0], logT[0], amp[1], logT[1], sx])
    return float(log_like(model, theta[None, :], t, y, s)[0]), theta


def mle(model, t, y, s, bounds) -> tuple[float, np.ndarray]:
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


def sample_law(model, theta0, t, y, s, bounds, settings, seed):
    """Posterior draws of law ``model`` by emcee from the maximum ``theta0``, run until R-hat
    and ESS pass (or the step cap): (draws by parameter, sigma_x linear; diagnostics)."""
    rng = np.random.default_rng(np.random.SeedSequence(seed).spawn(1)[0])
    nw = max(settings.n_walkers, 2 * theta0.size + 2)
    th = np.array(theta0, dtype=float)
    amp, logT, _ = split_theta(model, th[None, :])
    th[AMP_IDX[model]] = np.clip(amp[0], -0.9 * AMP_BOUND, 0.9 * AMP_BOUND)
    lo, hi = bounds
    idx_T = T_IDX[model]
    th[idx_T] = np.clip(logT[0], lo + 0.05, hi - 0.05)
    if model == "double" and th[idx_T[0]] >= th[idx_T[1]]:
        th[idx_T[1]] = th[idx_T[0]] + 1e-3
    th[-1] = np.log(np.clip(th[-1], 1e-8, 0.9 * AMP_BOUND))  # sampled as log sigma_x
    p0 = _start(model, th, t, y, s, bounds, nw, rng)
    names = PARAM_NAMES[model][:-1] + ["log_sigma_x"]  # the sampled coordinates
    # The single and constant laws are linear in their amplitudes: sample (log T, log sigma_x)
    # with the amplitudes integrated out and draw the amplitudes afterwards (2 and 1 sampled
    # dimensions instead of 4 and 2: an ensemble's autocorrelation time grows with the
    # dimension, and with 4 the log posterior's tau of ~30 steps left R-hat <= 1.01 to chance
    # at a few thousand steps).  The double law keeps its amplitudes, whose bounds shape its
    # degenerate posteriors.
    collapsed = model in ("single", "constant")
    if collapsed:
        keep = [i for i in range(th.size) if i not in AMP_IDX[model]]
        p0 = p0[:, keep]

        def lp(x):
            return log_post_collapsed(model, x, t, y, s, bounds)
    else:
        def lp(x):
            return log_post(model, x, t, y, s, bounds)

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
        full[..., AMP_IDX[model]] = amp
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
