"""The options of a fit (:class:`FitOptions`): everything a fit needs besides the trace,
picklable for worker processes; :data:`METHODS` and :data:`LAYER_MODES`."""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from ..bayes.budget import BudgetSpec
from ..bayes.priors import BASELINES, NOISE_MODELS, PriorSpec
from ..bayes.sampler import SamplerSettings
from ..errors import InputError
from ..fitdata import BONDINGS
from ..twin import PLATENS, Specimen

__all__ = ["FitOptions", "METHODS", "LAYER_MODES"]

METHODS = ("bayes", "lsq", "both")

#: How a fit treats the specimen's thickness: ``auto`` a layer on a rigid base wherever the
#: trace's thickness is known (else a half-space), ``off`` a half-space everywhere (the
#: paper's model), ``unknown`` a layer of unknown thickness (or none) everywhere.
LAYER_MODES = ("auto", "off", "unknown")


@dataclass(frozen=True)
class FitOptions:
    """Everything a fit needs besides the trace (picklable, for worker processes).

    Parameters
    ----------
    method
        ``"bayes"``, ``"lsq"`` or ``"both"``.
    nu
        Poisson ratio used for E = E*·(1 − nu²); None: a manifest row's own ``nu``, else
        :data:`~palpbayes.contact.DEFAULT_NU` (0.3, a foam value), and summary.csv says so
        (``nu_source``: ``option``, ``manifest`` or ``default``).
    layer
        How the specimen's thickness enters the Bayesian model (:data:`LAYER_MODES`):
        ``"auto"`` (default) a layer on a rigid base wherever the trace's thickness is known,
        ``"off"`` a half-space (the paper's model, ``--half-space``), ``"unknown"`` a layer
        of unknown thickness, or none (``--thickness unknown``).  The least-squares baseline
        is always the paper's half-space; its row says what the layer would change.
    bonding
        Base of the layer: ``"bonded"``, ``"free"`` or ``"unknown"`` (default: both, weighted
        by the data).
    thickness_range
        [m] (lo, hi) of the log-uniform prior of an unknown thickness; None: 1.5 to 1,000 times
        the indentation depth (:func:`palpbayes.bayes.layers.default_thickness_range`).
    f_unc
        [N] Sensor uncertainty (surface constraint, contact onset and F0 prior scale); None:
        the pre-contact baseline's noise as a peak-to-peak spec.
    fit_fraction
        Fraction of the penetration skipped (None: 0.2 for flat, 0 otherwise).
    max_depth
        [m] Only fit samples shallower than this below the contact onset.
    noise
        Noise model of the Bayesian fit.
    baseline
        Baseline of the Bayesian model: ``"constant"`` (F0) or ``"linear"`` (F0 + F1·(z −
        z_ref), drift or a tilted baseline).
    tare
        Subtract the pre-contact baseline level from the force before both fits (the paper's
        least squares has no offset term).
    priors, budget, settings
        Bayesian settings.
    seed
        Base seed; each trace's seed is derived from it and the trace id.
    strict
        Make non-convergence an error.
    engine
        Posterior engine of the Bayesian fit: ``"emcee"`` or ``"exact"``
        (:mod:`palpbayes.bayes.exact`: Gaussian or AR(1) noise only).
    model_form
        Widen a Bayesian fit's interval by the model form when a check finds a material
        misfit (:mod:`palpbayes.bayes.modelform`; default True).
    specimen
        The block as tested (:class:`~palpbayes.twin.Specimen`, ``--specimen``) for every
        trace whose manifest row gives no footprint of its own: the Bayesian model is then its
        finite-element twin (:mod:`palpbayes.twin`).
    platens
        The compression test's platens the Bayesian rows' Instron-equivalent modulus is for
        (``E_instron_pa``): ``"lubricated"``, ``"bonded"`` or ``"unknown"`` (default: an
        interval spanning both); used with a specimen only.
    """

    method: str = "bayes"
    nu: float | None = None
    layer: str = "auto"
    bonding: str = "unknown"
    thickness_range: tuple[float, float] | None = None
    f_unc: float | None = None
    fit_fraction: float | None = None
    max_depth: float | None = None
    noise: str = "gaussian"
    baseline: str = "constant"
    tare: bool = False
    priors: PriorSpec = field(default_factory=PriorSpec)
    budget: BudgetSpec = field(default_factory=BudgetSpec)
    settings: SamplerSettings = field(default_factory=SamplerSettings)
    seed: int = 0
    strict: bool = False
    engine: str = "emcee"
    model_form: bool = True
    specimen: Specimen | None = None
    platens: str = "unknown"

    def __post_init__(self) -> None:
        from ..bayes.fit import ENGINES  # here: the options alone do not load the fitting code

        for what, value, allowed in (("method", self.method, METHODS),
                                     ("engine", self.engine, ENGINES),
                                     ("noise model", self.noise, NOISE_MODELS),
                                     ("baseline", self.baseline, BASELINES)):
            if value not in allowed:
                raise InputError(f"unknown {what} {value!r}; use one of {', '.join(allowed)}")
        if isinstance(self.seed, bool) or not isinstance(self.seed, int | np.integer) or (
                self.seed < 0):
            raise InputError(f"seed {self.seed!r} must be a non-negative whole number")
        if self.platens not in PLATENS:
            raise InputError(f"unknown platens {self.platens!r}; use one of "
                             f"{', '.join(PLATENS)}")
        if self.layer not in LAYER_MODES:
            raise InputError(f"unknown layer mode {self.layer!r}; use one of "
                             f"{', '.join(LAYER_MODES)}")
        if self.bonding not in BONDINGS:
            raise InputError(f"unknown bonding {self.bonding!r}; use one of "
                             f"{', '.join(BONDINGS)}")
        if self.thickness_range is not None:
            lo, hi = self.thickness_range
            if not (0 < lo < hi and np.isfinite(hi)):
                raise InputError(f"thickness range {self.thickness_range!r} m must satisfy "
                                 "0 < LO < HI")

    def with_progress(self, progress: bool | None) -> FitOptions:
        return replace(self, settings=replace(self.settings, progress=progress))
