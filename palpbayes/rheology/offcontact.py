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
* **adhesion**: where the model's contact force has fallen below :data:`CONTACT_END` of its
  peak on the retract, the lowest mean residual over :data:`ADHESION_WINDOW` consecutive
  blocks: a sample that holds the tip before it lets go (pull-off) pulls the force below the
  baseline, which Ting's rule (a contact that only shrinks, no adhesion) cannot give.

Standard errors: least squares, inflated by the AR(1) long-run factor (1 + φ)/(1 − φ) of the
residuals' lag-one correlation φ (clipped to [0, 0.9]); for the adhesion window, the spread of
window means of the approach's out-of-contact residuals when there are enough of them.  A
departure is flagged beyond :data:`N_SE` standard errors (and, for a tilt, when it moves the
baseline by more than one block-mean noise sd over the out-of-contact range).
"""

from __future__ import annotations

import math

import numpy as np

from .cycle import CycleData

__all__ = ["drag_gap", "baseline_tilt", "adhesion_dip", "N_SE", "CONTACT_END",
           "ADHESION_WINDOW", "ABOVE"]

#: Standard errors beyond which a departure is flagged.
N_SE = 5.0
#: Share of the model's peak contact force below which the contact counts as ended.
CONTACT_END = 0.05
#: Consecutive blocks whose mean residual measures an adhesion dip.
ADHESION_WINDOW = 5
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
    phi = float(np.clip(np.corrcoef(res[1:], res[:-1])[0, 1], 0.0, _PHI_MAX))
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
    [N/m] and the height range it spans [m].  None with fewer than ten such blocks or no
    height range."""
    out = _outside(data, z_surf)
    if out.sum() < 10:
        return None
    z, r, seg = data.z[out], residual[out], data.segment[out]
    span = float(np.ptp(z))
    if not span > 0:
        return None
    codes = np.unique(seg)
    X = np.column_stack([z - data.z_ref] + [(seg == c).astype(float) for c in codes])
    coef, *_ = np.linalg.lstsq(X, r, rcond=None)
    res = r - X @ coef
    dof = r.size - X.shape[1]
    if dof < 3:
        return None
    factor = np.mean([_long_run(res[seg == c]) for c in codes])
    cov = np.linalg.pinv(X.T @ X) * (res @ res / dof) * factor
    return float(coef[0]), float(math.sqrt(max(cov[0, 0], 0.0))), span


def adhesion_dip(data: CycleData, residual: np.ndarray, contact: np.ndarray, z_surf: float
                 ) -> tuple[float, float, float] | None:
    """The lowest mean of ``residual`` [N] over :data:`ADHESION_WINDOW` consecutive retract
    blocks where the model's ``contact`` force [N] is below :data:`CONTACT_END` of its peak,
    its standard error [N] and the time [s] of that window's middle; None without a retract
    or without such a window."""
    w = ADHESION_WINDOW
    ended = (data.segment == 2) & (contact < CONTACT_END * max(float(contact.max()), 0.0))
    idx = np.flatnonzero(ended)
    if idx.size < w or not contact.max() > 0:
        return None
    # windows of w consecutive blocks, all of them past the contact's end
    start = idx[:-w + 1][idx[w - 1:] - idx[:-w + 1] == w - 1]
    if start.size == 0:
        return None
    means = np.array([residual[s:s + w].mean() for s in start])
    k = int(np.argmin(means))
    approach = _outside(data, z_surf) & (data.segment == 0)
    ra = residual[approach]
    if ra.size >= 4 * w:  # the spread of window means of the approach's own residuals
        n = ra.size // w
        se = float(np.std(ra[:n * w].reshape(n, w).mean(axis=1), ddof=1))
    else:
        se = data.sigma_center * math.sqrt(_long_run(ra) / w)
    mid = start[k] + w // 2
    return float(means[k]), se, float(data.time[mid])
