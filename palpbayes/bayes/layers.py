"""What a fit does not know of the specimen's layer: its base condition and its thickness.

A specimen of known thickness is a layer on a rigid base (:mod:`palpbayes.contact.layer`), but
a block lying on a plate is neither bonded to it nor free to slip, and a cell or a coating has a
thickness nobody measured.  The contact model of such a specimen
(:class:`~palpbayes.fitdata.ModelSpec` with ``bonding="unknown"`` or a ``thickness_range``) is
a *mixture of concrete models*, one per base condition and thickness:

* **base**: two components, bonded and free, with prior weights p and 1 − p
  (``ModelSpec.p_bonded``, 0.5 by default);
* **thickness**: either no layer at all (a half-space, prior probability
  :data:`P_HALFSPACE` = 0.5) or a layer with log h uniform on the stated range, integrated on an
  adaptive grid of log h (the exact engine's rule, :func:`palpbayes.bayes.exact.refine_grid`:
  nodes are added where the log evidence changes by more than 0.5 between neighbours), each
  node a component with the prior mass of its trapezoid cell.  The half-space is a component
  of its own because a log-uniform prior that stops at a finite h would leave a small layer
  effect in every fit (0.3 % in E for a paraboloid on a half-space with the default range),
  far outside a statistical interval of 0.1 %.

Given a component, the exact engine (:mod:`palpbayes.bayes.exact`) integrates everything else
(surface, offset, noise, AR(1) coefficient) and its evidence Z weights it:

    P(component | data) ∝ P(component) · Z(component),
    Z = Σ_nodes exp(log p(z_s, phi | data) + prior factor of E*) · cell widths.

The log-uniform prior of E* is what makes Z comparable between components: a bonded and a free
base give shape functions that differ mostly by a factor c, and under a flat E* prior the
evidence of c·s would be 1/c times that of s whatever the data; with the 1/E* prior the factor
cancels, and what is left is how well each *shape* fits.  A flat punch's factor does not depend
on depth, so its data cannot tell the bases apart (P(bonded) stays at its prior); a curved tip's
can, in part.  The posterior is the mixture of the components' posteriors; its draws carry the
base (``bonded``: 1 or 0) and the thickness (``thickness`` [m], log-uniform within the node's
cell).

The emcee engine samples the same mixture (base as a coordinate ``bond`` in [0, 1], bonded when
>= 0.5, with a swap move; ``log_h``): :mod:`palpbayes.bayes.layer_likelihood`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from scipy.special import logsumexp

from ..errors import InputError
from ..fitdata import FitData, ModelSpec
from ..intervals import LEVEL
from .exact import COARSE_NODES, ExactPosterior, cell_widths, exact_posterior, refine_grid
from .mixture import MixtureSummary
from .priors import P_HALFSPACE, TracePrior

__all__ = ["LayerComponent", "LayerPosterior", "layer_posterior", "log_evidence",
           "default_thickness_range", "THICKNESS_NODES", "MAX_THICKNESS_NODES",
           "THICKNESS_RANGE", "P_HALFSPACE", "HALFSPACE", "COARSE_THICKNESS_NODES",
           "COARSE_THICKNESS_STEP", "COARSE_THICKNESS_COARSE"]

#: First, uniform nodes of log h per base (an unknown thickness).
THICKNESS_NODES = 13
#: Most log-h nodes per base (refinement stops there and says so).
MAX_THICKNESS_NODES = 120
#: Refinement of log h: intervals within THICKNESS_KEEP of the best log evidence are halved
#: until it changes by at most THICKNESS_STEP between nodes (coarser than the surface's
#: 0.5 / 14: E hardly changes across such a step of h, and each node costs a whole fit).
THICKNESS_STEP, THICKNESS_KEEP = 1.0, 10.0
#: First, uniform surface nodes of each thickness node's posterior (the half-space component
#: and a known thickness take the exact engine's :data:`~palpbayes.bayes.exact.COARSE_NODES`,
#: which find the surface's basins; the layers' posteriors refine from a quarter of them).
THICKNESS_COARSE = 33
#: The coarser rule of ``ModelSpec(thickness_grid="coarse")``, the model form's layer
#: alternative (:func:`palpbayes.bayes.modelform.layer_alternative`): first nodes, the largest
#: change of log evidence between neighbours, and first surface nodes.  Its interval counts
#: only in the envelope of the model form, and only when the alternative is plausible (1 of
#: the 22 real AFM curves): on those curves 40 instead of 68 components (median) and every
#: full interval within 0.15 % of the fine rule's (docs/reference.md, "Speed").
COARSE_THICKNESS_NODES, COARSE_THICKNESS_STEP, COARSE_THICKNESS_COARSE = 7, 2.0, 17
#: Default prior range of an unknown thickness, in multiples of the indentation depth:
#: from a layer 1.5 times deeper than the tip goes (a thinner one would be pierced) to one
#: 1,000 times deeper (a half-space for any tip).
THICKNESS_RANGE = (1.5, 1000.0)
#: ``LayerComponent.base`` of the half-space component (its thickness is infinite).
HALFSPACE = "none"


def default_thickness_range(depth: float) -> tuple[float, float]:
    """[m] The default log-uniform range of an unknown thickness for an indentation of
    ``depth`` [m] (:data:`THICKNESS_RANGE` times it)."""
    if not (math.isfinite(depth) and depth > 0):
        raise InputError(f"indentation depth {depth!r} m must be positive to set the "
                         "thickness range; give it with --thickness-range LO HI")
    return THICKNESS_RANGE[0] * depth, THICKNESS_RANGE[1] * depth


def log_evidence(post: ExactPosterior) -> float:
    """log Z of one concrete model [-]: the exact engine's node densities with the E* prior's
    factor (:meth:`ExactPosterior.prior_factor`), summed over the (surface × phi) cells.

    Constants common to every model of the same trace and prior are left out, so only
    differences between components of one trace mean something.
    """
    lm = (post.post.logp + post.prior_factor() + np.log(cell_widths(post.z))[:, None]
          + np.log(cell_widths(post.phi))[None, :])
    lm = np.where(np.isfinite(lm), lm, -np.inf)
    return float(logsumexp(lm)) if np.isfinite(lm).any() else -np.inf


@dataclass
class LayerComponent:
    """One concrete model of the mixture.

    Attributes
    ----------
    base
        ``"bonded"``, ``"free"``, or :data:`HALFSPACE` for no layer.
    thickness
        [m] The layer thickness of this component (``inf`` for the half-space).
    log_h_cell
        (lo, hi) of ln h over which the component stands (equal ends for a known thickness and
        the half-space).
    post
        The exact posterior of the concrete model.
    log_evidence
        :func:`log_evidence` of ``post``.
    log_prior
        Log prior mass of the component (base weight times the thickness cell's share).
    """

    base: str
    thickness: float
    log_h_cell: tuple[float, float]
    post: ExactPosterior
    log_evidence: float
    log_prior: float


@dataclass
class LayerPosterior:
    """The mixture over a layer's unknown base and thickness (module docstring).

    Attributes
    ----------
    model
        The (not concrete) contact model.
    components
        Every component, any order.
    complete
        False if a surface or thickness refinement stopped at its node cap.
    """

    model: ModelSpec
    components: list[LayerComponent]
    complete: bool

    @property
    def log_weights(self) -> np.ndarray:
        """Normalised log posterior weight of each component."""
        lw = np.array([c.log_prior + c.log_evidence for c in self.components])
        return lw - logsumexp(lw)

    @property
    def weights(self) -> np.ndarray:
        return np.exp(self.log_weights)

    @property
    def n_nodes(self) -> int:
        return int(sum(c.post.n_nodes for c in self.components))

    def p_bonded(self) -> float:
        """Posterior probability of the bonded base given a layer [-] (NaN when the posterior
        has no layer component with weight)."""
        w = self.weights
        layer = sum(wi for wi, c in zip(w, self.components, strict=True) if c.base != HALFSPACE)
        bonded = sum(wi for wi, c in zip(w, self.components, strict=True) if c.base == "bonded")
        return float(bonded / layer) if layer > 0 else float("nan")

    def p_halfspace(self) -> float:
        """Posterior probability of no layer [-] (0 when the thickness is known)."""
        w = self.weights
        return float(sum(wi for wi, c in zip(w, self.components, strict=True)
                         if c.base == HALFSPACE))

    def log_bayes_factor(self) -> float:
        """ln [p(data | bonded) / p(data | free)]: what the data say about the base, without
        the prior weights (NaN when the base is known)."""
        out = {}
        for base in ("bonded", "free"):  # the half-space component is neither
            parts = [c for c in self.components if c.base == base]
            if not parts:
                return float("nan")
            lp = np.array([c.log_prior for c in parts])
            lz = np.array([c.log_evidence for c in parts])
            out[base] = float(logsumexp(lp + lz) - logsumexp(lp))
        return out["bonded"] - out["free"]

    def thickness_summary(self, level: float = LEVEL) -> MixtureSummary:
        """Marginal of h [m]: median and equal-tailed interval from the component weights,
        log-uniform within each cell; the half-space's mass lies at h = inf (a quantile in it
        is ``inf``; ``mean`` and ``sd`` are those of the layer components)."""
        w = self.weights
        comps = [c for c in self.components if c.base != HALFSPACE]
        p_inf = 1.0 - float(sum(wi for wi, c in zip(w, self.components, strict=True)
                                if c.base != HALFSPACE))
        if not comps or p_inf >= 1.0:
            inf = float("inf")
            return MixtureSummary(inf, float("nan"), inf, inf, inf, level)
        wl = np.array([wi for wi, c in zip(w, self.components, strict=True)
                       if c.base != HALFSPACE])
        order = np.argsort([c.log_h_cell[0] for c in comps])
        lo = np.array([comps[i].log_h_cell[0] for i in order])
        hi = np.array([comps[i].log_h_cell[1] for i in order])
        ww = wl[order]
        # merge the bases: piecewise-uniform density in ln h
        edges = np.unique(np.concatenate([lo, hi]))
        if edges.size < 2:
            h = float(np.exp(edges[0]))
            return MixtureSummary(h, 0.0, h, h, h, level)
        mass = np.zeros(edges.size - 1)
        for a, b, wi in zip(lo, hi, ww, strict=True):
            inside = (edges[:-1] >= a) & (edges[1:] <= b)
            width = np.diff(edges)[inside]
            mass[inside] += wi * width / max(b - a, 1e-300)
        cdf = np.concatenate([[0.0], np.cumsum(mass)])
        total = cdf[-1]
        cdf = cdf / total * (1.0 - p_inf)  # the half-space's mass sits beyond the last edge
        probs = np.array([(1 - level) / 2, 0.5, (1 + level) / 2])
        q = np.where(probs <= cdf[-1], np.interp(probs, cdf, edges), np.inf)
        mids = 0.5 * (edges[1:] + edges[:-1])
        mean = float(np.sum(mass * np.exp(mids)) / total)
        sd = float(np.sqrt(max(np.sum(mass * (np.exp(mids) - mean) ** 2) / total, 0.0)))
        h = np.exp(q)
        return MixtureSummary(mean, sd, float(h[1]), float(h[0]), float(h[2]), level)

    def best(self) -> ModelSpec:
        """The concrete model at the posterior's centre: the more probable base and the median
        thickness (the known one when known): what the model checks and the budget use."""
        if self.p_halfspace() > 0.5:
            return self.model.half_space()
        pb = self.p_bonded()
        base = "bonded" if not pb < 0.5 else "free"
        if self.model.bonding != "unknown":
            base = self.model.bonding
        h = self.model.thickness
        if h is None:  # the median thickness among the layer components
            w = np.array([wi if c.base != HALFSPACE else 0.0
                          for wi, c in zip(self.weights, self.components, strict=True)])
            order = np.argsort([c.thickness for c in self.components])
            cdf = np.cumsum(w[order]) / w.sum()
            h = self.components[order[int(np.searchsorted(cdf, 0.5))]].thickness
        return self.model.variant(thickness=h, base=base)

    def draws(self, rng: np.random.Generator, n: int) -> dict[str, np.ndarray]:
        """``n`` posterior draws: each component's exact draws in proportion to its weight,
        plus ``bonded`` (1.0/0.0) and ``thickness`` [m]; in random order."""
        w = self.weights
        counts = rng.multinomial(n, w / w.sum())
        parts: list[dict[str, np.ndarray]] = []
        for c, k in zip(self.components, counts, strict=True):
            if k == 0:
                continue
            d = c.post.draws(rng, int(k))
            a, b = c.log_h_cell
            d["thickness"] = np.exp(a + (b - a) * rng.random(int(k)))
            d["bonded"] = np.full(int(k), {"bonded": 1.0, "free": 0.0}.get(c.base, np.nan))
            parts.append(d)
        keys = parts[0].keys()
        out = {key: np.concatenate([p[key] for p in parts]) for key in keys}
        order = rng.permutation(n)
        return {key: v[order] for key, v in out.items()}


def _component(data: FitData, prior: TracePrior, model: ModelSpec,
               coarse: int = COARSE_NODES, nodes: np.ndarray | None = None) -> ExactPosterior:
    return exact_posterior(replace(data, model=model), prior, coarse, nodes)


def layer_posterior(data: FitData, prior: TracePrior) -> LayerPosterior:
    """The exact mixture posterior of a trace whose layer is partly unknown (module docstring).

    Raises
    ------
    InputError
        For a concrete model (use :func:`palpbayes.bayes.exact.exact_posterior`), and as
        :func:`palpbayes.bayes.exact.exact_posterior`.
    """
    model = data.model
    if model.is_concrete:
        raise InputError(f"the model {model.describe()} is concrete: fit it with "
                         "exact_posterior")
    log_p = {"bonded": math.log(model.p_bonded), "free": math.log1p(-model.p_bonded)}
    if len(model.bases) == 1:
        log_p = {model.bases[0]: 0.0}
    comps: list[LayerComponent] = []
    complete = True
    if model.thickness_unknown:  # no layer at all: the half-space component
        post = _component(data, prior, model.half_space())
        comps.append(LayerComponent(HALFSPACE, math.inf, (math.inf, math.inf), post,
                                    log_evidence(post), math.log(P_HALFSPACE)))
        log_p = {b: v + math.log1p(-P_HALFSPACE) for b, v in log_p.items()}
    first_nodes, step, surface_nodes = (
        (COARSE_THICKNESS_NODES, COARSE_THICKNESS_STEP, COARSE_THICKNESS_COARSE)
        if model.thickness_grid == "coarse"
        else (THICKNESS_NODES, THICKNESS_STEP, THICKNESS_COARSE))
    for base in model.bases:
        if model.thickness is not None:
            post = _component(data, prior, model.variant(base=base))
            lh = math.log(model.thickness)
            comps.append(LayerComponent(base, model.thickness, (lh, lh), post,
                                        log_evidence(post), log_p[base]))
            complete &= post.complete
            continue
        posts: dict[float, ExactPosterior] = {}

        def evaluate(nodes: np.ndarray, base=base, posts=posts) -> np.ndarray:
            out = np.empty(nodes.size)
            for i, lh in enumerate(nodes):
                # the surface nodes of the nearest thickness fitted so far, if any: the
                # posterior changes little from one thickness node to the next
                near = min(posts, key=lambda h: abs(h - lh)) if posts else None
                p = _component(data, prior, model.variant(thickness=math.exp(lh), base=base),
                               surface_nodes, None if near is None else posts[near].z)
                posts[float(lh)] = p
                out[i] = log_evidence(p)
            return out

        lo, hi = (math.log(v) for v in model.thickness_range)
        nodes, logz, done = refine_grid(lo, hi, evaluate, coarse=first_nodes,
                                        max_nodes=MAX_THICKNESS_NODES,
                                        max_step=step, keep=THICKNESS_KEEP)
        complete &= done
        cells = cell_widths(nodes)
        left = np.r_[0.0, np.diff(nodes)] / 2
        right = np.r_[np.diff(nodes), 0.0] / 2
        for lh, lz, cw, a, b in zip(nodes, logz, cells, left, right, strict=True):
            post = posts[float(lh)]
            complete &= post.complete
            comps.append(LayerComponent(base, math.exp(lh), (lh - a, lh + b), post, float(lz),
                                        log_p[base] + math.log(cw / (hi - lo))))
    if not any(np.isfinite(c.log_evidence) for c in comps):
        raise InputError("exact engine: no component of the layer model has a finite "
                         "evidence; the trace has (almost) no contact")
    return LayerPosterior(model=model, components=comps, complete=complete)
