"""Stiffness maps: E over a grid of palpations, with its uncertainty and the stiff lump.

Computation only (no plotting); the files of a map folder are written by :mod:`~.files`.

Modules
-------
:mod:`~palpbayes.maps.pertrace`
    Each palpation's posterior of log E (exact engine) on Dask: :func:`fit_points`.
:mod:`~palpbayes.maps.lattice`
    The regular lattice: :class:`Lattice`, inference from palpation positions, the Neumann
    graph Laplacian and its closed-form eigenvalues, padding.
:mod:`~palpbayes.maps.spde`
    The latent Gaussian model at fixed hyperparameters: SPDE (Matérn nu = 1) precision,
    exact marginal likelihood and exact posterior draws by sparse LU.
:mod:`~palpbayes.maps.hyper`
    PC priors of (sigma_f, range, tau) and the INLA-style integration grid with its flags.
:mod:`~palpbayes.maps.gmrf`
    The spatial field: :func:`fit_field` → :class:`FieldPosterior`.
:mod:`~palpbayes.maps.lump`
    The one-inclusion model: :func:`fit_lump` → :class:`LumpPosterior`.
:mod:`~palpbayes.maps.run`
    The three stages: :func:`make_map`, :func:`map_from_points` → :class:`MapResult`.
:mod:`~palpbayes.maps.files`
    Every file of a map folder: :func:`write_map`.

The public names are the submodules' ``__all__``.
"""

from __future__ import annotations

from . import files, gmrf, hyper, lattice, lump, pertrace, run, spde
from .files import *  # noqa: F403
from .gmrf import *  # noqa: F403
from .hyper import *  # noqa: F403
from .lattice import *  # noqa: F403
from .lump import *  # noqa: F403
from .pertrace import *  # noqa: F403
from .run import *  # noqa: F403
from .spde import *  # noqa: F403

__all__ = [*lattice.__all__, *spde.__all__, *hyper.__all__, *gmrf.__all__, *pertrace.__all__,
           *lump.__all__, *run.__all__, *files.__all__]
