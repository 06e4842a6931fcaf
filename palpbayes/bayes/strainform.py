"""The model form's finite-strain alternative: the neo-Hookean reading of a linear fit.

A linear fit of a trace pressed deep enough for finite strain to matter (the strain measure
a/R of a curved tip or d/a of a flat punch, :func:`palpbayes.twin.hyper_correction.
strain_measure`, at least :data:`NONLINEAR_STRAIN`) is read again with the compressible
neo-Hookean solid at the same nu and geometry: the linear model's shape times the neo-Hookean
half-space's F_NH/F_linear (:mod:`palpbayes.twin.hyper_correction`, a shipped table: no finite
elements at fit time), by the exact engine on the same data and prior.  E moves by the ratio of
the two statistical medians of E*, applied to the fit's budget draws (the alternative's
interval is the fitted one's, moved).  It enters E's full interval (:mod:`.modelform`, the
envelope) when the data favour it over the fitted linear law (its evidence under the 1/E*
prior at least :data:`NONLINEAR_ODDS` times the linear model's, "strong evidence" on Kass &
Raftery's scale, J. Am. Stat. Assoc. 90 (1995) 773: the models the data allow, docs/design.md
§11) and it moves E by more than half the statistical interval, whether or not a model check
fails.  Measured: on the 200 well-specified calibration traces (linear, 960 samples, nu 0.45,
3 mm deep, the reading 2 % away) ln odds at most +2.9 (median −2.3): none kept (odds 3 kept
17, odds 10 kept 5, each widening its interval by ~15 %); on neo-Hookean blocks (3,840
samples) ln odds 11 to 67 at nu 0.3 (every trace kept), −8 to +14 at nu 0.45, where the reading
moves E by 2 % and the budget covers it.  The neo-Hookean solid is one nonlinearity among many
(a foam softens where it stiffens): a law fit (``--law``) is the remedy, this alternative the
warning.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ..errors import PalpbayesError
from ..fitdata import FitData
from ..intervals import LEVEL, central
from .layers import log_evidence
from .modelform import Alternative, summarise
from .noisemodels import exact_noise
from .priors import PriorSpec

__all__ = ["nonlinear_alternative", "strain_reading", "NONLINEAR_STRAIN", "NONLINEAR_ODDS",
           "NEO_HOOKEAN"]

#: Name of the finite-strain alternative.
NEO_HOOKEAN = "neo-Hookean"
#: The neo-Hookean reading runs from this strain measure on (a/R of a curved tip, d/a of a
#: flat punch; a sphere pressed 1 % of its radius deep).
NONLINEAR_STRAIN = 0.1
#: The neo-Hookean reading is left out unless its evidence (under the 1/E* prior) is at least
#: these odds times the linear model's (strong evidence for it, Kass & Raftery 1995).
NONLINEAR_ODDS = 20.0


def nonlinear_alternative(data: FitData, E_total: np.ndarray, E_stat: np.ndarray,
                          z_surf: float, prior) -> Alternative | None:
    """The neo-Hookean reading of a linear fit (module docstring); None when it does not
    apply (a law already, a tip without the tabulated correction, a shallow trace, an exact
    engine that cannot run).

    Parameters
    ----------
    data
        The fitted data with the concrete linear model at the posterior's centre.
    E_total, E_stat
        [Pa] The fit's draws of E with the budget and at the stated inputs.
    z_surf
        [m] Its posterior median surface.
    prior
        A :class:`~palpbayes.bayes.priors.TracePrior` the exact engine takes (Gaussian or
        AR(1) noise, the 'loading' surface prior).
    """
    from ..twin.hyper_correction import has_correction, strain_measure
    from ..twin.hyper_shape import LawModel, table_depth
    from .exact import exact_posterior

    model = data.model
    depth = z_surf - float(np.min(data.z))
    if (model.law is not None or not model.is_concrete or not has_correction(model.tip)
            or not depth > 0 or not strain_measure(model.tip, depth) >= NONLINEAR_STRAIN):
        return None
    nh = replace(model, law=LawModel("neo-hookean", depth=table_depth(depth),
                                     mode="correction"))
    try:
        lin = exact_posterior(data, prior)
        alt = exact_posterior(replace(data, model=nh), prior)
    except (PalpbayesError, ValueError, np.linalg.LinAlgError):
        return None
    ratio = alt.estar_summary().median / lin.estar_summary().median
    odds = log_evidence(alt) - log_evidence(lin)
    out = summarise(NEO_HOOKEAN, np.ravel(E_total) * ratio, LEVEL)
    lo, hi = central(np.ravel(E_stat), LEVEL)
    why = []
    if odds < math.log(NONLINEAR_ODDS):
        why.append(f"the data do not favour it over the linear law (ln odds {odds:+.1f})")
    if abs(ratio - 1.0) * float(np.median(E_stat)) <= 0.5 * (hi - lo):
        why.append("within the statistical interval")
    return replace(out, plausible=not why, note=", ".join(why))



def strain_reading(fitted: FitData, post: dict, priors: PriorSpec, noise: str,
                   baseline: str) -> Alternative | None:
    """:func:`nonlinear_alternative` of a fit's posterior draws ``post`` on its concrete
    model's data ``fitted``, by the exact engine with the fit's noise where it can (Gaussian
    for Student-t) and the 'loading' surface prior."""
    exact = exact_noise(noise)
    prior = replace(priors, surface="loading").for_trace(fitted, exact, baseline)
    return nonlinear_alternative(fitted, post["E_total"], post["E"],
                                 float(np.median(post["z_surf"])), prior)
