"""Multi-palpation stiffening: E(t) = c1·e^(c2·t) + c3·e^(c4·t) versus rest time t.

The law and its numbers: docs/design.md §2.

Repeated palpation of foam without rest stiffens it; the paper describes the modulus measured
after a rest t [s] since the previous excitation by a sum of two exponentials.  This package fits
that law to per-trace estimates E_i ± s_i, Bayesian with emcee, and says whether the data can
tell the two exponentials apart.

Modules: :mod:`.model` (the three laws, their priors and posterior), :mod:`.sampler` (maximum
likelihood and emcee for one law), :mod:`.selection` (the checks that choose the law, the
message), :mod:`.result` (:class:`StiffeningResult`) and :mod:`.fit` (:func:`fit_stiffening`,
:func:`fit_stiffening_summary`).  The public names of each are imported here.
"""

from . import fit, model, result, selection
from .fit import *  # noqa: F403 - the names in fit.__all__
from .model import *  # noqa: F403
from .result import *  # noqa: F403
from .selection import *  # noqa: F403

__all__ = [*fit.__all__, *result.__all__, *model.__all__, *selection.__all__]
