"""Bayesian model of one indentation trace, sampled with emcee (docs/design.md §3).

>>> from palpbayes.bayes import fit_bayes                       # doctest: +SKIP
>>> result = fit_bayes(trace, noise="gaussian", seed=1)         # doctest: +SKIP
>>> result.summary()                                            # doctest: +SKIP
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import lazy_exports

if TYPE_CHECKING:  # the same names, for static tools
    from .budget import Budget, BudgetSpec, propagate
    from .diagnostics import ESS_MIN, RHAT_MAX, Diagnostics
    from .fit import fit_bayes, fit_bayes_data
    from .likelihood import TraceLikelihood
    from .noisemodels import NOISE_MODELS, NOISE_REGISTRY, NoiseModel
    from .priors import PriorSpec, param_names
    from .result import LEVEL, BayesResult
    from .sampler import SamplerSettings

#: Public name -> the submodule that defines it; imported on first use (PEP 562), so that
#: importing one submodule (e.g. :mod:`.priors` for its names) does not load the sampler.
_LAZY = {
    "Budget": "budget", "BudgetSpec": "budget", "propagate": "budget",
    "ESS_MIN": "diagnostics", "RHAT_MAX": "diagnostics", "Diagnostics": "diagnostics",
    "fit_bayes": "fit", "fit_bayes_data": "fit", "TraceLikelihood": "likelihood",
    "NOISE_MODELS": "noisemodels", "NOISE_REGISTRY": "noisemodels",
    "NoiseModel": "noisemodels", "PriorSpec": "priors", "param_names": "priors",
    "LEVEL": "result", "BayesResult": "result", "SamplerSettings": "sampler",
}

__all__ = [
    "fit_bayes", "fit_bayes_data", "BayesResult", "PriorSpec", "BudgetSpec", "Budget",
    "SamplerSettings", "TraceLikelihood", "Diagnostics", "propagate", "param_names",
    "NOISE_MODELS", "NOISE_REGISTRY", "NoiseModel", "RHAT_MAX", "ESS_MIN", "LEVEL",
]


__getattr__, __dir__ = lazy_exports(__name__, _LAZY)
