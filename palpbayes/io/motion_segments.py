"""Segments of one palpation cycle (approach, hold, retract) told apart by the tip motion alone.

For recordings that do not label their segments (a robot trace, a CSV without a ``segment``
column), :func:`segments_from_motion` gives the per-sample codes that
:class:`~palpbayes.trace.IndentationTrace` stores in its ``segment`` field::

    trace = trace.replace(segment=segments_from_motion(trace.time, trace.z))
    loading = trace.segments("approach,hold")

:func:`segment_durations` measures how long each segment of a recording lasts on its time
axis (``palpbayes inspect`` shows an AFM curve's from its data, not from the header, whose
``duration`` fields can be wrong: a JPK stress-relaxation file that holds 30 s says 1 s).
"""

from __future__ import annotations

import numbers

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from ..errors import InputError
from ..sensor_noise import mad_sd
from ..trace import SEGMENTS, IndentationTrace

__all__ = ["segments_from_motion", "cycle_segments", "segment_durations", "default_hold_tolerance",
           "SMOOTH_WINDOW", "NOISE_MULTIPLE", "RANGE_FRACTION"]

#: Samples in the running median that smooths z before the deepest point is looked for, so that
#: a single noise spike neither sets the deepest z nor ends the hold.
SMOOTH_WINDOW = 5
#: The default hold tolerance is at least this many noise standard deviations of z ...
NOISE_MULTIPLE = 6.0
#: ... and at least this fraction of the z range (for noise-free or quantised z).
RANGE_FRACTION = 1e-3

_APPROACH, _HOLD, _RETRACT = (SEGMENTS.index(n) for n in ("approach", "hold", "retract"))


def default_hold_tolerance(z: np.ndarray) -> float:
    """[m] The hold tolerance :func:`segments_from_motion` uses when none is given.

    ``max(NOISE_MULTIPLE * sigma, RANGE_FRACTION * (max(z) - min(z)))`` where ``sigma`` is a
    robust estimate of the z noise: 1.4826 × the median absolute deviation of the second
    differences of z, divided by √6 (the standard deviation of a second difference of white
    noise is √6 σ).  Second differences vanish on a ramp at constant speed and on a hold, so
    the estimate sees the noise, not the motion; the median ignores the few samples at the
    turning points.

    Why these numbers: the hold is judged on the 5-sample running median of z, whose noise is
    about 0.55 σ, so the samples of a true hold stay within about ±2.5 σ of their level and the
    deepest of them lies about 2 σ below it: 6 σ keeps a noisy hold in one piece.  A tolerance
    proportional to the z range instead (e.g. 2 %) would cut the end of the approach: on a robot
    stroke of 10 mm with a 2 mm indentation, 2 % is 0.2 mm, a tenth of the depth; the 0.1 %
    floor costs at most 0.1 % of the stroke and only matters when the noise estimate is zero
    (simulated or quantised z, where most second differences are exactly 0).

    Parameters
    ----------
    z
        [m] Tip height, one value per sample.

    Returns
    -------
    float
        [m] Tolerance, >= 0 (0 only for a constant z).
    """
    z = np.asarray(z, dtype=float)
    d2 = np.diff(z, 2)
    sigma = 0.0
    if d2.size:
        sigma = mad_sd(d2) / np.sqrt(6.0)
    return max(NOISE_MULTIPLE * sigma, RANGE_FRACTION * float(np.ptp(z)))


def _running_median(z: np.ndarray, window: int) -> np.ndarray:
    """Centred running median of odd ``window`` samples; the ends are padded with the end
    values, so the result has the length of ``z``."""
    if z.size < window:
        return z.copy()
    half = window // 2
    padded = np.pad(z, half, mode="edge")
    return np.median(sliding_window_view(padded, window), axis=1)


def segments_from_motion(time, z, *, hold_tolerance: float | None = None) -> np.ndarray:
    """Per-sample segment codes (indices into :data:`~palpbayes.trace.SEGMENTS`) of one cycle.

    The deepest point is the minimum of z after a 5-sample running median (:data:`SMOOTH_WINDOW`;
    a single spike does not count).  Then

    * **approach**: the samples before z first comes within ``hold_tolerance`` of the deepest
      point;
    * **hold**: from there to the last sample within ``hold_tolerance`` of the deepest point
      (a brief excursion above the band in between stays hold);
    * **retract**: the samples after the tip leaves the band for good.

    A trace that ends within the band (no return) has only approach and hold; a trace that
    starts within it has no approach.  One cycle is assumed: a second press deeper than the
    first would end the approach there.  The last ``hold_tolerance`` of the approach's depth is
    counted as hold, which is why the default tolerance is kept small
    (:func:`default_hold_tolerance`).

    Parameters
    ----------
    time
        [s] Sample times, strictly increasing.
    z
        [m] Tip height, up positive (pressing moves z down), one value per sample.
    hold_tolerance
        [m] How far above the deepest point the tip may be and still hold.  Default
        :func:`default_hold_tolerance`: ``max(6 σ, 0.1 % of the z range)``, σ the robust
        noise of z.  For a hold at constant force, where z creeps down, give the creep depth.

    Returns
    -------
    numpy.ndarray
        int8 codes, non-decreasing: 0 approach, 1 hold, 2 retract.

    Raises
    ------
    InputError
        If time and z are not one-dimensional of the same length, have fewer than 3 samples,
        hold NaN/inf, time is not strictly increasing, or ``hold_tolerance`` is not a
        non-negative number.
    """
    t = np.asarray(time, dtype=float)
    zz = np.asarray(z, dtype=float)
    if t.ndim != 1 or zz.ndim != 1:
        raise InputError(f"time and z must be one-dimensional arrays, got shapes {t.shape} "
                         f"and {zz.shape}")
    if t.size != zz.size:
        raise InputError(f"time has {t.size} samples but z has {zz.size}; give one z per time")
    if t.size < 3:
        raise InputError(f"only {t.size} sample(s); telling the segments apart needs at least 3")
    for name, a in (("time", t), ("z", zz)):
        bad = ~np.isfinite(a)
        if bad.any():
            raise InputError(f"{name} has {int(bad.sum())} non-finite value(s) (NaN/inf), first "
                             f"at sample {int(np.argmax(bad))}; remove or repair them")
    dt = np.diff(t)
    if np.any(dt <= 0):
        i = int(np.argmax(dt <= 0))
        raise InputError(f"time is not strictly increasing at sample {i + 1} ({t[i]:g} s -> "
                         f"{t[i + 1]:g} s); sort the samples by time")
    if hold_tolerance is None:
        tol = default_hold_tolerance(zz)
    else:
        if isinstance(hold_tolerance, bool) or not isinstance(hold_tolerance, numbers.Real) \
                or not np.isfinite(hold_tolerance) or hold_tolerance < 0:
            raise InputError(f"hold_tolerance {hold_tolerance!r} must be a non-negative "
                             "number [m], e.g. 1e-5")
        tol = float(hold_tolerance)
    smooth = _running_median(zz, SMOOTH_WINDOW)
    near = smooth <= smooth.min() + tol
    first = int(np.argmax(near))
    last = zz.size - 1 - int(np.argmax(near[::-1]))
    codes = np.full(zz.size, _APPROACH, dtype=np.int8)
    codes[first:last + 1] = _HOLD
    codes[last + 1:] = _RETRACT
    return codes


def segment_durations(time, segment) -> dict[int, float]:
    """[s] How long each segment of a recording lasts, measured on its time axis.

    A segment's duration is the time from its first sample to its last plus one sample period
    of that segment (the median step between its samples), so that segments recorded back to
    back add up to the recording's length, whatever rate each was sampled at (a JPK
    stress-relaxation curve samples its approach at 2048 Hz and its hold at 256 Hz).  A segment
    of one sample lasts 0 s.

    Parameters
    ----------
    time
        [s] Sample times, one per sample.
    segment
        Segment label per sample (afmformats' segment numbers, or the codes of
        :data:`~palpbayes.trace.SEGMENTS`); each label's samples are one segment.

    Returns
    -------
    dict
        Segment label (int) -> duration [s], in order of each segment's first sample.

    Raises
    ------
    InputError
        If time and segment differ in length or time holds NaN/inf.
    """
    t = np.asarray(time, dtype=float)
    seg = np.asarray(segment)
    if t.shape != seg.shape or t.ndim != 1:
        raise InputError(f"time has shape {t.shape} but segment {seg.shape}; give one segment "
                         "label per sample")
    if not np.isfinite(t).all():
        raise InputError("time has non-finite values (NaN/inf); repair them before measuring "
                         "the segments")
    ids, first = np.unique(seg, return_index=True)
    out = {}
    for i in ids[np.argsort(first)]:
        ts = t[seg == i]
        step = float(np.median(np.diff(ts))) if ts.size > 1 else 0.0
        out[int(i)] = float(ts[-1] - ts[0]) + step
    return out


def cycle_segments(trace: IndentationTrace) -> np.ndarray:
    """Segment codes of every sample of ``trace`` (:data:`~palpbayes.trace.SEGMENTS`): its own
    when it records them, else told apart by the motion (:func:`segments_from_motion`): what
    the rate check, the adhesion cut and the peer-compatible reading all start from."""
    if trace.segment is not None:
        return np.asarray(trace.segment)
    return segments_from_motion(trace.time, trace.z)
