"""Walker trace plots of the sampled parameters (convergence at a glance)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from .style import KPA, METHOD_COLORS, MN, UM

__all__ = ["plot_walkers"]


def _attrs(result: Any) -> dict:
    """Fit attributes (trace_id, burn, thin, model, ...) wherever arviz put them.

    In memory ``az.from_dict(attrs=...)`` keeps them on the InferenceData; after a netCDF round
    trip they sit on the groups (observed_data, constant_data).
    """
    idata = getattr(result, "idata", result)
    out: dict = {}
    for group in ("constant_data", "observed_data", "sample_stats", "posterior"):
        ds = getattr(idata, group, None) if hasattr(idata, group) else None
        if ds is not None:
            out.update({k: v for k, v in dict(getattr(ds, "attrs", {})).items()
                        if k not in out})
    out.update(dict(getattr(idata, "attrs", {}) or {}))
    return out


_WALKER_VARS: dict[str, tuple[str, float, str]] = {
    # name -> (label, scale, unit)
    "E_star": ("E*", KPA, "kPa"),
    "z_surf": ("z_surf − median", UM, "µm"),
    "sigma": ("sigma", MN, "mN"),
    "F0": ("F0", MN, "mN"),
    "phi": ("phi (AR(1))", 1.0, "-"),
    "nu_t": ("nu_t (Student-t)", 1.0, "-"),
}


def plot_walkers(result: Any, var_names: Sequence[str] | None = None, *,
                 fig: Figure | None = None, max_walkers: int = 64,
                 title: bool = True) -> Figure:
    """Trace plots: each sampled parameter vs sampler step, one thin line per walker.

    The stored chains are after burn-in and thinning (netCDF attributes ``burn`` and ``thin``);
    the x axis is the sampler step.  Well-mixed walkers overlap as a uniform band; a walker
    stuck apart or a drift is a convergence problem (R-hat, ESS in the title).

    Parameters
    ----------
    result
        A :class:`~palpbayes.bayes.BayesResult` or an arviz ``InferenceData``.
    var_names
        Posterior variables (default: E_star, z_surf, sigma, F0 and phi / nu_t if present).
    fig
        Figure to draw in (default: a new figure, one row per variable).
    max_walkers
        Walkers drawn at most.
    title
        Add a title naming the trace and the number of walkers.

    Returns
    -------
    matplotlib.figure.Figure
    """
    idata = getattr(result, "idata", result)
    post = idata.posterior
    if var_names is None:
        var_names = [n for n in _WALKER_VARS if n in post]
    attrs = _attrs(result)
    burn = int(attrs.get("burn", 0))
    thin = int(attrs.get("thin", 1))
    diag = getattr(result, "diagnostics", None)
    if fig is None:
        fig = Figure(figsize=(8.0, 1.6 * len(var_names) + 0.6), layout="constrained")
    axes = np.atleast_1d(fig.subplots(len(var_names), 1, sharex=True))
    for ax, name in zip(axes, var_names, strict=True):
        label, scale, unit = _WALKER_VARS.get(name, (name, 1.0, "-"))
        x = np.asarray(post[name])  # (chain = walker, draw)
        if name == "z_surf":
            x = x - np.median(x)
        x = x[:max_walkers] * scale
        steps = burn + thin * np.arange(x.shape[1])
        for w in x:
            ax.plot(steps, w, lw=0.3, alpha=0.5, color=METHOD_COLORS["bayes"], rasterized=True)
        ax.set_ylabel(f"{label} [{unit}]", fontsize="small")
        if diag is not None and name in getattr(diag, "rhat", {}):
            ax.set_title(f"{name}: R-hat {diag.rhat[name]:.4f}, ESS bulk "
                         f"{diag.ess_bulk[name]:.0f}, tail {diag.ess_tail[name]:.0f}",
                         fontsize="small", loc="left")
    axes[-1].set_xlabel(f"Sampler step (after burn-in {burn}, thinned by {thin})")
    tid = attrs.get("trace_id", getattr(result, "trace_id", ""))
    if title:
        fig.suptitle(f"Walkers{': ' + str(tid) if tid else ''} ({x.shape[0]} walkers)",
                     fontsize="medium")
    return fig
