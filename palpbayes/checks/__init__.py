"""Model-adequacy checks of a contact fit (docs/design.md §3 point 7).

A 3,840-point trace pins E* to a fraction of a percent, so a fit can be statistically tight and
physically wrong.  Each check here compares the data with what the fitted contact law
F = E*·s(d) + F0 (+ F1·(z - z_ref)), d = z_surf - z, implies, and returns a
:class:`CheckResult` whose ``flag`` names the likely cause and the fix when it fails:

``exponent``
    Free power law F = k·d_+^m + F0 (+ F1·(z - z_ref)) fitted with z_surf and m free
    (:func:`free_exponent_fit`) against the law's own exponent on the same depths (1 flat,
    1.5 paraboloid, 2 cone; the local log-slope for the exact sphere or a thickness-corrected
    law).  Stiffening with depth (m too high) points at finite thickness, strain-stiffening
    or a sharper tip; softening at a blunter tip, series compliance or a soft start.
``residual_structure``
    Mean residual in depth bins (pre-contact and contact), chi² against the AR(1)-aware
    variance of a bin mean; the pattern names drift/tilt, a gradual onset/adhesion, or a
    wrong law shape.  Durbin-Watson and lag-1 autocorrelation of the residuals in depth order
    are reported.
``ppc``
    Posterior-predictive check (Gelman, Meng & Stern 1996): the same binned chi² as the
    discrepancy T(y, theta), replicated data drawn from the fitted noise model (iid or AR(1))
    at each posterior draw; p = P(T(y_rep) >= T(y)).
``depth_consistency``
    E* refitted on the shallower half of the depth (z_surf, E*, F0 free) against E* over
    all points; the standard error of the difference is the Hausman form
    sqrt(se_shallow² - se_all²) for nested efficient estimators (Hausman 1978).

``rate``
    When the recording goes on past the loading (a hold, a retract: :mod:`.rate`): the force's
    relaxation over the hold beyond what the elastic law gives for the depth, and E* of the
    retract against the approach, each beyond 5 standard errors.  It names rate dependence
    and the time-dependent fit (``--rheology``) as the remedy.

**Thresholds.**  Standard errors of a long trace are tiny, so every check fails only when a
statistical test *and* a physical effect size agree (:data:`THRESHOLDS`): exponent
|m - m_law| > 3 se and > 3 % of m_law; binned residual chi² p < 0.01 and the largest bin mean
> 0.2 sigma; posterior-predictive p < 0.01; depth consistency |E*_shallow/E*_all - 1| > 3 se
and > 5 %.  They were calibrated on simulated traces (``tests/unit/test_model_checks.py``).

**Effect on E and severity** (:mod:`.effect`).  Each check also says how much its failure
moves E (the free exponent's E at the mean depth, the shallow-half window ratio, E with the
alternative the residual pattern names) and grades a failure *negligible* (|effect| within
2 % or within the statistical 90 % interval) or *material*.  ``model_ok`` follows material
misfit; a negligible failure is an ``info:`` line with its effect.

**Correlated noise.**  800 Hz force noise is autocorrelated.  The variance of the mean of n
consecutive AR(1) samples with lag-1 coefficient phi and marginal sd sigma is
(sigma²/n)·[(1+phi)/(1-phi) - 2·phi·(1-phi^n)/(n·(1-phi)²)] (e.g. Box & Jenkins); standard
errors of fitted parameters are inflated by the long-run factor sqrt((1+phi)/(1-phi)).  phi is
the noise's own lag-1 autocorrelation, best taken from the pre-contact baseline
(:func:`noise_lag1`); without it, it is estimated from the residuals' first differences,
phi = 1 + 2·corr(Δr_t, Δr_(t-1)) (exact for AR(1), and blind to smooth misfit).

**Baseline reference.**  A linear baseline is F0 + F1·(z - z_ref) with z_ref = the highest z of
the fitted samples (the start of the approach) unless ``z_ref`` is given: F0 is then the force
where the approach starts.

Pure numpy/scipy, no plotting.  Inputs are the fitted samples in time order (loading segment).

Modules: :mod:`.core` (result type, thresholds, AR(1) factors, least-squares helpers),
:mod:`.exponent`, :mod:`.residuals`, :mod:`.ppc`, :mod:`.depth`, :mod:`.rate` (one check each) and
:mod:`.effect` (effect sizes, severity, the summary columns) and :mod:`.run`
(:func:`run_checks`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import lazy_exports

if TYPE_CHECKING:  # the same names, for static tools
    from .core import THRESHOLDS, CheckResult, ar1_mean_variance_factor, noise_lag1
    from .depth import depth_consistency_check
    from .effect import EFFECT_REL, checks_summary, grade_checks, material
    from .exponent import exponent_check, free_exponent_fit, law_exponent
    from .ppc import posterior_predictive_check
    from .rate import rate_dependence_check
    from .residuals import binned_residuals, residual_structure_check
    from .run import check_fit, run_checks

#: Public name -> the submodule that defines it; imported on first use (PEP 562), so that
#: e.g. :func:`checks_summary` does not load the posterior-predictive check (scipy.signal).
_LAZY = {
    "THRESHOLDS": "core",
    "CheckResult": "core",
    "ar1_mean_variance_factor": "core",
    "noise_lag1": "core",
    "depth_consistency_check": "depth",
    "EFFECT_REL": "effect",
    "checks_summary": "effect",
    "grade_checks": "effect",
    "material": "effect",
    "exponent_check": "exponent",
    "free_exponent_fit": "exponent",
    "law_exponent": "exponent",
    "posterior_predictive_check": "ppc",
    "rate_dependence_check": "rate",
    "binned_residuals": "residuals",
    "residual_structure_check": "residuals",
    "check_fit": "run",
    "run_checks": "run",
}

__all__ = [
    "CheckResult",
    "THRESHOLDS",
    "ar1_mean_variance_factor",
    "noise_lag1",
    "law_exponent",
    "free_exponent_fit",
    "exponent_check",
    "binned_residuals",
    "residual_structure_check",
    "posterior_predictive_check",
    "depth_consistency_check",
    "rate_dependence_check",
    "run_checks",
    "check_fit",
    "EFFECT_REL",
    "grade_checks",
    "material",
    "checks_summary",
]


__getattr__, __dir__ = lazy_exports(__name__, _LAZY)
