"""The modulus columns of the viscoelastic fit tabulated for a chain: Chebyshev interpolation
in θ (alpha, or log tau) and in the surface height z_s, by panels.

A direct evaluation of :meth:`~palpbayes.rheology.posterior.NodeEvaluator.columns` builds a
kernel matrix per θ (30–140 ms for 700 block means on shared cores), too slow inside an emcee
chain (:mod:`~palpbayes.rheology.sampler`), so the columns are evaluated once on a tensor grid
of :data:`N_THETA` Chebyshev nodes in θ × up to :data:`N_Z` per z_s panel over a box, and
interpolated barycentrically.  Panels end where the columns bend (the surface at a knot's or
a sample's height); within one they are analytic in θ (Ting's t1 bends them slightly in
alpha) and smooth in z_s.  Outside the box the columns are evaluated directly
(``n_direct`` counts those).
"""

from __future__ import annotations

import math

import numpy as np

from .posterior import NUISANCE, NodeEvaluator

__all__ = ["ColumnTable", "chebyshev_points", "barycentric_weights", "N_THETA", "N_Z",
           "MAX_Z_NODES"]

#: Chebyshev nodes of the column table in θ, and at most per z panel.
N_THETA, N_Z = 9, 9
#: Most z nodes of the table (panels get fewer, at least 3, when the box spans many).
MAX_Z_NODES = 64


def chebyshev_points(a: float, b: float, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Chebyshev points of the first kind on [a, b], ascending, and barycentric weights."""
    angle = (2 * np.arange(n)[::-1] + 1) * np.pi / (2 * n)
    return a + (b - a) * (np.cos(angle) + 1) / 2, (-1.0) ** np.arange(n)[::-1] * np.sin(angle)


def barycentric_weights(x: np.ndarray, nodes: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Interpolation weights (W, n) at points ``x`` (W,) on ``nodes`` (W, n) or (n,)."""
    d = x[:, None] - nodes
    hit = d == 0
    c = np.where(hit.any(axis=1, keepdims=True), hit.astype(float), w / np.where(hit, 1.0, d))
    return c / c.sum(axis=1, keepdims=True)


class ColumnTable:
    """The modulus columns of :meth:`NodeEvaluator.columns` on a Chebyshev tensor grid over
    ``c_box`` × ``z_box`` (θ coordinate c: alpha, or log tau for the SLS; z_s [m] in panels
    between the heights where the columns bend: module docstring), direct outside the box.

    :meth:`columns` (W,), (W,) → (W, N, number of moduli) per unit modulus [N/Pa].
    """

    def __init__(self, ev: NodeEvaluator, c_box: tuple[float, float],
                 z_box: tuple[float, float], n_theta: int = N_THETA, n_z: int = N_Z):
        self.ev, self.log_theta = ev, ev.rheology == "sls"
        self.moduli = [i for i, name in enumerate(ev.names) if name not in NUISANCE]
        extra = [i for i, name in enumerate(ev.names) if name in NUISANCE and name != "offset"]
        (c0, c1), (z0, z1) = c_box, z_box
        self.c_box, self.z_box = (float(c0), float(c1)), (float(z0), float(z1))
        self.c_nodes, self.c_w = chebyshev_points(c0, c1, n_theta)
        d = ev.data
        heights = np.r_[d.z_edges, np.interp(d.sample_time.ravel(), d.edges, d.z_edges)]
        cuts = np.unique(heights[(heights > z0) & (heights < z1)])
        cuts = cuts[np.diff(np.r_[z0, cuts]) > 1e-3 * (z1 - z0)]  # no sliver panels
        if cuts.size + 1 > MAX_Z_NODES // 3:
            cuts = cuts[:: math.ceil((cuts.size + 1) / (MAX_Z_NODES // 3))]
        self.breaks = np.r_[z0, cuts, z1]
        P = self.breaks.size - 1
        nz = max(3, min(n_z, MAX_Z_NODES // P))
        self.z_nodes = np.stack([chebyshev_points(self.breaks[p], self.breaks[p + 1], nz)[0]
                                 for p in range(P)])  # (P, nz)
        self.z_w = chebyshev_points(0.0, 1.0, nz)[1]
        cols = ev.columns_at(self.theta(self.c_nodes), self.z_nodes.ravel())
        self.fixed = cols[0][0][:, extra]  # (N, extra): drag, tilt (no θ, no z_s)
        tab = np.stack([X[..., self.moduli] for X in cols])  # (n_theta, P·nz, N, moduli)
        n_t, _, N, pm = tab.shape
        self.table = np.ascontiguousarray(tab.reshape(n_t, P, nz, N * pm).transpose(1, 0, 2, 3)
                                          .reshape(P, n_t * nz, N * pm))
        self.shape, self.n_direct = (N, pm), 0

    def theta(self, c):
        """alpha [-] or tau [s] at the coordinate ``c``."""
        return np.exp(c) if self.log_theta else c

    def direct(self, c: float, z: float) -> np.ndarray:
        """(N, moduli) columns from :meth:`NodeEvaluator.columns` itself."""
        self.n_direct += 1
        return self.ev.columns(float(self.theta(c)), np.array([z]))[0][:, self.moduli]

    def columns(self, c: np.ndarray, z: np.ndarray) -> np.ndarray:
        c, z = np.atleast_1d(c).astype(float), np.atleast_1d(z).astype(float)
        out = np.empty((c.size, *self.shape))
        ok = ((c >= self.c_box[0]) & (c <= self.c_box[1])
              & (z >= self.z_box[0]) & (z <= self.z_box[1]))
        i = np.flatnonzero(ok)
        panel = np.clip(np.searchsorted(self.breaks, z[i], side="right") - 1, 0,
                        self.z_nodes.shape[0] - 1)
        wt = barycentric_weights(c[i], self.c_nodes, self.c_w)
        wz = barycentric_weights(z[i], self.z_nodes[panel], self.z_w)
        for p in np.unique(panel):
            sel = panel == p
            w = (wt[sel, :, None] * wz[sel, None, :]).reshape(int(sel.sum()), -1)
            # einsum, not BLAS: threaded BLAS runs this small product ~100× slower on
            # shared cores
            out[i[sel]] = np.einsum("wk,kn->wn", w, self.table[p]).reshape(-1, *self.shape)
        for k in np.flatnonzero(~ok):
            out[k] = self.direct(c[k], z[k])
        return out
