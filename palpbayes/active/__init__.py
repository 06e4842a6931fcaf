"""Active palpation: where to press next to find a lump with fewer presses.

:func:`next_presses` scores candidate presses on a :class:`SearchState` (the presses so far
and the specimen) by a stated criterion (:mod:`~.criteria`) against a fast grid posterior of
one lump or none (:mod:`~.posterior`), and says when to stop (:class:`StopRule`); the state's
files are :mod:`~.files`.
"""

from .posterior import LumpHypotheses, SearchPosterior, hypotheses, posterior
from .search import NextPresses, SearchState, StopRule, decide, next_presses

__all__ = ["LumpHypotheses", "SearchPosterior", "hypotheses", "posterior", "NextPresses",
           "SearchState", "StopRule", "decide", "next_presses"]
