"""What the force out of contact says about a viscoelastic fit: drag, a tilted baseline,
adhesion.

Out of contact the model's force is its baseline alone: the offset F0, with a viscous drag
b·(−dz/dt) and a tilt F1·(z − z_ref) when they are fitted (:mod:`~palpbayes.rheology.
posterior`).  Three departures are common on real AFM curves and each is read from the
block means with its own standard error, so that a fit never passes them over in silence:

* **drag gap** (when the drag is not fitted): the approach's out-of-contact force minus the
  retract's at the middle of the heights both cover (a line in z fitted to each); a drag
  b·v shifts them by ±b·v, so b ≈ gap/(2v) (Alcaraz et al. 2002, Langmuir 18:716);
* **tilt** (when the baseline is constant): the slope F1 [N/m] of the fit's residuals against
  z − z_ref on the out-of-contact blocks, one intercept per segment (so a drag's shift is not
  read as a tilt): an AFM's virtual deflection (light scattered by the sample), or a sensor
  drifting while the tip moves at constant speed;
* **adhesion**: on the retract, the force against the retract's own out-of-contact baseline
  (the fit's drag and tilt, at a level read from the retract's blocks in the upper half of
  the heights above the surface, so that no fit of the contact can absorb a dip); from where
  the force first comes down to it, the lowest mean over :data:`ADHESION_WINDOW` consecutive
  blocks among the windows that start within :data:`ADHESION_SEARCH` windows (a pull-off
  comes as the tip leaves; searching the whole retract would flag the lowest of many noise
  windows): a sample that holds the tip before it lets go pulls the force below the
  baseline, which Ting's rule (a contact that only shrinks, no adhesion) cannot give.

Standard errors: least squares, inflated by the AR(1) long-run factor (1 + φ)/(1 − φ) of the
residuals' lag-one correlation φ (clipped to [0, 0.9]); for the adhesion window, the sd of
the retract baseline's residuals with that factor.  A
departure is flagged beyond :data:`N_SE` standard errors (and, for a tilt, when it moves the
baseline by more than one block-mean noise sd over the out-of-contact range).
"""

from __future__ import annotations

import math

import numpy as np

from ..sensor_noise import acf1
from .cycle import CycleData

__all__ = ["drag_gap", "baseline_tilt", "adhesion_dip", "N_SE", "ADHESION_WINDOW",
           "ADHESION_SEARCH", "ABOVE"]

#: Standard errors beyond which a departure is flagged.
N_SE = 5.0
#: Consecutive blocks whose mean residual measures an adhesion dip.
ADHESION_WINDOW = 5
#: Windows after the contact's end among which the adhesion dip is sought.
ADHESION_SEARCH = 4
#: Blocks count as out of contact this share of the height range above the surface.
ABOVE = 0.05
#: Clip of the residuals' lag-one correlation in the long-run factor.
_PHI_MAX = 0.9


def _outside(data: CycleData, z_surf: float) -> np.ndarray:
    """Blocks above the surface by :data:`ABOVE` of the range from it to the first height."""
    return data.z > z_surf + ABOVE * (data.z_hi - z_surf)


def _long_run(res: np.ndarray) -> float:
    """AR(1) long-run variance factor (1 + φ)/(1 − φ) of residuals ``res``."""
    if res.size < 3 or not np.std(res) > 0:
        return 1.0
    phi = float(np.clip(acf1(res), 0.0, _PHI_MAX))
    return (1 + phi) / (1 - phi)


def drag_gap(data: CycleData, z_surf: float) -> tuple[float, float, float] | None:
    """Approach minus retract force out of contact [N] at the middle of the heights both
    cover above the surface (a line in z fitted to each), its standard error [N] and the
    mean tip speed there [m/s]; None without five blocks of each."""
    above = _outside(data, z_surf)
    a, r = above & (data.segment == 0), above & (data.segment == 2)
    if a.sum() < 5 or r.sum() < 5:
        return None
    lo, hi = max(data.z[a].min(), data.z[r].min()), min(data.z[a].max(), data.z[r].max())
    a, r = a & (data.z >= lo) & (data.z <= hi), r & (data.z >= lo) & (data.z <= hi)
    if a.sum() < 5 or r.sum() < 5 or not hi > lo:
        return None
    mid, var, values = 0.5 * (lo + hi), 0.0, []
    for sel in (a, r):  # each side's line, its value at the middle and its variance
        zz = data.z[sel]
        coef = np.polyfit(zz, data.force[sel], 1)
        res = data.force[sel] - np.polyval(coef, zz)
        values.append(float(np.polyval(coef, mid)))
        lever = 1.0 / zz.size + (mid - zz.mean()) ** 2 / np.sum((zz - zz.mean()) ** 2)
        var += res.var(ddof=2) * _long_run(res) * lever
    speed = float(np.mean(np.abs(np.diff(data.z[a])) / np.diff(data.time[a])))
    return values[0] - values[1], math.sqrt(var), speed


def baseline_tilt(data: CycleData, residual: np.ndarray, z_surf: float
                  ) -> tuple[float, float, float] | None:
    """Slope F1 [N/m] of ``residual`` [N] (data minus the fit's median force) against the
    height on the out-of-contact blocks, one intercept per segment; its standard error
    [N/m] and the height range it spans [m].  None with fewer than ten such blocks, no height
    range, or heights that do not vary within a segment."""
    out = _outside(data, z_surf)
    if out.sum() < 10:
        return None
    z, r, seg = data.z[out], residual[out], data.segment[out]
    span = float(np.ptp(z))
    if not span > 0:
        return None
    codes = np.unique(seg)
    # the height centred and scaled to its span: a pseudo-inverse of the raw design would drop
    # the slope's direction when the heights span a nanometre, and report a standard error of
    # zero (a tilt of 10^15 se on a real cell whose surface sits at the first height)
    X = np.column_stack([(z - z.mean()) / span] + [(seg == c).astype(float) for c in codes])
    dof = r.size - X.shape[1]
    xtx = X.T @ X
    if dof < 3 or np.linalg.cond(xtx) > 1e8:  # heights constant within each segment
        return None
    xtx_inv = np.linalg.inv(xtx)
    coef = xtx_inv @ (X.T @ r)
    res = r - X @ coef
    factor = np.mean([_long_run(res[seg == c]) for c in codes])
    var = xtx_inv[0, 0] * (res @ res / dof) * factor
    return float(coef[0] / span), float(math.sqrt(max(var, 0.0)) / span), span


def adhesion_dip(data: CycleData, z_surf: float, trend: np.ndarray | None = None
                 ) -> tuple[float, float, float] | None:
    """The adhesion dip of the retract (module docstring): the lowest mean, over
    :data:`ADHESION_WINDOW` consecutive blocks starting within :data:`ADHESION_SEARCH`
    windows of where the retract's force first falls to its own baseline, of the force minus
    that baseline [N]; its standard error [N] and the time [s] of that window's middle.

    The baseline is ``trend`` [N] per block (the fit's drag and tilt terms, without the
    offset; zero by default) plus a level: the median of force − trend over the retract's
    blocks in the upper half of the heights it reaches above the surface, where a pull-off is
    over.  The level comes from those blocks alone (no fit of the contact can absorb a dip
    into it).  None without a retract, without ten such blocks or without a crossing."""
    w = ADHESION_WINDOW
    ret = np.flatnonzero(data.segment == 2)
    if ret.size < 4 * w:
        return None
    z = data.z[ret]
    f = data.force[ret] - (0.0 if trend is None else np.asarray(trend)[ret])
    top = float(z.max())
    if not top > z_surf:
        return None
    far = z > z_surf + 0.5 * (top - z_surf)
    if far.sum() < 10:
        return None
    level = float(np.median(f[far]))
    resid = f - level
    peak = int(np.argmax(f))
    below = np.flatnonzero(resid[peak:] <= 0.0)
    if below.size == 0:
        return None
    cross = peak + int(below[0])
    starts = np.arange(cross, min(cross + ADHESION_SEARCH * w, resid.size - w + 1))
    if starts.size == 0:
        return None
    means = np.array([resid[s:s + w].mean() for s in starts])
    k = int(np.argmin(means))
    g = _long_run(resid[far])
    sd = float(np.std(resid[far], ddof=1))
    se = sd * math.sqrt(g / w + 1.5708 * g / far.sum())  # window + level (median: π/2)
    return float(means[k]), se, float(data.time[ret[starts[k] + w // 2]])
