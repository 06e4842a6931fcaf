"""Failure modes a converged posterior can still show: two surface heights, a surface the
data barely constrain, a parameter at a hard prior bound (the prior, not the data, shaping it)."""

from __future__ import annotations

import math

import numpy as np

from ..sensor_noise import mad_sd
from ..units import format_length, format_pressure
from .priors import TracePrior

__all__ = ["BOUND_SDS", "BASELINE_HINT", "is_bimodal", "bound_flags", "posterior_flags"]

#: A posterior whose median lies within this many posterior sd of a hard prior bound is flagged.
BOUND_SDS = 3.0
#: The hint of a flag that a tilted or drifting baseline may explain; ``palpbayes fit`` tries
#: it before it is given (:func:`palpbayes.campaign.fitjob.tried_baseline_hint`).
BASELINE_HINT = "try --baseline linear"


def is_bimodal(x: np.ndarray, gap: float = 6.0, min_mass: float = 0.05) -> bool:
    """True if the sorted draws ``x`` have an empty gap wider than ``gap`` robust sd (MAD of
    the larger side) with at least ``min_mass`` of the draws on each side of it.
    """
    x = np.sort(np.ravel(x))
    n = x.size
    if n < 20:
        return False
    lo_i, hi_i = int(min_mass * n), int((1 - min_mass) * n)
    d = np.diff(x)[lo_i:hi_i]
    if d.size == 0:
        return False
    i = lo_i + int(np.argmax(d))
    left, right = x[: i + 1], x[i + 1:]
    big = left if left.size >= right.size else right
    scale = mad_sd(big)
    return bool(scale > 0 and x[i + 1] - x[i] > gap * scale)


def bound_flags(post_theta: dict[str, np.ndarray], prior: TracePrior) -> list[str]:
    """A flag for every sampled parameter whose posterior reaches a hard prior bound.

    "Reaches": the median lies within :data:`BOUND_SDS` posterior sd of the bound (or the sd is
    zero at the bound).  The prior, not the data, then shapes that side of the posterior.
    """
    out = []
    causes = {
        ("z_surf", "upper"): "the surface sits at the top of the recorded approach: the trace "
                             f"may start in contact, or the baseline is not flat ({BASELINE_HINT}"
                             "), or record a longer approach",
        ("z_surf", "lower"): "the surface sits at the deepest point: no contact is resolved",
        ("log_Estar", "lower"): "E* at the lower end of its prior range (check units)",
        ("log_Estar", "upper"): "E* at the upper end of its prior range (check units)",
        ("phi", "upper"): "noise correlation phi at its bound: the residuals wander like drift "
                          f"({BASELINE_HINT}) or the model misfits",
        ("phi", "lower"): "noise correlation phi at its lower bound",
        ("log_nu_t", "lower"): "Student-t degrees of freedom at 2: heavy outliers",
        ("log_nu_t", "upper"): "Student-t degrees of freedom at 200: the noise is Gaussian",
    }
    causes[("log_h", "lower")] = (
        "the layer's thickness piles up at the thinnest the prior allows: the data ask for a "
        "layer thinner than the indentation, so the layer model does not explain how the "
        "force stiffens (a strain-stiffening material, an onset before the surface, a wrong "
        "tip?), and E and h are the prior's, not the data's")
    for name, (lo, hi) in prior.bounds.items():
        # the base coordinate and the half-space end of log_h are answers, not prior
        # artefacts (see layer_notes); a thickness at the lower end is one
        if name == "bond":
            continue
        x = post_theta[name]
        if name == "log_h":
            x = x[x <= prior.log_h_range[1]]  # the layer's draws
            if x.size < 20 or not _piled_low(x, prior.log_h_range):
                continue  # an h the data cannot tell is a note (layer_notes), not a bound
        med, sd = float(np.median(x)), float(np.std(x))
        for side, bound in (("lower", lo), ("upper", hi)):
            if name == "log_h" and side == "upper":
                continue
            dist = abs(med - bound)
            if dist < BOUND_SDS * sd or (sd == 0 and dist == 0):
                what = {"log_Estar": "E*", "log_nu_t": "nu_t", "log_h": "thickness"}.get(name,
                                                                                       name)
                if name == "z_surf":
                    value = format_length(bound)
                elif name == "log_h":
                    value = format_length(math.exp(bound))
                elif name == "log_Estar":
                    value = format_pressure(math.exp(bound))
                else:
                    value = f"{bound:.4g}"
                out.append(f"{what} posterior at its {side} prior bound ({value}): "
                           f"{causes[(name, side)]}")
    return out


def _piled_low(log_h: np.ndarray, log_h_range: tuple[float, float]) -> bool:
    """True if over half the layer's draws lie in the lowest tenth of the prior's ln h range
    (five times the prior's share): piled at the bound, not merely unidentified (a posterior
    that is its prior puts a tenth there)."""
    lo, hi = log_h_range
    return bool(np.mean(log_h <= lo + 0.1 * (hi - lo)) > 0.5)


def posterior_flags(post: dict, post_theta: dict, prior: TracePrior) -> list[str]:
    """Failure modes a converged chain can still show (bimodal, prior-dominated, at a bound)."""
    out = []
    if is_bimodal(post["z_surf"]):
        out.append("bimodal z_surf: two separated surface heights fit the data")
    lo, hi = prior.z_bounds
    z = post["z_surf"]
    if np.std(z) > 0.2 * (hi - lo) / np.sqrt(12):
        out.append("prior-dominated z_surf: the data barely constrain the surface")
    return out + bound_flags(post_theta, prior)
