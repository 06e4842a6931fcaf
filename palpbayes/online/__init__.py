"""Online estimation: the posterior of E while the tip is pressing, and when to stop.

>>> from palpbayes.online import OnlineEstimator, StoppingRule      # doctest: +SKIP
>>> est = OnlineEstimator(ModelSpec(tip), rule=StoppingRule(target=0.02))  # doctest: +SKIP
>>> for t, z, f in chunks:                                          # doctest: +SKIP
...     if est.update(t, z, f).should_stop:
...         break

:mod:`.estimator` holds the estimator, :mod:`.state` what an update says and the stopping rule
(re-exported by :mod:`.estimator`), :mod:`.samples` the samples it keeps, :mod:`.surface` its
posterior over the surface height, :mod:`.full_interval` E with the uncertainty budget,
:mod:`.adequacy` a state's flags and the model checks, :mod:`.recorded` replays a recorded
trace, :mod:`.stream` turns live lines (CSV or JSON) into chunks and :mod:`.tcp` a TCP
connection into lines (``palpbayes follow``; import them from their modules).
"""

from . import estimator as _estimator
from . import recorded as _recorded
from .estimator import *  # noqa: F403
from .recorded import *  # noqa: F403

__all__ = _estimator.__all__ + _recorded.__all__
