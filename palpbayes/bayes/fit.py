"""Fit one trace: profile-scan start, emcee posterior, arviz-stats diagnostics, flags, budget.

The draws stay numpy arrays (:class:`~palpbayes.bayes.posterior_data.PosteriorData`): a fit
imports neither arviz nor xarray's dask plumbing; the arviz ``InferenceData`` is made when a
user asks for it (:attr:`BayesResult.idata <palpbayes.bayes.BayesResult.idata>`)."""

# Long module: one job, the fit pipeline of one trace (start, chains, checks, arviz groups,
#   budget).

from __future__ import annotations

import warnings
from dataclasses import replace
from functools import partial

import numpy as np

from .. import __version__
from ..checks import check_fit
from ..contact import youngs_modulus
from ..errors import ConvergenceError, ConvergenceWarning, FitError, InputError, PalpbayesError
from ..fitdata import FitData, ModelSpec, prepare_trace
from ..intervals import central
from ..lsq import LSQResult, fit_lsq_data
from ..trace import IndentationTrace
from .budget import BudgetSpec, law_nu_nodes, nu_nodes, propagate
from .diagnostics import chain_passes, compute_diagnostics
from .exact import exact_posterior, sampled_coordinates
from .flags import bound_flags, is_bimodal, posterior_flags
from .instron import instron_bonded_draws
from .lawfit import check_law_model, exact_law_chains, law_columns, law_notes
from .layer_fit import (
    best_model,
    concrete_draws,
    emcee_layer_chains,
    exact_layer_chains,
    layer_columns,
    layer_notes,
    layer_warnings,
)
from .likelihood import TraceLikelihood
from .modelform import layer_alternative, model_form
from .noisemodels import EXACT_NOISE_MODELS
from .posterior_data import PosteriorData
from .priors import PriorSpec, TracePrior, log_posterior
from .result import BayesResult
from .sampler import ChainResult, SamplerSettings, run_emcee
from .start import Mode, find_modes, initial_ensemble, modes_from_exact
from .strainform import strain_reading

__all__ = ["fit_bayes", "fit_bayes_data", "is_bimodal", "bound_flags", "ENGINES",
           "EXACT_DRAWS"]

#: Posterior engines: emcee (every noise model and prior) or the exact quadrature
#: (:mod:`palpbayes.bayes.exact`: Gaussian or AR(1) noise, the 'loading' surface prior).
ENGINES = ("emcee", "exact")
#: Independent draws the exact engine returns (4 chains of 1,000, for arviz's diagnostics).
EXACT_DRAWS = (4, 1000)


def _posterior_dict(samples: np.ndarray, prior: TracePrior, nu: float, like=None
                    ) -> dict[str, np.ndarray]:
    post = {}
    for i, name in enumerate(prior.names):
        x = samples[..., i]
        if name == "log_Estar" and hasattr(like, "log_estar"):  # the layer's aligned ln E*
            x = like.log_estar(samples.reshape(-1, samples.shape[-1])).reshape(x.shape)
        if name == "log_Estar":
            post["E_star"] = np.exp(x)
            post["E"] = youngs_modulus(np.exp(x), nu)
        elif name == "log_sigma":
            post["sigma"] = np.exp(x)
        elif name == "log_nu_t":
            post["nu_t"] = np.exp(x)
        elif name == "bond":
            post["bonded"] = (x >= 0.5).astype(float)
        elif name == "log_h":
            post["thickness"] = prior.thickness_of(x)
        else:
            post[name] = x
    if "bonded" in post and "thickness" in post:  # no layer, no base
        post["bonded"] = np.where(np.isfinite(post["thickness"]), post["bonded"], np.nan)
    return post


# Many parameters: as fit_bayes: the layer below FitOptions takes its parts as objects and the
# engine's switches.
def fit_bayes_data(
    data: FitData,
    *,
    noise: str = "gaussian",
    baseline: str = "constant",
    priors: PriorSpec | None = None,
    budget: BudgetSpec | None = None,
    settings: SamplerSettings | None = None,
    seed: int | None = 0,
    tabulate: bool = True,
    strict: bool = False,
    trace_id: str = "trace",
    lsq: LSQResult | None = None,
    engine: str = "emcee",
    with_model_form: bool = True,
    log_prob: bool = True,
    platens: str = "unknown",
) -> BayesResult:
    """Posterior of one prepared trace; see :func:`fit_bayes` (``with_model_form=False``
    skips the model-form alternatives, :mod:`palpbayes.bayes.modelform`; ``log_prob=False``
    leaves the exact engine's draws of a partly unknown layer without their log posterior,
    ``sample_stats`` without ``lp``: for a fit whose InferenceData nobody keeps, the model
    form's layer alternative; ``platens``: the compression test the Instron-equivalent
    modulus of a fit with a specimen is for, :mod:`palpbayes.bayes.instron`)."""
    if engine not in ENGINES:
        raise InputError(f"unknown engine {engine!r}; use one of {', '.join(ENGINES)}")
    priors = priors or PriorSpec()
    budget = budget or BudgetSpec()
    settings = settings or SamplerSettings()
    prior = priors.for_trace(data, noise, baseline)
    names = list(prior.names)
    if lsq is None:
        try:  # the paper's fit, recorded beside the posterior; the posterior does not need it
            lsq = fit_lsq_data(replace(data, model=data.model.half_space()), trace_id=trace_id)
        except FitError:
            lsq = None
    ss = np.random.SeedSequence(seed)
    init_ss, sampler_ss, budget_ss, check_ss, form_ss = ss.spawn(5)  # first four as before
    mixture = extra = None
    law = data.model.law
    check_law_model(data.model, engine)
    if engine == "exact" and data.model.is_concrete:
        chains, modes, like = _exact_chains(data, prior, np.random.default_rng(sampler_ss))
        settings = f"exact engine, {chains.n_steps} (surface, phi) nodes"
    elif engine == "exact" and law is not None:
        chains, modes, like, mixture, extra = exact_law_chains(
            data, prior, np.random.default_rng(sampler_ss), EXACT_DRAWS)
        settings = (f"exact engine, {len(mixture.components)} law components, "
                    f"{chains.n_steps} (surface, phi) nodes")
    elif engine == "exact":
        chains, modes, like, mixture = exact_layer_chains(
            data, prior, np.random.default_rng(sampler_ss), EXACT_DRAWS, log_prob)
        settings = (f"exact engine, {len(mixture.components)} layer components, "
                    f"{chains.n_steps} (surface, phi) nodes")
    elif data.model.is_concrete:
        chains, modes, like, settings = _emcee_chains(data, prior, settings, tabulate,
                                                      init_ss, sampler_ss, trace_id)
    else:
        chains, modes, like, settings = emcee_layer_chains(
            data, prior, settings, tabulate, init_ss, sampler_ss, chain_passes)
    post = _posterior_dict(chains.samples, prior, data.model.nu, like)
    post.update(extra or {})  # a law's mixture: each draw's E at its nu, its shape
    post_theta = {n: chains.samples[..., i] for i, n in enumerate(names)}
    post_theta["log_Estar"] = np.log(post["E_star"])  # the real one (a layer's is aligned)
    best = best_model(data.model, post, mixture)
    fitted = replace(data, model=best)
    sampled_nu = law is not None and law.law.nu_parameter in law.free
    bud = propagate(post["E_star"], fitted, float(np.median(post["z_surf"])), budget,
                    np.random.default_rng(budget_ss), bonded=post.get("bonded"),
                    sampled_thickness=data.model.thickness_unknown,
                    nu_draws=post["nu"] if sampled_nu else None)
    post["E_total"] = bud.E
    if data.model.specimen is not None:  # what a compression test of the block would read
        post["E_instron_bonded"] = instron_bonded_draws(
            bud.E, bud.nu, data.model.specimen, nu_nodes(budget, data.model.nu))
    groups = _posterior_data(post, chains, data, trace_id, priors, budget, settings, seed, lsq,
                             noise, prior, modes)
    groups.posterior.attrs["engine"] = engine
    groups.posterior.attrs["model_fitted"] = best.describe()
    groups.posterior.attrs["platens"] = platens
    if mixture is not None and data.model.bonding == "unknown":
        groups.posterior.attrs["log_bf_bonded"] = mixture.log_bayes_factor()
    law_cols, law_more = law_columns(post, data, best, mixture if extra else None, bud.E,
                                     bud.nu, platens, law_nu_nodes(budget, best.nu))
    flags = posterior_flags(post, post_theta, prior) + layer_warnings(post, data, best)
    notes = (layer_notes(post, data, best) + law_notes(mixture if extra else None, data, best)
             + law_more)
    checks = _model_checks(post, fitted, like, int(check_ss.generate_state(1)[0]))
    form = None
    if with_model_form:
        layer = None if data.model.has_layer or law is not None else partial(
            layer_alternative, fit_bayes_data, data, float(np.median(post["z_surf"])),
            noise=noise, baseline=baseline, priors=priors, budget=budget, seed=seed,
            trace_id=trace_id, lsq=lsq)
        form = model_form(post["E_total"], checks, np.random.default_rng(form_ss), layer,
                          nonlinear=partial(strain_reading, fitted, post, priors, noise,
                                            baseline))
    return _finish(groups, post, chains, data, trace_id, bud, lsq, noise, strict, flags,
                   like, checks, notes, best, form, law_cols)


def _emcee_chains(data: FitData, prior: TracePrior, settings: SamplerSettings, tabulate: bool,
                  init_ss, sampler_ss, trace_id: str):
    """emcee, its walkers started at every mode (:mod:`palpbayes.bayes.start`)."""
    names = list(prior.names)
    modes = None
    if prior.noise in EXACT_NOISE_MODELS and prior.spec.surface == "loading":
        try:
            modes = modes_from_exact(exact_posterior(data, prior),
                                     np.random.default_rng(init_ss.spawn(1)[0])) or None
        except (PalpbayesError, ValueError, np.linalg.LinAlgError) as exc:
            warnings.warn(f"{trace_id}: the exact engine could not place the walkers ({exc}); "
                          "starting from the profile scan", RuntimeWarning, stacklevel=3)
    if modes is None:
        modes = find_modes(data, prior)
    centers = tuple((m.z_surf, float(np.sqrt(m.cov[1, 1]))) for m in modes
                    if np.isfinite(m.cov[1, 1]))
    like = TraceLikelihood(data, prior.noise, tabulate=tabulate, baseline=prior.baseline,
                           z_ref=prior.z_ref, centers=centers)
    log_prob = log_posterior(prior, like)
    n_walkers = max(settings.n_walkers, 2 * len(names) + 2)
    p0, used = initial_ensemble(modes, names, n_walkers, np.random.default_rng(init_ss),
                                prior.z_bounds, prior.bounds["log_Estar"], data.n_points)
    bad = ~np.isfinite(log_prob(p0))
    if bad.any():
        raise FitError(f"{trace_id}: {int(bad.sum())} initial walker(s) have zero posterior "
                       "density; the profile-scan start lies outside the prior")
    if len(used) > 1 and settings.moves == "de":
        settings = replace(settings, moves="de-snooker")  # emcee's advice for several modes
    chains = run_emcee(log_prob, p0, settings, int(sampler_ss.generate_state(1)[0]),
                       accept=chain_passes)
    return chains, modes, like, settings


def _exact_chains(data: FitData, prior: TracePrior, rng: np.random.Generator):
    """Independent draws of the exact engine, shaped as chains for arviz."""
    post = exact_posterior(data, prior)
    n_chains, n_draws = EXACT_DRAWS
    d = post.draws(rng, n_chains * n_draws)
    theta = sampled_coordinates(d, prior.names)
    ndim = len(prior.names)
    samples = np.column_stack([theta[n] for n in prior.names]).reshape(n_chains, n_draws, ndim)
    zs = post.z_summary()
    like = TraceLikelihood(data, prior.noise, baseline=prior.baseline, z_ref=prior.z_ref,
                           z_center=zs.mean, z_scale=zs.sd)
    lp = log_posterior(prior, like)(samples.reshape(-1, ndim))
    modes = [Mode(z_surf=z, beta=np.full(2, np.nan), rss=np.nan, loglik=np.nan,
                  cov=np.full((3, 3), np.nan), lag1=np.nan, weight=w)
             for z, w in post.modes()]
    chains = ChainResult(samples=samples, log_prob=lp.reshape(n_chains, n_draws),
                         tau=np.ones(ndim), n_steps=post.n_nodes, burn=0, thin=1,
                         acceptance=1.0, hit_cap=not post.complete)
    return chains, modes, like


def _model_checks(post: dict, data: FitData, like, seed: int) -> list:
    """Model-adequacy checks (:func:`palpbayes.checks.check_fit`) at the posterior medians of
    the concrete model ``data.model`` — over the draws of that model's base (and layer or
    none), so that a two-base mixture's E* does not mix into its medians — with the
    posterior-predictive check on all the draws (each with its own thickness and base when
    the layer is sampled).  The grading's statistical interval is that of the same draws
    (a base or thickness the data cannot tell does not widen it)."""
    draws = {n: np.ravel(post[n]) for n in ("E_star", "z_surf", "F0", "F1", "sigma", "phi",
                                            "thickness", "bonded")
             if n in post}
    mine = concrete_draws(data.model, draws["E_star"].size, draws.get("thickness"),
                          draws.get("bonded"))
    if mine.sum() < 50:
        mine[:] = True
    med = {n: float(np.median(x[mine])) for n, x in draws.items()
           if n not in ("thickness", "bonded")}
    lo, hi = central(draws["E_star"][mine])
    return check_fit(data, z_surf=med["z_surf"], estar=med["E_star"], f0=med["F0"],
                     f1=med.get("F1", 0.0), sigma=med["sigma"], baseline=like.baseline,
                     z_ref=like.z_ref, draws=draws, seed=seed,
                     stat_rel_halfwidth=0.5 * float(hi - lo) / med["E_star"])


def _posterior_data(post, chains, data, trace_id, priors, budget, settings, seed, lsq, noise,
                    prior, modes) -> PosteriorData:
    """The InferenceData's groups of the draws, with the fit's settings as attributes."""
    return PosteriorData.from_dicts(
        posterior=post,
        sample_stats=None if chains.log_prob is None else {"lp": chains.log_prob},
        observed_data={"force": data.force},
        constant_data={"z": data.z},
        attrs={
            "trace_id": trace_id,
            "palpbayes_version": __version__,
            "model": data.model.describe(),
            "layer": data.model.describe_layer(),
            "tip": data.model.tip.kind,
            "nu": data.model.nu,
            "noise_model": noise,
            "priors": repr(priors),
            "budget": repr(budget),
            "sampler": settings if isinstance(settings, str) else repr(settings),
            "seed": -1 if seed is None else int(seed),
            "f_unc_n": data.f_unc,
            "fit_fraction": data.fit_fraction,
            "z_admissible_m": [data.z_contact, data.z_top],
            "z_prior_m": list(prior.z_bounds),
            "baseline_model": prior.baseline,
            "z_ref_m": prior.z_ref,
            "F0_prior_n": [prior.f0_center, prior.f0_sd],
            "sigma_prior_center_n": prior.sigma_center,
            "tare_n": data.tare,
            "modes_z_surf_m": [m.z_surf for m in modes],
            "modes_weight": [m.weight for m in modes],
            "lsq_E_pa": np.nan if lsq is None else lsq.E,
            "lsq_z_surf_m": np.nan if lsq is None else lsq.z_surf,
            "n_steps": chains.n_steps,
            "burn": chains.burn,
            "thin": chains.thin,
        },
    )


def _finish(groups: PosteriorData, post, chains, data, trace_id, bud, lsq, noise, strict, flags,
            like, checks, notes, best, form=None, law=None):
    """Diagnostics, flags and the warning (or error in strict mode)."""
    diag_names = [n for n in ("E_star", "z_surf", "sigma", "F0", "F1", "phi", "nu_t")
                  if n in post]
    # tau follows θ, whose first entries are these in this order (the layer's come last)
    diag = compute_diagnostics(groups, diag_names, chains.tau[:len(diag_names)],
                               chains.acceptance, chains.n_steps, chains.hit_cap)
    result = BayesResult(groups=groups, diagnostics=diag, budget=bud, data=data, noise=noise,
                         trace_id=trace_id, lsq=lsq, warnings=flags,
                         baseline=like.baseline, z_ref=like.z_ref, checks=checks,
                         notes=notes, fitted_model=best,
                         layer=layer_columns(post, data, best), model_form=form,
                         law=law or {})
    if not result.converged:
        problems = "; ".join(result.warnings + diag.problems())
        msg = f"{trace_id}: Bayesian fit flagged as not converged: {problems}"
        if strict:
            raise ConvergenceError(msg)
        warnings.warn(msg, ConvergenceWarning, stacklevel=3)
    return result


# Many parameters: bayes/ lies below campaign/ (FitOptions' home, which imports it), so its entry
# point takes the model's parts as objects (ModelSpec, PriorSpec, BudgetSpec, SamplerSettings) plus
# the fit window's scalars.
def fit_bayes(
    trace: IndentationTrace,
    model: ModelSpec | None = None,
    *,
    f_unc: float | None = None,
    fit_fraction: float | None = None,
    max_depth: float | None = None,
    tare: bool = False,
    noise: str = "gaussian",
    baseline: str = "constant",
    priors: PriorSpec | None = None,
    budget: BudgetSpec | None = None,
    settings: SamplerSettings | None = None,
    seed: int | None = 0,
    tabulate: bool = True,
    strict: bool = False,
    engine: str = "emcee",
    with_model_form: bool = True,
    platens: str = "unknown",
) -> BayesResult:
    """Bayesian fit of E*, z_surf, sigma and F0 (and phi or nu_t) to one trace.

    Parameters
    ----------
    trace
        The measurement; its ``tip`` (and ``thickness``) are used when ``model`` is None.
    model
        Contact model (tip, nu, layer).  None: the trace's tip at nu = 0.3, as a layer of the
        trace's thickness on a rigid base with an unknown base condition when the thickness
        is known, else a half-space — the command line's default.
    f_unc
        [N] Sensor uncertainty: contact onset, fit window and the F0 prior's scale (None: the
        pre-contact baseline's noise as a peak-to-peak spec).
    fit_fraction, max_depth, tare
        Fit window and tare, shared with the least-squares baseline
        (:func:`palpbayes.fitdata.prepare`).
    noise
        Noise model: ``"gaussian"`` (default), ``"ar1"`` (autocorrelated) or ``"student"``.
    baseline
        Pre-contact force model: ``"constant"`` (default) or ``"linear"`` (drift).
    priors
        :class:`PriorSpec` (default ``PriorSpec()``).
    budget
        :class:`BudgetSpec` of the systematic errors propagated into E (default
        ``BudgetSpec()``).
    settings
        :class:`SamplerSettings` of the emcee run (default ``SamplerSettings()``).
    seed
        Seed of the start, the sampler and the budget draws (None: fresh entropy).
    tabulate
        Evaluate the Gaussian/AR(1) likelihood from tabulated sufficient statistics
        (default True; False: the direct sum, see :class:`TraceLikelihood`).
    strict
        Raise :class:`~palpbayes.errors.ConvergenceError` instead of warning when the fit is
        not converged.
    engine
        ``"emcee"`` (default: every noise model and prior) or ``"exact"`` (quadrature over
        the surface height with the linear parameters and the noise scale integrated out,
        :mod:`palpbayes.bayes.exact`; Gaussian or AR(1) noise; ``settings`` is then unused).
    with_model_form
        When a model check finds a material misfit, refit E under the alternatives it points
        to and widen E's interval to their envelope (:mod:`palpbayes.bayes.modelform`;
        default True).
    platens
        With a specimen in ``model``: the compression test's platens its Instron-equivalent
        modulus is for, ``"lubricated"``, ``"bonded"`` or ``"unknown"`` (default; an interval
        spanning both, :mod:`palpbayes.bayes.instron`).

    Returns
    -------
    BayesResult
    """
    if model is None and trace.tip is not None and trace.thickness is not None:
        model = ModelSpec(trace.tip, thickness=trace.thickness)
    half = None if model is None else model.half_space()
    data = prepare_trace(trace, half, f_unc=f_unc, fit_fraction=fit_fraction,
                         max_depth=max_depth, tare=tare)
    if model is not None:
        data = replace(data, model=model)
    return fit_bayes_data(data, noise=noise, baseline=baseline, priors=priors, budget=budget,
                          settings=settings, seed=seed, tabulate=tabulate, strict=strict,
                          trace_id=trace.trace_id, engine=engine,
                          with_model_form=with_model_form, platens=platens)
