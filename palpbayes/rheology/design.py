"""The Lee–Radok hereditary integral as regression columns for the block means of a record.

While the contact does not shrink, a rigid tip with elastic law F = C·E·d^m on a linear
viscoelastic half-space with relaxation modulus E(t) gives (Lee & Radok 1960; DESIGN §9)

    F(t) = C·∫_0^t E(t − s)·du/ds ds,    u(s) = d(s)^m,  d = z_s − z(s) (0 out of contact).

A fit sees block means of the force (:mod:`~palpbayes.rheology.cycle`), so the model is the
*mean of F over each block's samples*, not F at the block's mean time: at the contact onset
and where the hold starts F bends within a block, and the point value would miss the block
mean by several noise sd.  The source u is linear between knots e_k (the blocks' window
edges, and the corner where a hold starts), slope r_k, plus a quadratic bump per step
(below).  With Φ(x) = ∫_0^x E(y) dy and Ψ(x) = ∫_0^x Φ(y) dy (0 for x <= 0), the response of
block o to a unit slope on step k is the mean over its samples t of Φ(t − e_k) − Φ(t − e_{k+1});
far from the source Φ is smooth and that mean is the average over the block's window
[a_o, b_o] (half a step beyond its first and last samples: the midpoint rule, error
~dt²·Φ''/24), (Ψ(b_o − e_k) − Ψ(a_o − e_k))/(b_o − a_o); on the :data:`BAND` knots nearest the
block, where Φ bends within it, the mean is taken over the samples themselves.  So

    F̄_o = C·Σ_k r_k·W[o, k] = C·(W·r)_o,

one lower-triangular matrix W on the knot axis that does not depend on the surface height
z_s: every trial surface's column is one matrix product, and the modulus enters linearly.
(The products run on the knot steps, :func:`knot_products`, and the blocks' windows and band
corrections are applied to their results.)  When the knots lie on a regular lattice (equal
blocks of regularly sampled segments; a hold's corner and a few other knots may lie off it,
:class:`KnotLattice`) the lags are multiples of the step, the products are causal
convolutions and run by FFT in O(N log N) per surface; otherwise they are dense BLAS products
of the K × K step means (:func:`step_kernel_means`).  Irregular sampling costs first
order in the offset between a block's mean sample time and its window's centre (~1e-3 of the
peak at steps ± 50 %, ~3e-5 at ± 2 %).  The kernels (power law, exponential branch,
constant) and their integrals Φ, Ψ, Ψ₂ per unit modulus are :mod:`~palpbayes.rheology.kernels`'s.

Two corrections make the piecewise-linear u follow d^m (:func:`lee_radok_columns`): on every
step in contact u bends (d^m with d linear) by a quadratic bump through the step's midpoint,
which takes the interpolation's error from O(h²) to O(h³) near
the onset of a paraboloid or cone; and the step where the contact starts rises from the
crossing of d = 0 (linear in d), not from the step's start (:func:`onset_correction`; without
it a flat punch's kink would leak ~1e-3 of the peak force into the power law's singular
kernel).  Ting's rule for a shrinking contact (the retract) has columns of its own, in
:mod:`~palpbayes.rheology.ting`.
"""

# Long module: one job, the Lee-Radok hereditary integral as regression columns; window kernels
#   and their corrections are one design matrix.

from __future__ import annotations

import numpy as np
from scipy import fft as sp_fft

from ..errors import InputError
from .kernels import (
    PSI2_SERIES,
    Lags,
    check_kernel,
    double_integrated_kernel,
    psi2_series,
    triple_integrated_kernel,
)
from .lattice import KnotLattice, knot_lattice

__all__ = ["Windows", "block_kernel_means", "step_kernel_means", "knot_products",
           "band_corrections", "window_kernel", "window_kernels", "onset_correction",
           "lee_radok_columns", "BAND", "SPAN"]

#: Knots before a block's window (its own knots too) on which the block's response is the
#: mean over its own samples; :func:`window_kernel` takes the same blocks after a source.
BAND = 2
#: Most knot steps one block's window spans (two where the hold's corner lies inside it).
SPAN = 2


class Windows:
    """Knots e (K,) [s] of the piecewise-linear source and the blocks: window [e[lo], e[hi]]
    (spanning one or more knot steps) and sample times ``samples`` (B, n) of each block; the
    knots' lags max(e_i − e_j, 0) (``knot_lags``, their logarithms when the power law asks),
    built once per record.
    ``samples`` None takes every block's mean over its window (no sample-level band)."""

    def __init__(self, edges: np.ndarray, lo: np.ndarray | None = None,
                 hi: np.ndarray | None = None, samples: np.ndarray | None = None):
        e = np.asarray(edges, dtype=float)
        if e.ndim != 1 or e.size < 2 or not np.all(np.diff(e) > 0):
            raise InputError("window edges must be an increasing 1-D array of >= 2 times")
        self.edges = e
        self.lo = np.arange(e.size - 1) if lo is None else np.asarray(lo, dtype=int)
        self.hi = self.lo + 1 if hi is None else np.asarray(hi, dtype=int)
        if self.lo.size and (self.lo.min() < 0 or self.hi.max() > e.size - 1
                             or np.any(self.hi <= self.lo)):
            raise InputError("windows must run forward between knots of the edge axis")
        self.width = e[self.hi] - e[self.lo]
        self.samples = None if samples is None else np.asarray(samples, dtype=float)
        if self.samples is not None and (self.samples.ndim != 2
                                         or self.samples.shape[0] != self.lo.size):
            raise InputError("samples must be (blocks, samples per block)")
        self.knot_lags = Lags(e[:, None] - e[None, :])
        # the knots whose response a block takes from its samples: BAND before its window on
        band = self.lo[:, None] + np.arange(-BAND, SPAN + 1)[None, :]
        self.band_ok = (band >= 0) & (band <= e.size - 1)
        self.band = np.clip(band, 0, e.size - 1)
        self._steps = np.diff(e)[None, :]
        self._work: list[np.ndarray] | None = None
        self._constant: tuple[np.ndarray, ...] | None = None
        self._lags: dict[object, Lags] = {}
        self.lattice: KnotLattice | None = knot_lattice(e)

    def lags_of(self, key: object, make) -> Lags:
        """The :class:`Lags` of ``make()`` (lags the record fixes), built once per ``key``."""
        out = self._lags.get(key)
        if out is None:
            out = self._lags[key] = Lags(make())
        return out

    def window_means(self, R: np.ndarray) -> np.ndarray:
        """Means over every block's window (G, B) of quantities given per knot step as step
        means ``R`` (G, K − 1) (weighted by the steps' lengths)."""
        S = np.zeros((R.shape[0], self.edges.size))
        np.cumsum(R * self._steps, axis=1, out=S[:, 1:])
        return (S[:, self.hi] - S[:, self.lo]) / self.width[None, :]


def step_kernel_means(win: Windows, kernel: str | None, theta: float = 0.0, t0: float = 1.0,
                      *, scratch: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Means (K − 1, K) over every knot step [e_j, e_{j+1}] of Φ(t − e_k) [s] and of
    Ψ(t − e_k) [s²] per unit modulus: (Ψ(e_{j+1} − e_k) − Ψ(e_j − e_k))/h_j and the same
    with Ψ₂, from one Ψ per knot lag (module docstring).

    Parameters
    ----------
    win
        :class:`Windows` of the record.
    kernel
        ``"power-law"`` (``theta`` = alpha in [0, 1)), ``"exponential"`` (``theta`` = tau
        [s] > 0) or None (the constant kernel).
    t0
        [s] Reference time of the power law.
    scratch
        Write into ``win``'s work arrays (valid until its next call: a fit's inner loop
        rebuilds these matrices hundreds of times, and fresh multi-megabyte arrays cost
        more in page faults than the arithmetic).
    """
    check_kernel(kernel, theta)
    K = win.edges.size
    if scratch:
        if win._work is None:
            win._work = [np.empty((K, K)), np.empty((K, K)), np.empty((K - 1, K)),
                         np.empty((K - 1, K))]
        P, Q, D1, D2 = win._work
    else:
        P, Q, D1, D2 = (np.empty((K, K)), np.empty((K, K)), np.empty((K - 1, K)),
                        np.empty((K - 1, K)))
    lags = win.knot_lags.x
    inv_h = (1.0 / np.diff(win.edges))[:, None]
    if kernel == "power-law":  # Ψ = c·x^(2−alpha), Ψ₂ = Ψ·x/(3 − alpha): one exp per lag
        np.multiply(win.knot_lags.log, 2.0 - theta, out=P)
        np.exp(P, out=P)
        P *= t0**theta / ((1.0 - theta) * (2.0 - theta))
    elif kernel == "exponential":  # Ψ = tau²·(y + expm1(−y)), y = x/tau
        np.multiply(lags, -1.0 / theta, out=Q)
        np.expm1(Q, out=Q)
        np.multiply(lags, 1.0 / theta, out=P)
        P += Q
        P *= theta**2
    else:  # Ψ = x²/2
        np.multiply(lags, lags, out=P)
        P *= 0.5
    np.subtract(P[1:], P[:-1], out=D1)
    D1 *= inv_h
    if kernel == "power-law":
        P *= lags
        P *= 1.0 / (3.0 - theta)
    elif kernel == "exponential":  # Ψ₂ = tau³·(y²/2 − y − expm1(−y)), series for small y
        np.multiply(lags, 1.0 / theta, out=P)
        small = P < PSI2_SERIES
        y = P[small]
        np.multiply(P, 0.5 * P - 1.0, out=P)
        P -= Q
        P[small] = psi2_series(y)
        P *= theta**3
    else:  # Ψ₂ = x³/6
        P *= lags
        P *= 1.0 / 3.0
    np.subtract(P[1:], P[:-1], out=D2)
    D2 *= inv_h
    return D1, D2


def knot_products(win: Windows, a1: np.ndarray, a2: np.ndarray, kernel: str | None,
                  theta: float = 0.0, t0: float = 1.0) -> np.ndarray:
    """a1·D1ᵀ + a2·D2ᵀ (G, K − 1) for the step means D1, D2 of :func:`step_kernel_means`,
    for coefficients per knot ``a1``, ``a2`` (G, K).

    Entry (g, j) is Σ_k a1_gk·[Ψ(e_{j+1} − e_k) − Ψ(e_j − e_k)]/h_j plus the same with a2
    and Ψ₂.  On a lattice group (:class:`~palpbayes.rheology.lattice.KnotLattice`), for a
    step between two of its knots and a source k of the group, the bracket is a sum of the
    lattice differences ΔΨ(p) = Ψ((p + 1)·h) − Ψ(p·h) over the lattice points p of the step,
    shifted by n_k: the sums over k are causal convolutions (FFT), and each step adds its
    points' values (one, on a regular stretch).  The kernel is differenced before the sum,
    as in the dense products, so no precision is lost to cancellation.  Sources outside the
    group, and the steps that join two groups or touch a knot on no lattice, are taken
    directly.  Without a lattice: two dense products.
    """
    lat = win.lattice
    if lat is None:
        D1, D2 = step_kernel_means(win, kernel, theta, t0, scratch=True)
        return a1 @ D1.T + a2 @ D2.T
    check_kernel(kernel, theta)
    e = win.edges
    G, K = a1.shape
    out = np.zeros((G, K - 1))
    pairs = ((a1, double_integrated_kernel), (a2, triple_integrated_kernel))
    for gi, g in enumerate(lat.groups):
        grid = np.arange(g.size + 1) * g.step
        spec = 0.0
        for a, f in pairs:
            A = np.zeros((G, g.size))
            A[:, g.index] = a[:, g.members]
            spec = spec + (sp_fft.rfft(A, g.fft_size, axis=1)
                           * sp_fft.rfft(np.diff(f(grid, kernel, theta, t0)), g.fft_size))
        Z = sp_fft.irfft(spec, g.fft_size, axis=1)[:, :g.size]
        start = g.index[g.pos]
        if g.wide:  # the sum over each step's lattice points [n_j, n_{j+1})
            bounds = np.c_[start, g.index[g.pos + 1]].ravel()
            out[:, g.steps] = np.add.reduceat(np.c_[Z, np.zeros(G)], bounds, axis=1)[:, ::2]
        else:
            out[:, g.steps] = Z[:, start]
        if g.others.size:  # sources of other groups or none, before the group's end
            lags = win.lags_of(("others", gi), lambda g=g: e[np.r_[g.steps, g.steps + 1]][
                :, None] - e[None, g.others])
            n = g.steps.size
            for a, F in zip((a1, a2), lags.integrals((2, 3), kernel, theta, t0), strict=True):
                out[:, g.steps] += a[:, g.others] @ (F[n:] - F[:n]).T
    direct = lat.direct_steps
    if direct.size:  # every source into the steps that join two groups or touch no lattice
        lags = win.lags_of("direct", lambda: e[np.r_[direct, direct + 1]][:, None]
                           - e[None, :])
        for a, F in zip((a1, a2), lags.integrals((2, 3), kernel, theta, t0), strict=True):
            out[:, direct] += a @ (F[direct.size:] - F[:direct.size]).T
    out /= np.diff(e)[None, :]
    return out


def band_corrections(win: Windows, kernel: str | None, theta: float = 0.0,
                     t0: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """(δ1, δ2), each (B, nb): the mean over block o's samples of Φ(t − e_k) (Ψ(t − e_k))
    minus its window mean, for the knots k = ``win.band[o]`` near the block (0 where the band
    runs off the knot axis, or without samples)."""
    B, nb = win.band.shape
    if win.samples is None:
        return np.zeros((B, nb)), np.zeros((B, nb))
    src = win.edges[win.band]
    lo, hi = win.edges[win.lo][:, None], win.edges[win.hi][:, None]
    w = win.width[:, None]
    at_samples = win.lags_of("band samples", lambda: win.samples[:, :, None] - src[:, None, :])
    at_ends = win.lags_of("band windows", lambda: np.stack([hi - src, lo - src]))
    sample = [f.mean(axis=1) for f in at_samples.integrals((1, 2), kernel, theta, t0)]
    window = [(f[0] - f[1]) / w for f in at_ends.integrals((2, 3), kernel, theta, t0)]
    return tuple(np.where(win.band_ok, a - b, 0.0) for a, b in zip(sample, window,
                                                                    strict=True))


def block_kernel_means(win: Windows, kernel: str | None, theta: float = 0.0,
                       t0: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Block means (B, K) of Φ(t − e_k) [s] and Ψ(t − e_k) [s²] per unit modulus: the
    window means of :func:`step_kernel_means` with :func:`band_corrections` (a reference
    for tests; :func:`lee_radok_columns` applies the same pieces after its products)."""
    D1, D2 = step_kernel_means(win, kernel, theta, t0)
    d1, d2 = band_corrections(win, kernel, theta, t0)
    rows = np.arange(win.lo.size)[:, None]
    out = []
    for D, d in ((D1, d1), (D2, d2)):
        A = win.window_means(D.T).T
        np.add.at(A, (np.broadcast_to(rows, win.band.shape), win.band), d)
        out.append(A)
    return out[0], out[1]


def window_kernel(win: Windows, s: np.ndarray, kernel: str | None, theta: float = 0.0,
                  t0: float = 1.0, order: int = 1, side: str = "right") -> np.ndarray:
    """Block means (R, B) of Φ(t − s_r) (``order`` 1) or Ψ(t − s_r) (``order`` 2) for
    source times ``s`` (R,) [s]: over each block's window, e.g.
    (Ψ(b_o − s) − Ψ(a_o − s)) / (b_o − a_o), and over the samples of the blocks from the one
    that holds s_r to :data:`BAND` after it; a source on a block's upper edge belongs to the
    next block (``side`` "right") or to that block (``"left"``: the limit of sources just
    before the edge)."""
    return window_kernels(win, s, kernel, theta, t0, ((order, side),))[0]


def window_kernels(win: Windows, s: np.ndarray, kernel: str | None, theta: float,
                   t0: float, requests: tuple[tuple[int, str], ...],
                   at_edges: Lags | None = None) -> list[np.ndarray]:
    """:func:`window_kernel` for each (order, side) of ``requests``, the kernel's
    exponentials shared between them; ``at_edges``: the :class:`Lags` e_j − s_r (R, K) when
    the caller has them (sources at knots: columns of ``win``'s lags)."""
    s = np.asarray(s, dtype=float)
    if at_edges is None:
        at_edges = Lags(win.edges[None, :] - s[:, None])  # windows share edges
    orders = sorted({o for o, _ in requests})
    means = {o: (A[:, win.hi] - A[:, win.lo]) / win.width[None, :] for o, A in zip(
        orders, at_edges.integrals(tuple(o + 1 for o in orders), kernel, theta, t0),
        strict=True)}
    if win.samples is None or not s.size:
        return [means[o].copy() for o, _ in requests]
    out: dict[tuple[int, str], np.ndarray] = {}
    for side in dict.fromkeys(sd for _, sd in requests):  # each side's samples once
        first = np.searchsorted(win.edges[win.hi], s, side=side)
        near = np.clip(first[:, None] + np.arange(BAND + 1)[None, :], 0, win.lo.size - 1)
        x = win.samples[near.ravel()] - np.repeat(s, near.shape[1])[:, None]
        wanted = sorted({o for o, sd in requests if sd == side})
        for o, f in zip(wanted, Lags(x).integrals(tuple(wanted), kernel, theta, t0),
                        strict=True):
            res = means[o].copy()
            res[np.arange(s.size)[:, None], near] = f.mean(axis=1).reshape(near.shape)
            out[o, side] = res
    return [out[r] for r in requests]


def onset_correction(win: Windows, depth: np.ndarray, m: float, kernel: str | None,
                     theta: float = 0.0, t0: float = 1.0) -> np.ndarray:
    """Correction (G, B) to the columns for the step where each row's contact starts: u = d^m
    rises from the crossing s_c of d = 0 (linear in d between the two edges) to the step's
    end, as a line plus a quadratic bump through the midpoint of [s_c, e_k] (as on every other
    step), instead of the step's line from its start.  ``depth`` (G, K) [m] at the edges;
    rows that start in contact or never touch get no correction.  Both ends of the rise take
    the band of sample-mean blocks of a source just before e_k (``side="left"``), so that the
    differences over the rise, divided by its length and its square, stay finite as s_c
    reaches e_k (the surface a picometre above a knot); the subtracted line keeps e_k's own
    band, as the step's columns have it."""
    e = win.edges
    G, K = depth.shape
    out = np.zeros((G, win.lo.size))
    pos = depth > 0
    k = np.argmax(pos, axis=1)
    rows = np.flatnonzero(pos.any(axis=1) & (k >= 1))
    if not rows.size:
        return out
    kk = k[rows]
    d0, d1 = depth[rows, kk - 1], depth[rows, kk]
    ta, tb = e[kk - 1], e[kk]
    sc = ta + (tb - ta) * (-d0) / (d1 - d0)
    u1 = d1**m
    # e_{k-1} and e_k are knots, shared by many rows: each knot's means once
    knots, at = np.unique(np.r_[kk - 1, kk], return_inverse=True)
    # e_j - e_k at the knots: columns of the record's lags (their logarithms, if computed)
    lags = win.knot_lags.columns(knots)
    fk, fl, gb = window_kernels(win, e[knots], kernel, theta, t0,
                                ((1, "right"), (1, "left"), (2, "left")), lags)
    fa, fb = fk[at[: rows.size]], fk[at[rows.size:]]
    # the differences (fc − fb)/h and (gc − gb)/h² of the rise [s_c, e_k] take both ends with
    # the band of blocks of sources just before e_k: with e_k's own band (the next block's),
    # the one block where sample means and window means swap put an O(1) step over h², and a
    # surface a picometre above a knot gave a spike of ~d^(-1/2) in the columns (the density
    # jumped by -1,000 and then by +9 within nanometres)
    fl, gb = fl[at[rows.size:]], gb[at[rows.size:]]
    fc, gc = window_kernels(win, sc, kernel, theta, t0, ((1, "right"), (2, "right")))
    rise = tb - sc  # 0 when d1 is so small that the crossing rounds onto the edge
    ok = rise > 0
    h = np.where(ok, rise, 1.0)
    amp = np.where(ok, (0.5 * d1) ** m - 0.5 * u1, 0.0)  # the bump of d^m on [s_c, e_k]
    exact = ((u1 * ok / h)[:, None] * (fc - fl)
             + amp[:, None] * ((4.0 / h)[:, None] * (fc + fl)
                               - (8.0 / h**2)[:, None] * (gc - gb)))
    linear = (u1 / (tb - ta))[:, None] * (fa - fb)
    out[rows] = exact - linear
    return out


def lee_radok_columns(win: Windows, z_nodes: np.ndarray, z_edges: np.ndarray, m: float,
                      kernel: str | None, theta: float = 0.0, t0: float = 1.0) -> np.ndarray:
    """Block means of ∫_0^t K(t − s)·d/ds[d(s)^m] ds (G, B) for trial surfaces ``z_nodes``
    (G,) [m], with the tip heights ``z_edges`` (K,) [m] at the knots (z linear between them);
    ``kernel`` None is the constant kernel (the SLS's E_inf: the block mean of d^m).

    On step k (length h_k) u is the line through the knots' d^m (slope r_k) plus the bump
    c_k·b(s), b = 4·(s − e_k)·(e_{k+1} − s)/h_k², c_k = d_mid^m − (u_k + u_{k+1})/2.  The
    response to the line is r_k·[Φ̄(e_k) − Φ̄(e_{k+1})]; to the bump (by parts)
    c_k·{(4/h_k)·[Φ̄(e_k) + Φ̄(e_{k+1})] − (8/h_k²)·[Ψ̄(e_k) − Ψ̄(e_{k+1})]}, with Φ̄, Ψ̄ the
    means of :func:`block_kernel_means`: coefficients a1, a2 per knot, two matrix products on
    the knot steps (:func:`step_kernel_means`), then the window means and the band's
    corrections.  The step where the contact starts is :func:`onset_correction`'s.

    Parameters
    ----------
    win
        :class:`Windows` of the record.
    z_nodes
        [m] Trial surface heights (G,).
    z_edges
        [m] Tip height at the knots (K,).
    m
        Exponent of the tip's law F = C·E·d^m [-].
    kernel, theta, t0
        As :func:`block_kernel_means`.

    Returns
    -------
    numpy.ndarray
        (G, B) [m^m] per unit modulus and unit prefactor C: multiply by C·E0* (or E_inf*,
        E1*) for the force [N].
    """
    depth = np.asarray(z_nodes, float)[:, None] - np.asarray(z_edges, float)[None, :]
    d = np.clip(depth, 0.0, None)
    u = d**m
    h = np.diff(win.edges)[None, :]
    r = np.diff(u, axis=1) / h
    c = (0.5 * (d[:, 1:] + d[:, :-1])) ** m - 0.5 * (u[:, 1:] + u[:, :-1])
    c[(depth[:, :-1] <= 0) | (depth[:, 1:] <= 0)] = 0.0  # the onset step: onset_correction's
    G, K = u.shape
    a1, a2 = np.zeros((G, K)), np.zeros((G, K))
    b1, b2 = 4.0 * c / h, 8.0 * c / h**2
    a1[:, :-1] += r + b1
    a1[:, 1:] += b1 - r
    a2[:, :-1] -= b2
    a2[:, 1:] += b2
    if kernel is None:  # the same for every theta of a fit: once per record
        if win._constant is None:
            dense = step_kernel_means(win, None) if win.lattice is None else ()
            win._constant = (*band_corrections(win, None), *dense)
        d1, d2, *dense = win._constant
        # on a lattice by FFT, as every kernel: two dense K × K products cost 40-80 ms per
        # call on shared cores, most of the SLS's grid search (issue 47)
        prod = (knot_products(win, a1, a2, None) if not dense
                else a1 @ dense[0].T + a2 @ dense[1].T)
    else:
        prod = knot_products(win, a1, a2, kernel, theta, t0)
        d1, d2 = band_corrections(win, kernel, theta, t0)
    out = win.window_means(prod)
    for j in range(win.band.shape[1]):  # the band's corrections, one knot offset at a time
        out += a1[:, win.band[:, j]] * d1[:, j] + a2[:, win.band[:, j]] * d2[:, j]
    return out + onset_correction(win, depth, m, kernel, theta, t0)
