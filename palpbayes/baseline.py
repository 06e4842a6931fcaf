"""The pre-contact force baseline of a trace: level, trend, noise and its correlation.

Real sensors are rarely tared exactly (a UR e-series F/T sensor that was not zeroed reads
+0.2 N, an AFM cantilever carries a deflection offset of a few hundred pN), drift or tilt
during the approach, and their noise is correlated at high sample rates.  Everything that
reads "no force" from a trace — the contact onset, the sign check, the force-offset prior,
the noise spec when none is given, the residual checks — reads it from this estimate instead
of from zero.

Estimate (on the loading segment, in time order, over the samples where the tip reaches a new
deepest point, :func:`palpbayes.fitdata.first_passage`):

1. a first guess from the first 20 % of those samples (at least 10): median level ``b0`` and
   noise sd ``s0`` from the median absolute successive difference,
   s0 = 1.4826·median|ΔF|/sqrt(2) (insensitive to a slow trend);
2. the *provisional contact* is the last sample with |F − b0| <= 6·s0 (the ±3 sigma
   peak-to-peak convention of :mod:`palpbayes.sensor_noise`); the baseline samples are those before
   it, less a margin of 10 % of them (a gradual onset starts before the threshold is crossed);
3. on those samples: a least-squares line F = level + slope·(z − z_ref) with z_ref their mean
   height, the level reported as their median, the noise sd as 1.4826·MAD of the residuals of
   the line (robust), and the lag-one autocorrelation of those residuals.

The estimate needs an approach: at least 10 samples before contact.  A trace that starts in
contact gets ``reliable = False`` (callers then fall back on the user's noise spec).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from .sensor_noise import MAD_TO_SIGMA, acf1, mad_sd, pp_from_sigma

__all__ = ["Baseline", "estimate_baseline", "sign_flipped", "MIN_BASELINE_POINTS"]

#: Fewest pre-contact samples for a reliable baseline.
MIN_BASELINE_POINTS = 10
_MAD = MAD_TO_SIGMA


@dataclass(frozen=True)
class Baseline:
    """Pre-contact baseline of one trace (SI).

    Attributes
    ----------
    level
        [N] Median force before contact (the sensor's offset when untared).
    slope
        [N/m] Least-squares slope of the force against z before contact (drift or tilt).
    z_ref
        [m] Mean height of the baseline samples (where ``level`` applies to the line).
    sd
        [N] Robust noise standard deviation around the line (1.4826·MAD).
    lag1
        Lag-one autocorrelation of the baseline residuals (0 for white noise).
    n
        Number of baseline samples.
    z_low
        [m] Lowest height of the baseline samples.
    reliable
        At least :data:`MIN_BASELINE_POINTS` samples and a positive noise estimate.
    """

    level: float
    slope: float
    z_ref: float
    sd: float
    lag1: float
    n: int
    z_low: float
    reliable: bool

    @property
    def noise_pp(self) -> float:
        """[N] Peak-to-peak noise spec equivalent to ``sd`` (±3 sigma)."""
        return pp_from_sigma(self.sd)

    def shifted(self, offset: float) -> Baseline:
        """The same baseline with ``offset`` [N] added to the force (e.g. after a tare)."""
        return replace(self, level=self.level + offset)

    def at(self, z: np.ndarray | float) -> np.ndarray:
        """[N] The baseline line level + slope·(z − z_ref) at heights ``z`` [m]."""
        return self.level + self.slope * (np.asarray(z, dtype=float) - self.z_ref)


def _robust_sd_diff(f: np.ndarray) -> float:
    if f.size < 3:
        return 0.0
    return float(_MAD * np.median(np.abs(np.diff(f))) / np.sqrt(2.0))


def estimate_baseline(z: np.ndarray, force: np.ndarray) -> Baseline:
    """Estimate the pre-contact baseline of a loading segment.

    Parameters
    ----------
    z
        [m] Tip heights in time order (loading segment; z up, pressing moves it down).
    force
        [N] Compressive force, same length.

    Returns
    -------
    Baseline
        See the module docstring for the three steps.
    """
    z = np.asarray(z, dtype=float)
    f = np.asarray(force, dtype=float)
    keep = np.flatnonzero(np.diff(np.minimum.accumulate(z), prepend=np.inf) < 0)
    z, f = z[keep], f[keep]
    n_all = f.size
    head = f[: max(MIN_BASELINE_POINTS, n_all // 5)]
    b0 = float(np.median(head))
    s0 = _robust_sd_diff(head)
    if s0 == 0.0:
        s0 = float(_MAD * np.median(np.abs(head - b0)))
    inside = np.abs(f - b0) <= pp_from_sigma(s0) if s0 > 0 else f == b0
    last = int(np.flatnonzero(inside)[-1]) if inside.any() else 0
    n_base = int(last * 0.9)
    if n_base < MIN_BASELINE_POINTS:
        n_base = min(max(n_base, 3), n_all)
    zb, fb = z[:n_base], f[:n_base]
    z_ref = float(zb.mean())
    dz = zb - z_ref
    slope = float(dz @ (fb - fb.mean()) / (dz @ dz)) if n_base >= 3 and dz @ dz > 0 else 0.0
    resid = fb - fb.mean() - slope * dz
    level = float(np.median(fb - slope * dz))
    sd = mad_sd(resid) if n_base >= 3 else s0
    lag1 = acf1(resid) if resid.size >= 3 else 0.0
    return Baseline(level=level, slope=slope, z_ref=z_ref, sd=sd, lag1=lag1, n=n_base,
                    z_low=float(zb.min()) if n_base else float(z[0]),
                    reliable=bool(n_base >= MIN_BASELINE_POINTS and sd > 0))


def sign_flipped(z: np.ndarray, force: np.ndarray) -> tuple[bool, float, Baseline]:
    """Whether the force falls below its pre-contact baseline at the deepest indentation.

    Compares the median force of the deepest 1 % of the loading samples (at least 5) with the
    baseline level — not with zero, so an untared sensor with a negative offset is not mistaken
    for a flipped sign, and not over a fixed share of the samples, so a short contact after a
    long approach is seen.  Flipped: the force lies more than 6·sd (the baseline's own
    peak-to-peak noise; 1e-9 of the largest |force| for noise-free data) below the baseline.

    Returns
    -------
    flipped, rise, baseline
        The verdict, the rise [N] of the deepest force above the baseline, and the baseline.
    """
    z = np.asarray(z, dtype=float)
    f = np.asarray(force, dtype=float)
    base = estimate_baseline(z, f)
    k = min(f.size, max(5, f.size // 100))
    deepest = np.argsort(z, kind="stable")[:k]
    rise = float(np.median(f[deepest]) - base.level)
    # noise-free (simulated) data: any clear fall counts
    thr = pp_from_sigma(base.sd) if base.sd > 0 else 1e-9 * float(np.max(np.abs(f), initial=0))
    return bool(rise < -thr), rise, base
