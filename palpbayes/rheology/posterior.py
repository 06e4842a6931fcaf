"""Collapsed posterior of a viscoelastic fit on a (surface × alpha or tau) grid.

Model: block means F_i = β·X_i(z_s, θ) + F0 [+ b·v_i] [+ F1·(z_i − z_ref)] + e_i, with X
the Lee–Radok columns of :mod:`~palpbayes.rheology.design` (power law: β = E0*, θ = alpha,
and Ting's columns on the retract, :mod:`~palpbayes.rheology.ting`; standard linear solid:
β = (E_inf*, E1*), θ = tau; the elastic law: β = E*, the constant kernel, no θ, so that the
same block means compare all three) and e stationary AR(1) Gaussian noise (lag-one
correlation phi).

* With ``drag``, b [N·s/m] is a viscous drag on the probe and v_i = −dz/dt the block's
  downward tip speed (:attr:`~palpbayes.rheology.cycle.CycleData.speed`): the hydrodynamic
  force on an AFM cantilever moving through liquid (Alcaraz et al. 2002, Langmuir 18:716;
  Janovjak et al. 2005, Biophys. J. 88:L37), which shifts the approach up and the retract
  down by b·v, out of contact as in it.  It is told apart from the offset only where the
  speed changes out of contact (the retract, a pause before the approach), so it is fitted
  with the retract by default.
* With ``tilt``, F1 [N/m] is a baseline that tilts with the height (an AFM's virtual
  deflection, light scattered by a reflective sample, a sensor drifting during a
  constant-speed approach), z_ref the mean height of the baseline samples: the elastic fit's
  ``--baseline linear``.

Given (z_s, θ, phi) the mean is linear in β, F0, b and F1, so they and the noise scale
integrate out in closed form, exactly as the elastic exact engine does
(:mod:`palpbayes.bayes.exact`, :func:`palpbayes.bayes.conjugate.node_posterior`: Jeffreys
prior on the innovation sd, the offset prior N(baseline level, (100·sigma_c)²) as a
pseudo-observation, flat on β, b and F1).  What is
left is a 3-D density on (z_s, θ, phi), integrated on a grid:

1. a coarse grid (:data:`COARSE_THETA` × :data:`COARSE_Z`) over the whole prior finds the
   best basin (other basins within :data:`KEEP` of it are reported);
2. a sheared grid of :data:`FINE` × :data:`FINE` nodes follows the basin
   (:func:`~palpbayes.rheology.grid_search.box_search`): θ_i spans ±:data:`SPAN_SD` marginal
   sd of θ, and on each θ_i the surface nodes span ±SPAN_SD *conditional* sd of z_s around
   the regression line of z_s on θ, so a narrow, tilted ridge (surface and alpha trade off)
   is resolved as well as a round basin; the box is rebuilt until its moments are steady and
   resolved.  The box starts at the mode found on the profile max_z log p near the coarse
   grid's best node (:func:`~palpbayes.rheology.grid_search.climb`), with θ's sd, z_s's
   conditional sd and the ridge's slope from their curvatures; a box that does not settle
   from there searches again from the coarse node, and is flagged if it still does not;
3. the moduli's priors are applied to draws by importance resampling: log-uniform (1/E) on
   E0* and E1*, flat on E_inf* >= 0, each modulus positive.

Priors on θ: alpha uniform on [0, :data:`ALPHA_MAX`]; tau log-uniform on
[dt/10, 100·span] (dt the shortest step, span the record).  phi uniform on [0, 0.98]:
:data:`PHI_NODES` uniform nodes on the coarse grid and the climb, then nodes a quarter of
its sd apart around its density at the climbed mode (:meth:`NodeEvaluator.focus_phi`).
"""

# Long module: one job, the collapsed viscoelastic grid posterior; the node evaluator and the
#   basin search are its inside.

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.special import logsumexp

from ..bayes.conjugate import Gram, NodePosterior, node_posterior
from ..bayes.exact import cell_widths, phi_moments, phi_nodes_around
from ..errors import FitError, InputError
from .cycle import CycleData
from .design import lee_radok_columns
from .grid_search import FINE, KEEP, SEARCH_THETA, SPAN_SD, box_search, climb, log_cells, moments
from .ting import RETRACT, RetractDesign, with_retract

__all__ = ["RHEOLOGIES", "GridPosterior", "grid_posterior", "NodeEvaluator", "ALPHA_MAX",
           "KEEP", "FINE", "SEARCH_THETA", "SPAN_SD", "COARSE_THETA", "COARSE_Z", "PHI_BOUNDS",
           "NUISANCE"]

#: Relaxation models the grid engine fits, and the name of their grid parameter (the elastic
#: law E*(t) = E* has none: its grid is the surface alone).
RHEOLOGIES = {"power-law": "alpha", "sls": "tau", "elastic": None}
#: Upper end of the uniform alpha prior (1 is a dashpot).
ALPHA_MAX = 0.95
#: Coarse grid: theta nodes and surface nodes.
COARSE_THETA, COARSE_Z = 13, 97
#: Support of the uniform phi prior and its first grid (coarse grid and climb).
PHI_BOUNDS = (0.0, 0.98)
PHI_NODES = 25
#: Points of the phi density at the climbed mode from which the box's phi nodes are set.
PHI_SCAN = 2_000
#: Offset prior sd in units of the block-mean noise scale (vague: the data fix the offset).
OFFSET_SD = 100.0
#: Proposals per returned draw (importance resampling of the moduli's priors).
PROPOSALS = 8
#: Linear coefficients that are not moduli (no positivity, no log-uniform prior).
NUISANCE = ("offset", "drag", "tilt")


@dataclass
class GridPosterior:
    """The posterior on the final grid.

    ``theta`` (Gt,) alpha [-] or tau [s]; ``z`` (Gt, Gz) surface nodes [m] on each theta node
    (sheared: ``z[i] = z_c + slope·(θ_i − θ_c) + offsets``), ``slope`` dz/dθ-coordinate;
    ``phi`` (H,);
    ``log_mass`` (Gt, Gz, H) normalised log mass of each node's cell; ``post`` the conditional
    posterior of β = (modulus columns…, offset) at every node (arrays (Gt·Gz, H, …));
    ``names`` of β (moduli, ``"offset"`` and, with those terms, ``"drag"``, ``"tilt"``);
    ``other_basins`` [(z_s, θ, log density below the best)] of the coarse grid.
    """

    rheology: str
    data: CycleData
    z: np.ndarray
    theta: np.ndarray
    phi: np.ndarray
    log_mass: np.ndarray
    post: NodePosterior
    names: tuple[str, ...]
    t0: float
    bounds: tuple[float, float]
    slope: float = 0.0
    other_basins: list = field(default_factory=list)
    n_evaluations: int = 0
    converged: bool = True

    @property
    def theta_name(self) -> str | None:
        return RHEOLOGIES[self.rheology]

    @property
    def drag(self) -> bool:
        """The model has a viscous drag term b·(−dz/dt)."""
        return "drag" in self.names

    @property
    def tilt(self) -> bool:
        """The model's baseline tilts with the height, F0 + F1·(z − z_ref)."""
        return "tilt" in self.names

    def marginal(self, axis: str) -> tuple[np.ndarray, np.ndarray]:
        """Nodes and normalised cell masses of ``"z"`` (all nodes, sorted), ``"theta"`` or
        ``"phi"``."""
        m = np.exp(self.log_mass)
        if axis == "z":
            order = np.argsort(self.z.ravel())
            return self.z.ravel()[order], m.sum(axis=2).ravel()[order]
        if axis == "theta":
            return self.theta, m.sum(axis=(1, 2))
        return self.phi, m.sum(axis=(0, 1))

    def draws(self, rng: np.random.Generator, n: int) -> dict[str, np.ndarray]:
        """``n`` joint draws: moduli [Pa] (E*), theta, z_surf [m], offset [N], sigma [N] (block
        mean noise sd), phi; the moduli's priors by importance resampling (module docstring).
        ``ess`` is the importance sample's effective size.  The linear coefficients are drawn
        given the node (theta, z_surf), and theta and z_surf are then spread over the node's
        cell; ``_theta_node`` and ``_z_node`` keep the node's values (the force curve that
        goes with the coefficients)."""
        Gt, Gz, H = self.log_mass.shape
        k = PROPOSALS * n
        p = np.exp(self.log_mass.ravel() - logsumexp(self.log_mass.ravel()))
        pick = rng.choice(p.size, size=k, p=p)
        it, iz, ih = np.unravel_index(pick, (Gt, Gz, H))
        node = it * Gz + iz
        theta_c = self._theta_coord()
        ct = theta_c[it] + rng.uniform(-0.5, 0.5, k) * cell_widths(theta_c)[it]
        ct = np.clip(ct, theta_c[0], theta_c[-1])
        zw = np.stack([cell_widths(row) for row in self.z])
        zs = (self.z[it, iz] + self.slope * (ct - theta_c[it])
              + rng.uniform(-0.5, 0.5, k) * zw[it, iz])
        th = self._from_coord(ct)
        S, nu = self.post.S[node, ih], self.post.nu
        tau2 = S / rng.chisquare(nu, k)
        cov = self.post.scale[node, ih] * (tau2 * nu / S)[:, None, None]
        L = np.linalg.cholesky(cov)
        beta = self.post.beta[node, ih] + np.einsum("kij,kj->ki", L, rng.standard_normal(
            (k, cov.shape[-1])))
        phi = self.phi[ih]
        out = {name: beta[:, j] for j, name in enumerate(self.names)}
        out["offset"] = out.pop("offset") + self.data.f0_center
        logw = np.zeros(k)
        for name in self.names:
            if name in NUISANCE:
                continue
            ok = out[name] > 0
            logw = np.where(ok, logw - (np.log(np.where(ok, out[name], 1.0))
                                        if name != "E_inf" else 0.0), -np.inf)
        if not np.isfinite(logw).any():
            raise FitError("no posterior draw has positive moduli: the relaxation model does "
                           "not describe this record (check the segments and the sign of z)")
        w = np.exp(logw - logw.max())
        w /= w.sum()
        ess = 1.0 / float(w @ w)
        keep = rng.choice(k, size=n, p=w)
        out.update({"z_surf": zs, "sigma": np.sqrt(tau2 / (1.0 - phi**2)), "phi": phi,
                    "_z_node": self.z[it, iz]})
        if self.theta_name is not None:
            out[self.theta_name] = th
            out["_theta_node"] = self.theta[it]
        res = {key: np.asarray(v)[keep] for key, v in out.items()}
        res["ess"] = np.array(ess)
        return res

    def _theta_coord(self) -> np.ndarray:
        return np.log(self.theta) if self.rheology == "sls" else self.theta

    def _from_coord(self, c: np.ndarray) -> np.ndarray:
        return np.exp(c) if self.rheology == "sls" else c


def _theta_bounds(rheology: str, data: CycleData) -> tuple[float, float]:
    if rheology == "elastic":
        return 0.0, 0.0
    if rheology == "power-law":
        return 0.0, ALPHA_MAX
    return data.dt_min / 10.0, 100.0 * data.span


class NodeEvaluator:
    """log p(z_s, θ, phi | data) on (θ nodes × z nodes × phi), β and noise integrated;
    ``drag`` and ``tilt`` add the columns of a viscous drag and of a tilted baseline (module
    docstring)."""

    def __init__(self, data: CycleData, rheology: str, t0: float, drag: bool = False,
                 tilt: bool = False):
        self.data, self.rheology, self.t0 = data, rheology, t0
        self.drag, self.tilt = bool(drag), bool(tilt)
        moduli = {"power-law": ("E0", "offset"), "sls": ("E_inf", "offset", "E1"),
                  "elastic": ("E", "offset")}[rheology]
        self.names = moduli + (("drag",) if drag else ()) + (("tilt",) if tilt else ())
        self.windows = data.windows()
        self.y = data.force - data.f0_center
        self.weights = np.array([1.0 / OFFSET_SD**2])
        self.centers = np.zeros(1)
        self.phi = np.linspace(*PHI_BOUNDS, PHI_NODES)
        self._phi_found: tuple | None = None  # phi_density's last node and answer
        self.n = 0
        ret = data.segment == RETRACT
        self.retract = (RetractDesign(data.edges, data.z_edges, data.sample_time[ret], data.m,
                                      t0) if rheology == "power-law" and ret.any() else None)

    def phi_density(self, theta: float, z: float) -> tuple[np.ndarray, float, float] | None:
        """phi's density at the node (``theta``, ``z`` [m]): nodes around it (its mean ± 8 sd
        in steps of sd/4, :func:`~palpbayes.bayes.exact.phi_nodes_around`), its mean and sd;
        None where no phi has a finite density.  Two scans of :data:`PHI_SCAN` points: over
        the prior, then over the first scan's range (a density 1e-4 wide, as on real records,
        spans less than a step of the first).  The last node's answer is kept: the final
        box's mode is often the climbed one."""
        if self._phi_found is not None and self._phi_found[0] == (theta, z):
            return self._phi_found[1]
        g = self.gram(np.array([theta]), np.array([z]))
        scan, nodes = np.linspace(*PHI_BOUNDS, PHI_SCAN), None
        for _ in range(2):
            lp = node_posterior(g, scan, self.weights, self.centers).logp[0]
            if not np.isfinite(lp).any():
                return None
            nodes = phi_nodes_around(scan, lp, PHI_BOUNDS)
            mean, sd = phi_moments(scan, lp)
            scan = np.linspace(nodes[0], nodes[-1], PHI_SCAN)
        self._phi_found = ((theta, z), (nodes, mean, sd))
        return self._phi_found[1]

    def focus_phi(self, theta: float, z: float) -> np.ndarray:
        """Set :attr:`phi` to the nodes of :meth:`phi_density` at the node (``theta``, ``z``
        [m]) (unchanged where it has none); returns them.

        The first grid's :data:`PHI_NODES` are 0.04 apart, while phi's sd is ~
        sqrt((1 − phi²)/N): 0.01 on 10,000 block means, 1e-4 on real AFM records whose phi
        sits at 0.98.  One node then carries the whole phi marginal, the grid's draws all
        have that phi, and emcee's start (spread over the node's cell) is 50 times too wide
        in phi.  Moving the nodes changes neither the prior nor the density at a node: only
        the trapezoid rule over phi, now resolved.  Set them at the posterior's mode: at a
        surface far off it the residuals make phi look near its bound."""
        found = self.phi_density(theta, z)
        if found is not None:
            self.phi = found[0]
        return self.phi

    def resolves_phi(self, mean: float, sd: float) -> bool:
        """True when :attr:`phi` resolves a phi density of ``mean`` and ``sd``
        (:meth:`phi_density`): its nodes span the mean ± 6 sd (within the prior) in steps of
        at most sd/2."""
        lo, hi = max(PHI_BOUNDS[0], mean - 6 * sd), min(PHI_BOUNDS[1], mean + 6 * sd)
        step = float(np.diff(self.phi).max()) if self.phi.size > 1 else math.inf
        return bool(self.phi[0] <= lo + 1e-12 and self.phi[-1] >= hi - 1e-12
                    and step <= sd / 2)

    def columns(self, theta: float, z: np.ndarray, constant: np.ndarray | None = None
                ) -> np.ndarray:
        """X (G, N, q): one column per name of :attr:`names` (modulus, 1, second modulus,
        speed, height from z_ref) and y last, for surfaces ``z``; ``constant`` is the SLS's
        E_inf* column at ``z`` if already known (:meth:`constant_column`)."""
        d = self.data
        kind = {"power-law": "power-law", "sls": "exponential", "elastic": None}[self.rheology]
        b = lee_radok_columns(self.windows, z, d.z_edges, d.m, kind, theta, self.t0)
        if self.rheology == "power-law":  # Ting's rule on the retract (the SLS refuses one)
            b = with_retract(d, b, z, theta, self.t0, self.retract)
        b = d.C * b
        G, N = b.shape
        ones, y = np.ones((G, N)), np.broadcast_to(self.y, (G, N))
        extra = ([np.broadcast_to(d.speed, (G, N))] if self.drag else []) + (
            [np.broadcast_to(d.z - d.z_ref, (G, N))] if self.tilt else [])
        if self.rheology != "sls":
            return np.stack([b, ones, *extra, y], axis=-1)
        inf = self.constant_column(z) if constant is None else constant
        return np.stack([inf, ones, b, *extra, y], axis=-1)

    def constant_column(self, z: np.ndarray) -> np.ndarray:
        """The constant kernel's column (G, N) [N/Pa] at surfaces ``z``: the SLS's E_inf*
        term, the same for every tau."""
        d = self.data
        return d.C * lee_radok_columns(self.windows, z, d.z_edges, d.m, None)

    def columns_at(self, thetas: np.ndarray, z: np.ndarray) -> list[np.ndarray]:
        """:meth:`columns` for every theta of ``thetas`` on the same surfaces ``z``, the SLS's
        constant-kernel column computed once for all of them."""
        inf = self.constant_column(z) if self.rheology == "sls" and len(thetas) > 1 else None
        return [self.columns(float(th), z, inf) for th in thetas]

    def gram(self, thetas: np.ndarray, z: np.ndarray) -> Gram:
        n_contact = np.count_nonzero(self.data.z[None, :] < z[:, None], axis=1)
        X = np.concatenate(self.columns_at(thetas, z))  # (Gt·Gz, N, q)
        self.n += thetas.size * z.size
        Xt = X.swapaxes(1, 2)  # batched matmul: ~8x faster than einsum here
        m0 = Xt @ X
        m1 = Xt[:, :, 1:] @ X[:, :-1]
        return Gram(np.tile(z, thetas.size), m0, m1, X[:, 0].copy(), X[:, -1].copy(),
                    np.tile(n_contact, thetas.size), X.shape[1])

    def logp_rows(self, thetas: np.ndarray, z: np.ndarray) -> tuple[np.ndarray, NodePosterior]:
        """As :meth:`logp` with its own surface nodes on every theta node: ``z`` (Gt, Gz)."""
        grams = [self.gram(np.array([th]), row) for th, row in zip(thetas, z, strict=True)]
        g = Gram(np.concatenate([q.z for q in grams]), *[np.concatenate([getattr(q, f) for q
                 in grams]) for f in ("m0", "m1", "first", "last", "n_contact")], n=grams[0].n)
        post = node_posterior(g, self.phi, self.weights, self.centers)
        lp = logsumexp(post.logp + np.log(cell_widths(self.phi))[None, :], axis=1)
        return lp.reshape(z.shape), post

    def logp(self, thetas: np.ndarray, z: np.ndarray, phi: np.ndarray | None = None
             ) -> tuple[np.ndarray, NodePosterior]:
        """(Gt, Gz) log density marginal over phi, and the node posteriors (Gt·Gz, H)."""
        phi = self.phi if phi is None else phi
        post = node_posterior(self.gram(thetas, z), phi, self.weights, self.centers)
        lp = logsumexp(post.logp + np.log(cell_widths(phi))[None, :], axis=1)
        return lp.reshape(thetas.size, z.size), post


def _coarse_basins(lp: np.ndarray, thetas: np.ndarray, z: np.ndarray) -> list:
    """Local maxima of the coarse grid (8-neighbourhood) within KEEP of the best."""
    pad = np.pad(lp, 1, constant_values=-np.inf)
    peak = np.ones_like(lp, dtype=bool)
    for di in (-1, 0, 1):
        for dj in (-1, 0, 1):
            if di or dj:
                peak &= lp >= pad[1 + di:1 + di + lp.shape[0], 1 + dj:1 + dj + lp.shape[1]]
    top = lp.max()
    out = [(float(z[j]), float(thetas[i]), float(top - lp[i, j]))
           for i, j in zip(*np.nonzero(peak & (lp > top - KEEP)), strict=True)]
    return sorted(out, key=lambda b: b[2])


def _separate_basins(ev: NodeEvaluator, from_c, basins: list, best: tuple[float, float],
                     best_lp: float, step: tuple[float, float]) -> list:
    """The coarse grid's basins that a valley (a dip of more than 1 in log density below the
    lower end) separates from the final mode, as (z_s, θ, log density below the mode); a
    tilted ridge puts the coarse maximum far from the mode without a second basin."""
    out = []
    for z, c, _ in basins[:4]:
        if abs(z - best[1]) <= step[1] and abs(c - best[0]) <= step[0]:
            continue
        f = np.linspace(0.0, 1.0, 9)
        ct = best[0] + f * (c - best[0])
        zs = best[1] + f * (z - best[1])
        lp, _ = ev.logp_rows(from_c(ct), zs[:, None])
        line = lp[:, 0]
        if line[1:-1].min() >= min(line[0], line[-1]) - 1.0:
            continue
        out.append((float(z), float(from_c(c)), float(best_lp - line[-1])))
    return out


def grid_posterior(data: CycleData, rheology: str = "power-law", *, t0: float = 1.0,
                   drag: bool = False, tilt: bool = False, max_iterations: int = 20
                   ) -> GridPosterior:
    """The collapsed posterior of ``data`` under ``rheology`` (module docstring); ``drag``
    adds a viscous drag b·(−dz/dt) to the model, ``tilt`` a baseline F1·(z − z_ref).

    Raises
    ------
    InputError
        An unknown rheology or t0 <= 0.
    FitError
        No node has enough samples in contact (the record has no contact).
    """
    if rheology not in RHEOLOGIES:
        raise InputError(f"unknown rheology {rheology!r}; the viscoelastic fit knows "
                         f"{', '.join(RHEOLOGIES)}")
    if not (math.isfinite(t0) and t0 > 0):
        raise InputError(f"t0 = {t0!r} s must be positive")
    ev = NodeEvaluator(data, rheology, t0, drag, tilt)
    lo, hi = _theta_bounds(rheology, data)
    log_theta = rheology == "sls"
    to_c = (lambda v: np.log(v)) if log_theta else (lambda v: np.asarray(v, float))  # noqa
    from_c = (lambda c: np.exp(c)) if log_theta else (lambda c: c)  # noqa: E731
    c_lo, c_hi = float(to_c(lo)), float(to_c(hi))
    ct = np.linspace(c_lo, c_hi, COARSE_THETA if c_hi > c_lo else 1)
    cz = np.linspace(data.z_lo, data.z_hi, COARSE_Z)
    lp, _ = ev.logp(from_c(ct), cz)
    if not np.isfinite(lp).any():
        raise FitError(f"{data.trace.source or data.trace.trace_id}: no surface height has "
                       "enough block means in contact; the record has (almost) no contact")
    i, j = np.unravel_index(np.argmax(lp), lp.shape)
    basins = _coarse_basins(lp, ct, cz)
    step = (ct[1] - ct[0] if ct.size > 1 else 0.0, cz[1] - cz[0])
    centre, sd, slope = (float(ct[i]), float(cz[j])), step, 0.0
    bounds = ((c_lo, c_hi), (data.z_lo, data.z_hi))
    # the box starts at the mode climbed on the profile, with its sds and slope (half the
    # hereditary matrices of a box search from the coarse node, the same posterior to 0.023
    # sd); where it does not settle from there, the search from the coarse node is tried too
    # phi's nodes are then set around its density at that mode (NodeEvaluator.focus_phi),
    # and checked again at the final box's best node (below)
    box = None
    if c_hi > c_lo:
        try:
            top, sd_top, slope_top = climb(ev, from_c, bounds, centre, step)
            ev.focus_phi(float(from_c(top[0])), top[1])
            box = box_search(ev, from_c, bounds, top, sd_top, slope_top, max_iterations)
        except FitError:  # the climbed box held no finite density: the coarse node's search
            box = None
    if box is None or not box.converged:
        again = box_search(ev, from_c, bounds, centre, sd, slope, max_iterations)
        if box is None or (again.lp.max() > box.lp.max()
                           or again.converged and again.lp.max() >= box.lp.max() - KEEP):
            box = again
    k, l = np.unravel_index(np.argmax(box.lp), box.lp.shape)
    found = ev.phi_density(float(from_c(box.gt[k])), float(box.gz[k, l]))
    if found is not None and not ev.resolves_phi(*found[1:]):
        # the box's mode is not where phi's nodes were set (the elastic law, which has no
        # climb; a fallback search; a climb off the mode): nodes set there, and the box
        # searched again on them from its own moments (a sharper phi can narrow z_s a lot)
        ev.phi = found[0]
        lp_new, _ = ev.logp_rows(from_c(box.gt), box.gz)
        mt, st, b, mz, sz = moments(box.gt, box.gz, lp_new + log_cells(box.gt, box.gz))
        box = box_search(ev, from_c, bounds, (mt, mz), (st, max(sz, 1e-15)), b,
                         max_iterations)
    gt, gz, lp, post, slope, converged = (box.gt, box.gz, box.lp, box.post, box.slope,
                                          box.converged)
    log_cell = (post.logp.reshape(gt.size, FINE, -1) + log_cells(gt, gz)[:, :, None]
                + np.log(cell_widths(ev.phi))[None, None, :])
    log_mass = log_cell - logsumexp(log_cell)
    names = ev.names
    k, l = np.unravel_index(np.argmax(lp), lp.shape)
    others = _separate_basins(ev, from_c, basins, (float(gt[k]), float(gz[k, l])),
                              float(lp.max()), step)
    return GridPosterior(rheology, data, gz, from_c(gt), ev.phi, log_mass, post,
                         names, t0, (lo, hi), float(slope), others, ev.n, converged)
