"""Exact posterior of one trace by quadrature over the surface height (``--engine exact``).

Model (docs/design.md §3): F_j = E*·s(z_s − z_j) + F0 [+ F1·(z_j − z_ref)] + e_j with Gaussian
noise e, iid or stationary AR(1) with lag-one correlation phi.  Given z_s (and phi) the mean is
*linear* in β = (E*, F0[, F1]), so β and the noise scale integrate out in closed form
(Bayesian linear regression, e.g. Gelman et al., *Bayesian Data Analysis*, 3rd ed., §14.2):

* prewhitening: for AR(1) the rows x_1·sqrt(1 − phi²) and x_t − phi·x_{t−1} (t >= 2) turn the
  stationary likelihood into an iid one with innovation sd tau = sigma·sqrt(1 − phi²) and the
  Jacobian (1 − phi²)^(1/2); every cross-product of the whitened columns follows from the lag-0
  and lag-1 sums of the raw ones, so a phi grid costs no pass over the data;
* priors: Jeffreys 1/tau on the noise, flat on E* (then reweighted, below), and the offset (and
  slope) prior of the emcee model in its conjugate form F0 | sigma ~ N(b, (s_F0·sigma/sigma_c)²)
  — the same prior when sigma equals the noise spec's sigma_c — entering as pseudo-observations
  with weights w_k = (sigma_c/s_k)²·(1 − phi²);
* with A = XᵀX + W, b̂ = A⁻¹(Xᵀy + W·m) and S the penalised residual sum of squares, the
  marginal posterior is

      p(z_s, phi | data) ∝ |A|^(-1/2) · S^(-nu/2) · |W|^(1/2) · (1 − phi²)^(1/2),
      nu = n + k − p   (k pseudo-observations, p = dim β),

  and β | z_s, phi, data is multivariate Student-t with nu degrees of freedom, centre b̂ and
  scale matrix (S/nu)·A⁻¹; tau² | z_s, phi, data is S/chi²_nu;
* the emcee model's log-uniform prior on E* (bounded) is a factor 1{lo < E* < hi}/E* on top of
  the flat one: exact in the E* marginal (integrated on a grid against each node's Student-t,
  :func:`palpbayes.bayes.mixture.tilted_mixture`) and in the draws (truncated proposals with
  importance weights, :meth:`ExactPosterior.draws`); the surface marginal and the modes use the
  truncation mass and a first-order 1/E* factor per node (:meth:`ExactPosterior.prior_factor`),
  exact to O((sd/E*)²);
* the noise prior is Jeffreys' (emcee's is log-normal around the noise spec) and the offset
  prior is conditional on sigma: with thousands of samples both differences are far below the
  Monte Carlo error (tested against emcee).

The surface height is integrated on an adaptive grid (:func:`refine_grid`): a coarse grid over
the prior's support, then every interval whose log density changes by more than
:data:`MAX_STEP` (or that ends at a local maximum) among those within :data:`KEEP` of the best
is split, until none is left — every local mode is resolved, not only the best.  What the
engine does not cover (Student-t noise, the soft surface prior, the uncertainty budget's
inputs) stays with emcee.
"""

# Long module: one job, the exact engine; the grid refinement and ExactPosterior (its moments,
#   draws and marginals) are one computation.

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import special, stats
from scipy.special import logsumexp

from ..errors import InputError
from ..fitdata import FitData
from ..intervals import LEVEL
from ..units import format_length, format_pressure
from .conjugate import Gram, NodePosterior, gram, node_posterior
from .mixture import NORMAL_NU, MixtureSummary, tilted_mixture
from .noisemodels import EXACT_NOISE_MODELS
from .priors import TracePrior

__all__ = ["ExactPosterior", "exact_posterior", "refine_grid", "cell_widths", "phi_grid",
           "phi_moments", "phi_nodes_around", "node_log_mass", "sampled_coordinates",
           "log_marginal_phi", "COARSE_NODES",
           "MAX_STEP", "KEEP", "PHI_NODES", "truncated_standard_normal"]

#: Nodes of the first, uniform grid over the surface prior's support.
COARSE_NODES = 129
#: Largest change of the log density across one kept interval after refinement.
MAX_STEP = 0.5
#: Intervals whose higher end lies more than this below the best log density are not refined
#: (their cells hold < e^-14 of the mass each).
KEEP = 14.0
#: Nodes of the first phi grid (AR(1) only), uniform on the prior's support.
PHI_NODES = 41
#: Proposals per returned draw in :meth:`ExactPosterior.draws` (importance resampling).
PROPOSALS = 8
#: Most surface nodes in all (refinement stops there and says so).
MAX_NODES = 6000


def refine_grid(lo: float, hi: float, evaluate, coarse: int = COARSE_NODES,
                max_nodes: int = MAX_NODES, start: tuple[np.ndarray, np.ndarray] | None = None,
                max_step: float = MAX_STEP, keep: float = KEEP,
                ) -> tuple[np.ndarray, np.ndarray, bool]:
    """Adaptive nodes on [lo, hi] for a log density given by ``evaluate(nodes) -> logp``.

    Starts from ``coarse`` uniform nodes (or from the sorted nodes and log densities
    ``start``, as the online estimator does after each update) and halves every interval within
    ``keep`` (:data:`KEEP`) of the best whose log density changes by more than ``max_step``
    (:data:`MAX_STEP`), or that ends at a local maximum whose other side drops by more than
    that, until none is left.

    Returns
    -------
    nodes, logp, complete
        Sorted nodes, their log densities, and False if ``max_nodes`` stopped the refinement.
    """
    if start is None:
        nodes = np.linspace(lo, hi, coarse)
        logp = evaluate(nodes)
    else:
        nodes, logp = start
    while True:
        best = np.max(logp)
        if not np.isfinite(best):
            return nodes, logp, True
        lp = np.where(np.isfinite(logp), logp, best - 10 * keep)
        step = np.abs(np.diff(lp))
        peak = np.r_[False, (lp[1:-1] >= lp[:-2]) & (lp[1:-1] >= lp[2:]), False]
        drop = np.r_[0.0, np.maximum(lp[1:-1] - lp[:-2], lp[1:-1] - lp[2:]), 0.0]
        sharp = peak & (drop > max_step)
        split = ((np.maximum(lp[:-1], lp[1:]) > best - keep)
                 & ((step > max_step) | sharp[:-1] | sharp[1:])
                 & (np.diff(nodes) > 1e-12 * max(abs(hi), abs(lo), hi - lo)))
        if not split.any():
            return nodes, logp, True
        i = np.flatnonzero(split)
        if nodes.size + i.size > max_nodes:
            return nodes, logp, False
        new = nodes[i] + 0.5 * np.diff(nodes)[i]
        new_lp = evaluate(new)
        nodes = np.concatenate([nodes, new])
        logp = np.concatenate([logp, new_lp])
        order = np.argsort(nodes)
        nodes, logp = nodes[order], logp[order]


def _lower_tail(a, b) -> tuple[np.ndarray, ...]:
    """[a, b], or its mirror image [−b, −a] where a > 0, so that both ends lie in the lower
    tail, where log Phi keeps its precision: (lo, hi, mirrored, log Phi(lo), log Phi(hi))."""
    a, b = np.broadcast_arrays(np.asarray(a, dtype=float), np.asarray(b, dtype=float))
    flip = a > 0
    lo, hi = np.where(flip, -b, a), np.where(flip, -a, b)
    return lo, hi, flip, special.log_ndtr(lo), special.log_ndtr(hi)


def _log_normal_mass(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """log(Phi(b) − Phi(a)) for a < b, accurate in both tails."""
    return _mass(*_lower_tail(a, b)[3:])


def _mass(l_lo: np.ndarray, l_hi: np.ndarray) -> np.ndarray:
    with np.errstate(divide="ignore", invalid="ignore"):
        return l_hi + np.log1p(-np.exp(l_lo - l_hi))


def _truncated_draws(rng: np.random.Generator, a, b) -> tuple[np.ndarray, np.ndarray]:
    """:func:`truncated_standard_normal` and the log of each truncation's mass
    (:func:`_log_normal_mass`), from one evaluation of the tails."""
    lo, hi, flip, l_lo, l_hi = _lower_tail(a, b)
    u = rng.random(lo.shape)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        r = np.exp(l_lo - l_hi)  # Phi(lo)/Phi(hi) in [0, 1)
        x = special.ndtri_exp(l_hi + np.log(r + u * (1.0 - r)))
    x = np.clip(x, lo, hi)
    return np.where(flip, -x, x), _mass(l_lo, l_hi)


def truncated_standard_normal(rng: np.random.Generator, a: np.ndarray, b: np.ndarray
                              ) -> np.ndarray:
    """One draw per element of the standard normal truncated to [a, b] (a < b), by inverting
    its CDF in log space: x = Phi⁻¹(Phi(a) + u·(Phi(b) − Phi(a))), u uniform, on the mirror
    image [−b, −a] where a > 0, so that both ends lie in the lower tail, where log Phi keeps
    its precision (``scipy.special.log_ndtr``, ``ndtri_exp``).  The distribution of
    ``scipy.stats.truncnorm.rvs``, without its per-call overhead."""
    return _truncated_draws(rng, a, b)[0]


def cell_widths(x: np.ndarray) -> np.ndarray:
    """Trapezoid weights of sorted nodes x (half the two neighbouring intervals)."""
    if x.size == 1:
        return np.ones(1)
    d = np.diff(x)
    return 0.5 * (np.r_[d, 0.0] + np.r_[0.0, d])


@dataclass
class ExactPosterior:
    """Posterior on the (surface × phi) nodes; see the module docstring.

    Attributes
    ----------
    z
        [m] Surface nodes (G,).
    phi
        Phi nodes (H,); ``[0.0]`` for iid noise.
    post
        The conditional posteriors at the nodes.
    log_mass
        (G, H) normalised log probability of each node's cell under the flat E* prior.
    complete
        False if the refinement stopped at :data:`MAX_NODES`.
    prior
        The trace's prior (E* bounds, names).
    """

    z: np.ndarray
    phi: np.ndarray
    post: NodePosterior
    log_mass: np.ndarray
    complete: bool
    prior: TracePrior

    @property
    def n_nodes(self) -> int:
        return int(self.z.size * self.phi.size)

    def estar_summary(self, level: float = LEVEL) -> MixtureSummary:
        """Marginal of E* [Pa] under the log-uniform prior (:func:`tilted_mixture`)."""
        return tilted_mixture(self.log_mass, self.post.beta[..., 0],
                              np.sqrt(self.post.scale[..., 0, 0]), self.post.nu,
                              tuple(np.exp(self.prior.bounds["log_Estar"])), level)

    def prior_factor(self) -> np.ndarray:
        """(G, H) log of what the bounded log-uniform E* prior does to each node's mass:
        log P(lo < E* < hi | node) − log(centre), the second a first-order 1/E* tilt."""
        mu = self.post.beta[..., 0]
        sd = np.sqrt(self.post.scale[..., 0, 0])
        lo, hi = np.exp(self.prior.bounds["log_Estar"])
        with np.errstate(invalid="ignore", divide="ignore"):
            a, b = (lo - mu) / sd, (hi - mu) / sd
            if self.post.nu > NORMAL_NU:
                mass = _log_normal_mass(a, b)
            else:
                nu = self.post.nu  # upper tail by the survival function (no cancellation)
                p = np.where(a > 0, stats.t.sf(a, nu) - stats.t.sf(b, nu),
                             stats.t.cdf(b, nu) - stats.t.cdf(a, nu))
                mass = np.log(np.clip(p, 1e-300, None))
            tilt = -np.log(np.clip(mu, lo, hi))
        return np.where(np.isfinite(mass), mass + tilt, -np.inf)

    def modes(self) -> list[tuple[float, float]]:
        """Local maxima of the surface marginal [m] with the mass of their basins (between the
        neighbouring minima), largest mass first; basins under 1e-6 of the mass are left out."""
        return [(z, m) for z, m, _, _ in self.basins()]

    def basins(self) -> list[tuple[float, float, float, float]]:
        """(peak [m], mass, lower edge [m], upper edge [m]) of each basin of :meth:`modes`."""
        adj = self.prior_factor()
        w = np.exp(logsumexp(self.log_mass + adj, axis=1) - np.max(self.log_mass + adj))
        w /= w.sum()
        dens = w / cell_widths(self.z)
        peaks = [i for i in range(dens.size)
                 if (i == 0 or dens[i] >= dens[i - 1]) and (i == dens.size - 1
                                                            or dens[i] > dens[i + 1])]
        out = []
        for k, i in enumerate(peaks):
            a = 0 if k == 0 else peaks[k - 1] + int(np.argmin(dens[peaks[k - 1]:i + 1]))
            b = (dens.size if k == len(peaks) - 1
                 else i + int(np.argmin(dens[i:peaks[k + 1] + 1])))
            mass = float(w[a:b].sum())
            if mass >= 1e-6:
                lo_edge = -np.inf if k == 0 else float(self.z[a])
                hi_edge = np.inf if k == len(peaks) - 1 else float(self.z[b])
                out.append((float(self.z[i]), mass, lo_edge, hi_edge))
        return sorted(out, key=lambda m: -m[1])

    def z_summary(self, level: float = LEVEL) -> MixtureSummary:
        """Marginal of z_surf [m]: mean, sd and the equal-tailed interval from the node masses
        with the E* prior's factor (:meth:`prior_factor`)."""
        lm = self.log_mass + self.prior_factor()
        w = np.exp(logsumexp(lm - np.max(lm), axis=1))
        w /= w.sum()
        mean = float(w @ self.z)
        sd = float(np.sqrt(max(w @ (self.z - mean) ** 2, 0.0)))
        cdf = np.cumsum(w) - 0.5 * w
        q = np.interp([(1 - level) / 2, 0.5, (1 + level) / 2], cdf, self.z)
        return MixtureSummary(mean, sd, float(q[1]), float(q[0]), float(q[2]), level)

    def draws(self, rng: np.random.Generator, n: int) -> dict[str, np.ndarray]:
        """``n`` posterior draws under the priors of the module docstring.

        A (phi node, surface interval) pair is drawn by its mass, z_s within the interval from
        the log-linear interpolation of the density between its two nodes, and the conditional
        centre and scale are interpolated linearly there; then tau² and β from their
        conditionals under the flat E* prior.  The log-uniform E* prior is applied by sampling
        importance resampling from :data:`PROPOSALS`·n proposals: E* is drawn from its
        conditional normal truncated to the prior range (the others given E*), with weights
        P(range)/E*.
        """
        m = PROPOSALS * n
        adj = self.prior_factor()
        lp = self.post.logp + adj
        lp = np.where(np.isfinite(lp), lp, -np.inf)
        a, b = lp[:-1], lp[1:]                      # (G-1, H) interval ends
        dz = np.diff(self.z)[:, None]
        with np.errstate(invalid="ignore"):
            delta = b - a
        ok = np.isfinite(a) & np.isfinite(b)
        ad = np.abs(np.where(ok, delta, 0.0))
        # log ∫ exp(a + delta·t) dz over the interval = max(a, b) + log(dz·(1 − e^−|δ|)/|δ|)
        with np.errstate(divide="ignore"):
            shape_term = np.where(ad < 1e-8, 0.0,
                                  np.log(-np.expm1(-ad) / np.maximum(ad, 1e-300)))
        log_int = np.where(ok, np.maximum(a, b) + shape_term + np.log(dz), -np.inf)
        log_int = log_int + np.log(cell_widths(self.phi))[None, :]
        mass = np.exp(log_int - np.max(log_int)).ravel()
        flat = rng.choice(mass.size, size=m, p=mass / mass.sum())
        gi, hj = np.unravel_index(flat, log_int.shape)
        d, v = delta[gi, hj], rng.random(m)
        with np.errstate(invalid="ignore", over="ignore", divide="ignore"):
            t = np.where(np.abs(d) < 1e-8, v, np.log1p(v * np.expm1(d)) / d)
        t = np.clip(np.nan_to_num(t, nan=0.5), 0.0, 1.0)
        z = self.z[gi] + t * dz[gi, 0]
        phi_node = self.phi[hj]
        phi = phi_node
        if self.phi.size > 1:  # uniform within the node's trapezoid cell, inside the prior
            left = np.r_[0.0, np.diff(self.phi)][hj] / 2
            right = np.r_[np.diff(self.phi), 0.0][hj] / 2
            phi = phi_node - left + rng.random(m) * (left + right)
        at, above = gi * self.phi.size + hj, (gi + 1) * self.phi.size + hj  # flat (G·H) rows

        def lerp(x: np.ndarray) -> np.ndarray:  # x (G, H, ...) at z, linear between nodes
            flat = x.reshape((-1,) + x.shape[2:])
            a, b = flat.take(at, axis=0), flat.take(above, axis=0)
            return a + t.reshape((-1,) + (1,) * (x.ndim - 2)) * (b - a)

        centre, cov, S = lerp(self.post.beta), lerp(self.post.scale), lerp(self.post.S)
        nu = self.post.nu
        chi = rng.chisquare(nu, m) / nu  # multivariate t: normal / sqrt(chi²/nu)
        cov = cov / chi[:, None, None]
        tau = np.sqrt(S / (nu * chi))
        # E* from its conditional normal truncated to the prior range, the others given E*
        lo, hi = np.exp(self.prior.bounds["log_Estar"])
        mu0, sd0 = centre[:, 0], np.sqrt(cov[:, 0, 0])
        a, b = (lo - mu0) / sd0, (hi - mu0) / sd0
        x, log_mass = _truncated_draws(rng, a, b)
        estar = mu0 + sd0 * x
        c_r0 = cov[:, 1:, 0]
        rest_mean = centre[:, 1:] + c_r0 / cov[:, :1, 0] * (estar - mu0)[:, None]
        rest_cov = cov[:, 1:, 1:] - np.einsum("mi,mj->mij", c_r0, c_r0) / cov[:, 0, 0, None, None]
        rest = rest_mean + np.einsum("mij,mj->mi", np.linalg.cholesky(rest_cov),
                                     rng.standard_normal((m, centre.shape[1] - 1)))
        beta = np.column_stack([estar, rest])
        # importance weight: the truncation's probability (how much of the proposal's
        # conditional lies inside the range) times the log-uniform prior's 1/E*
        log_w = log_mass - np.log(estar) - lerp(adj)
        if not np.isfinite(log_w).any():
            raise InputError(f"exact engine: the posterior of E* has no mass inside its prior "
                             f"range [{format_pressure(lo)}, {format_pressure(hi)}]; the "
                             "force does not rise with depth there: check units and sign, or "
                             "widen the E* prior (PriorSpec.Estar_bounds)")
        w = np.exp(log_w - np.max(log_w[np.isfinite(log_w)]))
        w = np.where(np.isfinite(w), w, 0.0)
        pick = rng.choice(m, size=n, p=w / w.sum())
        out = {"E_star": estar[pick], "z_surf": z[pick],
               "sigma": tau[pick] / np.sqrt(1.0 - phi_node[pick] ** 2), "F0": beta[pick, 1]}
        if beta.shape[1] > 2:
            out["F1"] = beta[pick, 2]
        if self.phi.size > 1:
            out["phi"] = phi[pick]
        return out


def sampled_coordinates(draws: dict[str, np.ndarray], names: tuple[str, ...] | list[str]
                        ) -> dict[str, np.ndarray]:
    """The exact engine's draws (:meth:`ExactPosterior.draws`) in the coordinates emcee
    samples: ``log_Estar``, ``z_surf``, ``log_sigma``, ``F0`` and, when in ``names``, ``F1``
    and ``phi`` (the prior's parameter names, :attr:`TracePrior.names`)."""
    theta = {"log_Estar": np.log(draws["E_star"]), "z_surf": draws["z_surf"],
             "log_sigma": np.log(draws["sigma"]), "F0": draws["F0"], "F1": draws.get("F1"),
             "phi": draws.get("phi")}
    return {n: theta[n] for n in names}


def phi_grid(bounds: tuple[float, float], n: int = PHI_NODES) -> np.ndarray:
    """The first phi nodes: uniform on the prior's support, both bounds included (the
    trapezoid cells then cover the whole prior)."""
    return np.linspace(bounds[0], bounds[1], n)


def phi_moments(values: np.ndarray, logp_phi: np.ndarray) -> tuple[float, float]:
    """Mean and sd of a phi density known at sorted ``values`` (log density ``logp_phi``),
    by the trapezoid rule."""
    w = np.exp(logp_phi - logp_phi.max()) * cell_widths(values)
    w /= w.sum()
    mean = float(w @ values)
    return mean, float(np.sqrt(max(w @ (values - mean) ** 2, 0.0)))


def phi_nodes_around(values: np.ndarray, logp_phi: np.ndarray, bounds) -> np.ndarray:
    """A finer phi grid around a phi density known at ``values`` (log density ``logp_phi``):
    its mean ± 8 sd, cut to the prior's ``bounds``, in steps of sd/4 (9 to 65 nodes; the sd
    is at least an eighth of the smallest step of ``values``)."""
    mean, sd = phi_moments(values, logp_phi)
    step = np.diff(values).min()
    sd = max(sd, step / 8)
    lo, hi = max(bounds[0], mean - 8 * sd), min(bounds[1], mean + 8 * sd)
    k = int(np.clip(np.ceil((hi - lo) / (sd / 4)), 9, 65))
    return np.linspace(lo, hi, k)


def exact_posterior(data: FitData, prior: TracePrior, coarse: int = COARSE_NODES,
                    nodes: np.ndarray | None = None) -> ExactPosterior:
    """The exact posterior of one prepared trace (module docstring); ``coarse`` uniform
    surface nodes to start the refinement from (:func:`refine_grid`), or the surface
    ``nodes`` [m] given (e.g. those a similar model's posterior refined to, as the layer
    mixture's neighbouring thicknesses do, :mod:`palpbayes.bayes.layers`): the refinement
    rule then adds nodes wherever this posterior needs them, so that the result meets the
    same tolerances with fewer refinement rounds.

    Raises
    ------
    InputError
        For Student-t noise or the soft surface prior (use the emcee engine).
    """
    if prior.noise not in EXACT_NOISE_MODELS:
        raise InputError(f"the exact engine handles noise "
                         f"{' or '.join(map(repr, EXACT_NOISE_MODELS))}, not "
                         f"{prior.noise!r}; use --engine emcee")
    if prior.spec.surface != "loading":
        raise InputError("the exact engine takes the surface prior 'loading' only (the soft "
                         "constraint is not conjugate); use --engine emcee")
    ar1 = prior.noise == "ar1"
    linear = prior.baseline == "linear"
    u = (data.z - prior.z_ref) if linear else None
    y = data.force - prior.f0_center  # centred: less cancellation in S
    weights = (prior.sigma_center / np.array([prior.f0_sd] + ([prior.f1_sd] if linear
                                                                else []))) ** 2
    centers = np.zeros(weights.size)
    phi = phi_grid(prior.spec.phi_bounds) if ar1 else np.zeros(1)
    grams: list[Gram] = []

    lo, hi = prior.z_bounds
    d_max = hi - float(np.min(data.z))  # one shape table for every round of the refinement

    def evaluate(nodes: np.ndarray) -> np.ndarray:
        g = gram(data.z, y, nodes, data.model, u, ar1, d_max)
        grams.append(g)
        lp = node_posterior(g, phi, weights, centers).logp
        return log_marginal_phi(lp, phi)

    start = None
    if nodes is not None:
        first = np.unique(np.clip(np.asarray(nodes, dtype=float), lo, hi))
        start = (first, evaluate(first))
    nodes, _, complete = refine_grid(lo, hi, evaluate, coarse=coarse, start=start)
    g = grams[0]
    for other in grams[1:]:
        g = g.concat(other)
    if ar1:  # a finer phi grid around its marginal, then the nodes again
        post = node_posterior(g, phi, weights, centers)
        zw = cell_widths(g.z)
        lp_phi = logsumexp(post.logp + np.log(zw)[:, None], axis=0)
        phi = phi_nodes_around(phi, lp_phi, prior.spec.phi_bounds)
    post = node_posterior(g, phi, weights, centers)
    if not np.isfinite(post.logp).any():
        raise InputError(
            f"exact engine: no surface height in [{format_length(lo)}, {format_length(hi)}] "
            f"has {post.beta.shape[-1] + 1} or more samples in contact with a positive "
            "residual; the trace has (almost) no contact: check the recording and its units")
    post.beta[..., 1] += prior.f0_center
    return ExactPosterior(z=g.z, phi=phi, post=post, log_mass=node_log_mass(post.logp, g.z, phi),
                          complete=complete,
                          prior=prior)


def node_log_mass(logp: np.ndarray, z: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """Normalised log mass (G, H) of each node's trapezoid cell from its log density."""
    log_cell = logp + np.log(cell_widths(z))[:, None] + np.log(cell_widths(phi))[None, :]
    return log_cell - logsumexp(log_cell)


def log_marginal_phi(lp: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """log ∫ p(z, phi) dphi on the phi nodes (the value itself for iid noise)."""
    if phi.size == 1:
        return lp[:, 0]
    return logsumexp(lp + np.log(cell_widths(phi))[None, :], axis=1)

