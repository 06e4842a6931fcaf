"""Both engines for a layer whose base or thickness is unknown, and what the fit says about it.

:func:`exact_layer_chains` draws from the exact mixture (:mod:`palpbayes.bayes.layers`);
:func:`emcee_layer_chains` samples it with emcee (:mod:`palpbayes.bayes.layer_likelihood`),
its walkers started at draws of the exact mixture (with Gaussian noise and the 'loading'
surface prior standing in when the fit's own are not conjugate).  :func:`layer_notes` says what
the data did and did not tell about the layer; :func:`layer_columns` are its ``summary.csv``
columns; :func:`best_model` is the concrete model at the posterior's centre and
:func:`concrete_draws` the draws that belong to it.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..contact.layer import LAMBDA_VALID
from ..fitdata import FitData, ModelSpec
from ..intervals import LEVEL
from ..units import format_length, format_pressure
from .exact import sampled_coordinates
from .layer_likelihood import SWAP_WEIGHT, LayerLikelihood, base_swap_move
from .layers import LayerPosterior, layer_posterior
from .noisemodels import EXACT_NOISE_MODELS
from .priors import TracePrior, log_posterior, param_names
from .sampler import ChainResult, SamplerSettings, run_emcee
from .start import Mode

__all__ = ["exact_layer_chains", "emcee_layer_chains", "layer_coordinates", "layer_notes",
           "layer_warnings", "layer_columns", "best_model", "concrete_draws", "P_UNDECIDED",
           "STRAIN_VALID"]

#: A base posterior between P_UNDECIDED and 1 − P_UNDECIDED is reported as not identified.
P_UNDECIDED = 0.1
#: Indentation deeper than this fraction of the layer is beyond small strain (a note).
STRAIN_VALID = 0.25


def layer_coordinates(draws: dict[str, np.ndarray], prior: TracePrior,
                      rng: np.random.Generator, like: LayerLikelihood | None = None
                      ) -> dict[str, np.ndarray]:
    """The exact mixture's draws in emcee's coordinates, ``bond`` and ``log_h`` included.

    ``bond`` is drawn uniformly within the half of the draw's base (from the prior where the
    draw has no layer); ``log_h`` is ln h, or uniform in the half-space segment for h = inf;
    with ``like`` the first coordinate is the aligned ln E* (:mod:`palpbayes.bayes.
    layer_likelihood`), without it the real ln E*.
    """
    theta = sampled_coordinates(draws, [n for n in prior.names if n not in ("bond", "log_h")])
    n = draws["E_star"].size
    if "bond" in prior.names:
        b = np.asarray(draws.get("bonded", np.full(n, np.nan)), dtype=float)
        b = np.where(np.isnan(b), (rng.random(n) < prior.p_bonded).astype(float), b)
        theta["bond"] = 0.5 * b + 0.5 * rng.random(n)
    if "log_h" in prior.names:
        h = np.asarray(draws["thickness"], dtype=float)
        _, hi = prior.log_h_range
        seg = rng.uniform(hi, prior.log_h_top, n)
        theta["log_h"] = np.where(np.isfinite(h), np.log(np.where(np.isfinite(h), h, 1.0)), seg)
    if like is not None:
        X = np.column_stack([theta[n] for n in prior.names])
        theta["log_Estar"] = theta["log_Estar"] - like.offset(X)
    return theta


def _chains_of(theta: dict[str, np.ndarray], prior: TracePrior, shape: tuple[int, int]
               ) -> np.ndarray:
    ndim = len(prior.names)
    return np.column_stack([theta[n] for n in prior.names]).reshape(*shape, ndim)


def _modes(post: LayerPosterior) -> list[Mode]:
    """The surface modes of the most probable component (for the fit's record)."""
    best = post.components[int(np.argmax(post.weights))].post
    return [Mode(z_surf=z, beta=np.full(2, np.nan), rss=np.nan, loglik=np.nan,
                 cov=np.full((3, 3), np.nan), lag1=np.nan, weight=w) for z, w in best.modes()]


def exact_layer_chains(data: FitData, prior: TracePrior, rng: np.random.Generator,
                       shape: tuple[int, int], log_prob: bool = True):
    """Independent draws of the exact mixture, shaped as ``shape`` = (chains, draws).

    Returns the chains, the surface modes, the likelihood and the mixture posterior.  With
    ``log_prob`` False the chains carry no log posterior (``log_prob`` None): each draw's
    thickness is its own, so it costs a shape row per draw (~0.2 s on a 4,000-sample curve).
    """
    post = layer_posterior(data, prior)
    d = post.draws(rng, shape[0] * shape[1])
    z = d["z_surf"]
    like = LayerLikelihood(data, prior, centers=((float(np.mean(z)), float(np.std(z))),),
                           z_reference=float(np.median(z)))
    samples = _chains_of(layer_coordinates(d, prior, rng, like), prior, shape)
    lp = (log_posterior(prior, like, like.log_estar)(samples.reshape(-1, samples.shape[-1]))
          .reshape(shape) if log_prob else None)
    chains = ChainResult(samples=samples, log_prob=lp,
                         tau=np.ones(samples.shape[-1]), n_steps=post.n_nodes, burn=0, thin=1,
                         acceptance=1.0, hit_cap=not post.complete)
    return chains, _modes(post), like, post


def emcee_layer_chains(data: FitData, prior: TracePrior, settings: SamplerSettings,
                       tabulate: bool, init_ss, sampler_ss, accept):
    """emcee on the mixture, started at draws of the exact one (module docstring)."""
    start_prior = prior
    if prior.noise not in EXACT_NOISE_MODELS or prior.spec.surface != "loading":
        start_prior = replace(prior, noise="gaussian", spec=replace(prior.spec,
                                                                     surface="loading"),
                              names=tuple(param_names("gaussian", prior.baseline)
                                          + [n for n in prior.names
                                             if n in ("bond", "log_h")]))
    rng = np.random.default_rng(init_ss)
    post = layer_posterior(data, start_prior)
    n_walkers = max(settings.n_walkers, 2 * len(prior.names) + 2)
    d = post.draws(rng, n_walkers)
    z = d["z_surf"]
    like = LayerLikelihood(data, prior, tabulate=tabulate,
                           centers=((float(np.median(z)), float(np.std(z)) or 1e-9),),
                           z_reference=float(np.median(z)))
    theta = layer_coordinates(d, start_prior, rng, like)
    if "log_nu_t" in prior.names:
        theta["log_nu_t"] = np.log(20.0) + 0.2 * rng.standard_normal(n_walkers)
    if "phi" in prior.names and "phi" not in theta:
        theta["phi"] = 0.02 * rng.standard_normal(n_walkers)
    p0 = np.column_stack([theta[n] for n in prior.names])
    log_prob = log_posterior(prior, like, like.log_estar)
    extra = ([(base_swap_move(like, float(np.median(z))), SWAP_WEIGHT)]
             if "bond" in prior.names else None)
    chains = run_emcee(log_prob, p0, settings, int(sampler_ss.generate_state(1)[0]),
                       accept=None if accept is None else _with_real_estar(accept, like),
                       extra_moves=extra)
    return chains, _modes(post), like, settings


def _with_real_estar(accept, like: LayerLikelihood):
    """The sampler's stop test on the sampled coordinates and the real ln E* as one more
    column: the first coordinate is the aligned ln E* (module docstring of
    :mod:`palpbayes.bayes.layer_likelihood`), while the fit's diagnostics read the real E*,
    which also mixes over the base and the thickness; a test on the aligned one alone could
    stop the chains where the real one's R-hat is still above its bound."""
    def test(chain: np.ndarray, log_prob: np.ndarray) -> bool:
        real = like.log_estar(chain.reshape(-1, chain.shape[-1])).reshape(chain.shape[:-1])
        return accept(np.concatenate([chain, real[..., None]], axis=-1), log_prob)
    return test


def _h_interval(h: np.ndarray) -> tuple[float, float]:
    """Central 90 % interval of thickness draws, ``inf`` (no layer) included: order statistics
    (no interpolation between a finite draw and ``inf``)."""
    a = (1.0 - LEVEL) / 2.0
    lo, hi = np.quantile(np.asarray(h, dtype=float), [a, 1.0 - a], method="inverted_cdf")
    return float(lo), float(hi)


def _fitted_depth(z_surf: float, data: FitData) -> float:
    return max(z_surf - float(np.min(data.z)), 0.0)


#: P(half-space) above which a thickness-unknown fit says "no layer needed" (the prior gives
#: the half-space 0.5; a flat punch, whose curve is linear at any thickness, stays there).
P_NO_LAYER = 0.8
#: A footprint longer than this (length/width) carries a note: the twin's equal-area cylinder
#: is measured within 1 % of the block itself up to it (palpbayes.twin.table).
ELONGATED = 1.5


def layer_notes(post: dict[str, np.ndarray], data: FitData, best: ModelSpec) -> list[str]:
    """What the data told about the layer, as notes (information, not failures).  A note
    holds no '; ' (the separator of the ``flags`` column)."""
    model = data.model
    notes: list[str] = []
    # E at the stated inputs (the statistical draws), as the row's E_pa and its
    # E_bonded_pa/E_free_pa (result._alternatives) report it
    E = np.ravel(post["E"])
    if "bonded" in post and model.bonding == "unknown":
        b = np.ravel(post["bonded"])
        layer = ~np.isnan(b)
        if layer.any():
            pb = float(np.mean(b[layer]))
            if P_UNDECIDED < pb < 1.0 - P_UNDECIDED:
                eb = float(np.median(E[layer & (b == 1.0)])) if (b == 1.0).any() else np.nan
                ef = float(np.median(E[layer & (b == 0.0)])) if (b == 0.0).any() else np.nan
                notes.append(
                    f"base not identified (P(bonded) = {pb:.2f}): E is {format_pressure(eb)} "
                    f"if the specimen is bonded to its base, {format_pressure(ef)} if it lies "
                    "free on it, and the interval spans both (give --bonding bonded|free if "
                    "it is known)")
    if "thickness" in post and model.thickness_unknown:
        h = np.ravel(post["thickness"])
        p_half = float(np.mean(~np.isfinite(h)))
        lo, hi = _h_interval(h)
        lo_t, hi_t = model.thickness_range
        if p_half > P_NO_LAYER:
            notes.append(
                f"no layer needed (P(half-space) = {p_half:.2f}): the data only say h > "
                f"{format_length(lo)} (prior {format_length(lo_t)}..{format_length(hi_t)} or "
                "none)")
        elif not np.isfinite(hi) or hi / lo > 3.0:
            notes.append(
                f"thickness not identified: h in [{format_length(lo)}, "
                f"{'no layer' if not np.isfinite(hi) else format_length(hi)}] (90 %, "
                f"P(half-space) = {p_half:.2f}), and E's interval carries it")
    if best.has_layer:
        d_max = _fitted_depth(float(np.median(post["z_surf"])), data)
        a = _contact_radius(best, d_max)
        h = best.thickness
        if a / h > LAMBDA_VALID:
            notes.append(f"contact radius {a / h:.2g} times the layer thickness: the thin-layer "
                         "regime, where the answer hangs on compressibility and the base")
        if STRAIN_VALID < d_max / h <= 1.0:
            notes.append(f"indentation {100 * d_max / h:.0f} % of the layer thickness: "
                         "beyond the small strain of the layer solution")
    block = best.specimen
    if block is not None and block.aspect > ELONGATED:
        notes.append(
            f"the {block.describe()} is {block.aspect:.1f} times as long as wide: its twin, "
            "the cylinder of equal footprint area, reads it stiffer by up to ~1 % at 1.5:1, "
            "2.5 % at 2:1, 6 % at 3:1 (flat punch; half that for curved tips), so E may read "
            "that much low")
    return notes


def layer_warnings(post: dict[str, np.ndarray], data: FitData, best: ModelSpec) -> list[str]:
    """What makes a layer fit wrong, not merely uncertain: the tip going through the layer
    (the fitted indentation deeper than the fitted thickness)."""
    if not best.has_layer:
        return []
    d_max = _fitted_depth(float(np.median(post["z_surf"])), data)
    if d_max <= best.thickness:
        return []
    return [f"the fitted indentation ({format_length(d_max)}) is deeper than the fitted layer "
            f"({format_length(best.thickness)}): the tip would go through it, so the layer "
            "model cannot describe this curve (check --thickness, or the tip and the onset)"]


def _contact_radius(model: ModelSpec, depth: float) -> float:
    from ..contact import get_law

    law = get_law(model.tip)
    return float(law.contact_radius(np.array([depth]), model.tip)[0])


def layer_columns(post: dict[str, np.ndarray], data: FitData,
                  best: ModelSpec | None = None) -> dict:
    """``summary.csv`` columns of the layer: ``layer``, ``thickness_m`` (and its interval when
    sampled), ``p_bonded``, ``p_halfspace``.  A sampled thickness is reported as the fitted
    model's, ``best`` (:func:`best_model`: the median of the layer draws, ``inf`` when most
    draws have no layer), so that ``thickness_m`` and ``model_fitted`` say one thing; its
    interval runs over every draw."""
    model = data.model
    out = {"layer": model.describe_layer(), "thickness_m": model.thickness,
           "thickness_lo_m": np.nan, "thickness_hi_m": np.nan, "p_bonded": np.nan,
           "p_halfspace": np.nan}
    if model.has_layer and model.bonding != "unknown":
        out["p_bonded"] = 1.0 if model.bonding == "bonded" else 0.0
    if "bonded" in post:
        b = np.ravel(post["bonded"])
        if (~np.isnan(b)).any():
            out["p_bonded"] = float(np.nanmean(b))
    if "thickness" in post and model.thickness_unknown:
        h = np.ravel(post["thickness"])
        if best is None:
            out["thickness_m"] = float(np.median(h))
        else:
            out["thickness_m"] = float(best.thickness) if best.has_layer else np.inf
        out["thickness_lo_m"], out["thickness_hi_m"] = _h_interval(h)
        out["p_halfspace"] = float(np.mean(~np.isfinite(h)))
    elif model.thickness is None:
        out["thickness_m"] = np.nan
    if not model.has_layer:
        out["thickness_m"] = np.nan
    return out


def best_model(model: ModelSpec, post: dict, mixture) -> ModelSpec:
    """The concrete model at the posterior's centre (checks, budget): the model itself, the
    exact mixture's :meth:`~palpbayes.bayes.layers.LayerPosterior.best`, or the same read
    off the draws (the more probable base, the median thickness, no layer if most draws have
    none)."""
    if model.is_concrete:
        return model
    if mixture is not None:
        return mixture.best()
    h = np.ravel(post["thickness"]) if "thickness" in post else None
    if h is not None and np.mean(~np.isfinite(h)) > 0.5:
        return model.half_space()
    b = np.ravel(post["bonded"]) if "bonded" in post else None
    base = model.bonding if b is None else ("bonded" if not np.nanmean(b) < 0.5 else "free")
    thickness = model.thickness if h is None else float(np.median(h[np.isfinite(h)]))
    return model.variant(thickness=thickness, base=base)


def concrete_draws(model: ModelSpec, n: int, thickness: np.ndarray | None = None,
                   bonded: np.ndarray | None = None) -> np.ndarray:
    """Mask (n,) of the draws that belong to the concrete ``model``: a layer's (finite
    ``thickness`` [m], ``bonded`` 1/0 matching its base) or the half-space's (``inf``);
    all draws when neither was sampled."""
    mine = np.ones(n, dtype=bool)
    if thickness is not None:
        mine &= np.isfinite(np.ravel(thickness)) == model.has_layer
    if bonded is not None and model.has_layer:
        mine &= np.ravel(bonded) == (1.0 if model.base == "bonded" else 0.0)
    return mine
