"""emcee engine of the viscoelastic fit: every parameter sampled, the grid engine's posterior.

The grid engine (:mod:`~palpbayes.rheology.posterior`) integrates the moduli, offset, drag and
noise scale in closed form.  This module samples the *same* posterior with emcee, every
parameter explicit: the proof that the collapse is right.  Block means i = 1..N in time order::

    F_i = Σ_j E_j·X_ij(z_s, θ) + F0 [+ b·v_i] [+ F1·(z_i − z_ref)] + e_i,  e_1 ~ N(0, sigma²),
    e_i = phi·e_{i−1} + w_i,   w_i ~ N(0, s²),   s = sigma·sqrt(1 − phi²),

X the modulus columns of :meth:`NodeEvaluator.columns
<palpbayes.rheology.posterior.NodeEvaluator.columns>` (power law: E0*, θ = alpha; standard
linear solid: E_inf*, E1*, θ = tau; elastic: E*, no θ), v the blocks' downward speed, z_ref
the baseline's height.  Exact likelihood (:func:`ar1_log_likelihood`), r = F − mean::

    log L = −(N/2)·log(2π·s²) + ½·log(1 − phi²)
            − [(1 − phi²)·r_1² + Σ_{i>=2} (r_i − phi·r_{i−1})²] / (2·s²).

Priors, the grid's (:func:`~palpbayes.bayes.conjugate.node_posterior`): alpha U[0,
ALPHA_MAX]; tau log-uniform on [dt/10, 100·span]; z_s U[z_lo, z_hi] with more than p block
means in contact (p linear coefficients); phi U[PHI_BOUNDS]; F0 ~ N(f0_center,
(OFFSET_SD·sigma)²); Jeffreys 1/s on the innovation sd (p(sigma, phi) = 1/sigma: flat in
log sigma); 1/E on E0*, E1* and E*, flat on E_inf* >= 0, b and F1.  Coordinates: log moduli,
alpha or log tau, z_s, F0 − f0_center, b, F1, log sigma, phi, standardised (affine).

Start and speed.  The walkers start at distinct draws of the grid engine (``grid``, or
:func:`~palpbayes.rheology.posterior.grid_posterior` run here), phi spread over its cell:
legitimate (any start inside the posterior is), with a short burn-in.  A direct evaluation
of the columns builds a K² kernel matrix (30–140 ms for 700 block means on shared cores), too
slow for a chain, so they are tabulated once (:class:`~palpbayes.rheology.column_table.
ColumnTable`): Chebyshev interpolation, ``N_THETA`` nodes in alpha or log tau × up to ``N_Z``
per z_s panel, on a box holding
the start draws with :data:`BOX_PAD` sd to spare.  Panels end where the columns bend (the
surface at a knot's or a sample's height); within one they are analytic in θ (Ting's t1 bends
them slightly in alpha) and smooth in z_s.  ``table_error``, |Δ log L| against the direct
columns at :data:`N_CHECK` start draws, is measured <= 4e-3 (nodes doubled once above
:data:`TABLE_TOL`); proposals outside the box are evaluated directly (``n_direct``).

Moves: 50 % ``DEMove`` (differential evolution, affine invariant), 50 % an independence
Metropolis–Hastings move from a t fitted to the start draws, folded into the box at its bounds
(exact through its Hastings factor): autocorrelation times of 5–10 steps against 20–30 for
``DEMove`` alone.  Stopping
and seeding: :func:`palpbayes.bayes.sampler.run_emcee` (50 tau, tau steady, bulk and tail ESS
>= 400, R-hat <= 1.05 on every parameter and the log posterior as a guard, and ``n_draws`` thinned
draws; or ``n_steps``).  Diagnostics: arviz, walkers as chains.

Not here: the SLS on the retract (Ting's t1 depends on E1*/E_inf*: the force is not linear
in the moduli, the grid gives no start and the table would need a third axis); refused.
"""

# Long module: one job, the viscoelastic emcee engine; its target and independence move are
#   private to sample_emcee.

from __future__ import annotations

import math
import time
import warnings
from dataclasses import dataclass, field

import emcee
import numpy as np

from ..bayes.diagnostics import Diagnostics, chain_passes, compute_diagnostics, import_arviz
from ..bayes.sampler import SamplerSettings, run_emcee
from ..errors import FitError, InputError
from .column_table import N_THETA, N_Z, ColumnTable
from .cycle import CycleData
from .posterior import (
    NUISANCE,
    OFFSET_SD,
    PHI_BOUNDS,
    RHEOLOGIES,
    GridPosterior,
    NodeEvaluator,
    grid_posterior,
)
from .ting import RETRACT

__all__ = ["EmceeRheology", "sample_emcee", "ar1_log_likelihood", "BOX_PAD", "TABLE_TOL",
           "N_CHECK", "INDEPENDENCE"]

#: The table's box: the start draws' range widened by this many of their sd on each side.
BOX_PAD = 4.0
#: Largest |log L(table) − log L(direct)| at the check points before the table is refined.
TABLE_TOL = 0.05
#: Start draws at which the table is checked against direct evaluation.
N_CHECK = 3
#: Share of the independence move (the rest DEMove), its t's degrees of freedom and width.
INDEPENDENCE, T_DF, T_INFLATE = 0.5, 8.0, 1.1
#: Coordinates sampled as logarithms.
_LOG = ("E0", "E_inf", "E1", "E", "tau", "sigma")


def ar1_log_likelihood(resid: np.ndarray, sigma, phi) -> np.ndarray:
    """Exact log density of residuals ``resid`` (..., N) [N] under stationary AR(1) Gaussian
    noise of marginal sd ``sigma`` [N] and lag-one correlation ``phi`` (both broadcast
    against ``resid[..., 0]``): the first point at the marginal variance, then the
    conditional terms (module docstring)."""
    r = np.asarray(resid, dtype=float)
    sigma, phi = np.asarray(sigma, dtype=float), np.asarray(phi, dtype=float)
    one_m = 1.0 - phi**2
    s2 = sigma**2 * one_m
    e = r[..., 1:] - phi[..., None] * r[..., :-1]
    q = one_m * r[..., 0] ** 2 + np.einsum("...i,...i->...", e, e)
    return (-0.5 * r.shape[-1] * np.log(2 * math.pi * s2) + 0.5 * np.log(one_m)
            - 0.5 * q / s2)


class _Target:
    """log posterior of the standardised coordinates (module docstring), vectorised."""

    def __init__(self, table: ColumnTable, names: list[str], bounds, centre, scale):
        self.ev, self.table, self.c_bounds = table.ev, table, bounds
        self.k = len(table.moduli)
        self.j = names.index("z_surf")  # after the moduli and theta (if any)
        self.flat = names[0] == "E_inf"  # flat on E_inf*: its log's Jacobian
        self.centre, self.scale = centre, scale
        self.z_sorted = np.sort(self.ev.data.z)

    def unpack(self, x: np.ndarray) -> dict[str, np.ndarray]:
        """Natural parameters of coordinates ``x`` (W, ndim), not standardised."""
        k, j = self.k, self.j
        return {"moduli": np.exp(x[:, :k]), "c": x[:, k] if j > k else np.zeros(x.shape[0]),
                "z": x[:, j], "o": x[:, j + 1], "extra": x[:, j + 2:-2],
                "sigma": np.exp(x[:, -2]), "phi": x[:, -1]}

    def log_likelihood(self, v: dict, X: np.ndarray) -> np.ndarray:
        mean = (np.einsum("wnk,wk->wn", X, v["moduli"]) + v["o"][:, None]
                + np.einsum("wm,nm->wn", v["extra"], self.table.fixed))
        return ar1_log_likelihood(self.ev.y[None, :] - mean, v["sigma"], v["phi"])

    def __call__(self, u: np.ndarray) -> np.ndarray:
        x = self.centre + np.atleast_2d(u) * self.scale
        v, d = self.unpack(x), self.ev.data
        ok = ((v["c"] >= self.c_bounds[0]) & (v["c"] <= self.c_bounds[1])
              & (v["z"] >= d.z_lo) & (v["z"] <= d.z_hi) & (v["phi"] >= PHI_BOUNDS[0])
              & (v["phi"] <= PHI_BOUNDS[1]) & np.all(np.isfinite(x), axis=1)
              & (np.searchsorted(self.z_sorted, v["z"]) > len(self.ev.names)))
        out = np.full(x.shape[0], -np.inf)
        if ok.any():
            w = {key: val[ok] for key, val in v.items()}
            scale = OFFSET_SD * w["sigma"]  # F0's prior
            prior = (-np.log(scale) - 0.5 * (w["o"] / scale) ** 2
                     + (np.log(w["moduli"][:, 0]) if self.flat else 0.0))
            out[ok] = self.log_likelihood(w, self.table.columns(w["c"], w["z"])) + prior
        return out


def _independence_move(start: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> emcee.moves.MHMove:
    """Metropolis–Hastings move proposing every walker afresh from a multivariate t
    (:data:`T_DF` degrees of freedom, the mean and :data:`T_INFLATE`² × the covariance of
    ``start`` (n, ndim)) folded into the box [``lo``, ``hi``]: a coordinate beyond a bound is
    reflected back once (a posterior that piles up at a bound, as phi does on most real
    records, would otherwise lose half its proposals), and a draw still outside proposes to
    stay.  The proposal density at x is then the sum of the t over x's mirror images (one
    per bound and coordinate, each optional); the Hastings factor log g(x) − log g(x')
    (−inf from a walker outside) keeps the move exact."""
    mu, d = start.mean(axis=0), start.shape[1]
    S = np.atleast_2d(np.cov(start, rowvar=False)) * T_INFLATE**2
    L = np.linalg.cholesky(S + 1e-12 * np.trace(S) * np.eye(d))
    L_inv = np.linalg.inv(L)  # triangular: the Mahalanobis coordinates by one product
    # the mirror images of x as sign·x + shift, one row per image: each coordinate as it is
    # or reflected at one of its finite bounds, every combination
    sign, shift = np.ones((1, d)), np.zeros((1, d))
    for j in range(d):
        n = sign.shape[0]  # the images so far, each reflected at each bound of j
        for b in (lo[j], hi[j]):
            if np.isfinite(b):
                s_j, c_j = sign[:n].copy(), shift[:n].copy()
                s_j[:, j], c_j[:, j] = -s_j[:, j], 2 * b - c_j[:, j]
                sign, shift = np.r_[sign, s_j], np.r_[shift, c_j]
    sign, shift = sign[:, None, :], (shift - mu)[:, None, :]
    scale = -0.5 * (T_DF + d)

    def log_g(x):
        q = (sign * x[None] + shift) @ L_inv.T  # (images, walkers, ndim), standardised
        lt = scale * np.log1p(np.einsum("iwk,iwk->iw", q, q) / T_DF)
        top = lt.max(axis=0)  # log-sum-exp over the images (scipy's costs 10x the rest)
        total = top + np.log(np.exp(lt - top).sum(axis=0))
        inside = np.all((x >= lo) & (x <= hi), axis=1)
        return np.where(inside, total, -np.inf)

    def propose(coords, random):
        z = random.standard_normal(coords.shape) @ L.T
        new = mu + z / np.sqrt(random.chisquare(T_DF, coords.shape[0]) / T_DF)[:, None]
        new = np.where(new > hi, 2 * hi - new, np.where(new < lo, 2 * lo - new, new))
        out = ~np.all((new >= lo) & (new <= hi), axis=1)
        new[out] = coords[out]
        with np.errstate(invalid="ignore"):
            factor = np.where(out, 0.0, log_g(coords) - log_g(new))
        return new, np.nan_to_num(factor, nan=-np.inf)

    move = emcee.moves.MHMove(propose)
    move.log_density = log_g  # the proposal's density up to a constant (tests)
    return move


@dataclass
class EmceeRheology:
    """A viscoelastic posterior sampled by emcee.

    Attributes
    ----------
    rheology
        The relaxation model (t0, drag and tilt: ``grid``'s).
    draws
        Joint draws, the keys and units of :meth:`GridPosterior.draws
        <palpbayes.rheology.posterior.GridPosterior.draws>`: moduli E* [Pa] (``E0``, or
        ``E_inf`` and ``E1``), ``alpha`` [-] or ``tau`` [s], ``z_surf`` [m], ``offset`` [N],
        ``sigma`` [N] (marginal noise sd of a block mean), ``phi``, ``drag`` [N·s/m],
        ``tilt`` [N/m] (with those terms); no ``"ess"``.
    chains
        The same, (walkers, draws) after burn-in and thinning; ``idata`` as arviz
        ``InferenceData`` (``sample_stats.lp``: the log posterior).
    diagnostics
        arviz R-hat (``"lp"``: the log posterior's), bulk and tail ESS, autocorrelation times
        [steps], acceptance fraction, steps run, step cap hit.
    grid
        The grid posterior the walkers started from.
    n_walkers, burn, thin
        Ensemble size, steps discarded, thinning.
    n_direct, table_error
        Evaluations outside the column table; largest |Δ log L| of the table at the checks.
    seconds, seconds_start
        [s] Wall time of the call, and of it the grid start (~0 with ``grid`` given).
    table
        The column table the chain used (:class:`~palpbayes.rheology.column_table.
        ColumnTable`): the fit's force curves of the draws come from it.
    """

    rheology: str
    draws: dict[str, np.ndarray]
    chains: dict[str, np.ndarray]
    diagnostics: Diagnostics
    idata: object
    grid: GridPosterior
    n_walkers: int
    burn: int
    thin: int
    n_direct: int
    table_error: float
    seconds: float
    seconds_start: float
    table: ColumnTable | None = field(default=None, repr=False)

    @property
    def rhat(self) -> dict[str, float]:
        """R-hat per parameter (``"lp"``: the log posterior's)."""
        return self.diagnostics.rhat

    @property
    def ess(self) -> dict[str, float]:
        """Bulk ESS per parameter (tail ESS, tau, acceptance: :attr:`diagnostics`)."""
        return self.diagnostics.ess_bulk

    @property
    def converged(self) -> bool:
        """ESS >= 400, R-hat <= 1.05, the stopping rule met, the table within tolerance."""
        return self.diagnostics.converged and self.table_error <= TABLE_TOL

    def problems(self) -> list[str]:
        """Why :attr:`converged` is False (empty when it is True)."""
        out = self.diagnostics.problems()
        if not self.table_error <= TABLE_TOL:
            out.append(f"column table off by {self.table_error:.3g} in log density")
        return out


def _names(ev: NodeEvaluator) -> list[str]:
    """Parameter names in the order of the sampled coordinates."""
    theta = RHEOLOGIES[ev.rheology]
    return ([n for n in ev.names if n not in NUISANCE] + ([theta] if theta else [])
            + ["z_surf", "offset"] + [n for n in ev.names if n in NUISANCE and n != "offset"]
            + ["sigma", "phi"])


def _natural(x: np.ndarray, names: list[str], f0: float) -> dict[str, np.ndarray]:
    return {name: (np.exp(x[..., j]) if name in _LOG else
                   x[..., j] + f0 if name == "offset" else x[..., j])
            for j, name in enumerate(names)}


def _start(grid: GridPosterior, names: list[str], gen: np.random.Generator, n: int
           ) -> np.ndarray:
    """``n`` grid draws as coordinates (n, ndim), phi spread uniformly over its grid cell."""
    draws = grid.draws(gen, n)
    h = float(np.diff(grid.phi).mean())
    cols = []
    for k in names:
        v = np.asarray(draws[k], dtype=float)
        if k in _LOG:
            v = np.log(v)
        elif k == "offset":
            v = v - grid.data.f0_center
        elif k == "phi":
            lo, hi = PHI_BOUNDS  # reflected into the prior: the end nodes' half cells
            v = hi - np.abs(hi - lo - np.abs(v + gen.uniform(-h / 2, h / 2, n) - lo))
        cols.append(v)
    return np.column_stack(cols)


# Many parameters: one cycle's model switches (drag, tilt, t0) and emcee's run (walkers, steps,
# draws), each with a default.
def sample_emcee(data: CycleData, rheology: str = "power-law", *, t0: float = 1.0,
                 drag: bool = False, tilt: bool = False, n_draws: int = 4000, rng=0,
                 n_walkers: int = 32, n_steps: int = 6000, progress: bool | None = None,
                 grid: GridPosterior | None = None) -> EmceeRheology:
    """Sample the viscoelastic posterior of ``data`` with emcee (module docstring).

    Parameters
    ----------
    data
        Block means of the cycle (:func:`~palpbayes.rheology.cycle.prepare_cycle`).
    rheology, t0
        A model of :data:`~palpbayes.rheology.posterior.RHEOLOGIES`: ``"power-law"`` (E0*
        [Pa], alpha), ``"sls"`` (E_inf*, E1* [Pa], tau [s]; not on the retract), ...;
        [s] the power law's reference time.
    drag, tilt
        Fit a drag b·(−dz/dt) [N·s/m]; a baseline F1·(z − z_ref) [N/m] (flat priors).
    n_draws
        Joint draws returned, from the thinned chain (with replacement only if the step cap
        left fewer).
    rng
        Seed (int, SeedSequence) or Generator: the same seed gives the same draws.
    n_walkers, n_steps
        Ensemble size (>= 2·ndim); step cap (the stopping rule usually ends sooner).
    progress
        tqdm progress bar; None: only when stderr is a terminal.
    grid
        The grid posterior of this ``data`` and model (a fit's) to start from; computed here
        when None.

    Raises
    ------
    InputError
        Unknown rheology, the SLS with a retract, a ``grid`` of another model, bad settings.
    FitError
        A start draw without a finite posterior (report the record).
    """
    start = time.perf_counter()
    if rheology not in RHEOLOGIES:
        raise InputError(f"unknown rheology {rheology!r}; use one of {', '.join(RHEOLOGIES)}")
    if rheology == "sls" and np.any(data.segment == RETRACT):
        raise InputError("the SLS is not sampled on the retract: Ting's t1 depends on "
                         "E1*/E_inf*, so the force is not linear in the moduli; fit the "
                         "approach and hold, or the power law")
    ev = NodeEvaluator(data, rheology, t0, drag, tilt)
    names = _names(ev)
    for label, value, least in (("n_walkers", n_walkers, 2 * len(names)),
                                ("n_draws", n_draws, 1), ("n_steps", n_steps, 100)):
        if not (isinstance(value, int | np.integer) and value >= least):
            raise InputError(f"{label} = {value!r} must be a whole number >= {least}")
    if isinstance(rng, np.random.Generator):
        rng = int(rng.integers(2**63))
    seeds = (rng if isinstance(rng, np.random.SeedSequence)
             else np.random.SeedSequence(rng)).spawn(3)
    if grid is None:
        grid = grid_posterior(data, rheology, t0=t0, drag=drag, tilt=tilt)
    elif (grid.data is not data or grid.rheology != rheology or grid.t0 != t0
          or grid.names != ev.names):
        raise InputError("grid= is the posterior of another record or model")
    seconds_start = time.perf_counter() - start
    gen = np.random.default_rng(seeds[0])
    x = _start(grid, names, gen, max(4 * n_walkers, 2000))
    centre, scale = x.mean(axis=0), x.std(axis=0)
    scale = np.where(scale > 0, scale, np.maximum(np.abs(centre) * 1e-9, 1e-15))
    bounds = tuple(float(np.log(b) if rheology == "sls" else b) for b in grid.bounds)
    lo, hi = np.full(len(names), -np.inf), np.full(len(names), np.inf)
    box = [(names.index("z_surf"), (data.z_lo, data.z_hi))]
    if grid.theta_name is not None:
        box.append((names.index(grid.theta_name), bounds))
    for j, (a, b) in box:
        lo[j] = max(a, x[:, j].min() - BOX_PAD * scale[j])
        hi[j] = min(b, x[:, j].max() + BOX_PAD * scale[j])
    (jz, _), (jc, _) = box[0], box[-1]
    c_box = (lo[jc], hi[jc]) if len(box) > 1 else (0.0, 0.0)
    pick = gen.choice(x.shape[0], size=n_walkers, replace=False)
    for refine in (1, 2):
        table = ColumnTable(ev, c_box, (lo[jz], hi[jz]), N_THETA * refine if len(box) > 1
                            else 1, N_Z * refine)
        target = _Target(table, names, bounds, centre, scale)
        v = target.unpack(x[pick[:N_CHECK]])
        direct = np.stack([table.direct(c, z) for c, z in zip(v["c"], v["z"], strict=True)])
        table_error = float(np.max(np.abs(
            target.log_likelihood(v, table.columns(v["c"], v["z"]))
            - target.log_likelihood(v, direct))))
        table.n_direct = 0
        if table_error <= TABLE_TOL:
            break
    pool = (x[np.r_[pick, np.setdiff1d(np.arange(x.shape[0]), pick)[:3 * n_walkers]]]
            - centre) / scale  # the picks, then spares for those at a bound
    p0 = pool[np.isfinite(target(pool))][:n_walkers]
    if p0.shape[0] < n_walkers:
        raise FitError("the grid's draws have no finite posterior under the emcee model; "
                       "report this record")
    lo[-1], hi[-1] = PHI_BOUNDS
    moves = [(_independence_move((x - centre) / scale, (lo - centre) / scale,
                                 (hi - centre) / scale), INDEPENDENCE)]
    settings = SamplerSettings(n_walkers=int(n_walkers), max_steps=int(n_steps),
                               min_steps=min(300, int(n_steps)), check_every=100,
                               moves="de", progress=progress)
    res = run_emcee(target, p0, settings, int(seeds[1].generate_state(1)[0]),
                    accept=lambda c, lp: c.shape[0] * c.shape[1] >= n_draws
                    and chain_passes(c, lp), extra_moves=moves)
    xs = centre + res.samples * scale  # (walkers, draws, ndim)
    chains = _natural(xs, names, data.f0_center)
    flat = xs.reshape(-1, xs.shape[-1])
    keep = np.random.default_rng(seeds[2]).choice(flat.shape[0], size=n_draws,
                                                  replace=flat.shape[0] < n_draws)
    az = import_arviz()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        idata = az.from_dict(posterior=chains, sample_stats={"lp": res.log_prob})
    diag = compute_diagnostics(idata, names, res.tau, res.acceptance, res.n_steps, res.hit_cap)
    return EmceeRheology(rheology, _natural(flat[keep], names, data.f0_center), chains, diag,
                         idata, grid, int(n_walkers), res.burn, res.thin,
                         table.n_direct, table_error, time.perf_counter() - start,
                         seconds_start, table)
