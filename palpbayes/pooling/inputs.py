"""Stage-1 inputs of the pooling: per-trace posteriors and the shared systematic factor.

Reads the per-trace posterior netCDFs written by :func:`palpbayes.campaign.fitjob.fit_trace`,
rebuilds a trace's fitted points from them, and draws the systematic factor of the uncertainty
budget (:mod:`palpbayes.bayes.budget`) once per pooled draw (see :mod:`palpbayes.pooling`).
"""

from __future__ import annotations

import os

import numpy as np
import pandas as pd

from ..bayes.budget import BudgetSpec, propagate
from ..bayes.diagnostics import import_arviz
from ..contact import youngs_modulus
from ..errors import InputError
from ..fitdata import FitData, ModelSpec
from ..trace import IndentationTrace

__all__ = ["read_posterior", "posterior_attrs", "fitdata_from_posterior", "systematic_factor"]


def read_posterior(path: str | os.PathLike):
    """Read a posterior netCDF fully into memory (arviz InferenceData); the file is closed."""
    az = import_arviz()
    try:
        with az.rc_context(rc={"data.load": "eager"}):
            return az.from_netcdf(str(path))
    except (KeyError, ValueError):  # arviz without that rc key
        return az.from_netcdf(str(path))


def posterior_attrs(idata) -> dict:
    """The fit's attributes of a posterior (InferenceData-level, else its groups')."""
    attrs = dict(getattr(idata, "attrs", None) or {})
    for group in ("constant_data", "posterior"):
        if "z_admissible_m" in attrs:
            break
        try:
            attrs = {**dict(getattr(idata, group).attrs), **attrs}
        except AttributeError:
            continue
    return attrs


def fitdata_from_posterior(idata, model: ModelSpec) -> FitData:
    """Rebuild the fitted points of a trace from its posterior netCDF (for the budget).

    Uses ``constant_data.z`` and ``observed_data.force`` and the attributes ``z_admissible_m``,
    ``f_unc_n``, ``fit_fraction``, ``z_prior_m`` (its lower end is the deepest loading sample)
    and ``tare_n`` written by :func:`palpbayes.bayes.fit_bayes_data`; the fitted points stand
    in for the loading segment (only the depths and the model matter to
    :func:`palpbayes.bayes.budget.propagate`), and the pre-contact baseline is not stored.
    """
    try:
        z = np.asarray(idata.constant_data["z"], dtype=float).ravel()
        force = np.asarray(idata.observed_data["force"], dtype=float).ravel()
        attrs = posterior_attrs(idata)
        z_lo, z_hi = (float(v) for v in np.asarray(attrs["z_admissible_m"]).ravel()[:2])
        f_unc = float(attrs["f_unc_n"])
        fraction = float(attrs["fit_fraction"])
        z_prior = np.asarray(attrs.get("z_prior_m", [z.min()]), dtype=float).ravel()
        tare = float(attrs.get("tare_n", 0.0))
    except (KeyError, AttributeError, ValueError) as exc:
        raise InputError(f"posterior file lacks the fitted data needed for the budget ({exc})"
                         ) from None
    loading = IndentationTrace(np.arange(z.size, dtype=float), z, force,
                               trace_id=str(attrs.get("trace_id", "trace")))
    return FitData(z=z, force=force, z_contact=z_lo, z_top=z_hi, z_min=float(z_prior[0]),
                   f_unc=f_unc, fit_fraction=fraction, loading=loading, model=model, tare=tare)


def systematic_factor(data: FitData, z_surf: float, estar: float, spec: BudgetSpec, n: int,
                      rng: np.random.Generator
                      ) -> tuple[np.ndarray, pd.DataFrame, np.ndarray | None]:
    """Draws of the shared systematic factor f = E_budget / E_stat and its input table.

    :func:`palpbayes.bayes.budget.propagate` is run with the E* draws held at ``estar`` (the
    representative trace's posterior median), so its output divided by E_stat = estar·(1 − nu²)
    (nu the model's) is the product of the Poisson-ratio, tip-radius, gain and compliance
    factors only, drawn from the same :class:`BudgetSpec` distributions.

    Parameters
    ----------
    data
        Fitted points of the representative trace (depths, model).
    z_surf
        [m] Its posterior median surface height.
    estar
        [Pa] Its posterior median E*.
    spec
        Budget distributions (as used by the per-trace fits).
    n
        Number of draws.
    rng
        Random generator.

    Returns
    -------
    factor : ndarray
        (n,) draws of f [-].
    table : DataFrame
        One row per systematic input: ``input, distribution, var_log`` (variance of log f_k).
    nu : ndarray
        (n,) the Poisson ratio of each draw [-] (for the Instron-equivalent modulus).
    """
    bud = propagate(np.full(n, float(estar)), data, float(z_surf), spec, rng)
    factor = bud.E / youngs_modulus(float(estar), data.model.nu)
    tab = bud.table[bud.table["input"] != "E* (posterior)"].copy()
    tab["var_log"] = (tab["rel_sd_pct"] / 100.0) ** 2
    return factor, tab[["input", "distribution", "var_log"]].reset_index(drop=True), bud.nu
