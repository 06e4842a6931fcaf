"""All adequacy checks of one fit (:func:`run_checks`); see :mod:`palpbayes.checks`."""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from ..fitdata import FitData, ModelSpec
from ..intervals import central
from .core import CheckResult, ShapeTable, noise_lag1, validated_arrays
from .depth import depth_consistency_check
from .effect import grade_checks
from .exponent import exponent_check
from .ppc import posterior_predictive_check
from .rate import rate_dependence_check
from .residuals import residual_structure_check


# Many parameters: a fit's point estimates (surface, E*, offset, tilt, sigma) and draws are what
# every check tests; checks/ lies below the fits' result objects.
def run_checks(z, force, model: ModelSpec, *, z_surf: float, estar: float, f0: float,
               f1: float = 0.0, sigma: float, draws: dict | None = None,
               baseline_lag1: float | None = None, baseline: str | None = None,
               z_ref: float | None = None, stat_rel_halfwidth: float | None = None,
               rng: np.random.Generator | int | None = None,
               cycle=None) -> list[CheckResult]:
    """Run every adequacy check on one fit.

    Model force: mu(z) = E*·s(z_surf - z) + F0 + F1·(z - z_ref), z_ref = highest z unless
    given.  Runs the exponent, residual-structure and depth-consistency checks, and the
    posterior-predictive check when ``draws`` are given, and the rate-dependence check
    (:func:`~palpbayes.checks.rate.rate_dependence_check`) when ``cycle`` has a hold or a
    retract.

    Parameters
    ----------
    z, force
        [m], [N] fitted samples in time order.
    model
        The fitted contact model.
    z_surf, estar, f0, f1, sigma
        Point estimates (posterior medians): [m], [Pa], [N], [N/m], [N].
    draws
        Optional posterior draws: dict of equal-length arrays ``E_star`` [Pa], ``z_surf``
        [m], ``F0`` [N], ``sigma`` [N], optional ``F1`` [N/m] and ``phi``, and, for a layer
        whose thickness or base was sampled, ``thickness`` [m] and ``bonded`` (1/0/NaN).
    baseline_lag1
        Lag-1 autocorrelation of the noise; default the fit's median ``phi`` if drawn, else
        :func:`noise_lag1` of the pre-contact samples, else estimated from the residuals.
    baseline
        ``"constant"`` or ``"linear"``; default linear when f1 != 0 or ``F1`` is drawn.
    z_ref
        [m] Linear-baseline reference height.
    stat_rel_halfwidth
        Half width of E*'s statistical 90 % interval over E* [-] for the grading; default
        that of ``draws["E_star"]``, else 1.645 se of the depth check's fit.
    rng
        Generator or seed for the posterior-predictive replicates.
    cycle
        The whole recording (:class:`~palpbayes.trace.IndentationTrace`) when it goes on
        past the loading (a hold, a retract); None: no rate check.

    Returns
    -------
    list of CheckResult
        In the order exponent, residual_structure, depth_consistency[, ppc][, rate], each graded
        (:func:`~palpbayes.checks.effect.grade_checks`: its effect on E and severity; the
        statistical interval is the draws' 90 % interval of E*, else 1.645 se).
    """
    z, f = validated_arrays(z, force)
    z_ref = float(z.max()) if z_ref is None else float(z_ref)
    if baseline is None:
        baseline = "linear" if (f1 != 0 or (draws is not None and "F1" in draws)) else "constant"
    phi = baseline_lag1
    if phi is None and draws is not None and "phi" in draws:
        phi = float(np.median(draws["phi"]))
    if phi is None:
        phi = noise_lag1(z, f, z_surf)
    mu = estar * model.shape(z_surf - z) + f0 + f1 * (z - z_ref)
    out = [
        exponent_check(z, f, model, z_surf, baseline=baseline, z_ref=z_ref, noise_lag1=phi),
        residual_structure_check(z, f - mu, z_surf, sigma, baseline_lag1=phi),
        depth_consistency_check(z, f, model, z_surf, baseline=baseline, z_ref=z_ref,
                                noise_lag1=phi),
    ]
    if draws is not None:
        es = np.asarray(draws["E_star"], dtype=float)
        zs = np.asarray(draws["z_surf"], dtype=float)
        f0s = np.asarray(draws["F0"], dtype=float)
        f1s = np.asarray(draws.get("F1", np.zeros_like(es)), dtype=float)
        keep = np.linspace(0, es.size - 1, min(es.size, 200)).round().astype(int)
        depth = zs[keep, None] - z[None, :]
        if "thickness" in draws or "bonded" in draws:  # each draw its own layer
            layer = {k: np.asarray(draws[k], dtype=float)[keep] if k in draws else None
                     for k in ("thickness", "bonded")}
            s = model.shape_of_draws(depth, **layer)
        else:
            s = ShapeTable(model, 1.5 * (float(np.max(zs[keep])) - float(z.min()))).shape(depth)
        curves = (es[keep, None] * s + f0s[keep, None] + f1s[keep, None] * (z - z_ref)[None, :])
        sig = np.asarray(draws["sigma"], dtype=float)[keep]
        ph = np.asarray(draws["phi"], dtype=float)[keep] if "phi" in draws else None
        out.append(posterior_predictive_check(z, f, curves, sig, phi=ph, rng=rng,
                                              z_surf=z_surf))
    if cycle is not None:
        rate = rate_dependence_check(cycle, model, z_surf=z_surf, estar=estar, f0=f0, f1=f1,
                                     z_ref=z_ref, sigma=sigma, noise_lag1=phi)
        if rate is not None:
            out.append(rate)
    half = stat_rel_halfwidth
    if half is None and draws is not None:
        lo, hi = central(draws["E_star"])
        half = 0.5 * (hi - lo) / estar if estar > 0 else None
    return grade_checks(out, z, f, model, z_surf=z_surf, estar=estar, f0=f0, f1=f1,
                        stat_rel_halfwidth=half,
                        baseline=baseline, z_ref=z_ref, noise_lag1=phi)


# Many parameters: as run_checks, from a FitData: the point estimates every check tests.
def check_fit(data: FitData, *, z_surf: float, estar: float, f0: float, f1: float = 0.0,
              sigma: float, baseline: str = "constant", z_ref: float | None = None,
              draws: dict | None = None, stat_rel_halfwidth: float | None = None,
              seed: int = 0) -> list[CheckResult]:
    """:func:`run_checks` on the points of a prepared fit, with the rate check when the
    recording goes on past the loading (``data.cycle``: a hold, a retract).

    The noise's own lag-one correlation is read from the pre-contact baseline
    (:mod:`palpbayes.baseline`) when it is reliable, so correlated sensor noise is not taken
    for misfit.  A trace too short for the checks gets none (an empty list), not an error.

    Parameters
    ----------
    data
        The fitted points and their contact model.
    z_surf, estar, f0, f1, sigma
        [m], [Pa], [N], [N/m], [N] the fit's surface, modulus, baseline and noise.
    baseline, z_ref
        Baseline model and the linear baseline's reference height [m].
    draws
        Posterior draws (``E_star``, ``z_surf``, ``F0``, ``sigma`` [, ``F1``, ``phi``]) for
        the posterior-predictive check; None skips it.
    stat_rel_halfwidth
        As :func:`run_checks`.
    seed
        Seed of the replicated data.
    """
    base = data.baseline
    lag1 = base.lag1 if base is not None and base.reliable else None
    try:
        return run_checks(data.z, data.force, data.model, z_surf=z_surf, estar=estar, f0=f0,
                          f1=f1, sigma=sigma, draws=draws, baseline_lag1=lag1,
                          baseline=baseline, z_ref=z_ref,
                          stat_rel_halfwidth=stat_rel_halfwidth, rng=seed,
                          cycle=data.cycle)
    except InputError:
        return []
