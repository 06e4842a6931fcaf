"""What an online estimate cannot vouch for: the flags of a state, and the model checks.

:func:`state_flags` are the flags of an update's state (:attr:`OnlineState.flags
<palpbayes.online.state.OnlineState.flags>`): the force's unit
(:func:`palpbayes.forcescale.force_scale_flag`), a surface posterior at the lower end of its
prior, a grid refinement cut short, a relaxing hold, samples not kept, the noise correlation at
the end of its grid.

The online estimate's model is elastic.  On a viscoelastic material the estimate is the
apparent modulus of the speed and depth pressed so far (it grows with speed, ~speed^alpha for
a power law), and a hold shows what the model leaves out: when the tip has held its deepest
point (within :data:`HOLD_TOLERANCE` of the depth) for two windows of :data:`HOLD_WINDOW`
samples and the force of the last window lies more than :data:`RELAX_N_SE` standard errors
(AR(1) long-run factor of the baseline's lag-one correlation) and 1 % of the contact force
below the first, the state carries a relaxation flag naming the viscoelastic fit
(``palpbayes fit --rheology``; :func:`relaxation_flag`).

:func:`model_checks` runs the offline fit's adequacy checks (:mod:`palpbayes.checks`) on the
samples kept, at most :data:`CHECK_SAMPLES` of them, thinned evenly beyond (the lag-one
correlation of the noise taken to the stride's power): their posterior-predictive check holds
~8 kB per sample.  The estimator that asks for them is
:class:`palpbayes.online.estimator.OnlineEstimator`; the samples it keeps,
:mod:`palpbayes.online.samples`.
"""

from __future__ import annotations

import math

import numpy as np

from ..baseline import Baseline
from ..bayes.exact import ExactPosterior
from ..bayes.mixture import MixtureSummary
from ..checks import CheckResult, run_checks
from ..errors import InputError
from ..fitdata import ModelSpec
from ..forcescale import force_scale_flag
from ..intervals import central
from .samples import KeptSamples

__all__ = ["HOLD_WINDOW", "HOLD_TOLERANCE", "RELAX_N_SE", "CHECK_SAMPLES", "state_flags",
           "relaxation_flag", "model_checks"]

#: Samples per window of the relaxation flag (the first and the last of a hold).
HOLD_WINDOW = 20
#: A hold: the tip within this share of the depth reached from its deepest point.
HOLD_TOLERANCE = 0.01
#: Standard errors by which the force must fall over a hold to be flagged.
RELAX_N_SE = 5.0
#: Most samples the model checks run on, thinned evenly beyond (their posterior-predictive
#: check held 3.2 GB for 400,000 samples).
CHECK_SAMPLES = 20_000


def state_flags(post: ExactPosterior, E: MixtureSummary, zs: MixtureSummary, model: ModelSpec,
                base: Baseline, noise_pp: float | None, kept: KeptSamples, contact: int
                ) -> list[str]:
    """The flags of an update's state (module docstring), the force's unit first.

    ``post`` is the posterior, ``E`` [Pa] and ``zs`` [m] its summaries of E and the surface
    height; ``base`` the pre-contact baseline, ``noise_pp`` [N] the sensor's noise as given
    (None: the baseline's); ``kept`` the samples kept, ``contact`` the index of the first in
    contact among them."""
    flags = []
    z_lo, z_top = post.prior.z_bounds
    if zs.lo - z_lo < 0.01 * (z_top - z_lo):
        flags.append("z_surf posterior at the lower end of the online surface prior")
    if not post.complete:
        flags.append("surface grid refinement cut short")
    t, z, f = kept.arrays()
    relax = relaxation_flag(t[contact:], z[contact:], f[contact:], base, zs.median)
    if relax:
        flags.append(relax)
    # the force's unit, weighed once E is known to within a factor of about 1.5
    scale = force_scale_flag(model.tip, zs.median - float(z.min()), E.median,
                             base.noise_pp if base.reliable else None,
                             noise_pp) if E.rel_half_width < 0.5 else None
    if scale:
        flags.insert(0, scale)
    unkept = kept.unkept_flag()
    if unkept:
        flags.append(unkept)
    if post.phi.size > 1:
        w_phi = np.exp(post.log_mass - post.log_mass.max()).sum(axis=0)
        if w_phi[[0, -1]].max() > 0.5 * w_phi.sum():
            flags.append("noise correlation phi at the end of its grid: the residuals wander "
                         "like drift, or the noise is correlated beyond the prior's ±0.99")
    return flags


def relaxation_flag(t: np.ndarray, z: np.ndarray, f: np.ndarray, base: Baseline,
                    z_surf: float) -> str:
    """The relaxation flag of a hold (module docstring), '' when there is none.

    ``t`` [s], ``z`` [m], ``f`` [N]: the samples kept from the contact on; ``base`` the
    pre-contact baseline; ``z_surf`` [m] the surface height (the posterior median)."""
    w = HOLD_WINDOW
    if z.size < 2 * w:
        return ""
    depth = z_surf - float(z.min())
    if not depth > 0:
        return ""
    near = z <= z.min() + HOLD_TOLERANCE * depth
    first = int(np.argmax(near))
    if z.size - first < 2 * w or not near[first:].all():
        return ""
    f = f[first:]
    a, b = float(f[:w].mean()), float(f[-w:].mean())
    lag = min(max(base.lag1, 0.0), 0.9) if math.isfinite(base.lag1) else 0.0
    se = base.sd * math.sqrt(2.0 / w * (1 + lag) / (1 - lag))
    contact = a - base.level
    drop = a - b
    if not (drop > RELAX_N_SE * se and drop > 0.01 * contact):
        return ""
    held = float(t[-1] - t[first])
    return (f"relaxation: the force fell {100 * drop / contact:.1f} % of the contact force "
            f"({drop / se:.0f} se) over the {held:.3g} s the tip held its depth: the "
            "material is viscoelastic and this E is an apparent modulus of the speed "
            "pressed (fit the recording with palpbayes fit --rheology power-law,sls)")


def model_checks(post: ExactPosterior, z: np.ndarray, f: np.ndarray, model: ModelSpec,
                 base: Baseline, z_ref: float, level: float, seed: int = 0
                 ) -> list[CheckResult]:
    """The offline fit's adequacy checks (:func:`palpbayes.checks.run_checks`: exponent,
    residual structure, depth consistency, posterior-predictive) on the samples ``z`` [m],
    ``f`` [N], at most :data:`CHECK_SAMPLES` of them, thinned evenly beyond (the last always
    in, the noise's lag-one correlation taken to the stride's power), at the posterior
    medians of ``post``, graded against the statistical interval of E* at ``level``.

    ``base`` is the pre-contact baseline (its lag-one correlation, when reliable), ``z_ref``
    [m] the highest sample (the surface prior's top).

    Returns
    -------
    list of CheckResult
        Empty when the samples are too few for the checks.
    """
    draws = post.draws(np.random.default_rng(seed), 1000)
    med = {k: float(np.median(v)) for k, v in draws.items()}
    lo, hi = central(draws["E_star"], level)
    lag1 = base.lag1 if base.reliable else None
    n = z.size
    stride = -(-n // CHECK_SAMPLES)
    rows = slice(None, n) if stride == 1 else np.arange(n - 1, -1, -stride)[::-1]
    if lag1 is not None and stride > 1:
        lag1 = lag1 ** stride  # AR(1): the correlation at lag k is phi^k
    try:
        return run_checks(z[rows], f[rows], model, z_surf=med["z_surf"], estar=med["E_star"],
                          f0=med["F0"], sigma=med["sigma"], draws=draws, baseline_lag1=lag1,
                          baseline="constant", z_ref=z_ref, rng=seed,
                          stat_rel_halfwidth=0.5 * (hi - lo) / med["E_star"])
    except InputError:
        return []
