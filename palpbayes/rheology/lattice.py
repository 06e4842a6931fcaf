"""Knots of a record on a regular lattice: where the hereditary products are convolutions.

A viscoelastic fit's knots (:mod:`~palpbayes.rheology.design`) are the window edges of equal
blocks of samples; a regularly sampled segment puts them on a lattice e_0 + n·h.  On it the lag
between two knots is a multiple of h, so the products Σ_k a_k·Ψ(e_i − e_k) of
:func:`~palpbayes.rheology.design.knot_products` are causal convolutions (FFT).  A hold's
corner inside a block, or a few knots where segments meet, lie off the lattice and are taken
directly; a second segment sampled at another rate whose windows share the lattice (at a
finer step) is on it too, and one whose windows do not is a second lattice group.
"""

from __future__ import annotations

import numpy as np
from scipy import fft as sp_fft

__all__ = ["KnotLattice", "LatticeGroup", "knot_lattice", "LATTICE_MIN_KNOTS",
           "LATTICE_MAX_OFF", "LATTICE_MAX_SPAN", "LATTICE_MAX_GROUPS", "LATTICE_TOL",
           "LATTICE_MIN_RUN", "LATTICE_MAX_REFINE"]


class LatticeGroup:
    """Knots on one regular lattice o + n·h (n integer).

    Attributes
    ----------
    step
        [s] Lattice step h.
    members
        Knot indices on this lattice (increasing).
    index
        Lattice index n of every member, from the first (0).
    size
        N = index[-1] + 1.
    steps
        Knot steps j (knot j to j + 1) whose two knots are both members.
    pos
        Place in ``members`` of each step's first knot.
    wide
        Some step spans more than one lattice point (a coarser stretch, a gap).
    others
        Knots of other groups or on none that lie before the group's last member: the
        sources outside the group that act on its steps (set by :class:`KnotLattice`).
    """

    def __init__(self, step: float, members: np.ndarray, index: np.ndarray):
        self.step, self.members, self.index = step, members, index
        self.size = int(index[-1]) + 1
        self.fft_size = int(sp_fft.next_fast_len(2 * self.size, real=True))
        consecutive = np.flatnonzero(np.diff(members) == 1)
        self.steps = members[consecutive]
        self.pos = consecutive
        self.wide = bool(np.any(index[consecutive + 1] - index[consecutive] > 1))
        self.others = np.empty(0, dtype=int)


class KnotLattice:
    """The knots of a record as groups on regular lattices, and the few on none.

    On one lattice the lag between two knots is a multiple of its step h, so
    Σ_k a_k·Ψ(e_i − e_k) over its members is a causal convolution in n, done by FFT in
    O(N log N) per row instead of O(K²) (N: lattice points spanned, K: knots).  A record
    usually has one group (equal blocks of regularly sampled segments); a segment sampled at
    another rate, whose windows sit off the first lattice, is a second.  Sources in another
    group or on none, and the steps that join two groups or touch a knot on none, are taken
    directly (dense).

    Attributes
    ----------
    groups
        The :class:`LatticeGroup` s, the largest first.
    off
        Knot indices on no lattice.
    direct_steps
        Steps whose two knots are not members of one group.
    """

    def __init__(self, groups: list[LatticeGroup], knots: int):
        self.groups = groups
        for g in groups:  # knots are in time order: those before the last member
            g.others = np.setdiff1d(np.arange(g.members[-1]), g.members, assume_unique=True)
        member = np.zeros(knots, dtype=bool)
        on_step = np.zeros(knots - 1, dtype=bool)
        for g in groups:
            member[g.members] = True
            on_step[g.steps] = True
        self.off = np.flatnonzero(~member)
        self.direct_steps = np.flatnonzero(~on_step)


#: Fewest knots for which the lattice path pays (below it one dense product is as fast).
LATTICE_MIN_KNOTS = 64
#: Most share of knots on no lattice, and most lattice points per member of a group, for the
#: lattice path.
LATTICE_MAX_OFF, LATTICE_MAX_SPAN = 0.05, 4.0
#: Most lattice groups (each adds an FFT and a dense block of cross terms).
LATTICE_MAX_GROUPS = 4
#: A knot is on a lattice when within this fraction of h of a lattice point.
LATTICE_TOL = 1e-9
#: Fewest knots of a stretch of equal steps that starts a group of its own.
LATTICE_MIN_RUN = 8
#: Finest division q of a group's step h onto which a later stretch may join it (h/q): a
#: stretch off the group's lattice by a fraction p/q of h, q <= this, shares the finer one.
LATTICE_MAX_REFINE = 4


def _on(e: np.ndarray, origin: float, h: float) -> np.ndarray:
    x = (e - origin) / h  # in steps: the tolerance is relative to h
    return np.abs(x - np.rint(x)) <= LATTICE_TOL


def _common_step(knots: np.ndarray, origin: float, h: float, members: np.ndarray
                 ) -> float | None:
    """The step [s] of the lattice ``origin`` + n·h/q (q = 1 ... :data:`LATTICE_MAX_REFINE`,
    the smallest) that holds every one of ``knots``, or None when none does or when the group
    (its ``members`` and the knots) would span more than :data:`LATTICE_MAX_SPAN` of its
    points per knot.  A retract whose blocks are the approach's length but start a third of a
    block off its lattice (the hold's corner) shares a lattice of a third of the step with it:
    one FFT instead of a dense product of every approach knot into every retract step."""
    both = np.r_[members, knots]
    for q in range(1, LATTICE_MAX_REFINE + 1):
        if _on(knots, origin, h / q).all():
            points = (both.max() - both.min()) / (h / q) + 1
            return h / q if q == 1 or points <= LATTICE_MAX_SPAN * both.size else None
    return None


def knot_lattice(e: np.ndarray) -> KnotLattice | None:
    """The knots' :class:`KnotLattice`, or None when too few lie on lattices (dense path).

    Stretches of at least :data:`LATTICE_MIN_RUN` knots with one recurring step (>= 2 % of
    the steps) are placed, longest first, on the lattice of an earlier group they lie on
    (refined to a step h/q, q <= :data:`LATTICE_MAX_REFINE`, where that holds them:
    :func:`_common_step`), or start a group of their own (step: the stretch's mean step;
    members: its knots within :data:`LATTICE_TOL` of that lattice, so a drifting clock
    leaves knots off it); a knot
    outside every stretch joins a group whose lattice it lies on, within that group's span.
    The path is taken when at most :data:`LATTICE_MAX_OFF` of the knots are left on no
    lattice, with at most
    :data:`LATTICE_MAX_GROUPS` groups, each spanning at most :data:`LATTICE_MAX_SPAN` lattice
    points per member."""
    K = e.size
    if K < LATTICE_MIN_KNOTS:
        return None
    steps = np.diff(e)
    scale = steps.max()
    values, counts = np.unique(np.round(steps / scale, 9), return_counts=True)
    cands = values[counts >= max(2, 0.02 * K)] * scale
    if not cands.size:
        return None
    near = np.abs(steps[:, None] / cands[None, :] - 1.0) <= 1e-6
    which = np.where(near.any(axis=1), np.argmax(near, axis=1), -1)
    runs = []  # (first knot, last knot, step)
    j = 0
    while j < steps.size:
        k = j
        while k < steps.size and which[k] == which[j]:
            k += 1
        if which[j] >= 0 and k - j + 1 >= LATTICE_MIN_RUN:
            runs.append((j, k, float(cands[which[j]])))
        j = k
    runs.sort(key=lambda r: r[0] - r[1])
    lattices: list[tuple[float, float]] = []  # (origin, step)
    group = np.full(K, -1)
    for a, b, _h in runs:
        knots = e[a:b + 1]
        for gi, (o, hg) in enumerate(lattices):
            h = _common_step(knots, o, hg, e[group == gi])
            if h is not None:
                lattices[gi] = (o, h)
                group[a:b + 1] = gi
                break
        else:  # a lattice of its own: the run's mean step, and only the knots that lie on it
            h = float((knots[-1] - knots[0]) / (b - a))
            lattices.append((float(knots[0]), h))
            group[np.arange(a, b + 1)[_on(knots, knots[0], h)]] = len(lattices) - 1
    if not lattices or len(lattices) > LATTICE_MAX_GROUPS:
        return None
    for gi, (o, hg) in enumerate(lattices):  # knots outside the stretches
        span = np.flatnonzero(group == gi)
        lone = np.flatnonzero((group == -1) & (e >= e[span[0]]) & (e <= e[span[-1]] + hg))
        group[lone[_on(e[lone], o, hg)]] = gi
    if np.count_nonzero(group == -1) > LATTICE_MAX_OFF * K:
        return None
    groups = []
    for gi, (_o, hg) in enumerate(lattices):
        members = np.flatnonzero(group == gi)
        index = np.rint((e[members] - e[members[0]]) / hg).astype(int)
        if index[-1] + 1 > LATTICE_MAX_SPAN * members.size:
            return None
        groups.append(LatticeGroup(hg, members, index))
    return KnotLattice(groups, K)
