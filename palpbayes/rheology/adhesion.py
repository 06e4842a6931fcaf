"""The adhesive pull-off on a retract, found and cut out before a viscoelastic fit.

Where the tip leaves an adhesive sample the retract's force dips below the retract's own
out-of-contact baseline (the sample holds the tip) and recovers some tens of ms later.  Ting's
rule (a contact that only shrinks, no adhesion) cannot model that, and the fit flags it
(:func:`~palpbayes.rheology.offcontact.adhesion_dip`).  ``fit_rheology(...,
adhesion="cut")`` removes that stretch of the retract before the fit
(:func:`cut_adhesion`); what is left is fitted as usual (the model takes the time gap: the
block means carry their own sample times).

The window (:func:`adhesive_window`) is read from block means of the retract alone
(:data:`ADHESION_BLOCKS` blocks, at least one sample each, from the retract's first sample; the
leftover samples at its end are not read), so that noise does not decide it:

* **baseline**: a straight line in z fitted by least squares to the retract's blocks in the
  upper half of the heights it spans above the block of its largest force (where a pull-off
  is over): a constant drag b·v on the retract and a tilted baseline are both lines there.
  Its noise sd is the robust 1.4826·MAD of those blocks' residuals, sd_b [N] of one block
  mean;
* **start**: :data:`ADHESION_LEAD` blocks before the first block after the force's peak whose mean
  has come down to the baseline (residual <= 0), but after the peak.  The pull begins where
  the contact ends, and a block's mean reaches the baseline only once the pull outweighs the
  last of the contact force in it, so the first block below the baseline can come after the
  pull has begun (up to 1.2 blocks after the end of the contact on 20 simulated pull-offs;
  with the lead the cut starts 0.8–2.8 blocks before it).  Pull left in biases the fit of
  the retract (a cut that started one block late failed the posterior-predictive check on a
  simulated pull-off, with a shorter end than the one below), while a few hundred µs more of
  a contact's last, weakest force cost the fit little;
* **dip**: the lowest mean of :data:`DIP_WINDOW` consecutive blocks' residuals among those that
  start at or after that first block below the baseline and end before the baseline's
  blocks.  It must lie :data:`N_SE` standard errors below the baseline:
  se = sd_b·sqrt(g/w + g·h), w = :data:`DIP_WINDOW`, g the AR(1) long-run factor (1 + φ)/(1 − φ)
  of the baseline's residuals (φ their lag-one correlation clipped to [0, 0.9]) and h the
  line's leverage at the dip's height (1/n + (z − z̄)²/Σ(z_i − z̄)²: the baseline
  extrapolated there is uncertain too); otherwise nothing is cut;
* **end** (recovery): the first block k after the dip where both

  - the mean of the w blocks k..k+w−1 lies within one of its standard errors of the
    baseline, >= −sd_b·sqrt(g/w) (no dip is left just after the cut, where the fit's own
    check looks), and
  - the mean of all the n blocks from k to the last one below the baseline's lies within one
    of its standard errors, >= −sd_b·sqrt(g/n + g·h) (no long tail is left: a pull-off
    −A·(s/L)·exp(1 − s/L) still pulls 4 % of A at s = 6·L, a few pN over a hundred blocks,
    which the fit's posterior-predictive check, binning the residuals over such stretches,
    sees);

  the cut stops before block k, or at the baseline's first block when no such k comes (then
  all of the lower half after the dip is cut: the pull-off lasts that long, or the baseline
  is not a line there).

  Why this rule: one block back within 1 sd_b (the simplest rule) ends the cut early by
  chance (with the force still 2 sd_b down, one block in six comes that close) and leaves the
  tail in.  On the PyFMRheo map's curve 0 a cut of 0.217–0.26 s, where the blocks first come
  back to about 1 sd_b, left a dip that the fit still flagged (5.1 se); on simulated
  pull-offs (A = 100 pN, L = 0.3 µm, 15 pN noise) a cut that ended where w blocks first came
  back within their standard error failed the fit's posterior-predictive check on one seed in
  eight.  This rule ends the real curve's cut at 0.300 s and both pass.  It costs some of the
  retract's out-of-contact force, which the fit needs little (the drag and the tilt are read
  from the rest of it and from the approach).

The cut removes whole blocks, from the first sample of the start block to the last sample
before block k.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..io.motion_segments import cycle_segments
from ..sensor_noise import mad_sd
from ..trace import IndentationTrace
from .offcontact import ADHESION_WINDOW, N_SE, _long_run
from .ting import RETRACT

__all__ = ["AdhesionCut", "adhesive_window", "cut_adhesion", "ADHESION_BLOCKS", "DIP_WINDOW",
           "ADHESION_LEAD"]

#: Block means the retract is read as (its samples // this per block, at least one).
ADHESION_BLOCKS = 400
#: Consecutive blocks whose mean measures the dip and its recovery (the fit's own check's).
DIP_WINDOW = ADHESION_WINDOW
#: Blocks before the first below the baseline where the cut starts (module docstring).
ADHESION_LEAD = 2
#: Fewest baseline blocks (upper half of the retract's heights) the line is fitted to.
_MIN_BASELINE = 10


@dataclass(frozen=True)
class AdhesionCut:
    """The adhesive stretch of a retract (module docstring).

    Attributes
    ----------
    t_start, t_end
        [s] Times of the first and last samples removed (on the trace's time axis): every
        retract sample with t_start <= t <= t_end.
    n_samples
        Samples removed.
    depth
        [N] The baseline minus the lowest :data:`DIP_WINDOW`-block mean of the dip (> 0).
    sd
        [N] Robust sd of one block mean about the baseline (1.4826·MAD).
    se
        [N] Standard error of the dip's depth (module docstring).
    t_min
        [s] Middle of the lowest window.
    block
        Samples per block mean.
    """

    t_start: float
    t_end: float
    n_samples: int
    depth: float
    sd: float
    se: float
    t_min: float
    block: int


def adhesive_window(trace: IndentationTrace, *, n_se: float = N_SE) -> AdhesionCut | None:
    """The adhesive stretch of the retract of ``trace`` (module docstring), or None.

    Parameters
    ----------
    trace
        One cycle (SI; z up, force positive when pressing), its segments recorded or taken
        from the motion.
    n_se
        Standard errors by which the dip must lie below the baseline.

    Returns
    -------
    AdhesionCut or None
        None without a retract (or fewer than 4·:data:`DIP_WINDOW` blocks of it), without
        :data:`_MIN_BASELINE` blocks in the upper half of its heights, when the force never
        comes down to the baseline after its peak, or when the dip is not :data:`N_SE`
        standard errors deep.
    """
    return _window(trace, cycle_segments(trace), n_se)


def _window(trace: IndentationTrace, codes: np.ndarray, n_se: float) -> AdhesionCut | None:
    """:func:`adhesive_window` given the trace's segment codes."""
    w = DIP_WINDOW
    ret = np.flatnonzero(codes == RETRACT)
    if ret.size < 4 * w:
        return None
    b = max(1, ret.size // ADHESION_BLOCKS)
    nb = ret.size // b
    if nb < 4 * w:
        return None
    rows = ret[: nb * b].reshape(nb, b)
    t, z, f = (np.asarray(a)[rows].mean(axis=1) for a in (trace.time, trace.z, trace.force))
    peak = int(np.argmax(f))
    top = float(z[peak:].max())
    if not top > z[peak]:
        return None
    far = np.zeros(nb, dtype=bool)
    far[peak:] = z[peak:] > z[peak] + 0.5 * (top - z[peak])
    n_far = int(far.sum())
    if n_far < _MIN_BASELINE:
        return None
    zf = z[far]
    coef = np.polyfit(zf - zf.mean(), f[far], 1)
    resid = f - np.polyval(coef, z - zf.mean())
    sd = mad_sd(resid[far])
    if not sd > 0:  # quantised or noise-free: the plain sd, else nothing to compare with
        sd = float(np.std(resid[far], ddof=2))
    if not sd > 0:
        return None
    g = _long_run(resid[far])
    below = np.flatnonzero(resid[peak:] <= 0.0)
    if below.size == 0:
        return None
    cross = peak + int(below[0])
    first_far = int(np.flatnonzero(far)[0])
    if first_far - cross < w:
        return None
    run = np.convolve(resid, np.ones(w) / w, mode="valid")  # run[k]: blocks k..k+w-1
    k_min = cross + int(np.argmin(run[cross:first_far - w + 1]))
    z_min = float(z[k_min:k_min + w].mean())
    lever = 1.0 / n_far + (z_min - zf.mean()) ** 2 / float(np.sum((zf - zf.mean()) ** 2))
    se = sd * math.sqrt(g / w + g * lever)
    depth = -float(run[k_min])
    if not depth > n_se * se:
        return None
    # recovery: the next w blocks, and all the blocks left below the baseline's, each back
    # within one standard error of their mean (module docstring)
    k = np.arange(k_min + 1, first_far - w + 1)
    n = first_far - k
    rest = np.cumsum(resid[first_far - 1:k_min:-1])[::-1][: k.size] / n  # mean of k..first_far-1
    z_rest = np.cumsum(z[first_far - 1:k_min:-1])[::-1][: k.size] / n
    lever_rest = 1.0 / n_far + (z_rest - zf.mean()) ** 2 / float(np.sum((zf - zf.mean()) ** 2))
    ok = (run[k] >= -sd * math.sqrt(g / w)) & (rest >= -sd * np.sqrt(g / n + g * lever_rest))
    end = int(k[np.argmax(ok)]) if ok.any() else first_far
    start = max(cross - ADHESION_LEAD, peak + 1)
    i0, i1 = int(rows[start, 0]), int(rows[end - 1, -1])
    return AdhesionCut(t_start=float(trace.time[i0]), t_end=float(trace.time[i1]),
                       n_samples=int((end - start) * b), depth=depth, sd=float(sd),
                       se=float(se), t_min=float(t[k_min + w // 2]), block=int(b))


def cut_adhesion(trace: IndentationTrace, *, n_se: float = N_SE
                 ) -> tuple[IndentationTrace, AdhesionCut | None]:
    """``trace`` without the adhesive stretch of its retract (:func:`adhesive_window`), and
    the cut; ``trace`` itself and None when nothing is cut.

    Every per-sample array (time, z, force and the segment codes, from the motion when not
    recorded) loses the same samples; the rest of the trace (tip, metadata, labels) is kept.
    The samples are the retract's with t_start <= t <= t_end, which are consecutive.

    Parameters
    ----------
    trace
        A cycle with a retract (SI; z up, pressing positive).
    n_se
        Standard errors below the baseline a dip must reach to be cut.

    Returns
    -------
    trace, cut
        The trace without the stretch, and the :class:`AdhesionCut` (or ``trace`` and None).
    """
    codes = cycle_segments(trace)
    cut = _window(trace, codes, n_se)
    if cut is None:
        return trace, None
    keep = ~((codes == RETRACT) & (trace.time >= cut.t_start) & (trace.time <= cut.t_end))
    # the codes are kept even where they came from the motion: the motion across the cut's
    # time gap would not give them again
    return trace.replace(time=trace.time[keep], z=trace.z[keep], force=trace.force[keep],
                         segment=codes[keep]), cut
