"""One fitting job: a trace, its model and the chosen methods -> summary rows (+ posterior).

This is the unit of work that ``palpbayes fit`` runs for a single trace and that
:mod:`palpbayes.campaign` distributes over worker processes.  It does no output itself except
the per-trace netCDF when ``posterior_dir`` is given (written atomically).
"""

# Long module: one job, fitting one trace of a campaign; the fittability checks and their hints
#   are the job's first half.

from __future__ import annotations

import warnings
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from ..bayes import BayesResult, fit_bayes_data
from ..bayes.flags import BASELINE_HINT
from ..bayes.noisemodels import EXACT_NOISE_MODELS
from ..checks import CheckResult, check_fit, checks_summary
from ..contact import get_law
from ..errors import (
    ConvergenceWarning,
    FitError,
    GeometryError,
    InputError,
    NoContactError,
    PalpbayesError,
)
from ..fitdata import FitData, prepare
from ..fitdata import tared as tared_data
from ..flagcodes import flag_columns, split_flags
from ..forcescale import force_scale_flag as scale_flag
from ..lsq import LSQResult, fit_lsq_data
from ..outputs import posterior_file
from ..refit import layer_alternatives
from ..trace import IndentationTrace
from ..twin import twin_depth_limit, twin_depth_limit_reason
from ..units import format_pressure
from .options import LAYER_MODES, METHODS, FitOptions
from .tracemodel import nu_source, prepare_twin, trace_model, trace_seed, trace_specimen

# FitOptions, METHODS and LAYER_MODES (.options), trace_model and its helpers (.tracemodel) are
# imported from here too
__all__ = ["FitOptions", "FitOutcome", "fit_trace", "fit_trace_rows", "check_fittable",
           "force_scale_flag", "tried_baseline_hint",
           "trace_model", "nu_source", "fitted_methods", "failed_rows", "trace_specimen",
           "prepare_twin", "trace_seed", "SUMMARY_COLUMNS", "METHODS",
           "LAYER_MODES"]


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
    # ratio − 1 (fit_trace); NaN under a material law (its twin presses the true sphere)
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
    # the material law (bayes rows; palpbayes.bayes.lawfit): linear, or a hyperelastic law
    # whose E_pa is the small-strain modulus E0, its shape parameters (posterior medians and
    # intervals, each finite-element node's probability when they were free), and what a
    # compression test would read at instron_strain: the chord of the law's uniaxial curve
    # over the draws, with its 90 % interval
    "law", "law_params", "instron_strain", "E_instron_law_pa", "E_instron_law_lo_pa",
    "E_instron_law_hi_pa",
]

@dataclass
class FitOutcome:
    """Rows for ``summary.csv`` and the result objects of one trace."""

    rows: list[dict]
    lsq: LSQResult | None = None
    bayes: BayesResult | None = None
    posterior_path: Path | None = None


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
    flag = force_scale_flag(data, options)
    if flag is not None and options.strict:
        raise InputError(f"{src}: {flag} (an error with --strict)")

    depth = data.z_contact - data.z_min
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
            f"the twin of the {model.specimen.describe()} is solved to "
            f"({twin_depth_limit_reason(model.specimen, tip)}); fit a shallower window "
            "(--max-depth M)")
    if model.specimen is not None or model.law is not None:  # the finite elements, after
        try:                                                   # every cheap check
            prepare_twin(model, options)
        except GeometryError as exc:
            raise GeometryError(f"{src}: {exc}") from None
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
        models += [(f" (on a {b} layer)", model.linear().variant(thickness=h, base=b))
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


def force_scale_flag(data: FitData, options: FitOptions) -> str | None:
    """The ``force scale`` warning of a trace whose force reads as if it were in another unit,
    else None.

    A force in another unit than the one given (N read as mN) scales the data, their noise
    and E by the same factor: the fit itself cannot see it.  Two references can:

    * the declared sensor noise ``--noise-pp`` (``options.priors.noise_pp``): the noise before
      contact more than :data:`palpbayes.sensor_noise.NOISE_SCALE_FACTOR` times from it;
    * without one, the tip (:func:`palpbayes.forcescale.force_scale_doubt`): the noise before
      contact and E (:meth:`~palpbayes.fitdata.FitData.rough_modulus`) far more typical of
      an instrument of the tip's size with the force multiplied by a power of 1,000.

    ``--f-unc`` is not compared: it is a contact threshold, which a user may set far above the
    noise on purpose.
    """
    base = data.baseline
    noise = base.noise_pp if base is not None and base.reliable else None
    return scale_flag(data.model.tip, data.z_contact - data.z_min, data.rough_modulus(), noise,
                      options.priors.noise_pp)


def tried_baseline_hint(row: dict, data: FitData, options: FitOptions, seed: int,
                        trace_id: str, lsq: LSQResult | None) -> str:
    """``row``'s notes with each :data:`~palpbayes.bayes.flags.BASELINE_HINT` ("try
    --baseline linear") replaced by what trying it gave: a hint is tried before it is given.

    The Bayesian fit is run again with ``baseline="linear"`` (the exact engine where the noise
    model allows, without the model form: the question is only whether the flag goes away).
    The hint stays, with the E it gives, when that fit converges, none of the flags that carried
    the hint comes back and its model checks pass where the row's did; otherwise the notes say
    it was tried and why it does not help (a fit that fails, a flag that stays, a model check
    it fails), with its E, so that nobody follows a hint that makes the answer worse.
    """
    notes = str(row["notes"])
    heads = [f[:f.find(" (")] if " (" in f else f
             for f in split_flags(notes) if BASELINE_HINT in f]
    engine = ("exact" if options.noise in EXACT_NOISE_MODELS
              and options.priors.surface == "loading" else options.engine)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ConvergenceWarning)
            alt = fit_bayes_data(
                data, noise=options.noise, baseline="linear", priors=options.priors,
                budget=options.budget, settings=options.settings, seed=seed, strict=False,
                trace_id=trace_id, lsq=lsq, engine=engine, with_model_form=False,
                platens=options.platens).summary_row()
    except (PalpbayesError, ValueError, ArithmeticError) as exc:  # InputError: no mass, ...
        return notes.replace(BASELINE_HINT, f"--baseline linear was tried and its fit fails: "
                                            f"{str(exc).replace('; ', ', ')}")
    shift = f"E {format_pressure(alt['E_pa'])}, {alt['E_pa'] / row['E_pa'] - 1:+.1%} " \
            "against this row"
    stays = [h for h in heads if h in str(alt["notes"])]
    why = ("the same flag comes back" if stays else "its fit does not converge"
           if not alt["converged"] else "its model checks fail where this row's pass"
           if alt["model_ok"] is False and row["model_ok"] is True else None)
    if why is None:
        return notes.replace(BASELINE_HINT, f"{BASELINE_HINT}: tried, the flag goes away, "
                                            f"{shift}")
    return notes.replace(BASELINE_HINT, f"--baseline linear was tried and does not help, {why}, "
                                        f"{shift}")


def with_flag(row: dict, flag: str | None) -> dict:
    """``row`` with ``flag`` first among its flags (``notes``, ``flag_codes``, ``flag_level``)."""
    if flag is None:
        return row
    text = row.get("notes")
    return {**row, **flag_columns("; ".join(
        [flag] + ([text] if isinstance(text, str) and text else [])))}


def _check_prepared(data: FitData, trace: IndentationTrace, options: FitOptions) -> None:
    """``data`` were prepared from ``trace`` with ``options``' window (else an InputError
    naming the mismatch, raised, never recorded as a failed fit)."""
    same = (data.loading.n_points <= trace.n_points
            and data.max_depth == options.max_depth
            and (options.f_unc is None or data.f_unc == options.f_unc)
            and (options.fit_fraction is None or data.fit_fraction == options.fit_fraction)
            and (data.tare != 0.0) <= options.tare)
    if not same:
        raise InputError(f"{trace.trace_id}: the fit data given were prepared with other "
                         "options or from another trace; prepare them with check_fittable")


def check_columns(checks: list[CheckResult], notes: str) -> dict:
    """``model_ok``, ``m_free``, ``misfit_effect``, ``misfit_checks`` and the failed checks'
    flags appended to ``notes`` (:func:`palpbayes.checks.checks_summary`), as ``notes``,
    ``flag_codes`` and ``flag_level`` (:func:`palpbayes.flagcodes.flag_columns`)."""
    out = checks_summary(checks)
    out.update(flag_columns("; ".join([f for f in [notes] if f] + out.pop("flags"))))
    return out


def fit_trace(trace: IndentationTrace, options: FitOptions,
              posterior_dir: str | Path | None = None, *,
              data: FitData | None = None) -> FitOutcome:
    """Fit one trace with the requested method(s).

    ``data`` are the trace's fit data from :func:`check_fittable` with the same options, when
    the caller has checked it already (:func:`palpbayes.campaign.run.fit_campaign`): the trace
    is prepared once per fit.

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
    if data is None:
        data = check_fittable(trace, options)
    else:
        _check_prepared(data, trace, options)
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
        try:  # the paper's model has no offset: an untared one biases E
            tared = tared_data(paper)  # NoContactError: the tared window is too narrow
            hertz = replace(tared, model=replace(tared.model,
                                                 tip=approximation(tared.model.tip)))
            exact = (lsq.E if tared is paper and lsq is not None  # tared already: the row's
                     else fit_lsq_data(tared, trace_id=trace.trace_id).E)
            ratio = float(fit_lsq_data(hertz, trace_id=trace.trace_id).E / exact)
        except (FitError, NoContactError, ZeroDivisionError):
            ratio = float("nan")  # the Hertz column says NaN; the fits stand

    def with_hertz(row: dict) -> dict:
        e = row.get("E_pa")
        e = float("nan") if e is None or row.get("law", "linear") != "linear" else float(e)
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
        row = bayes.summary_row()
        if options.baseline == "constant" and BASELINE_HINT in str(row["notes"]):
            row = {**row, **flag_columns(tried_baseline_hint(row, data, options, seed,
                                                             trace.trace_id, lsq))}
        rows.append(with_hertz({**row, **meta}))
        if posterior_dir is not None:
            path = bayes.to_netcdf(posterior_file(posterior_dir, trace.trace_id))
    flag = force_scale_flag(data, options)
    rows = [with_flag(r, flag) for r in rows]
    return FitOutcome(rows=rows, lsq=lsq, bayes=bayes, posterior_path=path)


def failed_rows(trace: IndentationTrace, methods: list[str], exc: Exception) -> list[dict]:
    """``summary.csv`` rows saying why ``methods`` failed on ``trace`` (flag ``fit_failed``)."""
    return [{
        "trace_id": trace.trace_id, "method": m, "tip": trace.tip.kind,
        "converged": False, **flag_columns(f"fit failed: {exc}"), "material": trace.material,
        "specimen": trace.specimen, "repetition": trace.repetition,
        "rest_time_s": trace.rest_time,
    } for m in methods]


def fit_trace_rows(trace: IndentationTrace, options: FitOptions,
                   posterior_dir: str | Path | None = None, *,
                   data: FitData | None = None) -> FitOutcome:
    """:func:`fit_trace`, with a :class:`~palpbayes.errors.FitError` recorded in the rows
    instead of raised: what ``palpbayes fit`` (every trace of a campaign) and
    :func:`palpbayes.fit` run.

    With ``method="both"`` a failed Bayesian fit keeps the least-squares row and adds a
    ``fit_failed`` row for it; otherwise every method's row says why it failed.  Bad input
    (:class:`~palpbayes.errors.InputError`) is raised.
    """
    try:
        return fit_trace(trace, options, posterior_dir, data=data)
    except InputError:
        raise
    except FitError as exc:
        if options.method == "both":
            try:
                out = fit_trace(trace, replace(options, method="lsq"), data=data)
                return replace(out, rows=out.rows + failed_rows(trace, ["bayes"], exc))
            except InputError:
                raise
            except FitError:
                pass
        return FitOutcome(rows=failed_rows(trace, fitted_methods(options), exc))


def fitted_methods(options: FitOptions) -> list[str]:
    """The ``method`` values of a trace's rows under ``options``."""
    return ["bayes", "lsq"] if options.method == "both" else [options.method]
