"""Figures for papers and reports (matplotlib only here; docs/design.md §4).

Every function draws with matplotlib's object API on an optional ``ax`` (or ``fig``) and returns
the :class:`~matplotlib.figure.Figure`.  Without ``ax`` a new figure is made with
:class:`matplotlib.figure.Figure` directly, not through ``pyplot``: no global state, nothing to
close, any backend.  Nothing here calls ``matplotlib.use``; the caller chooses the backend (in
Jupyter, ``%matplotlib inline`` and ``display(fig)`` or a figure as the cell's last value).

Units on the axes: depth in mm, force in N, moduli in kPa, surface height relative to its
posterior median in µm (the posterior spread of z_surf is a few µm; mm would show only zeros).
Colours per method are fixed (Okabe-Ito, colour-blind safe): :data:`METHOD_COLORS`.  Dense data
points are rasterized so a PDF page stays small.

Functions
---------
:func:`plot_force_depth`     data, posterior-predictive band and least-squares curve
:func:`plot_residuals`       residuals vs depth, both methods, binned means and ±2 sigma
:func:`plot_posterior_E`     marginal posterior of E (statistical and with the budget)
:func:`plot_posterior_zsurf` marginal posterior of the surface height
:func:`plot_pair`            joint posterior of E and z_surf with the least-squares ellipse
:func:`plot_posterior`       the three above side by side
:func:`plot_walkers`         trace plots of the sampled parameters, one line per walker
:func:`plot_budget`          share of the variance of ln E per input of the budget
:func:`plot_comparison`      ground truth vs least squares vs Bayes per material × tip
:func:`plot_forest`          per-trace intervals of one material × tip with the pooled result
:func:`plot_stiffening`      modulus vs rest time with the fitted stiffening law and its band
:func:`plot_gap`             the paper's robot-vs-Instron gap against the layer's prediction
:func:`plot_strain_factors`  what finite strain multiplies that gap by, per foam and tip
:func:`plot_halfspace_vs_layer` a campaign's half-space and layer estimates side by side
:func:`plot_specimen_as_tested` palpation (the block's twin) and compression like for like
:func:`plot_cycle_fit`       a viscoelastic fit: force against time with its band
:func:`plot_relaxation`      the relaxation modulus E*(t) with its band, one or more fits
:func:`plot_hysteresis`      force against depth per segment (approach, hold, retract)
:func:`plot_compression_tests` compression tests' stress-strain curves with their fitted lines

Modules, by subject: :mod:`~palpbayes.plots.style` (colours, units, shared helpers),
:mod:`~palpbayes.plots.trace` (force-depth, residuals), :mod:`~palpbayes.plots.posterior`,
:mod:`~palpbayes.plots.walkers`, :mod:`~palpbayes.plots.budget`,
:mod:`~palpbayes.plots.campaign` (comparison, forest), :mod:`~palpbayes.plots.layer`
(finite thickness), :mod:`~palpbayes.plots.stiffening`, :mod:`~palpbayes.plots.rheology`
(viscoelastic fits) and :mod:`~palpbayes.plots.compression` (compression tests); the functions are
imported from here.
"""

from .budget import plot_budget
from .campaign import plot_comparison, plot_forest
from .compression import plot_compression_tests
from .layer import plot_gap, plot_halfspace_vs_layer, plot_strain_factors
from .posterior import plot_pair, plot_posterior, plot_posterior_E, plot_posterior_zsurf
from .rheology import plot_cycle_fit, plot_hysteresis, plot_relaxation
from .stiffening import plot_stiffening
from .style import INPUT_COLORS, METHOD_COLORS, METHOD_LABELS
from .trace import plot_force_depth, plot_residuals
from .twin import plot_specimen_as_tested
from .walkers import plot_walkers

__all__ = [
    "METHOD_COLORS",
    "METHOD_LABELS",
    "INPUT_COLORS",
    "plot_force_depth",
    "plot_residuals",
    "plot_posterior_E",
    "plot_posterior_zsurf",
    "plot_pair",
    "plot_posterior",
    "plot_walkers",
    "plot_budget",
    "plot_comparison",
    "plot_forest",
    "plot_stiffening",
    "plot_gap",
    "plot_strain_factors",
    "plot_halfspace_vs_layer",
    "plot_specimen_as_tested",
    "plot_cycle_fit",
    "plot_relaxation",
    "plot_hysteresis",
    "plot_compression_tests",
]
