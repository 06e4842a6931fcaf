"""The exact engine's posterior over the surface height, updated as samples arrive.

Updates are incremental: each surface node keeps the running cross-product sums of
:class:`palpbayes.bayes.conjugate.Gram`, so a chunk of k samples costs (nodes × k) shape
evaluations, plus n per node the refinement adds (:func:`palpbayes.bayes.exact.refine_grid`:
the posterior narrows as the tip goes deeper).  Nodes more than :data:`PRUNE` below the best
log density stop being updated; the first coarse nodes always stay, so that refinement can
reach any part of the surface prior.  The estimator that feeds the nodes (and chooses the
prior) is :class:`palpbayes.online.estimator.OnlineEstimator`.
"""

from __future__ import annotations

import copy

import numpy as np

from ..bayes.conjugate import Gram, NodePosterior, fixed_columns, node_posterior
from ..bayes.exact import (
    COARSE_NODES,
    ExactPosterior,
    log_marginal_phi,
    node_log_mass,
    refine_grid,
)
from ..bayes.priors import TracePrior
from ..fitdata import ModelSpec

__all__ = ["PRUNE", "SurfaceNodes"]

#: Nodes whose log density falls this far below the best are no longer updated.
PRUNE = 28.0


class SurfaceNodes:
    """The node posteriors on the surface prior [``z_lo``, ``z_top``] (module docstring).

    Parameters
    ----------
    model
        Contact model.
    noise
        ``"gaussian"`` or ``"ar1"``.
    phi
        The noise correlation's grid (one 0 for Gaussian noise).
    weights
        The node posterior's prior weights (:func:`palpbayes.bayes.conjugate.node_posterior`).
    level
        [N] The baseline's force level, taken off every force.
    z_lo, z_top
        [m] The surface prior's ends: the first nodes are
        :data:`~palpbayes.bayes.exact.COARSE_NODES` between them.
    z, f
        The samples kept so far: tip heights [m] and forces [N].
    """

    def __init__(self, model: ModelSpec, noise: str, phi: np.ndarray, weights: np.ndarray,
                 level: float, z_lo: float, z_top: float, z: np.ndarray, f: np.ndarray
                 ) -> None:
        self.model, self.ar1, self.phi, self.weights = model, noise == "ar1", phi, weights
        self.level, self.z_lo, self.z_top = level, z_lo, z_top
        nodes = np.linspace(z_lo, z_top, COARSE_NODES)
        self.skeleton = nodes
        self.gram = self._new(nodes, z, f)
        self.active = np.arange(nodes.size)
        # the last node posteriors and whether their refinement was complete (refresh)
        self.post: NodePosterior | None = None
        self.complete = False

    def _new(self, nodes: np.ndarray, z: np.ndarray, f: np.ndarray) -> Gram:
        return Gram.empty(nodes, 2, self.ar1).extend(z, fixed_columns(f - self.level, None),
                                                     self.model)

    def _gram_active(self) -> Gram:
        if self.active.size != self.gram.z.size:
            self.gram = self.gram.subset(self.active)
            self.active = np.arange(self.gram.z.size)
        return self.gram

    def extend(self, z: np.ndarray, y: np.ndarray) -> None:
        """Add samples to the sums of the nodes updated: tip heights [m], forces above the
        baseline [N]."""
        self._gram_active().extend(z, fixed_columns(y, None), self.model)

    def _node_posterior(self, g: Gram) -> NodePosterior:
        return node_posterior(g, self.phi, self.weights, np.zeros(1))

    def _logp_nodes(self, g: Gram) -> np.ndarray:
        return log_marginal_phi(self._node_posterior(g).logp, self.phi)

    def refresh(self, z: np.ndarray, f: np.ndarray, frozen: bool) -> None:
        """The node posteriors after new samples: refine the grid where needed (a new node
        takes the samples kept, ``z`` [m] and ``f`` [N]; none is added when ``frozen``: some
        samples were not kept), then prune (:data:`PRUNE`)."""
        added: list[Gram] = []

        def evaluate(nodes: np.ndarray) -> np.ndarray:
            g = self._new(nodes, z, f)
            added.append(g)
            return self._logp_nodes(g)

        g = self._gram_active()
        post = self._node_posterior(g)
        lp = log_marginal_phi(post.logp, self.phi)
        # a node added now would miss the samples not kept: none is added once there are some
        cut = {"max_nodes": g.z.size} if frozen else {}
        _, _, self.complete = refine_grid(self.z_lo, self.z_top, evaluate, start=(g.z, lp),
                                          **cut)
        for other in added:
            g = g.concat(other)
        self.gram = g
        if added:
            post = self._node_posterior(g)
        self.post = post
        lp = log_marginal_phi(post.logp, self.phi)
        best = np.max(lp)
        # the first coarse nodes always stay, so refinement can reach any part of the range
        keep = np.isin(g.z, self.skeleton)
        if np.isfinite(best):
            keep |= lp > best - PRUNE
        self.active = np.flatnonzero(keep)

    def posterior(self, prior: TracePrior) -> ExactPosterior:
        """The current posterior as an :class:`ExactPosterior` with ``prior`` (the offset
        back in the baseline's level)."""
        g = self.gram
        post = copy.copy(self.post)
        post.beta = post.beta.copy()
        post.beta[..., 1] += self.level
        return ExactPosterior(z=g.z, phi=self.phi, post=post,
                              log_mass=node_log_mass(post.logp, g.z, self.phi),
                              complete=self.complete, prior=prior)
