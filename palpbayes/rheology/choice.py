"""Which relaxation model the record prefers: PSIS-LOO on the block means, with its error.

Each fitted model's expected log predictive density elpd_loo (Vehtari, Gelman & Gabry 2017,
Pareto-smoothed importance sampling, through :func:`arviz.loo`) is computed from pointwise
log-likelihoods of the block means under the model's AR(1) noise, factored in time:

    log p(y_0 | θ) = log N(e_0; 0, sigma²),
    log p(y_i | y_{i-1}, θ) = log N(e_i; phi·e_{i-1}, sigma²·(1 − phi²)),   e = y − mu(θ),

so leaving out y_i leaves out its conditional term (the usual approximation for a series; it
judges one-step prediction, not a fresh record).  Models are compared on the same block means:
the difference of elpd_loo and its standard error sqrt(N·var(pointwise differences)), as
:func:`arviz.compare` does.  A difference within two standard errors is no preference; a
Pareto k above 0.7 makes that model's elpd_loo unreliable (reported, not hidden).
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import pandas as pd

from ..errors import InputError
from .fit import RheologyFit, curve_draws

__all__ = ["LooResult", "loo", "compare_rheology", "pointwise_loglik", "LOO_DRAWS", "K_WARN"]

#: Posterior draws behind each model's pointwise log-likelihood.
LOO_DRAWS = 200
#: Pareto k above which PSIS-LOO is unreliable (Vehtari et al. 2017).
K_WARN = 0.7


@dataclass(frozen=True)
class LooResult:
    """elpd_loo, its standard error, the effective number of parameters p_loo, the largest
    Pareto k, the count of block means with k > :data:`K_WARN`, and the pointwise elpd."""

    elpd: float
    se: float
    p_loo: float
    k_max: float
    n_bad_k: int
    pointwise: np.ndarray


def pointwise_loglik(fit: RheologyFit, n: int = LOO_DRAWS) -> np.ndarray:
    """(draws, block means) log-likelihood of every block mean given its predecessor."""
    idx = curve_draws(len(fit.draws["z_surf"]), n)
    mu = fit.force_curves(n)
    sigma, phi = fit.draws["sigma"][idx][:, None], fit.draws["phi"][idx][:, None]
    e = fit.data.force[None, :] - mu
    prev = np.concatenate([np.zeros((e.shape[0], 1)), e[:, :-1]], axis=1)
    scale = np.concatenate([sigma, np.broadcast_to(sigma * np.sqrt(1.0 - phi**2),
                                                   (e.shape[0], e.shape[1] - 1))], axis=1)
    mean = np.concatenate([np.zeros_like(sigma), phi * prev[:, 1:]], axis=1)
    z = (e - mean) / scale
    return -0.5 * z**2 - np.log(scale) - 0.5 * np.log(2.0 * np.pi)


def loo(fit: RheologyFit, n: int = LOO_DRAWS) -> LooResult:
    """PSIS-LOO of one fit (module docstring).

    Parameters
    ----------
    fit
        A :func:`~palpbayes.rheology.fit_rheology` result.
    n
        Posterior draws behind the pointwise log-likelihood (evenly spread).

    Returns
    -------
    LooResult
        elpd_loo [nats], its se, p_loo, the largest Pareto k and the pointwise elpd.
    """
    import arviz as az

    ll = pointwise_loglik(fit, n)
    idata = az.from_dict(log_likelihood={"y": ll[None]},
                         posterior={"sigma": fit.draws["sigma"][curve_draws(
                             len(fit.draws["z_surf"]), n)][None]})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a high Pareto k is reported in the result
        res = az.loo(idata, pointwise=True)
    k = np.asarray(res.pareto_k)
    return LooResult(elpd=float(res.elpd_loo), se=float(res.se), p_loo=float(res.p_loo),
                     k_max=float(k.max()), n_bad_k=int((k > K_WARN).sum()),
                     pointwise=np.asarray(res.loo_i))


def compare_rheology(fits: Mapping[str, RheologyFit], n: int = LOO_DRAWS) -> pd.DataFrame:
    """Compare fits of one record by PSIS-LOO (module docstring).

    Parameters
    ----------
    fits
        Model name -> fit, two or more, all of the same block means.
    n
        Posterior draws per model behind the pointwise log-likelihoods.

    Returns
    -------
    pandas.DataFrame
        One row per model, best first: ``rheology``, ``elpd_loo``, ``elpd_loo_se``,
        ``p_loo``, ``pareto_k_max``, ``n_bad_k``, ``elpd_diff`` (to the best, <= 0, [nats])
        and ``elpd_diff_se``, and ``preferred`` (the best, by more than two standard errors
        of the difference from every other; else no model is preferred).

    Raises
    ------
    InputError
        Fewer than two fits, or fits of different block means.
    """
    if len(fits) < 2:
        raise InputError("compare at least two relaxation models (e.g. power-law,sls)")
    first = next(iter(fits.values())).data
    if any(f.data.n_points != first.n_points or not np.array_equal(f.data.force, first.force)
           or not np.array_equal(f.data.time, first.time) for f in fits.values()):
        raise InputError("the fits to compare must see the same block means (same record, "
                         "segments and max_points)")
    res = {name: loo(f, n) for name, f in fits.items()}
    best = max(res, key=lambda m: res[m].elpd)
    rows = []
    for name, r in res.items():
        d = r.pointwise - res[best].pointwise
        rows.append({"rheology": name, "elpd_loo": r.elpd, "elpd_loo_se": r.se,
                     "p_loo": r.p_loo, "pareto_k_max": r.k_max, "n_bad_k": r.n_bad_k,
                     "elpd_diff": float(d.sum()),
                     "elpd_diff_se": float(np.sqrt(d.size * d.var()))})
    out = pd.DataFrame(rows).sort_values("elpd_loo", ascending=False, ignore_index=True)
    others = out.iloc[1:]
    clear = bool(((-others["elpd_diff"]) > 2.0 * others["elpd_diff_se"]).all())
    out["preferred"] = (out["rheology"] == best) & clear
    return out
