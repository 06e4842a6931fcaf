"""Fit one trace: least squares start, emcee posterior, arviz diagnostics, budget."""

from __future__ import annotations

import warnings

import numpy as np

from .. import __version__
from ..errors import ConvergenceError, ConvergenceWarning, FitError
from ..fitdata import DEFAULT_F_UNC, FitData, ModelSpec, prepare
from ..lsq import LSQResult, fit_lsq_data
from ..trace import IndentationTrace
from .budget import BudgetSpec, propagate
from .diagnostics import chain_passes, compute_diagnostics, import_arviz
from .likelihood import TraceLikelihood
from .priors import PriorSpec, param_names
from .result import BayesResult
from .sampler import SamplerSettings, run_emcee

__all__ = ["fit_bayes", "fit_bayes_data", "initial_ensemble", "is_bimodal"]


def initial_ensemble(lsq: LSQResult, data: FitData, noise: str, n_walkers: int,
                     z_bounds: tuple[float, float], rng: np.random.Generator,
                     estar_bounds: tuple[float, float] = (0.0, np.inf)) -> np.ndarray:
    """Walkers in a small Gaussian ball around the least-squares solution.

    Scales: the least-squares standard errors of log E* and z_surf (floored), 1/sqrt(2n) for
    log sigma, sigma/sqrt(n) for F0; z_surf is reflected into the prior support and log E*
    moved inside the prior bounds when the least-squares value lies outside them.
    """
    n = data.n_points
    sigma = max(lsq.rms, 1e-9)
    rel_e = lsq.Estar_sd / lsq.Estar if np.isfinite(lsq.Estar_sd) else 1e-3
    z_sd = lsq.z_surf_sd if np.isfinite(lsq.z_surf_sd) else 1e-7
    scale = [max(rel_e, 1e-6), max(z_sd, 1e-10), 1.0 / np.sqrt(2 * n), sigma / np.sqrt(n)]
    e_lo = np.log(estar_bounds[0]) + 5 * scale[0] if estar_bounds[0] > 0 else -np.inf
    e_hi = np.log(estar_bounds[1]) - 5 * scale[0]
    log_e = float(np.clip(np.log(lsq.Estar), e_lo, e_hi)) if e_lo < e_hi else np.log(lsq.Estar)
    center = [log_e, lsq.z_surf, np.log(sigma), 0.0]
    if noise == "ar1":
        center.append(0.0)
        scale.append(0.05)
    elif noise == "student":
        center.append(np.log(20.0))
        scale.append(0.2)
    p0 = np.asarray(center) + np.asarray(scale) * rng.standard_normal((n_walkers, len(center)))
    lo, hi = z_bounds
    z = p0[:, 1]
    z = np.where(z < lo, 2 * lo - z, z)
    z = np.where(z > hi, 2 * hi - z, z)
    p0[:, 1] = np.clip(z, lo, hi)
    return p0


def _posterior_dict(samples: np.ndarray, names: list[str], nu: float) -> dict[str, np.ndarray]:
    post = {}
    for i, name in enumerate(names):
        x = samples[..., i]
        if name == "log_Estar":
            post["E_star"] = np.exp(x)
            post["E"] = np.exp(x) * (1 - nu**2)
        elif name == "log_sigma":
            post["sigma"] = np.exp(x)
        elif name == "log_nu_t":
            post["nu_t"] = np.exp(x)
        else:
            post[name] = x
    return post


def is_bimodal(x: np.ndarray, gap: float = 6.0, min_mass: float = 0.05) -> bool:
    """True if the sorted draws ``x`` have an empty gap wider than ``gap`` robust sd (MAD of
    the larger side) with at least ``min_mass`` of the draws on each side of it.
    """
    x = np.sort(np.ravel(x))
    n = x.size
    if n < 20:
        return False
    lo_i, hi_i = int(min_mass * n), int((1 - min_mass) * n)
    d = np.diff(x)[lo_i:hi_i]
    if d.size == 0:
        return False
    i = lo_i + int(np.argmax(d))
    left, right = x[: i + 1], x[i + 1:]
    big = left if left.size >= right.size else right
    scale = 1.4826 * np.median(np.abs(big - np.median(big)))
    return bool(scale > 0 and x[i + 1] - x[i] > gap * scale)


def _flags(post: dict, data: FitData, priors: PriorSpec) -> list[str]:
    """Failure modes a converged chain can still show (bimodal, prior-dominated, at a bound)."""
    out = []
    if is_bimodal(post["z_surf"]):
        out.append("bimodal z_surf: two separated surface heights fit the data")
    lo, hi = data.z_contact, data.z_top
    z = post["z_surf"]
    if np.std(z) > 0.2 * (hi - lo) / np.sqrt(12):
        out.append("prior-dominated z_surf: the data barely constrain the surface")
    # a bound within 3 posterior sd of the median of log E*: the prior truncates the posterior
    log_e = np.log(post["E_star"])
    med, sd = np.median(log_e), np.std(log_e)
    if min(med - np.log(priors.Estar_bounds[0]), np.log(priors.Estar_bounds[1]) - med) < 3 * sd:
        out.append("E* posterior reaches the prior bound")
    return out


def fit_bayes_data(
    data: FitData,
    *,
    noise: str = "gaussian",
    priors: PriorSpec | None = None,
    budget: BudgetSpec | None = None,
    settings: SamplerSettings | None = None,
    seed: int | None = 0,
    tabulate: bool = True,
    strict: bool = False,
    trace_id: str = "trace",
    lsq: LSQResult | None = None,
) -> BayesResult:
    """Posterior of one prepared trace; see :func:`fit_bayes`."""
    priors = priors or PriorSpec()
    budget = budget or BudgetSpec()
    settings = settings or SamplerSettings()
    names = param_names(noise)
    if lsq is None:
        lsq = fit_lsq_data(data, trace_id=trace_id)
    like = TraceLikelihood(data, noise, tabulate=tabulate, z_center=lsq.z_surf,
                           z_scale=lsq.z_surf_sd)
    zb = like.z_bounds
    ss = np.random.SeedSequence(seed)
    init_ss, sampler_ss, budget_ss = ss.spawn(3)

    def log_prob(theta: np.ndarray) -> np.ndarray:
        lp = priors.log_prior(theta, zb, noise)
        ok = np.isfinite(lp)
        if ok.any():
            lp[ok] += like(theta[ok])
        return lp

    n_walkers = max(settings.n_walkers, 2 * len(names) + 2)
    p0 = initial_ensemble(lsq, data, noise, n_walkers, zb, np.random.default_rng(init_ss),
                          priors.Estar_bounds)
    bad = ~np.isfinite(log_prob(p0))
    if bad.any():
        raise FitError(f"{trace_id}: {int(bad.sum())} initial walker(s) have zero posterior "
                       "density; the least-squares start lies outside the prior")
    chains = run_emcee(log_prob, p0, settings, int(sampler_ss.generate_state(1)[0]),
                       accept=chain_passes)
    post = _posterior_dict(chains.samples, names, data.model.nu)
    bud = propagate(post["E_star"], data, float(np.median(post["z_surf"])), budget,
                    np.random.default_rng(budget_ss))
    post["E_total"] = bud.E
    az = import_arviz()
    with warnings.catch_warnings():
        # heavy thinning of a short chain can leave fewer draws than walkers: fine for us
        warnings.filterwarnings("ignore", message="More chains", category=UserWarning)
        idata = _to_idata(az, post, chains, data, trace_id, priors, budget, settings, seed,
                          lsq, noise)
    return _finish(idata, post, chains, data, trace_id, priors, bud, lsq, noise, strict)


def _to_idata(az, post, chains, data, trace_id, priors, budget, settings, seed, lsq, noise):
    """arviz InferenceData of the draws, with the fit's settings as attributes."""
    return az.from_dict(
        posterior=post,
        sample_stats={"lp": chains.log_prob},
        observed_data={"force": data.force},
        constant_data={"z": data.z},
        attrs={
            "trace_id": trace_id,
            "palpbayes_version": __version__,
            "model": data.model.describe(),
            "tip": data.model.tip.kind,
            "nu": data.model.nu,
            "noise_model": noise,
            "priors": repr(priors),
            "budget": repr(budget),
            "sampler": repr(settings),
            "seed": -1 if seed is None else int(seed),
            "f_unc_n": data.f_unc,
            "fit_fraction": data.fit_fraction,
            "z_admissible_m": [data.z_contact, data.z_top],
            "lsq_E_pa": lsq.E,
            "lsq_z_surf_m": lsq.z_surf,
            "n_steps": chains.n_steps,
            "burn": chains.burn,
            "thin": chains.thin,
        },
    )


def _finish(idata, post, chains, data, trace_id, priors, bud, lsq, noise, strict):
    """Diagnostics, flags and the warning (or error in strict mode)."""
    diag_names = [n for n in ("E_star", "z_surf", "sigma", "F0", "phi", "nu_t") if n in post]
    diag = compute_diagnostics(idata, diag_names, chains.tau, chains.acceptance,
                               chains.n_steps, chains.hit_cap)
    result = BayesResult(idata=idata, diagnostics=diag, budget=bud, data=data, noise=noise,
                         trace_id=trace_id, lsq=lsq, warnings=_flags(post, data, priors))
    if not result.converged:
        problems = "; ".join(result.warnings + diag.problems())
        msg = f"{trace_id}: Bayesian fit flagged as not converged: {problems}"
        if strict:
            raise ConvergenceError(msg)
        warnings.warn(msg, ConvergenceWarning, stacklevel=3)
    return result


def fit_bayes(
    trace: IndentationTrace,
    model: ModelSpec | None = None,
    *,
    f_unc: float = DEFAULT_F_UNC,
    fit_fraction: float | None = None,
    max_depth: float | None = None,
    **kwargs,
) -> BayesResult:
    """Bayesian fit of E*, z_surf, sigma and F0 (and phi or nu_t) to one trace.

    Parameters
    ----------
    trace
        The measurement; its ``tip`` is used when ``model`` is None.
    model
        Contact model (tip, nu, optional finite-thickness correction).
    f_unc
        [N] Sensor uncertainty defining the admissible surface range (prior support).
    fit_fraction, max_depth
        Fit window, shared with the least-squares baseline (:func:`palpbayes.fitdata.prepare`).
    **kwargs
        ``noise`` ("gaussian" | "ar1" | "student"), ``priors`` (:class:`PriorSpec`),
        ``budget`` (:class:`BudgetSpec`), ``settings`` (:class:`SamplerSettings`), ``seed``,
        ``tabulate``, ``strict`` (raise :class:`ConvergenceError` instead of warning).

    Returns
    -------
    BayesResult
    """
    if model is None:
        if trace.tip is None:
            raise FitError(f"{trace.trace_id}: no tip geometry given; pass a ModelSpec")
        model = ModelSpec(trace.tip)
    data = prepare(trace, model, f_unc=f_unc, fit_fraction=fit_fraction, max_depth=max_depth)
    return fit_bayes_data(data, trace_id=trace.trace_id, **kwargs)
