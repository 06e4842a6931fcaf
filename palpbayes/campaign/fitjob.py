"""One fitting job: a trace, its model and the chosen methods -> summary rows (+ posterior).

This is the unit of work that ``palpbayes fit`` runs for a single trace and that
:mod:`palpbayes.campaign` distributes over worker processes.  It does no output itself except
the per-trace netCDF when ``posterior_dir`` is given (written atomically).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from ..bayes import BayesResult, BudgetSpec, PriorSpec, SamplerSettings, fit_bayes_data
from ..bayes.budget import nu_nodes
from ..bayes.layers import default_thickness_range
from ..checks import CheckResult, check_fit, checks_summary
from ..contact import DEFAULT_NU, check_tip_plausible, get_law
from ..errors import ConvergenceWarning, FitError, GeometryError, InputError
from ..fitdata import BONDINGS, FitData, ModelSpec, prepare
from ..flagcodes import flag_columns
from ..lsq import LSQResult, fit_lsq_data
from ..refit import layer_alternatives
from ..trace import IndentationTrace
from ..twin import PLATENS, Specimen, prepare_tables, specimen_from_sizes, twin_depth_limit
from ..twin.specimen import FOOTPRINT_COLUMNS
from .layout import posterior_file

__all__ = ["FitOptions", "FitOutcome", "fit_trace", "check_fittable", "trace_model", "nu_source",
           "trace_specimen", "prepare_twin",
           "SUMMARY_COLUMNS", "METHODS", "LAYER_MODES"]

METHODS = ("bayes", "lsq", "both")

#: Columns of ``summary.csv`` in order (docs/design.md §7 first, then extras).
SUMMARY_COLUMNS = [
    "trace_id", "method", "tip", "n_points", "E_pa", "E_sd_pa", "E_lo_pa", "E_hi_pa",
    "Estar_pa", "z_surf_m", "z_surf_sd_m", "sigma_n", "converged", "rhat_max", "ess_min",
    "material", "specimen", "repetition", "rest_time_s", "nu", "nu_source", "noise_model",
    "E_stat_pa", "E_stat_sd_pa", "E_stat_lo_pa", "E_stat_hi_pa", "k", "m", "rss_n2",
    "constraint_active", "tau_max", "acceptance", "n_steps",
    # the flags in words, their codes and the highest level (palpbayes.flagcodes)
    "notes", "flag_codes", "flag_level",
    # the pre-contact baseline and the noise spec used (F_unc), read from the data unless given
    "baseline_n", "f_unc_n", "baseline_model", "F0_n",
    # model-adequacy checks (palpbayes.checks): no material misfit, and the free exponent m of
    # F = k·d^m + baseline (compare with the tip law's); the largest effect on E of a
    # material check [-] and the names of those checks; failed checks are named in notes
    # (negligible ones as info: lines with their effect)
    "model_ok", "m_free", "misfit_effect", "misfit_checks",
    # E's interval in three parts (bayes; palpbayes.bayes.modelform): E_stat_lo/hi the
    # statistical 90 % interval, E_budget_lo/hi with the budget's inputs, E_lo/hi the full one
    # (with a material misfit: the envelope of the fitted model's and its plausible
    # alternatives' budget intervals), the share of the full width the model form adds [%]
    # and the alternatives with their E and interval
    "E_budget_lo_pa", "E_budget_hi_pa", "modelform_share_pct", "modelform_models",
    # the Bayesian engine: emcee, or the exact quadrature (palpbayes.bayes.exact)
    "engine",
    # tip "sphere" only (a law with a hertz_approximation; else NaN): the paper's choice for a
    # sphere, least squares with the paraboloid (Hertz) law at the sphere's radius on the same
    # (tared) points, as the ratio to the Sneddon least squares: the row's E times it, and the
    # ratio − 1 (fit_trace)
    "E_hertz_pa", "E_hertz_rel_diff",
    # the specimen's layer (finite thickness): the model of the row (lsq: always the paper's
    # half-space; bayes: a layer on a rigid base wherever the thickness is known), the concrete
    # model at the posterior's centre, the thickness (its 90 % interval when sampled), the
    # posterior probabilities of a bonded base and of no layer, and the row's fitted curve
    # read as a half-space, a bonded and a free layer (palpbayes.refit.layer_alternatives)
    "layer", "model_fitted", "thickness_m", "thickness_lo_m", "thickness_hi_m", "p_bonded",
    "p_halfspace", "E_halfspace_pa", "E_bonded_pa", "E_free_pa",
    # the specimen as tested (a block's footprint known: its finite-element twin, bayes
    # rows): what a compression test of the block between these platens would report, with
    # its 90 % interval (palpbayes.bayes.instron); the bonded and free columns above are then
    # the twin's
    "platens", "E_instron_pa", "E_instron_lo_pa", "E_instron_hi_pa",
]

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


@dataclass
class FitOutcome:
    """Rows for ``summary.csv`` and the result objects of one trace."""

    rows: list[dict]
    lsq: LSQResult | None = None
    bayes: BayesResult | None = None
    posterior_path: Path | None = None


def nu_source(trace: IndentationTrace, options: FitOptions) -> str:
    """Where a trace's Poisson ratio came from: ``"manifest"`` (its row's ``nu``),
    ``"option"`` (the run's ``nu``) or ``"default"`` (:data:`~palpbayes.contact.DEFAULT_NU`)."""
    if "nu" in (trace.metadata or {}):
        return "manifest"
    return "default" if options.nu is None else "option"


def trace_seed(base: int, trace_id: str) -> int:
    """A per-trace seed from the base seed and the trace id (independent of trace order)."""
    words = np.frombuffer(trace_id.encode("utf-8"), dtype=np.uint8).astype(np.uint32)
    return int(np.random.SeedSequence([int(base), *words.tolist()]).generate_state(1)[0])


def trace_model(trace: IndentationTrace, options: FitOptions,
                depth: float | None = None) -> ModelSpec:
    """The contact model a Bayesian fit of ``trace`` uses: its tip (checked for
    plausibility), the run's ``nu`` unless the manifest row gives its own
    (``trace.metadata["nu"]``), and its layer (``options.layer``, ``options.bonding``).

    Parameters
    ----------
    trace
        The trace.
    options
        The fit options.
    depth
        [m] Indentation depth, for the default range of an unknown thickness.

    Raises
    ------
    GeometryError
        No tip or an implausible tip size.
    """
    src = trace.source or trace.trace_id
    tip = trace.tip
    if tip is None:
        raise GeometryError(f"{src}: no tip geometry; give --tip and its size")
    try:
        check_tip_plausible(tip)
    except GeometryError as exc:
        raise GeometryError(f"{src}: {exc}") from None
    # a manifest's per-row nu (trace.metadata["nu"]) overrides the run's option
    nu = trace.metadata.get("nu", DEFAULT_NU if options.nu is None else options.nu)
    block = trace_specimen(trace, options)
    if options.layer == "off" or (options.layer == "auto" and trace.thickness is None
                                  and block is None):
        return ModelSpec(tip, nu=nu, bonding=options.bonding)
    if block is not None:
        if options.layer == "unknown":
            raise InputError(f"{src}: the specimen {block.describe()} has a known height; an "
                             "unknown thickness (--thickness unknown) contradicts it")
        return ModelSpec(tip, nu=nu, bonding=options.bonding, specimen=block)
    if options.layer == "auto":
        return ModelSpec(tip, nu=nu, thickness=trace.thickness, bonding=options.bonding)
    rng = options.thickness_range
    if rng is None:
        rng = default_thickness_range(np.nan if depth is None else depth)
    return ModelSpec(tip, nu=nu, bonding=options.bonding, thickness_range=tuple(rng))


def trace_specimen(trace: IndentationTrace, options: FitOptions) -> Specimen | None:
    """The block a trace was pressed into: its manifest row's footprint (``length_m``,
    ``width_m`` or ``diameter_m`` with ``thickness_m``), else the run's ``specimen`` option;
    None without either.

    Raises
    ------
    GeometryError
        An incomplete footprint, or a ``specimen`` option whose height differs from the
        trace's own thickness.
    """
    meta = trace.metadata or {}
    src = trace.source or trace.trace_id
    try:
        block = specimen_from_sizes(trace.thickness, *(meta.get(c) for c in FOOTPRINT_COLUMNS))
    except GeometryError as exc:
        raise GeometryError(f"{src}: {exc}") from None
    if block is not None or options.specimen is None:
        return block
    if trace.thickness is not None and not np.isclose(trace.thickness,
                                                      options.specimen.height, rtol=1e-9):
        raise GeometryError(
            f"{src}: the specimen's height {options.specimen.height:g} m (--specimen) differs "
            f"from the trace's thickness {trace.thickness:g} m (--thickness or thickness_m): "
            "give one of the two")
    return options.specimen


def prepare_twin(model: ModelSpec, options: FitOptions) -> int:
    """Build (or load from the cache) the twin's tables a fit of ``model`` needs: its nu and
    the budget's nodes of nu (a Bayesian fit), for each base it allows; 0 without a
    specimen.  A progress bar shows on stderr while new tables are solved."""
    if model.specimen is None:
        return 0
    nus = [model.nu]
    if options.method in ("bayes", "both"):
        nus += list(nu_nodes(options.budget, model.nu))
    return prepare_tables(model.specimen, model.tip, nus, model.bases,
                          progress=options.settings.progress)


def check_fittable(trace: IndentationTrace, options: FitOptions) -> FitData:
    """The trace's prepared fit data; raises the :class:`InputError` a fit would raise.

    Cheap (no fitting): geometry, Poisson ratio, thickness, contact onset and fit window, unit
    plausibility, and the contact model (with its finite-thickness correction) evaluated at the
    deepest depth any fit of this trace evaluates, so that no :class:`GeometryError` can arise
    once fitting has started.

    Checks, besides those of :func:`palpbayes.fitdata.prepare`:

    * tip size plausible (:func:`palpbayes.contact.check_tip_plausible`: radius <= 0.1 m);
    * indentation depth (contact onset to deepest point) at most the specimen thickness, when
      the thickness is known (z in the wrong unit);
    * paraboloid and sphere: depth (contact onset to deepest fitted point) at most the tip
      radius R, the limit of the Hertz and Sneddon laws;
    * the model's shape function finite and positive at the deepest admissible depth
      d = z_top − min(z) (surface at the start of the approach), for every base and (an
      unknown thickness) at the thinnest layer allowed, also with the tip radius scaled by
      the budget's tolerance when the Bayesian fit runs.

    The returned data carry the Bayesian model (:func:`trace_model`); the least-squares
    baseline fits them as a half-space (``data.model.half_space()``).

    Raises
    ------
    GeometryError
        Missing or implausible geometry, depth beyond thickness or radius, or a correction
        outside its range.
    NoContactError, InputError
        As :func:`palpbayes.fitdata.prepare`.
    """
    src = trace.source or trace.trace_id
    half = trace_model(trace, replace(options, layer="off"))
    tip = half.tip
    data = prepare(trace, half, f_unc=options.f_unc, fit_fraction=options.fit_fraction,
                   max_depth=options.max_depth, tare=options.tare)
    model = trace_model(trace, options, depth=data.z_contact - data.z_min)
    data = replace(data, model=model)

    depth = data.z_contact - data.z_min
    if model.specimen is not None:
        try:
            prepare_twin(model, options)
        except GeometryError as exc:
            raise GeometryError(f"{src}: {exc}") from None
    known = trace.thickness if trace.thickness is not None else (
        None if model.specimen is None else model.specimen.height)
    if known is not None and depth > known:
        raise GeometryError(
            f"{src}: the indentation depth {depth * 1e3:.4g} mm (contact onset to deepest "
            f"point) exceeds the specimen thickness {known * 1e3:.4g} mm; is z in "
            "another unit (give it, e.g. --z-unit mm or --z-unit cm)? or check the thickness "
            "(--thickness, thickness_m, in metres)"
        )
    fitted = data.z_contact - float(data.z.min())
    if model.specimen is not None and fitted > twin_depth_limit(model.specimen, tip):
        raise GeometryError(
            f"{src}: the indentation depth {fitted * 1e3:.4g} mm (contact onset to deepest "
            f"fitted point) exceeds the {twin_depth_limit(model.specimen, tip) * 1e3:.4g} mm "
            f"the twin of the {model.specimen.describe()} is solved to (half its height, a "
            "contact radius at most half its footprint's); fit a shallower window "
            "(--max-depth M)")
    law = get_law(tip)
    if law.max_depth is not None and fitted > law.max_depth(tip):
        raise GeometryError(
            f"{src}: the indentation depth {fitted * 1e3:.4g} mm (contact onset to deepest "
            f"fitted point) exceeds the {law.max_depth_name} {law.max_depth(tip) * 1e3:.4g} mm, "
            f"outside the {law.name} law's validity; is z in another unit (give it, e.g. "
            "--z-unit mm or --z-unit cm)? or fit a shallower window (--max-depth M)"
        )

    # the depths every fit evaluates: up to the deepest fitted point below the contact onset
    # (what the data say), and up to z_top - min(z) (trial surfaces up to the start of the
    # approach, tried by the least-squares grid and the likelihood table)
    deepest = data.z_top - float(data.z.min())
    approach = (f"; fits try every surface up to the start of the recorded approach, i.e. "
                f"depths up to {deepest * 1e3:.4g} mm (indentation {fitted * 1e3:.4g} mm): "
                "cropping a long approach from the file lowers this")
    models = [("", half)]
    if options.method in ("bayes", "both") and model.has_layer:
        h = model.thickness if model.thickness is not None else model.thickness_range[0]
        models += [(f" (on a {b} layer)", model.variant(thickness=h, base=b))
                   for b in model.bases]
    tol = options.budget.radius_tolerance
    if options.method in ("bayes", "both") and tol > 0 and tip.has_length_scale:
        # the budget refits a scaled tip without the specimen's footprint (budget.propagate)
        models += [(f"{note} (with the tip radius scaled by the budget's +{tol * 100:g} % "
                    "tolerance)", replace(m.layer_only(), tip=tip.scaled(1.0 + tol)))
                   for note, m in models]
    for note, m in models:
        for d, where in ((max(fitted, 0.0), ""), (deepest, approach)):
            try:
                s = m.shape(np.array([d]))
            except GeometryError as exc:
                raise GeometryError(f"{src}: {exc}{note}{where}") from None
            if not (np.all(np.isfinite(s)) and np.all(s > 0)):
                raise GeometryError(
                    f"{src}: the contact model ({m.describe()}) gives no positive force at "
                    f"depth {d * 1e3:.4g} mm{note}; check the tip geometry and thickness{where}"
                )
    return data


def check_columns(checks: list[CheckResult], notes: str) -> dict:
    """``model_ok``, ``m_free``, ``misfit_effect``, ``misfit_checks`` and the failed checks'
    flags appended to ``notes`` (:func:`palpbayes.checks.checks_summary`), as ``notes``,
    ``flag_codes`` and ``flag_level`` (:func:`palpbayes.flagcodes.flag_columns`)."""
    out = checks_summary(checks)
    out.update(flag_columns("; ".join([f for f in [notes] if f] + out.pop("flags"))))
    return out


def fit_trace(trace: IndentationTrace, options: FitOptions,
              posterior_dir: str | Path | None = None) -> FitOutcome:
    """Fit one trace with the requested method(s).

    The least-squares fit always runs (its E is recorded beside the posterior); its row is
    returned for ``method`` "lsq" or "both", with the model checks (:mod:`palpbayes.checks`)
    of its own fit.  A least-squares failure (the paper's model has no offset) does not stop
    the Bayesian fit: the row says why.

    For tip ``sphere`` (the exact Sneddon law, docs/design.md §1; any tip whose law has a
    ``hertz_approximation``) the paper's choice is also fitted:
    least squares with the paraboloid (Hertz) law at the sphere's radius on the same points
    (same window, constraint, Poisson ratio and thickness model).  The two least-squares fits
    share the points and the paper's model, both on the force tared by the pre-contact
    baseline (the paper's model has no offset: an untared one would pose as the Hertz gap), so
    their ratio is the Hertz approximation's effect alone: ``E_hertz_rel_diff`` =
    E_hertz,lsq/E_lsq − 1, and every row gets ``E_hertz_pa`` = its own E times that ratio
    (the Bayesian row: the modulus its fit would give with the Hertz law).  Hertz
    overestimates the force at a given E, so E_hertz is a few per cent *below* E at the
    paper's depths (about −3 % at d/R ≈ 0.3).  Other tips, or a failed fit: NaN.
    """
    data = check_fittable(trace, options)
    paper = replace(data, model=data.model.half_space())  # the least-squares baseline's
    try:
        lsq = fit_lsq_data(paper, trace_id=trace.trace_id)
        lsq_row = {**lsq.summary_row(), "layer": "half-space (the paper's)",
                   "model_fitted": "half-space",
                   **layer_alternatives(lsq.E, lsq.z_surf, paper.z, paper.model, data.model)}
    except FitError as exc:
        if options.method == "lsq":
            raise
        # the paper's model (no offset) can fail where the Bayesian one fits: say so in its row
        lsq = None
        lsq_row = {"trace_id": trace.trace_id, "method": "lsq", "tip": data.model.tip.kind,
                   "n_points": data.n_points, "E_pa": float("nan"), "nu": data.model.nu,
                   **flag_columns(f"least squares failed: {exc}")}
    ratio = float("nan")  # E_hertz / E of the paper's least squares on the tared force
    approximation = get_law(data.model.tip).hertz_approximation
    if approximation is not None:
        tared = paper
        if not options.tare:  # the paper's model has no offset: an untared one biases E
            tared = replace(prepare(trace, paper.model, f_unc=options.f_unc,
                                    fit_fraction=options.fit_fraction,
                                    max_depth=options.max_depth, tare=True),
                            model=paper.model)
        hertz = replace(tared, model=replace(tared.model, tip=approximation(tared.model.tip)))
        try:
            ratio = float(fit_lsq_data(hertz, trace_id=trace.trace_id).E
                          / fit_lsq_data(tared, trace_id=trace.trace_id).E)
        except (FitError, ZeroDivisionError):
            ratio = float("nan")

    def with_hertz(row: dict) -> dict:
        e = row.get("E_pa")
        e = float("nan") if e is None else float(e)
        return {**row, "E_hertz_pa": e * ratio, "E_hertz_rel_diff": ratio - 1.0}

    meta = {"material": trace.material, "specimen": trace.specimen,
            "repetition": trace.repetition, "rest_time_s": trace.rest_time,
            "nu_source": nu_source(trace, options),
            "baseline_n": data.baseline.level if data.baseline is not None else float("nan"),
            "f_unc_n": data.f_unc}
    rows = []
    seed = trace_seed(options.seed, trace.trace_id)
    if options.method in ("lsq", "both"):
        if lsq is not None:  # the paper's model: no offset term
            lsq_row.update(check_columns(check_fit(
                paper, z_surf=lsq.z_surf, estar=lsq.Estar, f0=0.0, sigma=lsq.rms, seed=seed),
                lsq_row.get("notes", "")))
        rows.append(with_hertz({**lsq_row, **meta}))
    bayes = None
    path = None
    if options.method in ("bayes", "both"):
        with warnings.catch_warnings():
            if not options.strict:
                warnings.simplefilter("ignore", ConvergenceWarning)  # flagged in the row
            bayes = fit_bayes_data(
                data, noise=options.noise, baseline=options.baseline, priors=options.priors,
                budget=options.budget,
                settings=options.settings, seed=seed,
                strict=options.strict, trace_id=trace.trace_id, lsq=lsq,
                engine=options.engine, with_model_form=options.model_form,
                platens=options.platens,
            )
        rows.append(with_hertz({**bayes.summary_row(), **meta}))
        if posterior_dir is not None:
            path = bayes.to_netcdf(posterior_file(posterior_dir, trace.trace_id))
    return FitOutcome(rows=rows, lsq=lsq, bayes=bayes, posterior_path=path)
