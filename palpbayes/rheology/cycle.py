"""The samples a viscoelastic fit sees: chosen segments, block means, baseline, surface range.

Rules:

* the fit takes whole segments of one cycle (:data:`palpbayes.trace.SEGMENTS`), in time order,
  and must start with the approach: the hereditary integral needs the material at rest, so the
  record begins out of contact;
* a trace that does not record its segments gets them from the motion
  (:func:`palpbayes.io.motion_segments.segments_from_motion`);
* long records are reduced to block means of ``block`` consecutive samples (the same count in
  every block, so the noise of every mean has the same variance; blocks never straddle two
  segments; the approach drops its first < ``block`` samples, the other segments their last):
  a 30-s hold at 800 Hz becomes a few hundred points; the model is the force averaged over each
  block's time window (half a step beyond its first and last samples), with the tip height at
  the window edges from a straight line fitted to each block's samples (two blocks that share
  an edge average their two lines there; a line also ends at the corner where a hold starts);
* the pre-contact baseline (:func:`palpbayes.baseline.estimate_baseline` of the approach) sets
  the offset prior's centre and the noise scale; the force is *not* tared;
* the surface prior is uniform on [z_min, z_first]: deepest point to the first (block-mean)
  height, so the record starts out of contact whatever the surface.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..baseline import estimate_baseline
from ..contact import Tip, exponent, prefactor
from ..errors import FitError, InputError, NoContactError
from ..sensor_noise import mad_sd
from ..trace import IndentationTrace, parse_segments
from .design import Windows

__all__ = ["CycleData", "prepare_cycle", "check_segments", "DEFAULT_SEGMENTS", "MAX_POINTS"]

#: Segments fitted by default: the loading and the hold (Lee–Radok: the contact never shrinks).
DEFAULT_SEGMENTS = ("approach", "hold")
#: Most block means a fit sees (the hereditary matrix is MAX_POINTS² numbers).
MAX_POINTS = 800


@dataclass(frozen=True)
class CycleData:
    """Block means of the fitted segments and what the model needs to know about them.

    Attributes
    ----------
    time, z, force
        [s], [m], [N] block means in time order (time from the first kept sample).
    segment
        Segment code of every block (index into :data:`~palpbayes.trace.SEGMENTS`).
    edges, z_edges
        [s], [m] Knots of the model's piecewise-linear motion (window edges and corners, on
        the time axis of ``time``) and the tip height there.
    window
        (n, 2) Knot indices of every block's window ``[edges[lo], edges[hi]]``.
    sample_time
        [s] (n, block) Times of every block's samples (same axis).
    block
        Raw samples per block mean.
    z_lo, z_hi
        [m] Support of the uniform surface prior.
    f0_center, sigma_center
        [N] Baseline level (offset prior centre) and the noise sd of one block mean implied
        by the baseline's sample noise (sd/sqrt(block)).
    z_ref
        [m] Mean height of the baseline samples, where ``f0_center`` applies (the reference
        of a linear baseline F0 + F1·(z − z_ref)).
    C, m
        Prefactor [N/(Pa·m^m)] (per unit E*) and exponent of the tip's law F = C·E*·d^m.
    trace
        The kept raw samples (chosen segments).
    segments
        Names of the fitted segments.
    """

    time: np.ndarray
    z: np.ndarray
    force: np.ndarray
    segment: np.ndarray
    edges: np.ndarray
    z_edges: np.ndarray
    window: np.ndarray
    sample_time: np.ndarray
    block: int
    z_lo: float
    z_hi: float
    f0_center: float
    sigma_center: float
    z_ref: float
    C: float
    m: float
    trace: IndentationTrace
    segments: tuple[str, ...]

    @property
    def n_points(self) -> int:
        return int(self.time.size)

    def windows(self) -> Windows:
        """:class:`~palpbayes.rheology.design.Windows` of the blocks."""
        return Windows(self.edges, self.window[:, 0], self.window[:, 1], self.sample_time)

    @property
    def speed(self) -> np.ndarray:
        """[m/s] Downward tip speed −dz/dt averaged over every block's window (exact for the
        model's piecewise-linear motion): the column of a viscous drag F = b·(−dz/dt)."""
        lo, hi = self.window[:, 0], self.window[:, 1]
        return -(self.z_edges[hi] - self.z_edges[lo]) / (self.edges[hi] - self.edges[lo])

    @property
    def dt_min(self) -> float:
        """[s] Shortest step between block means."""
        return float(np.diff(self.time).min())

    @property
    def span(self) -> float:
        """[s] Duration of the fitted record."""
        return float(self.time[-1] - self.time[0])


def check_segments(segments) -> tuple[str, ...]:
    """The segment names a viscoelastic fit takes (names or a comma-separated string): known,
    with the approach (:class:`~palpbayes.errors.InputError` otherwise)."""
    names = parse_segments(segments)
    if "approach" not in names:
        raise InputError("--segments must include the approach: the hereditary integral "
                         "starts from the material at rest before contact")
    return names


def _blocks(trace: IndentationTrace, block: int) -> np.ndarray:
    """Indices (n_blocks, block) of the samples of every block mean."""
    rows = []
    for code in np.unique(trace.segment):
        idx = np.flatnonzero(trace.segment == code)
        n = idx.size // block * block
        if n == 0:
            continue
        idx = idx[idx.size - n:] if code == 0 else idx[:n]
        rows.append(idx.reshape(-1, block))
    return np.concatenate(rows)


def _neighbour_slopes(t: np.ndarray, z: np.ndarray, seg: np.ndarray) -> np.ndarray:
    """[m/s] dz/dt at every sample: the mean of the forward and backward differences that stay
    in the sample's segment (0 for a segment of one sample)."""
    dz = np.diff(z) / np.diff(t)
    same = seg[1:] == seg[:-1]
    fwd = np.concatenate([np.where(same, dz, np.nan), [np.nan]])
    bwd = np.concatenate([[np.nan], np.where(same, dz, np.nan)])
    both = np.stack([fwd, bwd])
    n = np.isfinite(both).sum(axis=0)
    return np.where(n > 0, np.nansum(both, axis=0) / np.maximum(n, 1), 0.0)


def _edges(t: np.ndarray, z: np.ndarray, rows: np.ndarray, seg: np.ndarray,
           seg_of_sample: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Knots [s], the tip height there [m] and each block's window (lo, hi knot indices),
    from the samples ``t``, ``z`` (segment codes ``seg_of_sample``), the blocks' sample
    indices ``rows`` and their segment codes ``seg`` (module rules; blocks of one sample take
    their slope from the neighbours).

    A block's window runs half a step beyond its first and last samples; the height at an
    edge is the block's fitted line there, averaged over the two blocks that share it.  Where
    two touching blocks of different segments meet (the hold starts), their lines' crossing,
    if it lies within the two blocks, is a knot of its own (the corner of the motion), and
    each side keeps its own line (within 1 % of a step of the shared edge, that edge is the
    corner)."""
    n = t.size
    first, last = rows[:, 0], rows[:, -1]
    step_in = np.where(first > 0, t[first] - t[np.maximum(first - 1, 0)],
                       t[np.minimum(first + 1, n - 1)] - t[first])
    step_out = np.where(last < n - 1, t[np.minimum(last + 1, n - 1)] - t[last],
                        t[last] - t[np.maximum(last - 1, 0)])
    left, right = t[first] - 0.5 * step_in, t[last] + 0.5 * step_out
    tb, zb = t[rows], z[rows]
    tm, zm = tb.mean(axis=1), zb.mean(axis=1)
    var = ((tb - tm[:, None]) ** 2).sum(axis=1)
    cov = ((tb - tm[:, None]) * (zb - zm[:, None])).sum(axis=1)
    slope = np.divide(cov, var, out=np.zeros_like(cov), where=var > 0)
    if rows.shape[1] == 1:  # single samples: the slope from the neighbours in the segment
        slope = _neighbour_slopes(t, z, seg_of_sample)[first]
    B = rows.shape[0]
    at = [left, right]
    height = [zm + slope * (left - tm), zm + slope * (right - tm)]
    weight = [np.ones(B), np.ones(B)]
    # where the segment changes, the crossing of the two blocks' lines is the corner; two
    # blocks either touch, or the hold's leftover samples (not a whole block) lie between them:
    # then the corner is placed inside that gap (the tip holds until it, not a line across)
    for i in np.flatnonzero(seg[1:] != seg[:-1]):
        j = i + 1
        ds = slope[i] - slope[j]
        if ds == 0:
            continue
        tc = (zm[j] - zm[i] + slope[i] * tm[i] - slope[j] * tm[j]) / ds
        if first[j] > last[i] + 1:  # a gap between the blocks
            if not right[i] + 0.01 * step_out[i] < tc < left[j] - 0.01 * step_in[j]:
                continue
        elif not left[i] < tc < right[j]:
            continue  # the lines cross outside the two blocks: no corner to place
        elif min(tc - left[i], right[j] - tc) <= 0.01 * min(step_in[i], step_out[j]):
            continue  # on an outer edge: a step of almost no length would magnify rounding
        elif abs(tc - right[i]) > 0.01 * step_out[i]:
            # the shared edge takes the line of the block on its side of the corner
            side = 1 if tc < right[i] else 0
            weight[side][i if side else j] = 0.0
        else:  # the corner is the shared edge
            tc = right[i]
            weight[0][j] = weight[1][i] = 0.0
        at.append(np.array([tc]))
        height.append(np.array([zm[i] + slope[i] * (tc - tm[i])]))
        weight.append(np.ones(1))
    at, height, weight = (np.concatenate(a) for a in (at, height, weight))
    knots, inverse = np.unique(at, return_inverse=True)
    z_knots = np.bincount(inverse, height * weight) / np.bincount(inverse, weight)
    return knots, z_knots, inverse[:B], inverse[B:2 * B]


def prepare_cycle(trace: IndentationTrace, tip: Tip | None = None, *,
                  segments=DEFAULT_SEGMENTS, max_points: int = MAX_POINTS) -> CycleData:
    """The block means of ``segments`` of ``trace`` and the model's constants (module rules).

    Parameters
    ----------
    trace
        The recording (SI; z up, pressing positive).
    tip
        The indenter (default ``trace.tip``); its law must be a power law F = C·E*·d^m.
    segments
        Names or a comma-separated string of :data:`~palpbayes.trace.SEGMENTS`; must include
        the approach.
    max_points
        Most block means kept (>= 50).

    Raises
    ------
    InputError
        Unknown or missing segments (naming what the trace has), a tip without a power law.
    NoContactError
        Too few block means, or a record that never moves the tip down.
    """
    names = check_segments(segments)
    tip = tip if tip is not None else trace.tip
    if tip is None:
        raise FitError(f"{trace.trace_id}: no tip geometry given; pass tip=")
    g, m = prefactor(tip), exponent(tip)
    if g is None or m is None:
        raise InputError(f"tip '{tip.kind}' has no power-law form F = C·E·d^m; the "
                         "viscoelastic fit needs one (flat, paraboloid, cone, power)")
    if not (isinstance(max_points, int | np.integer) and max_points >= 50):
        raise InputError(f"max_points = {max_points!r} must be a whole number >= 50")
    if trace.segment is None:
        from ..io.motion_segments import segments_from_motion
        trace = trace.replace(segment=segments_from_motion(trace.time, trace.z))
    kept = trace.segments(names)
    block = max(1, math.ceil(kept.n_points / max_points))
    rows = _blocks(kept, block)
    t, z, f = (a[rows].mean(axis=1) for a in (kept.time, kept.z, kept.force))
    if t.size < 20:
        raise NoContactError(f"{trace.source or trace.trace_id}: only {t.size} block means "
                             "in the chosen segments; record more samples")
    seg = kept.segment[rows[:, 0]]
    edges, z_edges, lo, hi = _edges(kept.time, kept.z, rows, seg, kept.segment)
    base = estimate_baseline(kept.z[kept.segment == 0], kept.force[kept.segment == 0])
    sd = base.sd
    if not sd > 0:  # a flat, quantised baseline: the sample-to-sample scatter of the approach
        step = np.diff(kept.force[kept.segment == 0])
        sd = mad_sd(step) / math.sqrt(2)
    z_lo, z_hi = float(z.min()), float(z[0])
    if not z_hi > z_lo:
        raise NoContactError(f"{trace.source or trace.trace_id}: the tip never moves down in "
                             "the chosen segments; is z down-positive? flip it with --z-sign -1")
    return CycleData(time=t - t[0], z=z, force=f, segment=seg, edges=edges - t[0],
                     z_edges=z_edges, window=np.stack([lo, hi], axis=1),
                     sample_time=kept.time[rows] - t[0], block=block, z_lo=z_lo,
                     z_hi=z_hi, f0_center=float(base.level),
                     sigma_center=float(sd) / math.sqrt(block) if sd > 0 else 1e-12,
                     z_ref=float(base.z_ref) if math.isfinite(base.z_ref) else z_hi,
                     C=float(g), m=float(m), trace=kept, segments=names)
