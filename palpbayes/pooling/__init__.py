"""Hierarchical pooling: one material × tip estimate from the per-trace Bayesian posteriors.

Pooling is computation only: it reads posterior files but writes nothing and imports neither
the campaign code (:mod:`palpbayes.campaign`, which calls it from ``palpbayes compare``) nor
plotting.

Modules
-------
:mod:`~palpbayes.pooling.model`
    The two-stage model: per-trace Normal summaries of log E, emcee over (mu, tau), the shared
    systematic factor applied once to the pooled draws (:func:`pool_group`).
:mod:`~palpbayes.pooling.inputs`
    Its stage-1 inputs: reading a trace's posterior netCDF, its fitted points, and the draws of
    the systematic factor of the uncertainty budget.

The public names are the submodules' ``__all__``.
"""

from __future__ import annotations

from . import inputs, model
from .inputs import *  # noqa: F403
from .model import *  # noqa: F403

__all__ = [*model.__all__, *inputs.__all__]
