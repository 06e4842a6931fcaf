"""The two-stage hierarchical model that pools one material × tip (docs/design.md §3, item 3).

Model
-----
Trace i of a material × tip group measures its own modulus E_i (a new location, a new
specimen); the material is described by the population

    log E_i ~ Normal(mu, tau²),

so exp(mu) is the material's median (geometric-mean) modulus and tau [-] the between-trace
scatter of log E (≈ the coefficient of variation for small tau).  The population mean is
exp(mu + tau²/2), larger by tau²/2 (0.5 % at tau = 0.1); both are reported.

Two-stage fit (Lunn et al. 2013)
--------------------------------
Stage 1 is the per-trace Bayesian fit (:mod:`palpbayes.bayes`), run independently and in
parallel.  Its *statistical* posterior of log E (netCDF variable ``E``, at the model's fixed nu,
without the uncertainty budget) is summarised as Normal(m_i, s_i²).  Stage 2 samples (mu,
log tau) with emcee from the marginal likelihood

    p(m | mu, tau) = Π_i Normal(m_i | mu, tau² + s_i²).

Why this is (very nearly) the full hierarchical posterior: the per-trace prior of E* is
log-uniform, i.e. flat in log E, so trace i's posterior of log E is its normalised likelihood
(the nuisances z_surf, sigma, F0 are trace-specific and already integrated out).  Replacing
that likelihood by a Normal and integrating log E_i out analytically gives the expression above
(the random-effects model of meta-analysis, DerSimonian & Laird 1986).  The approximation only
matters where a trace's likelihood is visibly non-Normal *and* comparable in width to tau; in
practice s_i (0.01–1 %) is one to three orders of magnitude below tau (~10 %), so the group
result is insensitive to the shape of each trace's posterior.  The alternative, one joint
emcee run over 4·n + 2 parameters, would refit every trace for every grouping and lose the
per-trace parallelism and the resumable per-trace results.

Priors: flat on mu (the data fix mu to ~tau/sqrt(n); each likelihood factor is integrable in
mu, so the posterior is proper); tau ~ HalfNormal(``tau_prior_sd`` = 0.5) on the log-E scale,
sampled as log tau with the Jacobian.  The half-normal is the weakly-informative choice of
Gelman (2006) and the Stan prior recommendations: foam specimen-to-specimen CVs are ~10 % (the
paper's Instron 13/111, 14/136, 17/194 kPa), where the prior is nearly flat
(p(0.2)/p(0) = 0.92), while it rules out factor-of-five scatter (tau > 1.6 has 0.1 % prior
mass) that a flat prior would leave open with only two or three traces.

Systematic inputs
-----------------
The budget inputs (Poisson ratio, tip radius, force-sensor gain, compliance;
:mod:`palpbayes.bayes.budget`) are *shared* by every trace of a material × tip: pooling the
per-trace ``E_total`` draws as if independent would shrink them by sqrt(n).  They are applied
once, to the pooled draws: one independent draw of the factor per posterior draw of (mu, tau),

    E = exp(mu)·f,    E_new = exp(mu + tau·z)·f,   z ~ Normal(0, 1),

where f = E_budget / E_stat is drawn by :func:`palpbayes.bayes.budget.propagate` on a
representative trace of the group (the one whose posterior median is the group median; the
radius and compliance factors depend on the depths and force level, which the traces of one
group share up to a few per cent).  E_new, the posterior predictive of a new specimen, is what
compares with the Instron mean ± sd.

A layer's base
--------------
A specimen's base condition (bonded to its plate or lying free on it;
:mod:`palpbayes.bayes.layers`) is shared too: every trace of a group lies on the same plate.
Each trace's posterior is read as if bonded (its free draws divided by the ratio r =
E_free/E_bonded of the same curve), the group's evidence for the base is the product of the
traces' Bayes factors, and the base is drawn once per pooled draw with that posterior weight,
multiplying E by r when free.

Reporting E_new
---------------
With a handful of traces the posterior of tau keeps a long right tail (the half-normal prior allows
tau up to ~1 and two or three traces cannot exclude it), and exp(mu + tau·z) turns that tail into
rare, very large draws: the sd of the E_new draws (``E_new_sd_pa``) then describes the tail, not
the spread of a typical new specimen.  Quote the central 90 % interval (``E_new_lo_pa`` …
``E_new_hi_pa``) and the median instead, as :mod:`palpbayes.campaign.compare_text` and the
``gt_z_new`` of :mod:`palpbayes.campaign.comparison` do, and state the prior of tau
(``tau_prior_sd`` in ``pooled.csv`` and ``comparison.csv``).

References
----------
Lunn, D., Barrett, J., Sweeting, M. & Thompson, S. (2013). Fully Bayesian hierarchical modelling
in two stages, with application to meta-analysis. J. R. Stat. Soc. C 62(4), 551–572.
DerSimonian, R. & Laird, N. (1986). Meta-analysis in clinical trials. Control. Clin. Trials 7.
Gelman, A. (2006). Prior distributions for variance parameters in hierarchical models.
Bayesian Analysis 1(3), 515–534.
"""

# Long module: one job, the two-stage hierarchical model: its log posterior, sampler and pooled
#   estimate.

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
import pandas as pd

from ..bayes.budget import BudgetSpec
from ..bayes.diagnostics import Diagnostics, chain_passes, compute_diagnostics, import_arviz
from ..bayes.sampler import SamplerSettings, run_emcee
from ..errors import FitError, InputError
from ..fitdata import FitData
from ..flagcodes import flag_columns
from ..intervals import LEVEL, central, hull
from .inputs import systematic_factor

__all__ = [
    "TAU_PRIOR_SD",
    "POOLING_SETTINGS",
    "log_normal_summary",
    "hierarchical_log_posterior",
    "HierarchicalPosterior",
    "sample_hierarchical",
    "PooledEstimate",
    "pool_group",
]

#: Scale of the half-normal prior of tau (sd of log E between traces).
TAU_PRIOR_SD = 0.5

#: emcee settings of the two-parameter stage-2 sampler.
POOLING_SETTINGS = SamplerSettings(n_walkers=32, max_steps=20000, min_steps=1000,
                                   check_every=250, moves="de", progress=False)

_LOG_TAU_BOUNDS = (np.log(1e-6), np.log(10.0))


def log_normal_summary(draws: np.ndarray) -> tuple[float, float]:
    """Normal summary (m, s) of log(draws): mean and sd (ddof 1) of the log of positive draws.

    Raises
    ------
    FitError
        If fewer than two draws or any draw is not a positive finite number.
    """
    x = np.asarray(draws, dtype=float).ravel()
    if x.size < 2 or not np.all(np.isfinite(x) & (x > 0)):
        raise FitError("posterior draws of E must be at least two positive finite numbers")
    lx = np.log(x)
    return float(lx.mean()), float(lx.std(ddof=1))


def _check_ms(m, s) -> tuple[np.ndarray, np.ndarray]:
    m = np.atleast_1d(np.asarray(m, dtype=float))
    s = np.atleast_1d(np.asarray(s, dtype=float))
    if m.ndim != 1 or m.shape != s.shape or m.size == 0:
        raise InputError("m and s must be non-empty 1-D arrays of the same length")
    if not (np.all(np.isfinite(m)) and np.all(np.isfinite(s)) and np.all(s >= 0)):
        raise InputError("m must be finite and s finite and non-negative")
    return m, s


def hierarchical_log_posterior(theta: np.ndarray, m: np.ndarray, s: np.ndarray,
                               tau_prior_sd: float = TAU_PRIOR_SD) -> np.ndarray:
    """Log posterior (up to a constant) of θ = (mu, log tau), vectorised over rows.

    log p = Σ_i log Normal(m_i | mu, tau² + s_i²) − tau²/(2·tau_prior_sd²) + log tau

    (flat prior on mu; half-normal on tau; + log tau is the Jacobian of sampling log tau).
    Rows with log tau outside [log 1e-6, log 10] get −inf.

    Parameters
    ----------
    theta
        (W, 2) or (2,) array of (mu, log tau).
    m, s
        Per-trace Normal summaries of log E (mean, sd).
    tau_prior_sd
        Scale of the half-normal prior of tau.
    """
    theta = np.atleast_2d(np.asarray(theta, dtype=float))
    mu, lt = theta[:, 0], theta[:, 1]
    ok = (lt > _LOG_TAU_BOUNDS[0]) & (lt < _LOG_TAU_BOUNDS[1]) & np.isfinite(mu)
    tau = np.exp(np.where(ok, lt, 0.0))
    v = tau[:, None] ** 2 + np.asarray(s)[None, :] ** 2
    ll = -0.5 * np.sum(np.log(2 * np.pi * v) + (np.asarray(m)[None, :] - mu[:, None]) ** 2 / v,
                       axis=1)
    lp = ll - 0.5 * (tau / tau_prior_sd) ** 2 + lt
    return np.where(ok, lp, -np.inf)


@dataclass
class HierarchicalPosterior:
    """Stage-2 posterior draws of (mu, tau) of one group.

    Attributes
    ----------
    mu
        Draws of mu (log of the material's median modulus, log Pa).
    tau
        Draws of tau (sd of log E between traces) [-].
    m, s
        The per-trace summaries the posterior was computed from.
    diagnostics
        R-hat / ESS / autocorrelation of mu and log tau.
    tau_prior_sd
        Scale of the half-normal prior of tau.
    """

    mu: np.ndarray
    tau: np.ndarray
    m: np.ndarray
    s: np.ndarray
    diagnostics: Diagnostics
    tau_prior_sd: float

    @property
    def converged(self) -> bool:
        return bool(self.diagnostics.converged)

    @property
    def n(self) -> int:
        return int(self.m.size)

    def log_predictive(self, rng: np.random.Generator) -> np.ndarray:
        """Draws of log E_new = mu + tau·z for a new trace/specimen (one z per draw)."""
        return self.mu + self.tau * rng.standard_normal(self.mu.size)


def sample_hierarchical(m, s, *, tau_prior_sd: float = TAU_PRIOR_SD, seed: int | None = 0,
                        settings: SamplerSettings | None = None) -> HierarchicalPosterior:
    """Sample the stage-2 posterior of (mu, log tau) with emcee (see module docstring).

    Parameters
    ----------
    m, s
        Per-trace means and sds of log E [log Pa] (:func:`log_normal_summary`).
    tau_prior_sd
        Scale of the half-normal prior of tau (default :data:`TAU_PRIOR_SD`).
    seed
        Seed of the initial ensemble and the sampler.
    settings
        emcee settings (default :data:`POOLING_SETTINGS`; ``progress`` is forced off).

    Returns
    -------
    HierarchicalPosterior
    """
    m, s = _check_ms(m, s)
    if not (np.isfinite(tau_prior_sd) and tau_prior_sd > 0):
        raise InputError(f"tau prior scale {tau_prior_sd!r} must be positive")
    settings = settings or POOLING_SETTINGS
    if settings.progress:
        from dataclasses import replace

        settings = replace(settings, progress=False)
    init_ss, run_ss = np.random.SeedSequence(seed).spawn(2)
    rng = np.random.default_rng(init_ss)
    n_walkers = max(settings.n_walkers, 8)
    spread = float(np.std(m, ddof=1)) if m.size > 1 else 0.0
    tau0 = min(max(spread, 0.05 * tau_prior_sd, float(np.median(s))), 2 * tau_prior_sd)
    se = max(tau0 / np.sqrt(m.size), 1e-4)
    p0 = np.column_stack([
        float(np.mean(m)) + se * rng.standard_normal(n_walkers),
        np.log(tau0) + 0.3 * rng.standard_normal(n_walkers),
    ])

    def log_prob(theta: np.ndarray) -> np.ndarray:
        return hierarchical_log_posterior(theta, m, s, tau_prior_sd)

    chains = run_emcee(log_prob, p0, settings, int(run_ss.generate_state(1)[0]),
                       accept=chain_passes)
    az = import_arviz()
    post = {"mu": chains.samples[..., 0], "log_tau": chains.samples[..., 1]}
    with warnings.catch_warnings():  # short, heavily thinned chains: fewer draws than walkers
        warnings.filterwarnings("ignore", "More chains", UserWarning)
        idata = az.from_dict(posterior=post)
    diag = compute_diagnostics(idata, ["mu", "log_tau"], chains.tau, chains.acceptance,
                               chains.n_steps, chains.hit_cap)
    return HierarchicalPosterior(mu=post["mu"].ravel().copy(),
                                 tau=np.exp(post["log_tau"].ravel()),
                                 m=m, s=s, diagnostics=diag, tau_prior_sd=float(tau_prior_sd))


@dataclass
class PooledEstimate:
    """Pooled result of one material × tip group (Bayesian rows).

    Attributes
    ----------
    material, tip
        Group labels.
    posterior
        Stage-2 draws of (mu, tau).
    factor
        Draws of the shared systematic factor (ones when no budget).
    E
        [Pa] Draws of the material's median modulus with the budget, exp(mu)·f.
    E_new
        [Pa] Posterior-predictive draws for a new specimen, exp(mu + tau·z)·f.
    budget
        Variance shares of log E: ``input, distribution, rel_sd_pct, share_pct``.
    nu
        The Poisson ratio of each draw [-] (the budget's), None without a budget.
    base
        The sampled base's factor of each draw (``base_ratio`` where it is free, else 1), None
        without a sampled base; part of ``factor``.
    """

    material: str
    tip: str
    posterior: HierarchicalPosterior
    factor: np.ndarray
    E: np.ndarray
    E_new: np.ndarray
    budget: pd.DataFrame
    nu: np.ndarray | None = None
    base: np.ndarray | None = None

    @property
    def stated(self) -> np.ndarray:
        """The factor of each draw at the inputs the user stated: the sampled base's (E × the
        free/bonded ratio where the base drawn is free), ones without one; the budget's share
        of ``factor`` is ``factor / stated``."""
        return np.ones_like(self.factor) if self.base is None else self.base

    def at_inputs(self, with_budget: np.ndarray, level: float = LEVEL
                  ) -> tuple[float, float, float]:
        """[Pa] Draws with the budget summarised as a per-trace row reports E
        (:meth:`palpbayes.bayes.result.BayesResult.intervals`): the median at the stated
        inputs (the draws divided by the budget's share of :attr:`factor`) and the budget's
        central ``level`` interval widened where needed to hold that of the stated draws.

        Returns
        -------
        tuple of float
            (median, lo, hi).
        """
        at_inputs = with_budget / (self.factor / self.stated)
        lo, hi = hull(central(with_budget, level), central(at_inputs, level))
        return float(np.median(at_inputs)), lo, hi

    def headline(self, level: float = LEVEL) -> dict[str, float]:
        """[Pa] The group's E and a new specimen's E as the per-trace rows report theirs
        (:meth:`at_inputs`: exp(mu) and exp(mu + tau·z) times :attr:`stated`, no budget, with
        the budget's interval around them), the numbers of ``pooled.csv`` and
        ``comparison.csv`` alike.  Keys ``E``, ``E_lo``, ``E_hi``, ``E_new``, ``E_new_lo``,
        ``E_new_hi``."""
        out = {}
        for key, with_budget in (("E", self.E), ("E_new", self.E_new)):
            med, lo, hi = self.at_inputs(with_budget, level)
            out.update({key: med, f"{key}_lo": lo, f"{key}_hi": hi})
        return out

    @property
    def E_stat(self) -> np.ndarray:
        """[Pa] exp(mu): the material's median modulus without the budget."""
        return np.exp(self.posterior.mu)

    @property
    def E_mean(self) -> np.ndarray:
        """[Pa] Population-mean modulus exp(mu + tau²/2)·f."""
        return np.exp(self.posterior.mu + 0.5 * self.posterior.tau ** 2) * self.factor

    def row(self, level: float = LEVEL) -> dict:
        """One row of ``pooled.csv``: medians, sds and central ``level`` intervals; the moduli
        with the budget (E, E_mean, E_new) as :meth:`at_inputs` summarises them, the same
        numbers as ``comparison.csv``'s, their sd that of the draws with the budget."""
        p = self.posterior
        out = {"material": self.material, "tip": self.tip, "n_traces": p.n}
        for stem, unit, x in (("mu", "", p.mu), ("tau", "", p.tau),
                              ("E_stat", "_pa", self.E_stat), ("E", "_pa", self.E),
                              ("E_mean", "_pa", self.E_mean), ("E_new", "_pa", self.E_new),
                              ("factor", "", self.factor)):
            med, (lo, hi) = float(np.median(x)), central(x, level)
            if stem in ("E", "E_mean", "E_new"):
                med, lo, hi = self.at_inputs(x, level)
            out[f"{stem}{unit}"] = med
            out[f"{stem}_sd{unit}"] = float(np.std(x, ddof=1))
            out[f"{stem}_lo{unit}"] = lo
            out[f"{stem}_hi{unit}"] = hi
        d = p.diagnostics
        out.update({
            "m_spread": float(np.std(p.m, ddof=1)) if p.n > 1 else np.nan,
            "s_max": float(np.max(p.s)),
            "tau_prior_sd": p.tau_prior_sd,
            "rhat_max": d.rhat_max, "ess_min": d.ess_min,
            "tau_max": float(max(d.tau.values())), "n_steps": d.n_steps,
            "n_draws": int(p.mu.size), "converged": p.converged,
            **flag_columns("; ".join(d.problems())),
        })
        return out


# Many parameters: one group's repeated estimates (m, s), its labels, the data of its
# representative fit and the budget's inputs.
def pool_group(m, s, *, material: str = "", tip: str = "", data: FitData | None = None,
               z_surf: float | None = None, estar: float | None = None,
               budget: BudgetSpec | None = None, tau_prior_sd: float = TAU_PRIOR_SD,
               seed: int | None = 0, settings: SamplerSettings | None = None,
               p_bonded: float | None = None, base_ratio: float = 1.0) -> PooledEstimate:
    """Pool one group: stage-2 posterior, shared systematic factor and predictive draws.

    Parameters
    ----------
    m, s
        Per-trace Normal summaries of the statistical log E (log Pa).
    material, tip
        Labels carried into the result.
    data, z_surf, estar
        Representative trace's fitted points, median surface [m] and median E* [Pa]; when
        ``data`` is None or ``budget`` is None no systematic factor is applied (f = 1).
    budget
        Budget distributions (None: statistical only).
    tau_prior_sd
        Scale of the half-normal prior of tau.
    seed
        Seed; the stage-2 sampler, the factor draws and the predictive draws use independent
        children of it.
    settings
        emcee settings of stage 2.
    p_bonded, base_ratio
        A layer whose base was sampled: the traces' ``m`` are read as bonded (each free draw
        divided by ``base_ratio`` = E_free/E_bonded of the same curve), and the base, shared by
        the group, is drawn once per pooled draw — free with probability 1 − ``p_bonded``,
        then E is multiplied by ``base_ratio`` (a row ``base condition`` of the budget).
        None: no sampled base.
    """
    post_ss, factor_ss, pred_ss = np.random.SeedSequence(seed).spawn(3)
    post = sample_hierarchical(m, s, tau_prior_sd=tau_prior_sd,
                               seed=int(post_ss.generate_state(1)[0]), settings=settings)
    n = post.mu.size
    var_mu = float(np.var(post.mu))
    rows = [{"input": "mu (pooled posterior)",
             "distribution": f"hierarchical posterior of {post.n} trace(s)", "var_log": var_mu}]
    if data is not None and budget is not None:
        if z_surf is None or estar is None:
            raise InputError("the budget needs the representative trace's z_surf and E*")
        factor, tab, nu = systematic_factor(data, z_surf, estar, budget, n,
                                            np.random.default_rng(factor_ss))
        rows += tab.to_dict("records")
    else:
        factor, nu = np.ones(n), None
    f_base = None
    if p_bonded is not None:
        free = np.random.default_rng(factor_ss.spawn(1)[0]).random(n) >= p_bonded
        f_base = np.where(free, base_ratio, 1.0)
        factor = factor * f_base
        rows.append({"input": "base condition",
                     "distribution": f"bonded {p_bonded:.3g} / free {1 - p_bonded:.3g} "
                                     f"(E x {base_ratio:.3g} if free)",
                     "var_log": float(np.var(np.log(f_base)))})
    table = pd.DataFrame(rows)
    total = float(table["var_log"].sum())
    table["rel_sd_pct"] = 100.0 * np.sqrt(table["var_log"])
    table["share_pct"] = 100.0 * table["var_log"] / total if total > 0 else np.nan
    table = table[["input", "distribution", "rel_sd_pct", "share_pct"]]
    rng = np.random.default_rng(pred_ss)
    E = np.exp(post.mu) * factor
    E_new = np.exp(post.log_predictive(rng)) * factor
    return PooledEstimate(material=material, tip=tip, posterior=post, factor=factor, E=E,
                          E_new=E_new, budget=table, nu=nu, base=f_base)
