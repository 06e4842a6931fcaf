"""What a fit does not know of a material law: its shape parameters (and the base under it).

A model with a hyperelastic law (:class:`~palpbayes.twin.hyper_shape.LawModel`) is linear in
the small-strain modulus at fixed shape parameters, F = E0·Phi(d; shape, nu), so each point of
the shape parameters is a *concrete model* that the exact engine (:mod:`palpbayes.bayes.exact`)
integrates exactly as it does the paper's law, and an unknown shape is a *mixture of concrete
models*, as an unknown layer is (:mod:`palpbayes.bayes.layers`, the template):

    P(component | data) ∝ P(component) · Z(component),

Z the exact engine's evidence under the log-uniform (1/E*) prior (:func:`~palpbayes.bayes.
layers.log_evidence`), which makes Z of two shapes comparable: a shape that differs from
another by a factor only fits equally well.  The prior of each free shape parameter is uniform
on its nodes' range (:attr:`palpbayes.material.ShapeParameter.bounds` unless narrowed).

**The components.**  The finite elements run at the law's nodes only (:data:`LAW_NODES` per free
parameter, uniform on its range, one curve each, cached on disk); between them the twin's table
interpolates ln F linearly (:meth:`palpbayes.twin.HyperTable.force`), so components cost an
exact posterior each, not a finite-element solve:

* one free parameter: the nodes and their midpoints, then every interval within
  :data:`LAW_KEEP` of the best log evidence is halved while it changes by more than
  :data:`LAW_STEP` between neighbours (:func:`~palpbayes.bayes.exact.refine_grid`, as the
  layer's log h), each point a component with the prior mass of its trapezoid cell;
* two free parameters: the same refinement along the first, each of its points integrating the
  second over its nodes and their midpoints (fixed);
* an unknown base (a specimen or a known thickness with ``--bonding unknown``): both bases,
  each with its components, weighted p and 1 − p (``ModelSpec.p_bonded``).

A point whose table holds a node that did not converge has no shape (NaN) and no weight; the
notes name such nodes.  The draws carry each component's E = E*·(1 − nu²) (a foam's nu is its
component's), its shape parameters (``law_<name>``) and its base (``bonded``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from scipy.special import logsumexp

from ..contact import youngs_modulus
from ..errors import InputError, PalpbayesError
from ..fitdata import FitData, ModelSpec
from ..intervals import LEVEL
from .exact import ExactPosterior, cell_widths, exact_posterior, refine_grid
from .layers import log_evidence
from .priors import TracePrior

__all__ = ["LawComponent", "LawPosterior", "law_posterior", "LAW_NODES", "MAX_FREE",
           "LAW_STEP", "LAW_KEEP", "MAX_LAW_POINTS", "LAW_COARSE", "law_nodes"]

#: Finite-element nodes per free shape parameter: with one free parameter, with two.
LAW_NODES = {1: 5, 2: 4}
#: Most free shape parameters a fit mixes over (each more multiplies the curves to solve).
MAX_FREE = 2
#: Refinement of a free parameter between the nodes (the layer's thickness rule).
LAW_STEP, LAW_KEEP = 1.0, 10.0
#: Most points along the first free parameter.
MAX_LAW_POINTS = 65
#: First, uniform surface nodes of a component after the first of its base (the layer's).
LAW_COARSE = 33


def law_nodes(lo: float, hi: float, n_free: int) -> tuple[float, ...]:
    """The finite-element nodes of a free shape parameter on [lo, hi]: :data:`LAW_NODES`
    uniform points (``n_free`` free parameters in all)."""
    if n_free > MAX_FREE:
        raise InputError(f"a fit mixes over at most {MAX_FREE} free shape parameters")
    return tuple(float(v) for v in np.linspace(lo, hi, LAW_NODES[max(n_free, 1)]))


@dataclass
class LawComponent:
    """One concrete model of the mixture.

    Attributes
    ----------
    point
        The free shape parameters' values (by name).
    base
        ``"bonded"`` or ``"free"``.
    nu
        [-] Its Poisson ratio (a foam's own).
    post
        Its exact posterior (None when its shape is undefined: a node that did not converge).
    log_evidence, log_prior
        As :class:`~palpbayes.bayes.layers.LayerComponent`'s.
    """

    point: dict[str, float]
    base: str
    nu: float
    post: ExactPosterior | None
    log_evidence: float
    log_prior: float


@dataclass
class LawPosterior:
    """The mixture over a law's free shape parameters and an unknown base (module docstring).

    Attributes
    ----------
    model
        The (not concrete) contact model.
    components
        Every component with a finite evidence.
    complete
        False if a refinement stopped at its cap.
    failed
        Points whose shape is undefined (a table node did not converge), in words.
    """

    model: ModelSpec
    components: list[LawComponent]
    complete: bool
    failed: tuple[str, ...] = ()

    @property
    def weights(self) -> np.ndarray:
        lw = np.array([c.log_prior + c.log_evidence for c in self.components])
        return np.exp(lw - logsumexp(lw))

    @property
    def n_nodes(self) -> int:
        return int(sum(c.post.n_nodes for c in self.components))

    def log_bayes_factor(self) -> float:
        """ln [p(data | bonded) / p(data | free)], the shape parameters integrated out (NaN
        when the base is known)."""
        out = {}
        for base in ("bonded", "free"):
            parts = [c for c in self.components if c.base == base]
            if not parts:
                return float("nan")
            lp = np.array([c.log_prior for c in parts])
            lz = np.array([c.log_evidence for c in parts])
            out[base] = float(logsumexp(lp + lz) - logsumexp(lp))
        return out["bonded"] - out["free"]

    def concrete(self, c: LawComponent) -> ModelSpec:
        """The concrete model of component ``c``."""
        return self.model.variant(base=c.base if self.model.has_layer else None,
                                  law_point=c.point)

    def best(self) -> ModelSpec:
        """The concrete model at the posterior's centre: the more probable base, and the
        component of that base nearest the weighted median of each free parameter (in units
        of its range): what the model checks and the budget use."""
        w = self.weights
        bases = sorted({c.base for c in self.components})
        mass = {b: sum(wi for wi, c in zip(w, self.components, strict=True) if c.base == b)
                for b in bases}
        base = max(bases, key=lambda b: (mass[b], b == "bonded"))
        mine = [(wi, c) for wi, c in zip(w, self.components, strict=True) if c.base == base]
        grids = dict(self.model.law.nodes)
        target = {n: self._median(n, [c for _, c in mine], np.array([wi for wi, _ in mine]))
                  for n in self.model.law.free}

        def distance(c: LawComponent) -> float:
            return sum(((c.point[n] - target[n]) / (grids[n][-1] - grids[n][0])) ** 2
                       for n in target)
        return self.concrete(min((c for _, c in mine), key=distance))

    @staticmethod
    def _median(name: str, comps: list[LawComponent], w: np.ndarray) -> float:
        x = np.array([c.point[name] for c in comps])
        order = np.argsort(x, kind="stable")
        cdf = np.cumsum(w[order]) / w.sum()
        return float(x[order][int(np.searchsorted(cdf, 0.5))])

    def parameter_summary(self, level: float = LEVEL) -> dict[str, tuple[float, float, float]]:
        """(median, lo, hi) of each free shape parameter's marginal over the components
        (each at its point; the central ``level`` interval)."""
        w = self.weights
        out = {}
        for name in self.model.law.free:
            x = np.array([c.point[name] for c in self.components])
            order = np.argsort(x, kind="stable")
            cdf = np.cumsum(w[order]) / w.sum()
            q = [float(x[order][min(int(np.searchsorted(cdf, p)), x.size - 1)])
                 for p in (0.5, (1 - level) / 2, (1 + level) / 2)]
            out[name] = (q[0], q[1], q[2])
        return out

    def node_weights(self) -> dict[str, list[tuple[float, float]]]:
        """Per free parameter, (node, posterior probability) of each finite-element node: each
        component's weight shared between the two nodes around it in proportion to its
        distance from them (the table's own interpolation)."""
        w = self.weights
        out = {}
        for name, grid in self.model.law.nodes:
            if len(grid) < 2:
                continue
            g = np.asarray(grid)
            p = np.zeros(g.size)
            for wi, c in zip(w, self.components, strict=True):
                x = c.point[name]
                i = int(np.clip(np.searchsorted(g, x) - 1, 0, g.size - 2))
                t = (x - g[i]) / (g[i + 1] - g[i])
                p[i] += wi * (1 - t)
                p[i + 1] += wi * t
            out[name] = [(float(a), float(b)) for a, b in zip(g, p / p.sum(), strict=True)]
        return out

    def draws(self, rng: np.random.Generator, n: int) -> dict[str, np.ndarray]:
        """``n`` posterior draws: each component's exact draws in proportion to its weight,
        with ``E`` [Pa] (E*·(1 − nu²) at its nu), ``nu``, ``law_<name>`` of each free shape
        parameter and, on a layer, ``bonded`` (1.0/0.0); in random order."""
        w = self.weights
        counts = rng.multinomial(n, w / w.sum())
        parts = []
        for c, k in zip(self.components, counts, strict=True):
            if k == 0:
                continue
            d = c.post.draws(rng, int(k))
            d["E"] = youngs_modulus(d["E_star"], c.nu)
            d["nu"] = np.full(int(k), c.nu)
            for name, v in c.point.items():
                d[f"law_{name}"] = np.full(int(k), v)
            if self.model.has_layer:
                d["bonded"] = np.full(int(k), 1.0 if c.base == "bonded" else 0.0)
            parts.append(d)
        out = {key: np.concatenate([p[key] for p in parts]) for key in parts[0]}
        order = rng.permutation(n)
        return {key: v[order] for key, v in out.items()}


def _fit(data: FitData, prior: TracePrior, model: ModelSpec, near: ExactPosterior | None
         ) -> ExactPosterior | None:
    """The exact posterior of a concrete law model (None when its shape is undefined)."""
    s = model.shape(np.array([model.law.depth]))
    if not np.all(np.isfinite(s)):
        return None
    try:
        return exact_posterior(replace(data, model=model), prior,
                               *((LAW_COARSE, near.z) if near is not None else ()))
    except PalpbayesError:
        return None


class _Axis:
    """The components of one base along the free parameters (module docstring)."""

    def __init__(self, data: FitData, prior: TracePrior, base: str):
        self.data, self.prior, self.base = data, prior, base
        self.model = data.model
        self.law = self.model.law
        self.posts: dict[tuple[float, ...], ExactPosterior | None] = {}

    def component(self, point: dict[str, float]) -> tuple[ExactPosterior | None, float]:
        key = tuple(point[n] for n in self.law.free)
        if key not in self.posts:
            near = None
            done = [k for k, p in self.posts.items() if p is not None]
            if done:
                near = self.posts[min(done, key=lambda k: sum((a - b) ** 2 for a, b
                                                              in zip(k, key, strict=True)))]
            model = self.model.variant(base=self.base if self.model.has_layer else None,
                                       law_point=point)
            self.posts[key] = _fit(self.data, self.prior, model, near)
        post = self.posts[key]
        return post, (-math.inf if post is None else log_evidence(post))


def _inner_points(grid: tuple[float, ...]) -> np.ndarray:
    """A free parameter's nodes and their midpoints."""
    return np.linspace(grid[0], grid[-1], 2 * (len(grid) - 1) + 1)


def law_posterior(data: FitData, prior: TracePrior) -> LawPosterior:
    """The exact mixture posterior of a trace fitted with a law whose shape parameters (or
    base) are unknown (module docstring).

    Raises
    ------
    InputError
        No law, more than :data:`MAX_FREE` free parameters, or no component with a finite
        evidence (every table node failed, or no contact).
    """
    model = data.model
    law = model.law
    if law is None:
        raise InputError(f"the model {model.describe()} has no material law")
    free = law.free
    if len(free) > MAX_FREE:
        raise InputError(f"the {law.law.title} law has {len(free)} free shape parameters "
                         f"({', '.join(free)}); a fit mixes over at most {MAX_FREE}: fix the "
                         "others with --law-shape NAME=VALUE")
    bases = model.bases if model.has_layer else ("bonded",)
    log_p = ({"bonded": math.log(model.p_bonded), "free": math.log1p(-model.p_bonded)}
             if len(bases) == 2 else {bases[0]: 0.0})
    grids = dict(law.nodes)
    comps: list[LawComponent] = []
    complete = True
    failed: list[str] = []
    for base in bases:
        axis = _Axis(data, prior, base)
        if not free:
            post, lz = axis.component({})
            comps.append(LawComponent({}, base, _nu(model, {}), post, lz, log_p[base]))
            continue
        outer = free[0]
        inner = free[1] if len(free) == 2 else None
        inner_x = _inner_points(grids[inner]) if inner else np.zeros(1)
        inner_cells = (np.log(cell_widths(inner_x) / (inner_x[-1] - inner_x[0]))
                       if inner else np.zeros(1))
        rows: dict[float, list[float]] = {}

        def evaluate(xs: np.ndarray, axis=axis, outer=outer, inner=inner, inner_x=inner_x,
                     inner_cells=inner_cells, rows=rows) -> np.ndarray:
            out = np.empty(xs.size)
            for i, x in enumerate(xs):
                lz = [axis.component({outer: float(x), **({inner: float(y)} if inner else {})}
                                     )[1] for y in inner_x]
                rows[float(x)] = lz
                out[i] = logsumexp(np.asarray(lz) + inner_cells)
            return out

        lo, hi = grids[outer][0], grids[outer][-1]
        xs, _, done = refine_grid(lo, hi, evaluate, coarse=2 * (len(grids[outer]) - 1) + 1,
                                  max_nodes=MAX_LAW_POINTS, max_step=LAW_STEP, keep=LAW_KEEP)
        complete &= done
        cells = np.log(cell_widths(xs) / (hi - lo))
        for x, cell in zip(xs, cells, strict=True):
            for y, icell in zip(inner_x, inner_cells, strict=True):
                point = {outer: float(x), **({inner: float(y)} if inner else {})}
                post, lz = axis.component(point)
                if post is None:
                    failed.append(", ".join(f"{n} {v:g}" for n, v in point.items()))
                    continue
                comps.append(LawComponent(point, base, _nu(model, point), post, lz,
                                          log_p[base] + cell + icell))
    comps = [c for c in comps if c.post is not None and math.isfinite(c.log_evidence)]
    if not comps:
        raise InputError(f"exact engine: no shape of the {law.law.title} law has a finite "
                         "evidence: its twin did not converge at these depths, or the trace "
                         "has (almost) no contact")
    complete &= all(c.post.complete for c in comps)
    return LawPosterior(model, comps, complete, tuple(dict.fromkeys(failed)))


def _nu(model: ModelSpec, point: dict[str, float]) -> float:
    """[-] The Poisson ratio of the component at ``point`` (a foam's own)."""
    return model.variant(base=model.bases[0] if model.has_layer else None,
                         law_point=point).nu if model.law.free else model.nu
