"""The emcee side of a layer whose base or thickness is unknown (:mod:`palpbayes.bayes.layers`).

The sampled vector is the usual one (:mod:`palpbayes.bayes.priors`) followed by ``bond`` (the
base: bonded when >= 0.5) and/or ``log_h`` (ln h; beyond ln h_hi the half-space).  Each walker
then has its own shape function:

* thickness known, base unknown: two tabulated :class:`~palpbayes.bayes.likelihood.
  TraceLikelihood` objects, one per base, each walker evaluated by the one of its base;
* thickness unknown: every walker's shape row E*-free, s(z_s − z; h, base), evaluated directly
  (O(n) per walker, no table) and turned into the same quadratic forms.

**The aligned coordinate.** The two bases explain the same curve with E* values a factor r
apart (r = E*_free/E*_bonded of the same curve: 1.08–1.3 for the paper's geometry), while the
posterior of E* is ~0.03 % wide: two modes that emcee's differential-evolution moves cannot
bridge (half the walker pairs would propose jumps across the gap). So the first coordinate is
not ln E* but ln E* − [free]·ln r: both bases' modes then lie on top of each other, and the
walkers move between them as freely as within one. r is the least-squares ratio of the same
curve at a reference surface (:func:`palpbayes.refit.refit_factor`) on the known thickness; the
map has unit Jacobian, so the log-uniform prior of E* is unchanged (it is evaluated on the real
ln E*, :func:`palpbayes.bayes.priors.log_posterior`). ``E_star`` in the posterior is the real
E*. With the thickness unknown the same holds along h: a thinner layer explains the curve with
a smaller E* (for the flat punch, whose factor does not depend on depth, h and E* are exactly
degenerate), a curved ridge 0.03 % wide in ln E* and decades long in ln h on which stretch
moves stall. There the first coordinate is ln E* − ln c(h, base), c the least-squares ratio
E*_layer/E*_half-space of the same curve (1 in the half-space segment): the ridge becomes a
straight line along ln h.

**The base swap.**  :func:`base_swap_move` proposes the
mirror image bond -> 1 − bond together with ln E* -> ln E* ± ln r, r the least-squares
ratio E*_free/E*_bonded of the same curve (:func:`palpbayes.refit.refit_factor`), and, for an
unknown thickness, ln h -> the thickness of the other base whose shape matches best
(:func:`_swap_maps`).  The map is its own inverse, so it is a valid Metropolis proposal whose
acceptance is the posterior ratio times the map's Jacobian.
"""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from ..fitdata import FitData
from ..refit import fitted_depths, refit_factor
from .likelihood import TraceLikelihood
from .priors import TracePrior, param_names

if TYPE_CHECKING:  # emcee is imported where the move is made: an exact fit does not need it
    import emcee

__all__ = ["LayerLikelihood", "base_swap_move", "SWAP_WEIGHT"]

#: Share of the steps that propose a base swap (the rest: the configured moves).
SWAP_WEIGHT = 0.2


class LayerLikelihood:
    """Log-likelihood of θ = (log E*, z_s, log sigma, F0[, F1][, phi | log nu_t][, bond]
    [, log_h]) for a trace whose layer is partly unknown (module docstring).

    Parameters
    ----------
    data
        Prepared data whose model is a layer with an unknown base and/or thickness.
    prior
        The trace's prior (names, the ``log_h`` segments).
    tabulate, centers
        As :class:`TraceLikelihood` (used when the thickness is known).
    z_reference
        [m] Surface height at which the aligned coordinate's ratio r(h) is computed (module
        docstring; default: the contact onset).
    """

    def __init__(self, data: FitData, prior: TracePrior, tabulate: bool = True,
                 centers: tuple[tuple[float, float], ...] = (),
                 z_reference: float | None = None):
        self.data = data
        self.model = data.model
        self.prior = prior
        self.noise = prior.noise
        self.baseline = prior.baseline
        self.z_ref = prior.z_ref
        self.k = len(param_names(prior.noise, prior.baseline))
        names = list(prior.names)
        self.i_bond = names.index("bond") if "bond" in names else None
        self.i_logh = names.index("log_h") if "log_h" in names else None
        kw = {"noise": prior.noise, "baseline": prior.baseline, "z_ref": prior.z_ref}
        if self.model.thickness is not None:
            self.parts = {b: TraceLikelihood(replace(data, model=self.model.variant(base=b)),
                                             tabulate=tabulate, centers=centers, **kw)
                          for b in self.model.bases}
            self.core = None
        else:
            self.parts = {}
            self.core = TraceLikelihood(replace(data, model=self.model.half_space()),
                                        tabulate=False, **kw)
        self.z_reference = float(data.z_contact if z_reference is None else z_reference)
        if self.i_logh is not None:
            self._log_c = {b: _log_layer_ratio(self, self.z_reference, b)
                           for b in self.model.bases}
            self._log_r = None
        else:
            self._log_c = None
            self._log_r = _log_ratio(self, self.z_reference) if self.i_bond is not None else None

    def offset(self, theta: np.ndarray) -> np.ndarray:
        """ln E* − θ[0] of each walker (module docstring): thickness known, ln r on a free
        layer and 0 on a bonded one; thickness unknown, ln c(h, base)."""
        theta = np.atleast_2d(theta)
        if self._log_c is not None:
            bases = self.bases(theta)
            log_h = theta[:, self.i_logh]
            out = np.zeros(theta.shape[0])
            for b, log_c in self._log_c.items():
                rows = bases == b
                if rows.any():
                    out[rows] = log_c(log_h[rows])
            return out
        if self._log_r is None:
            return np.zeros(theta.shape[0])
        free = self.bases(theta) == "free"
        return np.where(free, self._log_r, 0.0)

    def log_estar(self, theta: np.ndarray) -> np.ndarray:
        """The real ln E* of each walker."""
        theta = np.atleast_2d(theta)
        return theta[:, 0] + self.offset(theta)

    def bases(self, theta: np.ndarray) -> np.ndarray:
        """Each walker's base (``"bonded"``/``"free"``)."""
        theta = np.atleast_2d(theta)
        if self.i_bond is None:
            return np.full(theta.shape[0], self.model.bases[0])
        return np.where(theta[:, self.i_bond] >= 0.5, "bonded", "free")

    def thickness(self, theta: np.ndarray) -> np.ndarray:
        """Each walker's thickness [m] (``inf``: the half-space)."""
        theta = np.atleast_2d(theta)
        if self.i_logh is None:
            return np.full(theta.shape[0], float(self.model.thickness))
        return self.prior.thickness_of(theta[:, self.i_logh])

    def shape_rows(self, z_surf: np.ndarray, thickness: np.ndarray, bases: np.ndarray,
                   z: np.ndarray | None = None) -> np.ndarray:
        """F/E* [m²] of each walker (rows) at heights ``z`` (default: the fitted samples)."""
        z = self.data.z if z is None else np.asarray(z, dtype=float)
        depth = np.asarray(z_surf, dtype=float)[:, None] - z[None, :]
        return self.model.shape_of_draws(depth, thickness=np.asarray(thickness, dtype=float),
                                         bonded=(np.asarray(bases) == "bonded").astype(float))

    def __call__(self, theta: np.ndarray) -> np.ndarray:
        """Log-likelihood (W,) of θ (W, ndim)."""
        theta = np.atleast_2d(theta)
        head = theta[:, :self.k].copy()
        head[:, 0] = self.log_estar(theta)
        bases = self.bases(theta)
        out = np.empty(theta.shape[0])
        if self.core is None:
            for b, like in self.parts.items():
                rows = bases == b
                if rows.any():
                    out[rows] = like(head[rows])
            return out
        h = self.thickness(theta)
        zs = head[:, 1]

        def rows_fn(rows):
            return self.shape_rows(zs[rows], h[rows], bases[rows])

        if self.noise == "student":
            return self.core.student_rows(head, rows_fn)
        for rows in self.data.blocks(theta.shape[0]):
            idx = np.arange(theta.shape[0])[rows]
            out[idx] = self.core.from_statistics(self.core.stats_of_rows(rows_fn(idx)),
                                                 head[idx])
        return out

    def mean_force(self, theta: np.ndarray, z: np.ndarray | None = None) -> np.ndarray:
        """Model force [N] at heights ``z`` for one θ."""
        theta = np.atleast_2d(np.asarray(theta, dtype=float))
        z = self.data.z if z is None else np.asarray(z, dtype=float)
        s = self.shape_rows(theta[:, 1], self.thickness(theta), self.bases(theta), z)[0]
        out = np.exp(self.log_estar(theta)[0]) * s + theta[0, 3]
        if self.baseline == "linear":
            out = out + theta[0, 4] * (z - self.z_ref)
        return out


def _depths(like: LayerLikelihood, z_surf: float) -> np.ndarray:
    """The fitted depths at ``z_surf`` [m], at most 400 of them (evenly picked)."""
    depth = fitted_depths(z_surf, like.data.z)
    if depth.size > 400:
        depth = depth[np.linspace(0, depth.size - 1, 400).round().astype(int)]
    return depth


def _log_ratio(like: LayerLikelihood, z_surf: float) -> float:
    """ln r: E*_free/E*_bonded of the same curve at ``z_surf`` [m] on the known thickness."""
    depth = _depths(like, z_surf)
    if depth.size == 0:
        return 0.0
    model = like.model
    return float(np.log(refit_factor(depth, model.variant(base="bonded").shape,
                                     model.variant(base="free").shape)))


def _log_layer_ratio(like: LayerLikelihood, z_surf: float, base: str):
    """ln c(ln h): E*_layer/E*_half-space of the same curve at ``z_surf`` [m] on a layer of
    ``base`` (interpolated on 64 nodes of ln h; 0 in the half-space segment)."""
    depth = _depths(like, z_surf)
    model = like.model
    lo, hi = like.prior.log_h_range
    grid = np.linspace(lo, hi, 64)
    if depth.size == 0:
        vals = np.zeros(grid.size)
    else:
        half = model.half_space().shape
        vals = np.array([np.log(refit_factor(
            depth, half, model.variant(thickness=float(np.exp(g)), base=base).shape))
            for g in grid])
    return lambda log_h: np.where(np.asarray(log_h) <= hi, np.interp(log_h, grid, vals), 0.0)


def _swap_maps(like: LayerLikelihood, z_surf: float):
    """The base swap's map at the reference surface ``z_surf`` [m]: ``swap(log_h, to_free)
    -> (log_h', ln E* shift, ln |Jacobian|)``.

    Known thickness: h stays, ln E* moves by ln r, r = E*_free/E*_bonded of the same curve.
    Unknown thickness: a free layer of another thickness mimics a bonded one best (a 30 mm
    bonded layer under a paraboloid looks like a ~20 mm free one), so h moves too, along the
    map g(h_bonded) = h_free of the free layer whose shape fits the bonded one best (least
    squares on the fitted depths, tabulated on 48 nodes of ln h, made increasing with a slope of
    at least 0.05, linear between the nodes); the Jacobian of g (its segment's slope) enters
    the acceptance.  Points whose image would leave the tabulated range,
    and the half-space segment, are left where they are (the identity is its own inverse).
    """
    depth = _depths(like, z_surf)
    model = like.model

    def shape(h: float, base: str):
        return model.variant(thickness=h, base=base).shape

    if model.thickness is not None:
        h = model.thickness
        lr = float(np.log(refit_factor(depth, shape(h, "bonded"), shape(h, "free")))) if (
            depth.size) else 0.0

        def swap_known(log_h, to_free):
            n = np.shape(to_free)
            return (np.asarray(log_h, dtype=float), np.where(to_free, lr, -lr), np.zeros(n))
        return swap_known

    lo, hi = like.prior.log_h_range
    xb = np.linspace(lo, hi, 48)
    yf = np.linspace(lo, hi, 480)
    free = np.array([model.shape_at(depth, thickness=float(np.exp(y)), base="free") for y in yf])
    nf = np.einsum("ij,ij->i", free, free)
    g, shift = [], []
    for x in xb:
        sb = model.shape_at(depth, thickness=float(np.exp(x)), base="bonded")
        c = free @ sb / nf                       # best scale of each free shape
        res = np.einsum("ij,ij->i", sb[None, :] - c[:, None] * free,
                        sb[None, :] - c[:, None] * free)
        k = int(np.argmin(res))
        g.append(yf[k])
        shift.append(np.log(c[k]))               # E*_free = c·E*_bonded
    g = np.asarray(g)
    for i in range(1, g.size):  # strictly increasing, slope >= 0.05: a well-posed inverse
        g[i] = max(g[i], g[i - 1] + 0.05 * (xb[i] - xb[i - 1]))
    shift = np.asarray(shift)
    slope = np.diff(g) / np.diff(xb)  # g is piecewise linear: its slope per segment

    def log_slope(x):
        i = np.clip(np.searchsorted(xb, x, side="right") - 1, 0, slope.size - 1)
        return np.log(np.maximum(slope[i], 1e-12))

    def swap(log_h, to_free):
        x = np.asarray(log_h, dtype=float)
        new, sh, jac = x.copy(), np.zeros(x.shape), np.zeros(x.shape)
        fwd = to_free & (x >= lo) & (x <= hi)
        back = ~to_free & (x >= g[0]) & (x <= g[-1])
        new[fwd] = np.interp(x[fwd], xb, g)
        sh[fwd] = np.interp(x[fwd], xb, shift)
        jac[fwd] = log_slope(x[fwd])
        xi = np.interp(x[back], g, xb)               # g⁻¹
        new[back] = xi
        sh[back] = -np.interp(xi, xb, shift)
        jac[back] = -log_slope(xi)
        return new, sh, jac
    return swap


def base_swap_move(like: LayerLikelihood, z_surf: float) -> emcee.moves.MHMove:
    """The Metropolis move bond -> 1 − bond with the matching ln E* (and ln h) (module
    docstring, :func:`_swap_maps`)."""
    i_b, i_h = like.i_bond, like.i_logh
    swap = _swap_maps(like, z_surf)

    def proposal(coords: np.ndarray, random) -> tuple[np.ndarray, np.ndarray]:
        new = np.array(coords, dtype=float, copy=True)
        to_free = coords[:, i_b] >= 0.5
        log_h = coords[:, i_h] if i_h is not None else np.zeros(coords.shape[0])
        new_h, shift, log_jac = swap(log_h, to_free)
        moved = (new_h != log_h) | (i_h is None) | (log_h > like.prior.log_h_range[1]
                                                    if i_h is not None else False)
        log_e = like.log_estar(coords) + np.where(moved, shift, 0.0)  # the real ln E*
        new[:, i_b] = np.where(moved, 1.0 - coords[:, i_b], coords[:, i_b])
        if i_h is not None:
            new[:, i_h] = new_h
        new[:, 0] = log_e - like.offset(new)  # back to the aligned coordinate
        return new, np.where(moved, log_jac, 0.0)

    import emcee

    return emcee.moves.MHMove(proposal)
