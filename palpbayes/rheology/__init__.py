"""Viscoelastic palpation: the whole recorded cycle fitted with a relaxation modulus.

One module per job, imports flowing one way (``results`` -> ``store``, ``choice`` -> ``fit`` ->
``posterior`` -> ``cycle`` -> ``design`` -> ``kernels``; ``posterior``, ``fit`` -> ``ting`` ->
``design``, ``kernels``;
``fit`` -> ``compression``; ``pool`` -> ``fit``, ``posterior``; ``campaign`` -> ``pool``;
``sampler`` -> ``column_table`` -> ``posterior``; ``fit`` -> ``sampler``, ``flags`` ->
``offcontact``):

* :mod:`~palpbayes.rheology.cycle` -- the samples a viscoelastic fit sees: the chosen
  segments, block means, the knots of the motion, the pre-contact baseline and the surface
  range;
* :mod:`~palpbayes.rheology.design` -- the Lee–Radok hereditary integral as regression
  columns, block means of the force for every trial surface at once;
* :mod:`~palpbayes.rheology.kernels` -- the relaxation kernels (power law, exponential
  branch, constant) and their integrals per unit modulus, at lags a record fixes;
* :mod:`~palpbayes.rheology.ting` -- Ting's rule on the retract as regression columns (power
  law: t1 depends on alpha and the motion only, so the force stays linear in E0*);
* :mod:`~palpbayes.rheology.posterior` -- the collapsed posterior on a (surface × alpha or
  tau) grid: moduli, offset and noise integrated in closed form, draws;
* :mod:`~palpbayes.rheology.sampler` -- the same posterior sampled by emcee, every parameter
  explicit (exact AR(1) likelihood, the columns tabulated once), started from the grid's
  draws: :func:`sample_emcee`, the check that the collapse is right;
* :mod:`~palpbayes.rheology.column_table` -- the regression columns tabulated on a
  Chebyshev grid in (theta, surface) for the chain;
* :mod:`~palpbayes.rheology.offcontact` -- what the force out of contact shows: a drag gap,
  a tilted baseline, adhesion at pull-off;
* :mod:`~palpbayes.rheology.adhesion` -- an adhesive pull-off found on the retract and cut
  out before the fit (``adhesion="cut"``, ``--adhesion cut``);
* :mod:`~palpbayes.rheology.peer` -- a trace read as a peer's fit reads it
  (``--peer-compatible pyfmrheo``: straight ramps, its fixed drag), to compare like for like;
* :mod:`~palpbayes.rheology.flags` -- the flags of a fit in words;
* :mod:`~palpbayes.rheology.fit` -- :func:`fit_rheology`, its result and table;
* :mod:`~palpbayes.rheology.choice` -- which relaxation model a record prefers (PSIS-LOO,
  with the standard error of the difference);
* :mod:`~palpbayes.rheology.compression` -- the modulus a compression test at a chosen
  speed would report for the fitted relaxation modulus (the ground truth's own rule);
* :mod:`~palpbayes.rheology.pool` -- one material at several speeds: the power law's
  (E0*, alpha) pooled over palpations;
* :mod:`~palpbayes.rheology.results` -- many traces into ``rheology.csv`` (``palpbayes fit
  --rheology``);
* :mod:`~palpbayes.rheology.campaign` -- a manifest's traces of one specimen and tip at
  several speeds pooled into ``rheology_pooled.csv`` (``fit MANIFEST --rheology power-law``);
* :mod:`~palpbayes.rheology.store` -- one fit's draws, force band and E*(t) band in
  ``rheology/<trace_id>_<rheology>.nc``, read back for the report without refitting.

The hereditary integral itself (Lee–Radok and Ting on a measured time axis, the closed forms)
is :mod:`palpbayes.contact.viscoelastic`; it checks the regression columns here.
"""

from __future__ import annotations

from . import (
    adhesion,
    campaign,
    choice,
    column_table,
    compression,
    cycle,
    design,
    fit,
    flags,
    kernels,
    offcontact,
    peer,
    pool,
    posterior,
    results,
    sampler,
    store,
    ting,
)
from .adhesion import *  # noqa: F403
from .campaign import *  # noqa: F403
from .choice import *  # noqa: F403
from .column_table import *  # noqa: F403
from .compression import *  # noqa: F403
from .cycle import *  # noqa: F403
from .design import *  # noqa: F403
from .fit import *  # noqa: F403
from .flags import *  # noqa: F403
from .kernels import *  # noqa: F403
from .offcontact import *  # noqa: F403
from .peer import *  # noqa: F403
from .pool import *  # noqa: F403
from .posterior import *  # noqa: F403
from .results import *  # noqa: F403
from .sampler import *  # noqa: F403
from .store import *  # noqa: F403
from .ting import *  # noqa: F403

__all__: list[str] = []
__all__ += choice.__all__
__all__ += column_table.__all__
__all__ += compression.__all__
__all__ += cycle.__all__
__all__ += design.__all__
__all__ += kernels.__all__
__all__ += posterior.__all__
__all__ += fit.__all__
__all__ += flags.__all__
__all__ += offcontact.__all__
__all__ += pool.__all__
__all__ += results.__all__
__all__ += sampler.__all__
__all__ += store.__all__
__all__ += campaign.__all__
__all__ += ting.__all__
__all__ += adhesion.__all__
__all__ += peer.__all__

