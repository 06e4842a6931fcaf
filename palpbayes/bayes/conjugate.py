"""Closed-form posterior of the linear parameters and the noise at fixed surface heights.

For a trial surface z_s (and AR(1) coefficient phi) the model F = E*·s(z_s − z) + F0
[+ F1·u] + e is a linear regression; this module holds its sufficient statistics
(:class:`Gram`, :func:`gram`: lag-0 and lag-1 cross-products of the columns, which can be
summed incrementally as samples arrive) and the conjugate posterior they give
(:func:`node_posterior`).  The formulas are in :mod:`palpbayes.bayes.exact`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..modelspec import ModelSpec
from ..shapekernel import cross_sums

__all__ = ["Gram", "gram", "fixed_columns", "NodePosterior", "node_posterior"]


@dataclass
class Gram:
    """Cross-product sums of the columns [s(z_s − z), 1, (u), y] at each surface node.

    ``m0[g]`` = Σ_t x_t x_tᵀ, ``m1[g]`` = Σ_{t>=2} x_t x_{t−1}ᵀ, ``first``/``last`` the first
    and last rows, ``n_contact`` the samples with s > 0; q = p + 1 columns, y last.
    """

    z: np.ndarray
    m0: np.ndarray
    m1: np.ndarray | None
    first: np.ndarray
    last: np.ndarray
    n_contact: np.ndarray
    n: int

    @classmethod
    def empty(cls, nodes: np.ndarray, n_fixed: int, ar1: bool) -> Gram:
        """Sums over no sample yet, for ``n_fixed`` columns besides s (1, (u), y)."""
        G, q = np.asarray(nodes).size, n_fixed + 1
        return cls(np.asarray(nodes, dtype=float).copy(), np.zeros((G, q, q)),
                   np.zeros((G, q, q)) if ar1 else None, np.zeros((G, q)), np.zeros((G, q)),
                   np.zeros(G, dtype=int), 0)

    def extend(self, z: np.ndarray, C: np.ndarray, model: ModelSpec,
               d_max: float | None = None) -> Gram:
        """Add samples (heights ``z`` [m] and fixed columns ``C`` (k, q − 1), in time order,
        following those already summed) to every node's sums, in place; returns self.

        ``model`` is the concrete contact model whose shape s(z_s − z) is the first column;
        ``d_max`` [m] as in
        :func:`~palpbayes.shapekernel.cross_sums`.  The (nodes × k) shape
        evaluations are summed by the compiled loop of :func:`palpbayes.shapekernel.cross_sums`
        without forming that array — an online update does not revisit old samples.
        """
        k = z.size
        if k == 0:
            return self
        lag = self.m1 is not None
        ss, sc, l00, l0c, lc0, s_first, s_last, n_contact = cross_sums(self.z, z, C, model, lag,
                                                                        d_max)
        self.m0[:, 1:, 1:] += C.T @ C
        self.m0[:, 0, 0] += ss
        self.m0[:, 0, 1:] += sc
        self.m0[:, 1:, 0] += sc
        if lag:
            self.m1[:, 1:, 1:] += C[1:].T @ C[:-1]
            self.m1[:, 0, 0] += l00
            self.m1[:, 0, 1:] += l0c
            self.m1[:, 1:, 0] += lc0
            if self.n:  # the pair (first new sample, last old one)
                self.m1[:, 1:, 1:] += np.outer(C[0], self.last[0, 1:])
                self.m1[:, 0, 0] += s_first * self.last[:, 0]
                self.m1[:, 0, 1:] += s_first[:, None] * self.last[:, 1:]
                self.m1[:, 1:, 0] += C[0][None, :] * self.last[:, :1]
        if self.n == 0:
            self.first[:, 0] = s_first
            self.first[:, 1:] = C[0]
        self.last[:, 0] = s_last
        self.last[:, 1:] = C[-1]
        self.n_contact += n_contact
        self.n += k
        return self

    def concat(self, other: Gram) -> Gram:
        """Both node sets (over the same samples), sorted by height."""
        cat = lambda a, b: None if a is None else np.concatenate([a, b])  # noqa: E731
        z = np.concatenate([self.z, other.z])
        order = np.argsort(z, kind="stable")
        keep = order[np.r_[True, np.diff(z[order]) > 0]]
        parts = [cat(getattr(self, f), getattr(other, f))
                 for f in ("m0", "m1", "first", "last", "n_contact")]
        return Gram(z[keep], *[None if a is None else a[keep] for a in parts], n=self.n)

    def subset(self, keep: np.ndarray) -> Gram:
        """The nodes selected by ``keep`` (mask or indices)."""
        return Gram(self.z[keep], self.m0[keep], None if self.m1 is None else self.m1[keep],
                    self.first[keep], self.last[keep], self.n_contact[keep], self.n)


def fixed_columns(y: np.ndarray, u: np.ndarray | None) -> np.ndarray:
    """The columns besides s: [1, (u), y], shape (n, q − 1)."""
    return np.column_stack([np.ones(y.size)] + ([u] if u is not None else []) + [y])


def gram(data_z: np.ndarray, y: np.ndarray, nodes: np.ndarray, model: ModelSpec,
         u: np.ndarray | None, ar1: bool, d_max: float | None = None) -> Gram:
    """Sums of :class:`Gram` at ``nodes`` [m] for samples (``data_z`` [m], ``y`` [N], in time
    order), the concrete contact ``model`` (its shape F/E* [m²] of the depth) and baseline
    column ``u``; ``d_max`` [m] as in :func:`~palpbayes.shapekernel.cross_sums`."""
    C = fixed_columns(y, u)
    return Gram.empty(nodes, C.shape[1], ar1).extend(np.asarray(data_z, dtype=float), C, model,
                                                     d_max)


def _whitened(g: Gram, phi: np.ndarray) -> np.ndarray:
    """Cross-products of the prewhitened columns, shape (G, H, q, q) for H values of phi."""
    if g.m1 is None:
        return g.m0[:, None]
    ph = np.asarray(phi)[None, :, None, None]
    ends = (np.einsum("gi,gj->gij", g.first, g.first)
            + np.einsum("gi,gj->gij", g.last, g.last))[:, None]
    sym = (g.m1 + np.swapaxes(g.m1, 1, 2))[:, None]
    return g.m0[:, None] * (1 + ph**2) - ph * sym - ph**2 * ends


@dataclass
class NodePosterior:
    """Conditional posterior at every (surface node, phi node): see the module docstring.

    ``logp`` (G, H) unnormalised log p(z_s, phi | data) (−inf where fewer than p + 1 samples
    are in contact); ``beta`` (G, H, p) centres; ``scale`` (G, H, p, p) = (S/nu)·A⁻¹;
    ``S`` (G, H); ``nu`` degrees of freedom.
    """

    logp: np.ndarray
    beta: np.ndarray
    scale: np.ndarray
    S: np.ndarray
    nu: int


def node_posterior(g: Gram, phi: np.ndarray, weights: np.ndarray,
                   centers: np.ndarray) -> NodePosterior:
    """Closed-form conditional posterior at each node (module docstring).

    ``weights``/``centers`` are the pseudo-observations of β[1:] (offset, slope) in units of
    the marginal noise variance; they are multiplied by (1 − phi²) for the innovations.
    """
    phi = np.atleast_1d(np.asarray(phi, dtype=float))
    M = _whitened(g, phi)  # (G, H, q, q)
    p = M.shape[-1] - 1
    k = weights.size
    one_m = 1.0 - phi**2
    w = weights[None, :] * one_m[:, None]  # (H, k)
    A = M[..., :p, :p].copy()
    bvec = M[..., :p, p].copy()
    idx = 1 + np.arange(k)
    A[..., idx, idx] += w[None]
    bvec[..., idx] += (w * centers)[None]
    yy = M[..., p, p] + (w * centers**2).sum(-1)[None]
    # equilibrate: the columns differ by many decades (m² against 1)
    d = 1.0 / np.sqrt(np.where(np.diagonal(A, axis1=-2, axis2=-1) > 0,
                               np.diagonal(A, axis1=-2, axis2=-1), 1.0))
    Ae = A * d[..., :, None] * d[..., None, :]
    ok = g.n_contact[:, None] > p
    Ae = np.where(ok[..., None, None], Ae, np.eye(p))
    L = np.linalg.cholesky(Ae)
    logdet = 2 * np.log(np.diagonal(L, axis1=-2, axis2=-1)).sum(-1) - 2 * np.log(d).sum(-1)
    inv_e = np.linalg.inv(Ae)
    Ainv = inv_e * d[..., :, None] * d[..., None, :]
    beta = np.einsum("...ij,...j->...i", Ainv, bvec)
    S = yy - np.einsum("...i,...i->...", bvec, beta)
    nu = g.n + k - p
    S_ok = ok & (S > 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        logp = (-0.5 * logdet - 0.5 * nu * np.log(np.where(S_ok, S, 1.0))
                + 0.5 * np.log(w).sum(-1)[None] + 0.5 * np.log(one_m)[None])
    logp = np.where(S_ok, logp, -np.inf)
    scale = (np.where(S_ok, S, np.nan) / nu)[..., None, None] * Ainv
    return NodePosterior(logp, beta, scale, S, nu)
