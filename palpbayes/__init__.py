"""palpbayes: elastic modulus with an honest uncertainty from robotic palpation data.

The contact force of a rigid tip pressed into a soft specimen follows F = E*·s(z_surf - z); the
package fits E (and the unknown surface height z_surf) by the paper's least-squares baseline
(:mod:`palpbayes.lsq`) and by a Bayesian model sampled with emcee (:mod:`palpbayes.bayes`).
"""

from __future__ import annotations

__version__ = "0.1.0"

from .contact import Tip, force
from .errors import PalpbayesError
from .trace import IndentationTrace

__all__ = ["__version__", "Tip", "force", "IndentationTrace", "PalpbayesError"]
