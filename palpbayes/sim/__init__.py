"""The simulator: synthetic palpation traces, compression tests and campaigns from a known truth.

One module per job, imports flowing one way (``map`` -> ``campaign``;
``campaign`` -> ``series``/``compression`` -> ``trace`` -> ``force``; ``visco_campaign`` ->
``campaign``/``viscoelastic``):

* :mod:`~palpbayes.sim.force` -- the noise-free contact force and its physics knobs (strain
  stiffening, gradual onset, finite thickness, a blunted apex, series compliance);
* :mod:`~palpbayes.sim.trace` -- one palpation trace: motion, AR(1) force noise, offset, drift,
  registration and encoder errors, with the truth in its metadata;
* :mod:`~palpbayes.sim.compression` -- an Instron compression test and its export file;
* :mod:`~palpbayes.sim.series` -- repeated palpation with rest-time stiffening;
* :mod:`~palpbayes.sim.campaign` -- a whole campaign folder with its truth tables;
* :mod:`~palpbayes.sim.map` -- a stiffness-map phantom folder: a grid of palpations over it,
  the lump seen through :mod:`palpbayes.inclusion` (the forward model maps and the active
  search own as well);
* :mod:`~palpbayes.sim.misfit` -- palpations with a misfit the user did not model (an unknown
  layer, stiffening, a gradual onset, a blunted apex), the model-form calibration's traces;
* :mod:`~palpbayes.sim.viscoelastic` -- a ramp–hold–retract on a viscoelastic half-space
  (power-law or Prony relaxation, Lee–Radok/Ting), one trace or one per speed;
* :mod:`~palpbayes.sim.visco_campaign` -- a campaign folder of such palpations: specimens x
  tips x speeds, with the segment column and the truth tables.

The paper's numbers the simulator reproduces live in :mod:`palpbayes.paper`, the peak-to-peak
noise convention in :mod:`palpbayes.sensor_noise` (both are shared with the fitting side).

>>> from palpbayes.paper import PAPER_TIPS
>>> from palpbayes.sim import simulate_trace
>>> simulate_trace(111e3, PAPER_TIPS["sphere"], thickness=0.03, rng=1).n_points
3840
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import lazy_modules

#: Submodules whose ``__all__`` make up the package's public names, in the order of
#: ``__all__``; they are imported on first use (PEP 562), so that importing one submodule, or
#: building the command line's parser, does not load the whole simulator (and scipy.signal).
API_MODULES = ("force", "trace", "compression", "series", "campaign", "map", "misfit",
               "viscoelastic", "visco_campaign")

if TYPE_CHECKING:  # the same names, for static tools
    from .campaign import *  # noqa: F403
    from .compression import *  # noqa: F403
    from .force import *  # noqa: F403
    from .map import *  # noqa: F403
    from .misfit import *  # noqa: F403
    from .series import *  # noqa: F403
    from .trace import *  # noqa: F403
    from .visco_campaign import *  # noqa: F403
    from .viscoelastic import *  # noqa: F403


__getattr__, __dir__ = lazy_modules(__name__, API_MODULES)
