"""Fit the stiffening law to a palpation series and choose the law the data support.

:func:`fit_stiffening` fits the three laws of :mod:`palpbayes.stiffening.model` to estimates
E_i ± s_i at rest times t_i (:mod:`palpbayes.stiffening.sampler`), checks them
(:mod:`palpbayes.stiffening.selection`) and returns a
:class:`~palpbayes.stiffening.result.StiffeningResult`; :func:`fit_stiffening_summary` does it
for the rows of a ``summary.csv`` table.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike

from ..bayes.sampler import SamplerSettings
from ..errors import InputError
from ..intervals import LEVEL
from .model import N_PARAMS, PARAM_UNITS, physical_draws
from .result import StiffeningResult, parameter_table
from .sampler import mle, sample_law
from .selection import double_law_reasons, selection_message, single_law_reasons

__all__ = ["STIFFENING_SETTINGS", "fit_stiffening", "fit_stiffening_summary"]

#: emcee settings (5 parameters; degenerate posteriors need the DE moves).
STIFFENING_SETTINGS = SamplerSettings(n_walkers=40, max_steps=20000, min_steps=2000,
                                      check_every=500, moves="de", progress=False)


def fit_stiffening(rest_time: ArrayLike, E: ArrayLike, E_sd: ArrayLike | None = None, *,
                   seed: int | None = 0, settings: SamplerSettings | None = None,
                   level: float = LEVEL) -> StiffeningResult:
    """Fit E(t) = c1·e^(c2·t) + c3·e^(c4·t), the single exponential + constant and a constant.

    The preferred law is the double law if it is identifiable, else the single law if it
    passes its checks, else the constant ("no stiffening detected");
    :mod:`palpbayes.stiffening.selection`.

    Parameters
    ----------
    rest_time
        [s] Rest time before each palpation (finite, >= 0; at least two positive values).
    E
        [Pa] Modulus estimate of each palpation.
    E_sd
        [Pa] Its standard uncertainty (None: zero, the extra scatter absorbs the noise).
    seed
        Seed of the samplers.
    settings
        emcee settings (default :data:`STIFFENING_SETTINGS`).
    level
        Probability content of the reported intervals.

    Returns
    -------
    StiffeningResult
    """
    t = np.asarray(rest_time, dtype=float).ravel()
    y = np.asarray(E, dtype=float).ravel()
    s = np.zeros_like(y) if E_sd is None else np.asarray(E_sd, dtype=float).ravel()
    if not (t.size == y.size == s.size) or t.size < 3:
        raise InputError("rest_time, E and E_sd must have the same length, at least 3")
    if not (np.all(np.isfinite(t)) and np.all(t >= 0) and np.all(np.isfinite(y))
            and np.all(np.isfinite(s)) and np.all(s >= 0)):
        raise InputError("rest times must be finite and >= 0, E finite and E_sd finite >= 0")
    pos = t[t > 0]
    if np.unique(pos).size < 2:
        raise InputError("the stiffening law needs at least two distinct positive rest times")
    settings = settings or STIFFENING_SETTINGS
    scale = float(np.median(np.abs(y)))
    if not scale > 0:
        raise InputError("the modulus estimates are all zero")
    ys, ss = y / scale, s / scale
    t_min, t_max = float(pos.min()), float(t.max())
    bounds = (float(np.log(t_min / 5.0)), float(np.log(100.0 * t_max)))
    n, n_distinct = t.size, int(np.unique(t).size)
    # seeds: the first two children as before (double, single), a third for the constant
    ss_seed = np.random.SeedSequence(seed).spawn(3)
    seeds = [int(x.generate_state(1)[0]) for x in ss_seed]

    fits = {}
    for model, seed_k in zip(("double", "single", "constant"), seeds, strict=True):
        ll, theta = mle(model, t, ys, ss, bounds)
        raw, diag = sample_law(model, theta, t, ys, ss, bounds, settings, seed_k)
        fits[model] = (N_PARAMS[model] * np.log(n) - 2 * ll, raw, diag)
    bic_d, raw_d, diag_d = fits["double"]
    bic_s, raw_s, diag_s = fits["single"]
    bic_c, raw_c, diag_c = fits["constant"]

    draws, single, constant = (physical_draws(raw, scale) for raw in (raw_d, raw_s, raw_c))

    reasons = double_law_reasons(draws, bic_d, bic_s, n_distinct, t_max, diag_d, level)
    single_reasons = single_law_reasons(single, bic_s, bic_c, n_distinct, t_min, t_max, diag_s,
                                     level)
    identifiable = not reasons
    single_ok = not single_reasons
    preferred = "double" if identifiable else ("single" if single_ok else "constant")
    mean, sd = float(y.mean()), float(y.std(ddof=1))
    message = selection_message(n, draws, single, constant, bic_d, bic_s, bic_c, reasons,
                                single_reasons, mean, sd, level)
    converged_laws = {"double": bool(diag_d.converged), "single": bool(diag_s.converged),
                      "constant": bool(diag_c.converged)}
    return StiffeningResult(
        identifiable=identifiable, message=message, preferred=preferred,
        double=parameter_table(draws, PARAM_UNITS, level),
        single=parameter_table(single, PARAM_UNITS, level),
        draws=draws, single_draws=single, bic_double=float(bic_d), bic_single=float(bic_s),
        converged=converged_laws[preferred], n_points=n, n_distinct=n_distinct,
        reasons=reasons, single_identifiable=single_ok, single_reasons=single_reasons,
        constant=parameter_table(constant, PARAM_UNITS, level), constant_draws=constant,
        bic_constant=float(bic_c), converged_laws=converged_laws, E_mean_pa=mean, E_sd_pa=sd,
    )


def fit_stiffening_summary(summary: pd.DataFrame, *, method: str = "bayes",
                           seed: int | None = 0, settings: SamplerSettings | None = None,
                           **select: object) -> StiffeningResult:
    """:func:`fit_stiffening` on the rows of a ``summary.csv`` table with a rest time.

    Bayesian rows use the *statistical* estimate (``E_stat_pa`` ± ``E_stat_sd_pa``): the budget's
    systematic inputs are common to every palpation of a specimen and scale the whole curve,
    not its shape.  Least-squares rows use ``E_pa`` ± ``E_sd_pa``.  ``select`` filters rows by
    column value (e.g. ``material="White", tip="sphere"``).
    """
    e_col, s_col = ("E_stat_pa", "E_stat_sd_pa") if method == "bayes" else ("E_pa", "E_sd_pa")
    missing = {"method", "rest_time_s", e_col, s_col} - set(summary.columns)
    if missing:
        raise InputError(f"summary lacks column(s) {', '.join(sorted(missing))} for {method} "
                         "rows")
    df = summary[summary["method"] == method]
    for col, value in select.items():
        if col not in df.columns:
            raise InputError(f"summary has no column {col!r} to select on")
        df = df[df[col] == value]
    df = df[np.isfinite(df["rest_time_s"].astype(float))]
    df = df[np.isfinite(df[e_col].astype(float))]
    if df.empty:
        raise InputError(f"no {method} rows with a rest time to fit")
    return fit_stiffening(df["rest_time_s"].to_numpy(float), df[e_col].to_numpy(float),
                          df[s_col].to_numpy(float), seed=seed, settings=settings)
