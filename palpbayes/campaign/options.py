"""The options of a fit (:class:`FitOptions`): everything a fit needs besides the trace,
picklable for worker processes, its material law's among them (:class:`LawOptions`);
:data:`METHODS` and :data:`LAYER_MODES`."""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from ..bayes.budget import BudgetSpec
from ..bayes.noisemodels import NOISE_MODELS
from ..bayes.priors import BASELINES, PriorSpec
from ..bayes.sampler import SamplerSettings
from ..errors import InputError
from ..fitdata import BONDINGS
from ..material import LINEAR, law_names, material_law
from ..twin import PLATENS, Specimen
from ..twin.hyper_shape import INSTRON_STRAIN, LAW_MESHES

__all__ = ["FitOptions", "LawOptions", "METHODS", "LAYER_MODES", "parse_law_shape"]

METHODS = ("bayes", "lsq", "both")

#: How a fit treats the specimen's thickness: ``auto`` a layer on a rigid base wherever the
#: trace's thickness is known (else a half-space), ``off`` a half-space everywhere (the
#: paper's model), ``unknown`` a layer of unknown thickness (or none) everywhere.
LAYER_MODES = ("auto", "off", "unknown")


def parse_law_shape(law: str, text: str | None) -> tuple[tuple[str, tuple[float, ...]], ...]:
    """``--law-shape`` as (name, (value,)) for a fixed shape parameter and (name, (lo, hi))
    for a narrowed range: ``"alpha_1=8,nu=0.1"``, ``"alpha_1=4:12"``.

    Raises
    ------
    InputError
        A malformed entry, a parameter the law lacks, a value outside its bounds.
    """
    spec = material_law(law)
    bounds = {s.name: s.bounds for s in spec.shape}
    out = {}
    for item in filter(None, (t.strip() for t in str(text or "").split(","))):
        name, sep, value = item.partition("=")
        name = name.strip()
        if not sep or name not in bounds:
            raise InputError(f"--law-shape {item!r}: give NAME=VALUE or NAME=LO:HI with NAME "
                             f"one of the {spec.title} law's shape parameters "
                             f"({', '.join(bounds) or 'none'})")
        try:
            values = tuple(float(v) for v in value.split(":"))
        except ValueError:
            raise InputError(f"--law-shape {item!r}: {value!r} is not a number or LO:HI"
                             ) from None
        lo, hi = bounds[name]
        if len(values) > 2 or not all(lo <= v <= hi for v in values) or (
                len(values) == 2 and not values[0] < values[1]):
            raise InputError(f"--law-shape {item!r}: {name} must lie in [{lo:g}, {hi:g}] (a "
                             "value, or LO:HI with LO < HI)")
        out[name] = values
    return tuple(out.items())


@dataclass(frozen=True)
class LawOptions:
    """The material law of a fit (``--law``, ``--law-shape``, ``--law-mesh``,
    ``--instron-strain``).

    Parameters
    ----------
    name
        ``"linear"`` (the paper's model, the default) or a registered law
        (:func:`palpbayes.material.law_names`).
    shape
        (name, values) per shape parameter: one value fixes it, (lo, hi) narrows its uniform
        prior (:func:`parse_law_shape`); the others span their registry bounds.  A foam's nu
        is fixed by ``--nu`` (or a manifest's ``nu``) when given.
    mesh
        The finite-strain twin's mesh (``default``; ``coarse`` is 3-4 times faster and within
        0.1-0.4 % of it; ``fine`` for checks).
    instron_strain
        [-] The compressive strain of ``E_instron_law_pa``'s chord (default 0.2: the paper's
        5 mm of 20-30 mm).
    """

    name: str = LINEAR
    shape: tuple[tuple[str, tuple[float, ...]], ...] = ()
    mesh: str = "default"
    instron_strain: float = INSTRON_STRAIN

    def __post_init__(self) -> None:
        name = str(self.name).strip().lower().replace("_", "-")
        if name != LINEAR:
            name = material_law(name).name  # InputError naming the laws there are
        elif self.shape:
            raise InputError("--law-shape needs a hyperelastic law (--law NAME); the linear "
                             "law has no shape parameters")
        object.__setattr__(self, "name", name)
        if name != LINEAR:
            given = ",".join(f"{n}={':'.join(f'{v!r}' for v in vs)}" for n, vs in self.shape)
            object.__setattr__(self, "shape", parse_law_shape(name, given))
        if self.mesh not in LAW_MESHES:
            raise InputError(f"unknown --law-mesh {self.mesh!r}; use one of "
                             f"{', '.join(LAW_MESHES)}")
        if not 0.0 < float(self.instron_strain) < 0.95:
            raise InputError(f"--instron-strain {self.instron_strain!r} must be a compressive "
                             "strain in (0, 0.95), e.g. 0.2 for 5 mm of a 25 mm block")

    @property
    def is_linear(self) -> bool:
        return self.name == LINEAR

    @staticmethod
    def names() -> list[str]:
        """``linear`` and the registered laws."""
        return law_names()


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
        interval spanning both); used with a specimen only (and for ``E_instron_law_pa``).
    law
        The material law (:class:`LawOptions`; default linear, the paper's model).
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
    law: LawOptions = field(default_factory=LawOptions)

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
        if self.f_unc is not None and not (np.isfinite(self.f_unc) and self.f_unc > 0):
            raise InputError(f"f_unc {self.f_unc!r} must be a positive force in newtons (the "
                             "contact threshold)")
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
