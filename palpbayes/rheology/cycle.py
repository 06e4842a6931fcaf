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
  a 30-s hold at 800 Hz becomes a few hundred points, and the hereditary integral is evaluated
  on the block means' own time axis;
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
from ..trace import IndentationTrace, parse_segments

__all__ = ["CycleData", "prepare_cycle", "DEFAULT_SEGMENTS", "MAX_POINTS"]

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
    block
        Raw samples per block mean.
    z_lo, z_hi
        [m] Support of the uniform surface prior.
    f0_center, sigma_center
        [N] Baseline level (offset prior centre) and the noise sd of one block mean implied
        by the baseline's sample noise (sd/sqrt(block)).
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
    block: int
    z_lo: float
    z_hi: float
    f0_center: float
    sigma_center: float
    C: float
    m: float
    trace: IndentationTrace
    segments: tuple[str, ...]

    @property
    def n_points(self) -> int:
        return int(self.time.size)

    @property
    def dt_min(self) -> float:
        """[s] Shortest step between block means."""
        return float(np.diff(self.time).min())

    @property
    def span(self) -> float:
        """[s] Duration of the fitted record."""
        return float(self.time[-1] - self.time[0])


def _segment_names(segments) -> tuple[str, ...]:
    names = parse_segments(segments)
    if "approach" not in names:
        raise InputError("--segments must include the approach: the hereditary integral "
                         "starts from the material at rest before contact")
    if "retract" in names:
        raise InputError("the retract segment (Ting's rule, a shrinking contact) is not in the "
                         "viscoelastic fit yet; fit --segments approach,hold")
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
        the approach; ``retract`` is refused (Ting's rule is not in the fit yet).
    max_points
        Most block means kept (>= 50).

    Raises
    ------
    InputError
        Unknown or missing segments (naming what the trace has), a tip without a power law.
    NoContactError
        Too few block means, or a record that never moves the tip down.
    """
    names = _segment_names(segments)
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
    base = estimate_baseline(kept.z[kept.segment == 0], kept.force[kept.segment == 0])
    sd = base.sd
    if not sd > 0:  # a flat, quantised baseline: the sample-to-sample scatter of the approach
        step = np.diff(kept.force[kept.segment == 0])
        sd = 1.4826 * float(np.median(np.abs(step - np.median(step)))) / math.sqrt(2)
    z_lo, z_hi = float(z.min()), float(z[0])
    if not z_hi > z_lo:
        raise NoContactError(f"{trace.source or trace.trace_id}: the tip never moves down in "
                             "the chosen segments; is z down-positive? flip it with --z-sign -1")
    return CycleData(time=t - t[0], z=z, force=f, segment=seg, block=block, z_lo=z_lo,
                     z_hi=z_hi, f0_center=float(base.level),
                     sigma_center=float(sd) / math.sqrt(block) if sd > 0 else 1e-12,
                     C=float(g), m=float(m), trace=kept, segments=names)
