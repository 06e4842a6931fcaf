"""Bayesian model of one indentation trace, sampled with emcee (docs/design.md §3).

>>> from palpbayes.bayes import fit_bayes                       # doctest: +SKIP
>>> result = fit_bayes(trace, noise="gaussian", seed=1)         # doctest: +SKIP
>>> result.summary()                                            # doctest: +SKIP
"""

from .budget import Budget, BudgetSpec, propagate
from .diagnostics import ESS_MIN, RHAT_MAX, Diagnostics
from .fit import fit_bayes, fit_bayes_data
from .likelihood import TraceLikelihood
from .priors import NOISE_MODELS, PriorSpec, param_names
from .result import LEVEL, BayesResult
from .sampler import SamplerSettings

__all__ = [
    "fit_bayes", "fit_bayes_data", "BayesResult", "PriorSpec", "BudgetSpec", "Budget",
    "SamplerSettings", "TraceLikelihood", "Diagnostics", "propagate", "param_names",
    "NOISE_MODELS", "RHAT_MAX", "ESS_MIN", "LEVEL",
]
