"""Young's modulus from uniaxial compression tests (Instron exports): the ground truth.

>>> from palpbayes.compression import analyse                   # doctest: +SKIP
>>> per_file, summary = analyse("groundtruth/")                 # doctest: +SKIP

Engineering quantities: strain eps = compression / initial height [-], stress sigma = load /
initial cross-section [Pa], both positive in compression.  Each test's modulus is the slope of
a straight line fitted over a window of toe-compensated strain (default 0-5 %), with a standard
error that allows for autocorrelated residuals.

Modules: :mod:`.fit` (the rule and :func:`fit_modulus`, one test), :mod:`.hac` (the line and
the HAC standard error of its slope), :mod:`.window` (the strain window, the sensitivity
windows, the rule text), :mod:`.tables` (:func:`analyse`, :func:`summarise`, and which number
to compare with what) and :mod:`.platens` (E from what a test between bonded platens read).
Reading the exports is :mod:`palpbayes.io.instron`, finding them
:mod:`palpbayes.io.groundtruth_inputs`. The public names of each module are imported here.
"""

from ..io.instron import CompressionTest  # the input of fit_modulus
from . import fit, hac, platens, tables, window
from .fit import *  # noqa: F403 - the names in fit.__all__
from .hac import *  # noqa: F403
from .platens import *  # noqa: F403
from .tables import *  # noqa: F403
from .window import *  # noqa: F403

__all__ = ["CompressionTest", *window.__all__, *fit.__all__, *hac.__all__, *tables.__all__,
           *platens.__all__]
