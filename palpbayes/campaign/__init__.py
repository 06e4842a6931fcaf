"""Campaigns: fit every trace of a manifest into a results folder, read it back, compare.

A *results folder* is what ``palpbayes fit`` writes and ``compare``, ``groundtruth`` and
``report`` add to; every file name in it is owned by :mod:`~palpbayes.outputs`.

Modules, one job each
---------------------
:mod:`~palpbayes.outputs`
    The name of every file of a results folder (no other module spells one).
:mod:`~palpbayes.campaign.fitjob`
    One trace's fit (least squares and/or Bayes) and its ``summary.csv`` rows.
:mod:`~palpbayes.campaign.options`, :mod:`~palpbayes.campaign.tracemodel`
    :class:`FitOptions`; the contact model a trace is fitted with (its tip, nu and specimen:
    a half-space, a layer or the block's twin) and the twin's tables built before the fit.
:mod:`~palpbayes.campaign.source`
    Reading a campaign's traces (manifest or list) and ``traces.csv``.
:mod:`~palpbayes.campaign.settings`
    ``settings.json``: how a results folder was fitted.
:mod:`~palpbayes.campaign.partial`
    One trace inside a run (a worker's job) and its ``.partial/`` record for ``--resume``
    (internal to :mod:`~palpbayes.campaign.run`).
:mod:`~palpbayes.campaign.run`
    :func:`fit_campaign`: every trace over a process pool, resumable, into a results folder.
:mod:`~palpbayes.campaign.results`
    Reading a results folder back (:func:`load_results`) and one trace's fit
    (:func:`load_fit`, equal to the fit that was saved).
:mod:`~palpbayes.campaign.reference`
    What a campaign is compared with: the Instron ground truth and the paper's estimates.
:mod:`~palpbayes.campaign.comparison`, :mod:`~palpbayes.campaign.compare_text`
    Pooling per material × tip (:mod:`palpbayes.pooling`) and the comparison with the ground
    truth and the paper (``palpbayes compare``), and its text table.
:mod:`~palpbayes.campaign.instron`
    A pooled group's Instron-equivalent modulus beside the Instron, like for like.
:mod:`~palpbayes.campaign.stiffening_tables`, :mod:`~palpbayes.campaign.indentation`
    The compare step's stiffening law per group (parameters, E(t) band) and each trace
    replayed through the online estimator: the tables the report draws.
:mod:`~palpbayes.campaign.pipeline`
    Fit, ground truth and compare in one call (``palpbayes report CAMPAIGN``).

The package's public names are the ``__all__`` of the modules in :data:`API_MODULES`.  They are
imported on first use (PEP 562), so that importing :mod:`~palpbayes.outputs` or
:mod:`~palpbayes.campaign.reference` alone does not load the fitting code.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import lazy_modules

#: Submodules whose ``__all__`` make up the package's public names.
API_MODULES = ("fitjob", "source", "settings", "run", "results", "comparison", "compare_text",
               "instron", "pipeline", "stiffening_tables", "indentation")

if TYPE_CHECKING:  # the same names, for static tools
    from .compare_text import *  # noqa: F403
    from .comparison import *  # noqa: F403
    from .fitjob import *  # noqa: F403
    from .indentation import *  # noqa: F403
    from .instron import *  # noqa: F403
    from .pipeline import *  # noqa: F403
    from .results import *  # noqa: F403
    from .run import *  # noqa: F403
    from .settings import *  # noqa: F403
    from .source import *  # noqa: F403
    from .stiffening_tables import *  # noqa: F403


__getattr__, __dir__ = lazy_modules(__name__, API_MODULES)
