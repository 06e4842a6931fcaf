"""Rate dependence: what the hold and the retract of a cycle say about an elastic fit.

An elastic law F = E*·s(d) + F0 (+ F1·(z − z_ref)) fixes the force by the depth alone: at a
held depth the force stays put, and on the way back up it retraces the loading curve.  A
viscoelastic material does neither (Lee & Radok 1960; Ting 1966): the force relaxes while the
tip holds still, and the retract lies below the approach.  The elastic modulus read from the
loading is then an *apparent* modulus of that speed, not a property of the material, and no
wider elastic interval repairs that: the remedy is the time-dependent fit
(``palpbayes fit --rheology``, :mod:`palpbayes.rheology`).

Two numbers, each with its standard error under the fit's AR(1) noise:

**Hold relaxation** r = [(F̄_a − μ̄_a) − (F̄_b − μ̄_b)] / (F̄_a − b̄_a): the windows a and b are
the first and last tenth of the hold (at least :data:`HOLD_WINDOW` samples), μ the elastic
fit's force at each sample's depth, b its baseline.  The elastic law's own change with depth
(the tip creeping into the specimen under force control, a robot settling) is taken out, so a
creep test (constant force, growing depth) reads as relaxation too.  se(r) =
σ·sqrt(2·g(w, φ)/w)/(F̄_a − b̄_a) with g the AR(1) variance factor of a w-sample mean.  Its
effect on E is −r: the modulus the same depth reads at the end of the hold against the start.

**Retract modulus** E*_ret/E*_load − 1: E* refitted (baseline and surface fixed at the fit's)
to the retract's samples in contact, against the same estimator on the loading's samples in
contact, so that a misfit of the law's shape cancels.  se from the long-run AR(1) factor
(1 + φ)/(1 − φ).  The effect on E is the ratio itself.

The check fails when either number exceeds :data:`THRESHOLDS` ``["rate_n_se"]`` standard
errors; its severity (:mod:`.effect`) compares the larger effect with 2 % and with the
statistical interval.  A trace without a hold or a retract in contact gets no check (None).
"""

from __future__ import annotations

import math

import numpy as np

from ..contact import touching
from ..errors import InputError
from ..fitdata import ModelSpec
from ..io.motion_segments import cycle_segments
from ..trace import SEGMENTS, IndentationTrace
from .core import THRESHOLDS, CheckResult, ar1_mean_variance_factor

__all__ = ["rate_dependence_check", "HOLD_WINDOW", "MIN_RETRACT"]

#: Fewest samples in each of the two hold windows (the hold needs twice as many).
HOLD_WINDOW = 5
#: Fewest retract samples in contact for the retract modulus.
MIN_RETRACT = 10

_HOLD, _RETRACT = SEGMENTS.index("hold"), SEGMENTS.index("retract")


def _hold_relaxation(t, z, f, hold, mu, base, sigma, phi):
    """(r, se, hold duration [s]) of the hold samples ``hold`` (module docstring), or None."""
    if hold.size < 2 * HOLD_WINDOW:
        return None
    w = max(HOLD_WINDOW, hold.size // 10)
    a, b = hold[:w], hold[-w:]
    load = float(np.mean(f[a] - base[a]))
    if not load > 0:
        return None
    change = float(np.mean(f[a] - mu[a]) - np.mean(f[b] - mu[b]))
    se = sigma * math.sqrt(2.0 * float(ar1_mean_variance_factor(w, phi)) / w)
    return change / load, se / load, float(np.mean(t[b]) - np.mean(t[a]))


def _retract_ratio(f, contact_load, contact_ret, s, base, sigma, phi, estar):
    """(E*_ret/E*_load − 1, se) of the retract's contact samples, or None."""
    if contact_ret.sum() < MIN_RETRACT or contact_load.sum() < MIN_RETRACT:
        return None
    long_run = (1.0 + phi) / (1.0 - phi)
    out = []
    for sel in (contact_load, contact_ret):
        ss = float(np.dot(s[sel], s[sel]))
        if not ss > 0:
            return None
        out.append((float(np.dot(s[sel], f[sel] - base[sel])) / ss,
                    sigma * math.sqrt(long_run / ss)))
    (e_load, se_load), (e_ret, se_ret) = out
    if not e_load > 0:
        return None
    ratio = e_ret / e_load
    return ratio - 1.0, math.hypot(se_ret / e_load, ratio * se_load / e_load)


def rate_dependence_check(trace: IndentationTrace, model: ModelSpec, *, z_surf: float,
                          estar: float, f0: float = 0.0, f1: float = 0.0,
                          z_ref: float | None = None, sigma: float,
                          noise_lag1: float | None = None) -> CheckResult | None:
    """Does the cycle's hold or retract show rate dependence the elastic fit cannot explain?

    Parameters
    ----------
    trace
        The whole recording (SI; z up, pressing positive), with its hold and/or retract;
        segments from the motion when it does not record them.
    model
        The fitted elastic contact model.
    z_surf, estar, f0, f1
        [m], [Pa], [N], [N/m] The elastic fit's surface, E*, and baseline
        F0 + F1·(z − z_ref).
    z_ref
        [m] Reference height of a linear baseline (default the highest z of the trace).
    sigma
        [N] Noise standard deviation of one sample.
    noise_lag1
        Lag-one autocorrelation of the noise [-] (default 0).

    Returns
    -------
    CheckResult or None
        ``name`` "rate", ``statistic`` the hold relaxation r (the retract ratio when there is
        no hold); ``details``: ``relaxation``, ``relaxation_se``, ``hold_s`` [s],
        ``retract_ratio`` (E*_ret/E*_load − 1), ``retract_se``, ``effect`` [-] and
        ``effect_source``.  None when the trace has neither a hold nor a retract in contact.

    Raises
    ------
    InputError
        ``sigma`` not positive, or ``estar`` not positive and finite.
    """
    if not (math.isfinite(sigma) and sigma > 0):
        raise InputError(f"noise sd sigma = {sigma!r} N must be positive")
    if not (math.isfinite(estar) and estar > 0):
        raise InputError(f"E* = {estar!r} Pa must be positive and finite")
    phi = float(np.clip(0.0 if noise_lag1 is None else noise_lag1, -0.99, 0.99))
    seg = cycle_segments(trace)
    t, z, f = trace.time, trace.z, trace.force
    z_ref = float(z.max()) if z_ref is None else float(z_ref)
    depth = z_surf - z
    inside = depth > 0
    s = touching(model.shape, depth)
    base = f0 + f1 * (z - z_ref)
    mu = estar * s + base
    end = int(np.argmin(z)) + 1  # the loading segment, as the elastic fit reads it
    load = np.zeros(z.size, dtype=bool)
    load[:end] = True
    hold = _hold_relaxation(t, z, f, np.flatnonzero(seg == _HOLD), mu, base, sigma, phi)
    ret = _retract_ratio(f, load & inside, (seg == _RETRACT) & inside, s, base, sigma, phi,
                         estar)
    if hold is None and ret is None:
        return None
    n_se = THRESHOLDS["rate_n_se"]
    details: dict = {"relaxation": math.nan, "relaxation_se": math.nan, "hold_s": math.nan,
                     "retract_ratio": math.nan, "retract_se": math.nan}
    failed, texts, effects = [], [], []
    if hold is not None:
        r, se, span = hold
        details.update(relaxation=r, relaxation_se=se, hold_s=span)
        if abs(r) > n_se * se:
            failed.append("hold")
            texts.append(f"over the {span:.3g} s hold the force {'falls' if r > 0 else 'rises'}"
                         f" {100 * abs(r):.1f} % {'below' if r > 0 else 'above'} what the "
                         "elastic law gives for its depth (relaxation or creep)")
            effects.append((-r, f"force at the end of the {span:.3g} s hold"))
    if ret is not None:
        q, se = ret
        details.update(retract_ratio=q, retract_se=se)
        if abs(q) > n_se * se:
            failed.append("retract")
            texts.append("the retract's force is at or below zero where the approach pushed"
                         " (hysteresis, adhesion)" if q <= -1.0 else
                         f"the retract reads E* {100 * abs(q):.1f} % "
                         f"{'below' if q < 0 else 'above'} the approach (hysteresis)")
            effects.append((q, "E* of the retract"))
    if effects:
        eff, source = max(effects, key=lambda e: abs(e[0]))
    else:
        eff, source = 0.0, ""
    details.update(effect=eff, effect_source=source)
    flag = ""
    if failed:
        flag = ("rate dependence: " + " and ".join(texts) + " -> the material is "
                "viscoelastic: E from the loading is an apparent modulus of this speed; fit "
                "the whole cycle with --rheology power-law,sls (palpbayes.rheology)")
    statistic = hold[0] if hold is not None else ret[0]
    return CheckResult("rate", float(statistic), not failed, flag, details)
