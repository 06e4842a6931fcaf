"""palpbayes: elastic modulus with an honest uncertainty from robotic palpation data.

The contact force of a rigid tip pressed into a soft specimen follows F = E*·s(z_surf - z); the
package fits E (and the unknown surface height z_surf) by the paper's least-squares baseline
(:mod:`palpbayes.lsq`) and by a Bayesian model sampled with emcee (:mod:`palpbayes.bayes`).

The public names, with examples, are in docs/api.md::

    import palpbayes as pb
    f = pb.fit("press.csv", tip="sphere", radius=0.01, nu=0.45)

Reading and fitting: :func:`read`, :func:`fit` (a :class:`Fit`), :func:`load_fit` (a saved
:class:`Fit`), :func:`fit_options`, :func:`fit_campaign`, :func:`compare`,
:func:`run_pipeline`, :func:`load_results`, :func:`report` (the PDF); the ground truth:
:func:`groundtruth` (Young's modulus of compression tests, as ``palpbayes groundtruth``); the
model: :class:`Tip`, :class:`Specimen`, :class:`ModelSpec`, :class:`BudgetSpec`, :func:`force`;
simulating: :func:`simulate` (a campaign folder), :func:`simulate_trace`; online:
:func:`replay` (a recorded trace as if live: where would the stopping rule have
stopped?), :class:`OnlineEstimator`, :class:`StoppingRule`; maps: :func:`fit_map` (a manifest
or an AFM map in one call; :func:`make_map` the step after reading); active search:
:func:`next_presses` (the subpackage :mod:`active`); viscoelastic fits: :func:`fit_rheology`,
:func:`compare_rheology` (PSIS-LOO), :func:`pool_rheology` (one power law over speeds); the
example campaign: :func:`example_campaign_dir`; the subpackages :mod:`contact` (the contact
laws and their formulas), :mod:`errors`, :mod:`stiffening`, :mod:`plots`, :mod:`paper`,
:mod:`gap`, :mod:`gap_strain`, :mod:`twin`, :mod:`sim`, :mod:`compression` (compression tests),
:mod:`material` (the hyperelastic laws and ``Solid``), :mod:`reporting` (the report's tables
and pages).  They are imported when first used (``import palpbayes`` stays quick).
"""

from __future__ import annotations

import importlib

__version__ = "0.1.0"

from .contact import Tip, force
from .errors import PalpbayesError
from .trace import IndentationTrace

#: Public name -> (module, attribute); None: the module itself.
_LAZY = {
    "read": ("api", "read"),
    "write_trace": ("io.trace_csv", "write_trace"),
    "fit": ("api", "fit"),
    "Fit": ("api", "Fit"),
    "load_fit": ("api", "load_fit"),
    "fit_options": ("campaign.options", "fit_options"),
    "fit_campaign": ("api", "fit_campaign"),
    "compare": ("campaign.comparison", "compare"),
    "groundtruth": ("api_groundtruth", "groundtruth"),
    "run_pipeline": ("campaign.pipeline", "run_pipeline"),
    "load_results": ("campaign.results", "load_results"),
    "example_campaign_dir": ("campaign.pipeline", "example_campaign_dir"),
    "report": ("reporting.build", "report"),
    "BudgetSpec": ("bayes.budget", "BudgetSpec"),
    "ModelSpec": ("modelspec", "ModelSpec"),
    "Specimen": ("specimen", "Specimen"),
    "simulate": ("sim.campaign", "simulate"),
    "simulate_trace": ("sim.trace", "simulate_trace"),
    "replay": ("api_replay", "replay"),
    "OnlineEstimator": ("online.estimator", "OnlineEstimator"),
    "StoppingRule": ("online.state", "StoppingRule"),
    "fit_map": ("api_map", "fit_map"),
    "make_map": ("maps.run", "make_map"),
    "next_presses": ("active.front", "next_presses"),
    "active": ("active", None),
    "fit_rheology": ("api_rheology", "fit_rheology"),
    "compare_rheology": ("rheology.choice", "compare_rheology"),
    "pool_rheology": ("rheology.pool", "pool_rheology"),
    "contact": ("contact", None),
    "errors": ("errors", None),
    "stiffening": ("stiffening", None),
    "plots": ("plots", None),
    "paper": ("paper", None),
    "gap": ("gap", None),
    "gap_strain": ("gap_strain", None),
    "twin": ("twin", None),
    "sim": ("sim", None),
    "compression": ("compression", None),
    "material": ("material", None),
    "reporting": ("reporting", None),
}

__all__ = ["__version__", "Tip", "force", "IndentationTrace", "PalpbayesError", *_LAZY]


def __getattr__(name: str):
    """The public names of :data:`_LAZY`, imported on first use."""
    try:
        module, attr = _LAZY[name]
    except KeyError:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}") from None
    mod = importlib.import_module(f"{__name__}.{module}")
    value = mod if attr is None else getattr(mod, attr)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))
