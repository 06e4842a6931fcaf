"""Knots of a record on a regular lattice: where the hereditary products are convolutions.

A viscoelastic fit's knots (:mod:`~palpbayes.rheology.design`) are the window edges of equal
blocks of samples; a regularly sampled segment puts them on a lattice e_0 + n·h.  On it the lag
between two knots is a multiple of h, so the products Σ_k a_k·Ψ(e_i − e_k) of
:func:`~palpbayes.rheology.design.knot_products` are causal convolutions (FFT).  A hold's
corner inside a block, or a few knots where segments meet, lie off the lattice and are taken
directly; a second segment sampled at another rate whose windows share the lattice (at a
finer step) is on it too.
"""

from __future__ import annotations

import numpy as np
from scipy import fft as sp_fft

__all__ = ["KnotLattice", "knot_lattice", "LATTICE_MIN_KNOTS", "LATTICE_MAX_OFF",
           "LATTICE_MAX_SPAN", "LATTICE_TOL"]


class KnotLattice:
    """Knots on a regular lattice e_0 + n·h (n integer) and the few that are not (a hold's
    corner inside a block, a segment sampled at another rate).

    On the lattice the lag between two knots is a multiple of h, so Σ_k a_k·Ψ(e_i − e_k) is a
    causal convolution in n, done by FFT in O(N log N) per row instead of O(K²) (N: lattice
    points spanned, K: knots); the off-lattice knots' rows and columns are taken directly.

    Attributes
    ----------
    step
        [s] Lattice step h (the median knot step).
    index
        Lattice index n of every on-lattice knot (increasing).
    on, off
        Knot indices on and off the lattice.
    size
        N = index[-1] + 1.
    """

    def __init__(self, step: float, index: np.ndarray, on: np.ndarray, off: np.ndarray,
                 knots: int):
        self.step, self.index, self.on, self.off = step, index, on, off
        self.size = int(index[-1]) + 1
        self.fft_size = int(sp_fft.next_fast_len(2 * self.size, real=True))
        is_on = np.zeros(knots, dtype=bool)
        is_on[on] = True
        both = is_on[:-1] & is_on[1:]
        #: steps between two lattice knots (their start's place in ``index``: ``lattice_pos``)
        self.lattice_steps = np.flatnonzero(both)
        #: steps that touch an off-lattice knot
        self.direct_steps = np.flatnonzero(~both)
        pos = np.cumsum(is_on) - 1  # place in ``index`` of every on-lattice knot
        self.lattice_pos = pos[self.lattice_steps]
        #: some step spans more than one lattice point (a coarser segment, a gap)
        self.wide = bool(np.any(np.diff(index) > 1))


#: Fewest knots for which the lattice path pays (below it one dense product is as fast).
LATTICE_MIN_KNOTS = 64
#: Most share of knots off the lattice, and most lattice points per knot, for the lattice path
#: (measured: at N = K the FFTs cost a quarter of one dense product; a segment sampled at
#: another rate whose windows sit half a fine step off the others' needs N ~ 13·K).
LATTICE_MAX_OFF, LATTICE_MAX_SPAN = 0.05, 4.0
#: A knot is on the lattice when within this fraction of h of a lattice point.
LATTICE_TOL = 1e-9


def knot_lattice(e: np.ndarray) -> KnotLattice | None:
    """The knots' :class:`KnotLattice`, or None when too few lie on one (the dense path).

    The step is one of the knot steps that recur (a segment sampled at another rate has its
    own): the candidate that leaves at most :data:`LATTICE_MAX_OFF` of the knots off the
    lattice with the fewest lattice points N, if N <= :data:`LATTICE_MAX_SPAN`·K."""
    K = e.size
    if K < LATTICE_MIN_KNOTS:
        return None
    steps = np.diff(e)
    values, counts = np.unique(np.round(steps / steps.max(), 9), return_counts=True)
    best = None
    for h in values[counts >= max(2, 0.02 * K)] * steps.max():
        x = (e - e[0]) / h
        n = np.rint(x)
        # x is in steps: the tolerance is relative to h (and keeps one knot per point)
        on = np.abs(x - n) <= LATTICE_TOL
        size = n[-1] + 1
        if (not on[0] or (~on).sum() > LATTICE_MAX_OFF * K
                or size > LATTICE_MAX_SPAN * K):
            continue
        if best is None or size < best.size:
            best = KnotLattice(float(h), n[on].astype(int), np.flatnonzero(on),
                               np.flatnonzero(~on), K)
    return best
