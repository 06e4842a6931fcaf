"""The options of a fit (:class:`FitOptions`): everything a fit needs besides the trace,
picklable for worker processes, its material law's among them (:class:`LawOptions`);
:data:`METHODS` and :data:`LAYER_MODES`."""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from ..arguments import check_seed
from ..bayes.budget import BudgetSpec
from ..bayes.noisemodels import EXACT_NOISE_MODELS, NOISE_MODELS, get_noise_model
from ..bayes.priors import BASELINES, PriorSpec
from ..bayes.sampler import SamplerSettings
from ..contact import check_nu
from ..errors import InputError
from ..fitdata import BONDINGS
from ..material import LINEAR, law_names, material_law
from ..twin import PLATENS, Specimen
from ..twin.hyper_shape import INSTRON_STRAIN, LAW_MESHES

__all__ = ["FitOptions", "LawOptions", "METHODS", "LAYER_MODES", "parse_law_shape", "fit_options"]

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
        check_seed(self.seed)
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


# Many parameters: the command line's fit options by their Python names; this is the one builder of
# a FitOptions, which every fit layer below passes on as one object.
def fit_options(*, method: str = "bayes", nu: float | None = None,
                nu_range: tuple[float, float] | None = None, layer: str = "auto",
                bonding: str = "unknown", thickness_range: tuple[float, float] | None = None,
                specimen: Specimen | None = None, platens: str = "unknown",
                engine: str = "emcee", noise: str = "gaussian", noise_pp: float | None = None,
                f_unc: float | None = None, baseline: str = "constant", tare: bool = False,
                surface_prior: str = "loading", fit_fraction: float | None = None,
                max_depth: float | None = None, radius_tolerance: float = 0.01,
                gain_sd: float = 0.01, compliance_max: float = 2e-6, model_form: bool = True,
                max_steps: int = 20000, seed: int = 0, strict: bool = False,
                progress: bool | None = None, budget: BudgetSpec | None = None,
                law: str | LawOptions = "linear", law_shape: str | None = None,
                law_mesh: str = "default", instron_strain: float = 0.2) -> FitOptions:
    """The :class:`~palpbayes.campaign.options.FitOptions` of a fit, from the command line's
    options by their Python names and defaults (``palpbayes fit --help``): the one place both
    ways in build them.

    Parameters
    ----------
    nu, nu_range
        Poisson ratio [-] (None: a manifest row's, else 0.3 with a note), or a uniform range
        for the budget (the fit at its midpoint); not both.
    layer
        ``"auto"`` (a layer wherever the thickness is known), ``"off"`` (``--half-space``)
        or ``"unknown"`` (``--thickness unknown``).
    noise_pp, f_unc
        [N] Sensor peak-to-peak noise (the sigma prior) and the contact threshold (default:
        the noise spec, else 6 sd of the baseline).
    radius_tolerance, gain_sd, compliance_max
        The uncertainty budget's inputs.
    budget
        A whole :class:`~palpbayes.bayes.BudgetSpec` instead (e.g. ``BudgetSpec.none()``:
        the statistical interval alone); then ``nu_range`` only sets the fit's nu.
    max_steps, progress
        emcee's step cap and progress bars (None: on a terminal).
    law, law_shape, law_mesh, instron_strain
        The material law (``--law``: ``"linear"``, the paper's, or a registered hyperelastic
        law, or a whole :class:`~palpbayes.campaign.options.LawOptions`), its shape
        parameters fixed or narrowed (``"alpha_1=8,nu=0.1"``, ``"alpha_1=4:12"``), the
        finite-strain twin's mesh and the strain of ``E_instron_law`` (docs/reference.md,
        "Finite strain in the fits").

    Raises
    ------
    InputError
        A value out of range or options that contradict each other.
    """
    if nu is not None and nu_range is not None:
        raise InputError("give --nu or --nu-range, not both")
    if nu_range is not None:
        lo, hi = (check_nu(v) for v in nu_range)
        if hi < lo:
            raise InputError(f"--nu-range {lo} {hi}: LO must not exceed HI")
        nu, budget_nu = 0.5 * (lo + hi), (lo, hi)
    else:
        nu, budget_nu = (None if nu is None else check_nu(nu)), None
    for name, v in (("radius_tolerance", radius_tolerance), ("gain_sd", gain_sd),
                    ("compliance_max", compliance_max)):
        if not (math.isfinite(v) and v >= 0):
            raise InputError(f"--{name.replace('_', '-')} {v!r} must be a non-negative number")
    for name, v in (("noise_pp", noise_pp), ("f_unc", f_unc)):
        if v is not None and not (math.isfinite(v) and v > 0):
            what = ("the sensor's peak-to-peak noise" if name == "noise_pp"
                    else "the contact threshold")
            raise InputError(f"--{name.replace('_', '-')} {v!r} must be a positive force in "
                             f"newtons ({what})")
    get_noise_model(noise)  # an unknown model: its own error, before the engine's
    if engine == "exact" and (noise not in EXACT_NOISE_MODELS or surface_prior == "soft"):
        what = (f"--noise {noise}" if noise not in EXACT_NOISE_MODELS
                else "--surface-prior soft")
        raise InputError(f"--engine exact takes --noise {' or '.join(EXACT_NOISE_MODELS)} and "
                         f"--surface-prior loading, not {what}: use --engine emcee for it")
    if layer not in LAYER_MODES:
        raise InputError(f"unknown layer mode {layer!r}; use one of {', '.join(LAYER_MODES)}")
    if not isinstance(law, LawOptions):
        name = str(law).strip().lower()
        law = LawOptions(name, () if name == "linear" or not law_shape
                         else parse_law_shape(name, law_shape), law_mesh, instron_strain)
        if name == "linear" and law_shape:
            raise InputError("--law-shape needs a hyperelastic law (--law NAME)")
    if budget is None:
        budget = BudgetSpec(nu_range=budget_nu, radius_tolerance=radius_tolerance,
                            gain_sd=gain_sd, compliance_max=compliance_max)
    return FitOptions(
        method=method, nu=nu, layer=layer, bonding=bonding,
        thickness_range=None if thickness_range is None else tuple(thickness_range),
        f_unc=f_unc if f_unc is not None else noise_pp, fit_fraction=fit_fraction,
        max_depth=max_depth, noise=noise, baseline=baseline, tare=tare,
        priors=PriorSpec(noise_pp=noise_pp, surface=surface_prior), budget=budget,
        settings=SamplerSettings(max_steps=max_steps, progress=progress), seed=seed,
        strict=strict, engine=engine, model_form=model_form, specimen=specimen,
        platens=platens, law=law)
