"""Like-for-like settings for users moving from a peer's viscoelastic fit (PyFMRheo).

PyFMRheo's Ting fit (``pyfmrheo.routines.TingFit.doTingFit``, model ``"analytical"``, the
setting of its example notebook ``ViscoelasticFitExample.ipynb``) does not use the recorded
heights in contact.  It takes the indentation as two straight ramps: down at
v0t = (max − min height of the approach)/duration and up at v0r, the same for the retract,
turning at the force's maximum (the closed forms of Ting's power-law solution for a
triangular history).  palpbayes integrates the measured heights (Lee & Radok 1960, Ting
1966; DESIGN §9).  On a real AFM map the piezo does not move at constant speed: on curve 0 of
PyFMRheo's own map the tip comes down at 23.8 µm/s near the surface (v0t 22.8) and goes up at
13.7 µm/s in the first 20 ms of the retract (v0r 18.9 µm/s).  A model that assumes the faster
retract expects the force to fall sooner than the data's does and reads that as a more
elastic sample: on PyFMRheo's map its notebook's alpha is about half palpbayes' (0.17 against
0.40 on curve 0); its own numerical model, which integrates the measured indentation, reads
0.39 (``benchmarks/bench_visco_peer.py``, with simulations of known truth that settle which
history is right).

:func:`pyfmrheo_compatible` makes a trace that a palpbayes fit reads as PyFMRheo's notebook
does, so that a user can check their old numbers like for like:

* the heights replaced by straight ramps per segment from the first to the last height of
  that segment (:func:`nominal_ramps`): the analytical model's constant speeds;
* the viscous drag fixed at the notebook's b = 2.5e-6 N·s/m: b·(−dz/dt) subtracted from the
  force, with the drag then left out of the fit (``drag=False``);
* approach and retract fitted, t0 = 1 s.

The result answers the peer's question, not the recording's: use it to compare, never to
report a modulus (the constant speeds are not what the tip did).
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from ..io.motion_segments import cycle_segments
from ..trace import SEGMENTS, IndentationTrace

__all__ = ["PEERS", "PYFMRHEO_DRAG", "TURN_SHARE", "nominal_ramps", "pyfmrheo_compatible",
           "peer_compatible"]

#: Peers :func:`pyfmrheo_compatible` (``--peer-compatible``) can imitate.
PEERS = ("pyfmrheo",)
#: [N·s/m] The viscous drag PyFMRheo's viscoelastic example notebook fixes.
PYFMRHEO_DRAG = 2.5e-6
_APPROACH, _HOLD, _RETRACT = (SEGMENTS.index(n) for n in ("approach", "hold", "retract"))
#: A "hold" shorter than this share of the approach's duration is the turn of a triangle.
TURN_SHARE = 0.01


def _turn_into_ramps(trace: IndentationTrace) -> np.ndarray:
    """The segment codes, with a "hold" of under :data:`TURN_SHARE` of the approach's duration
    (the turn itself, as the motion classifies a trace without codes) given to the approach up
    to the lowest height and to the retract after it."""
    codes = np.array(cycle_segments(trace))
    hold, app = np.flatnonzero(codes == _HOLD), np.flatnonzero(codes == _APPROACH)
    if hold.size and app.size > 1:
        span = trace.time[hold[-1]] - trace.time[hold[0]]
        if span <= TURN_SHARE * (trace.time[app[-1]] - trace.time[app[0]]):
            low = hold[0] + int(np.argmin(trace.z[hold]))
            codes[hold] = np.where(hold <= low, _APPROACH, _RETRACT)
    return codes


def nominal_ramps(trace: IndentationTrace) -> IndentationTrace:
    """``trace`` with the heights of each segment replaced by a straight line in time from
    the segment's first height to its last (a constant speed per segment, as a
    triangular-history model assumes).

    Parameters
    ----------
    trace
        SI units, z [m] up; segments from the motion when the trace records none (they are
        then stored in the result).

    Returns
    -------
    IndentationTrace
        The same samples, forces and segments; the heights on the ramps [m].
    """
    codes = cycle_segments(trace)
    z = np.array(trace.z, dtype=float)
    for code in np.unique(codes):
        rows = np.flatnonzero(codes == code)
        t = trace.time[rows]
        if rows.size < 2 or not t[-1] > t[0]:
            continue
        z[rows] = z[rows[0]] + (z[rows[-1]] - z[rows[0]]) * (t - t[0]) / (t[-1] - t[0])
    return trace.replace(z=z, segment=codes)


def pyfmrheo_compatible(trace: IndentationTrace, drag: float = PYFMRHEO_DRAG
                        ) -> tuple[IndentationTrace, dict]:
    """The trace and :func:`~palpbayes.rheology.fit_rheology` options that read a cycle as
    PyFMRheo's analytical Ting fit does (module docstring).

    Parameters
    ----------
    trace
        Approach then retract, nothing between them (segment codes, or from the motion), SI
        units, z up, pressing positive.
    drag
        [N·s/m] The fixed viscous drag subtracted, b·(−dz/dt) with each ramp's own speed
        (default PyFMRheo's notebook).

    Returns
    -------
    trace, options
        The nominal-ramp trace with the drag taken off, and ``segments``, ``drag``, ``t0``
        for ``fit_rheology``.

    Raises
    ------
    InputError
        A negative drag; a trace without an approach and a retract; a hold, or a gap in time
        between the approach and the retract (a hold left out): the peer's closed forms are
        for a triangle, and palpbayes would read the two ramps as if they touched.
    """
    if not (np.isfinite(drag) and drag >= 0):
        raise InputError(f"peer-compatible drag = {drag!r} N·s/m must be >= 0")
    where = trace.source or trace.trace_id
    ramps = nominal_ramps(trace.replace(segment=_turn_into_ramps(trace)))
    codes = ramps.segment
    names = {SEGMENTS[c] for c in np.unique(codes)}
    if not {"approach", "retract"} <= names:
        raise InputError(f"{where}: PyFMRheo's Ting fit takes the approach and the retract; "
                         f"this trace has {', '.join(sorted(names)) or 'no segments'}")
    app, ret = np.flatnonzero(codes == _APPROACH), np.flatnonzero(codes == _RETRACT)
    if min(app.size, ret.size) < 2:
        raise InputError(f"{where}: {min(app.size, ret.size)} sample in the approach or the "
                         "retract; a ramp's speed needs two")
    gap = float(ramps.time[ret[0]] - ramps.time[app[-1]])
    dt = float(np.median(np.diff(ramps.time)))
    if "hold" in names or gap > 2.0 * dt:
        raise InputError(f"{where}: a hold ({gap:.3g} s between the approach and the retract); "
                         "PyFMRheo's Ting fit is for an approach followed at once by the "
                         "retract, so --peer-compatible cannot read this cycle: fit it without "
                         "that option")
    speed = np.zeros(ramps.n_points)
    for rows in (app, ret):
        t, z = ramps.time[rows], ramps.z[rows]
        speed[rows] = (z[-1] - z[0]) / (t[-1] - t[0])
    ramps = ramps.replace(force=ramps.force - drag * (-speed))
    return ramps, {"segments": "approach,retract", "drag": False, "t0": 1.0}


def peer_compatible(trace: IndentationTrace, peer: str) -> tuple[IndentationTrace, dict]:
    """:func:`pyfmrheo_compatible` by the peer's name in :data:`PEERS` (``--peer-compatible``).

    Raises
    ------
    InputError
        A peer palpbayes cannot imitate (naming the ones it can), or the trace's own errors.
    """
    if peer != "pyfmrheo":
        raise InputError(f"--peer-compatible {peer!r}: palpbayes can read a trace as "
                         f"{', '.join(PEERS)} does")
    return pyfmrheo_compatible(trace)
