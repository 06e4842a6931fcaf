"""The methods text of the report: models, priors, least squares, the sampler's stopping rule,
the budget, pooling and the ground truth, with the numbers of the run (``settings.json``,
``pooled.csv``, ``groundtruth_summary.csv``) and of the package.

Text only (lines of (style, text), see :func:`palpbayes.reporting.layout._text_lines`); the page
that draws it is :mod:`palpbayes.reporting.pages_methods`.
"""

from __future__ import annotations

import pandas as pd

from ..bayes.sampler import MOVES
from ..campaign.results import ResultsFolder
from ..sensor_noise import PAPER_NOISE_PP
from ..units import format_length
from .format import force_setting, wrap

__all__ = ["MOVES_TEXT", "PRIORS_TABLE", "sampler_settings", "methods_lines"]

#: What each ``SamplerSettings.moves`` value means (emcee moves).
MOVES_TEXT = MOVES  # description of each move schedule, defined beside the sampler

#: The priors of the per-trace model (:mod:`palpbayes.bayes.priors`, defaults of
#: :class:`~palpbayes.bayes.priors.PriorSpec`) as the monospaced lines of the methods page:
#: parameter, then its prior.  Keep in step with the priors module when they change.
PRIORS_TABLE: tuple[str, ...] = (
    "log_Estar     ln(E*/Pa).  Uniform on [ln 1 Pa, ln 1e12 Pa] by default: the scale-free",
    "                  (Jeffreys) prior 1/E* truncated to twelve decades, so kPa foams and kPa "
    "cells",
    "                  measured in µm/nN units (converted to SI) are both inside.",
    "z_surf        [m] Uniform over the whole loading range [z_min, z_top]: the likelihood,",
    "                  with the free offset, places the surface ('soft': plus the paper's",
    "                  constraint as a soft penalty).  Walkers start at every profile mode.",
    "log_sigma     ln(sigma/N).  Normal(ln(pp/6), 1): centred on the noise spec (given, or",
    "                  the pre-contact baseline's) read as ±3 sigma; a factor e is 1 sd.",
    "F0            [N] Force offset, Normal(b, F_unc), b the pre-contact baseline level:",
    "                  an untared sensor is normal input.",
    "F1            (linear baseline only) [N/m] slope, Normal(0, rise/span).",
    "phi           (AR(1) only) lag-one correlation, Uniform(−0.99, 0.99).",
    "log_nu_t      (Student-t only) ln of the degrees of freedom, Uniform(ln 2, ln 200).",
)


def layer_setting_text(o: dict) -> str:
    """How a run treated the specimen's thickness, in words (from ``settings.json``)."""
    layer = o.get("layer", "auto" if o.get("thickness_correction") else "off")
    bonding = o.get("bonding", "unknown")
    base = {"bonded": "bonded to its base", "free": "lying free on its base",
            "unknown": "bonded or free, weighted by the data"}.get(bonding, bonding)
    if layer == "off":
        return "half-space everywhere (the paper's model)"
    if layer == "unknown":
        return (f"a layer of unknown thickness (log-uniform prior) or none, {base} (Bayesian "
                "rows; least squares: the paper's half-space)")
    specimen = o.get("specimen")
    block = ""
    if specimen:
        block = (" (the --specimen block's finite-element twin for every trace without a "
                 "footprint of its own)")
    platens = o.get("platens", "unknown")
    return (f"a layer on a rigid base wherever the thickness is known (exact layer solution: "
            f"Hayes et al. 1972, Dimitriadis et al. 2002), and the block's finite-element twin "
            f"wherever its footprint is known as well (docs/design.md §9; E_instron for "
            f"{platens} platens){block}, {base} (Bayesian rows; least squares: the paper's "
            "half-space, with the layer's or twin's effect in E_bonded/E_free)")


def sampler_settings(recorded: dict | None) -> tuple[dict, bool]:
    """Sampler settings as a dict: the recorded ones (``settings.json``) completed by the
    package defaults; the flag says whether anything came from the defaults."""
    from dataclasses import asdict

    from ..bayes.sampler import SamplerSettings

    default = asdict(SamplerSettings())
    rec = dict(recorded or {})
    missing = any(k not in rec for k in ("n_walkers", "max_steps", "min_steps", "check_every",
                                         "tau_factor", "tau_rtol", "moves"))
    return {**default, **{k: v for k, v in rec.items() if v is not None}}, missing


def _stopping_rule(smp: dict) -> str:
    """The sampler's stopping rule in words, with the numbers of ``smp``."""
    from ..bayes.diagnostics import ESS_MIN, RHAT_MAX

    moves = str(smp.get("moves"))
    return (
        f"emcee, {int(smp['n_walkers'])} walkers, moves: {MOVES_TEXT.get(moves, repr(moves))}. "
        f"Stopping rule: every {int(smp['check_every'])} steps after {int(smp['min_steps'])}, "
        f"stop when the chain is longer than {float(smp['tau_factor']):g} × the integrated "
        "autocorrelation time (tau) of every parameter, tau changed by less than "
        f"{100 * float(smp['tau_rtol']):g} % since the last check, and the post-burn-in "
        f"chain has bulk and tail ESS ≥ {ESS_MIN:.0f} for every parameter, with max R-hat ≤ "
        f"{RHAT_MAX:g} over every parameter and the log posterior as a guard — or at "
        f"{int(smp['max_steps'])} steps (then flagged). Burn-in 2·max tau, thinning "
        "floor(min tau / 2)."
    )


def _pooling_text(res: ResultsFolder) -> str:
    """Pooling paragraph: sampler from :data:`palpbayes.pooling.POOLING_SETTINGS`, the tau
    prior scale from ``pooled.csv`` (else :data:`palpbayes.pooling.TAU_PRIOR_SD`)."""
    from dataclasses import asdict

    from ..pooling import POOLING_SETTINGS, TAU_PRIOR_SD

    scales: list[float] = []
    if res.pooled is not None and "tau_prior_sd" in res.pooled:
        scales = sorted(set(pd.to_numeric(res.pooled["tau_prior_sd"], errors="coerce")
                            .dropna().astype(float)))
    prior = ", ".join(f"{v:g}" for v in scales) if scales else f"{TAU_PRIOR_SD:g}"
    smp = asdict(POOLING_SETTINGS)
    return (
        "Per material × tip: log E_i ~ Normal(mu, tau²), fitted in two stages (Lunn et al. "
        "2013): each trace's statistical posterior of log E summarised as Normal(m_i, s_i²), "
        f"then (mu, log tau) sampled with {_stopping_rule(smp)} Flat prior on mu, "
        f"tau ~ HalfNormal({prior}) on the log-E scale. The systematic budget inputs are "
        "shared by the traces of a group and applied once to the pooled draws. 'New "
        "specimen' is the posterior predictive exp(mu + tau·z)·f, the quantity to compare "
        "with the Instron mean ± sd.")


def methods_lines(res: ResultsFolder) -> list[tuple[str, str]]:
    from ..contact import registered_laws
    from ..lsq import GRID_POINTS

    o = res.options
    W = 150
    smp, from_defaults = sampler_settings(o.get("settings"))
    frac = o.get("fit_fraction")
    skipped = [f"{100 * law.default_fit_fraction:g} % of a {law.label}'s"
               for law in registered_laws() if law.default_fit_fraction > 0]
    if frac is None and skipped:
        window = (f"Fit window: the paper's default, the first {' and '.join(skipped)} "
                  "penetration is not fitted (non-linear start of contact), every sample in "
                  "contact for the other tips.")
    elif frac is None:
        window = "Fit window: every sample in contact, for every tip."
    else:
        window = (f"Fit window: the first {100 * float(frac):g} % of the penetration is not "
                  "fitted, for every tip (fit_fraction option of this run).")
    if o.get("max_depth") is not None:
        window += (f" Only samples shallower than {format_length(float(o['max_depth']), 6)} "
                   "are fitted.")
    lines: list[tuple[str, str]] = [("h", "Contact models (docs/design.md §1)")]
    lines += [("t", ln) for ln in wrap(
        "Rigid axisymmetric tip on an elastic half-space, F = E*·s(d) with E* = E/(1 − nu²) and "
        "depth d = z_surf − z_tip (F = 0 for d ≤ 0). "
        + " ".join(law.summary for law in registered_laws())
        + " Finite thickness: " + layer_setting_text(o) + ".", W)]
    lines += [("h", "Least-squares baseline (the paper's eqs. 12–13)")]
    lines += [("t", ln) for ln in wrap(
        "Minimise L = Σ (F_j − k·d_j^m)² over k and z_surf subject to |F(z_surf)| ≤ F_unc "
        f"(F_unc = {force_setting(o.get('f_unc', PAPER_NOISE_PP))}; measured from the pre-contact "
        "level when the sensor was not tared, with a note in the row): for fixed z_surf E* has "
        f"a closed form; z_surf by a {GRID_POINTS}-point grid and bounded Brent search over the "
        "admissible range. Interval: Gauss-Newton covariance of (E*, z_surf) from the "
        "residuals, E ± t(0.95, n − 2)·sd — the textbook interval, assuming iid residuals and "
        f"ignoring the constraint. {window}", W)]
    lines += [("h", "Bayesian model per trace")]
    lines += [("t", ln) for ln in wrap(
        f"F_j = E*·s(z_surf − z_j) + F0 + e_j, noise model '{o.get('noise', 'gaussian')}' "
        "(gaussian: iid Normal(0, sigma); ar1: stationary AR(1) with marginal sd sigma; "
        f"student: Student-t). Sampled with {_stopping_rule(smp)}"
        + (" (Sampler settings not recorded in settings.json: package defaults shown.)"
           if from_defaults else "")
        + " Convergence is checked with arviz-stats (rank-normalised split R-hat, bulk and tail "
        "ESS, walkers as chains); a fit that fails is flagged in every table. Priors "
        "(palpbayes.bayes.priors):", W)]
    lines += [("m", ln) for ln in PRIORS_TABLE]
    lines += [("h", "Uncertainty budget (GUM Supplement 1)")]
    lines += [("t", ln) for ln in wrap(
        "Inputs a trace cannot identify are propagated by Monte Carlo, one input draw per "
        "posterior draw: E = E*·(1 − nu²)·f_R/g_F·f_C with the Poisson ratio nu, the tip-radius "
        "tolerance f_R, the force-sensor gain g_F and a series compliance f_C (distributions on "
        "the budget page). Shares are each input's part of the variance of ln E.", W)]
    lines += [("h", "Pooling of repeated indentations")]
    lines += [("t", ln) for ln in wrap(_pooling_text(res), W)]
    gt = res.groundtruth_summary
    if gt is not None and "window_lo" in gt:
        win = (f"{100 * float(gt['window_lo'].iloc[0]):g}–"
               f"{100 * float(gt['window_hi'].iloc[0]):g} %")
    else:
        from ..compression import DEFAULT_STRAIN_WINDOW

        win = (f"{100 * DEFAULT_STRAIN_WINDOW[0]:g}–{100 * DEFAULT_STRAIN_WINDOW[1]:g} % "
               "(default)")
    lines += [("h", "Ground truth")]
    lines += [("t", ln) for ln in wrap(
        "Uniaxial compression (Instron exports): engineering stress vs strain, straight line "
        f"sigma = E·(eps − eps0) fitted over the toe-compensated strain window {win}; the "
        "material's ground truth is the mean ± sd (ddof 1) over its specimens.", W)]
    return lines
