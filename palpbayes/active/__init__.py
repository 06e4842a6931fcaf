"""Active palpation: where to press next to find a lump with fewer presses.

:func:`next_presses` scores candidate presses on a :class:`SearchState` (the presses so far
and the specimen) by a stated criterion (:mod:`~.criteria`) against a fast grid posterior of
one lump or none (:mod:`~.posterior`), and says when the search has decided
(:class:`SearchStopRule`; the online estimator's :class:`~palpbayes.online.StoppingRule` says
when to stop one press); the state's files are :mod:`~.files`.  With a set of press depths
(:mod:`~.depth`) a press is (x, y, depth), chosen by the information per second.
"""

import warnings

from .depth import PressDepths
from .posterior import LumpHypotheses, SearchPosterior, hypotheses, posterior
from .search import NextPresses, SearchState, SearchStopRule, decide, next_presses

__all__ = ["LumpHypotheses", "SearchPosterior", "hypotheses", "posterior", "NextPresses",
           "SearchState", "SearchStopRule", "decide", "next_presses", "PressDepths"]


def __getattr__(name: str):
    """``StopRule``, the old name of :class:`SearchStopRule` (with a DeprecationWarning)."""
    if name == "StopRule":
        warnings.warn("palpbayes.active.StopRule is now SearchStopRule (when the search has "
                      "decided; palpbayes.StoppingRule is when to stop one press)",
                      DeprecationWarning, stacklevel=2)
        return SearchStopRule
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
