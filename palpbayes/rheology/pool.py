"""One material, several speeds: the power law's (E0*, alpha) pooled over palpations.

Traces of one specimen at different speeds share the relaxation modulus E*(t) =
E0*·(t/t0)^(−alpha); each keeps its own surface, offset and AR(1) noise.  With flat priors on
the per-trace nuisances the pooled posterior is the product of each trace's likelihood of
(E0*, alpha) with those integrated out, times the prior (log-uniform E0*, uniform alpha):

    p(E0*, alpha | all) ∝ p(E0*)·Π_i L_i(E0*, alpha).

Each L_i comes from the trace's own collapse (:class:`~palpbayes.rheology.posterior.
NodeEvaluator`): on every (alpha, surface, phi) node the modulus' conditional posterior under
a flat prior is Student-t (location, scale and degrees of freedom in closed form), so

    L_i(E0*, alpha) = Σ_{z, phi} p(y_i | alpha, z, phi)·t_nu(E0*; beta0, s0)·Δz·Δphi,

evaluated on one (alpha × E0*) grid for all traces (the surface nodes follow each trace's
own tilted ridge, extended linearly in alpha).  The apparent elastic modulus of a ramp then
scales as speed^alpha (:meth:`~palpbayes.rheology.fit.RheologyFit.apparent_modulus`), which
is what several speeds measure.  A trace whose own (E0*, alpha) lies more than
:data:`DISAGREE_SD` of its own posterior sd from the pooled medians is flagged: one power law
does not describe it with the others (another material, or rate dependence beyond a power law).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from scipy.special import gammaln, logsumexp

from ..bayes.exact import cell_widths
from ..errors import InputError
from ..intervals import LEVEL, central_band
from .fit import RheologyFit
from .grid_search import FINE, SPAN_SD
from .posterior import ALPHA_MAX, NodeEvaluator

__all__ = ["PooledPowerLaw", "pool_rheology", "DISAGREE_SD"]

#: A trace is flagged when its own E0* or alpha median is this many of its own sd from the
#: pooled median.
DISAGREE_SD = 4.0


@dataclass
class PooledPowerLaw:
    """The pooled posterior: grid ``alpha`` (A,), ``E0`` (E,) [Pa] and normalised ``log_mass``
    (A, E); ``draws`` of E0 [Pa] and alpha; the pooled traces' ids; ``t0`` [s]; ``flags`` one
    line each."""

    alpha: np.ndarray
    E0: np.ndarray
    log_mass: np.ndarray
    draws: dict[str, np.ndarray]
    trace_ids: list[str]
    t0: float
    flags: list[str] = field(default_factory=list)

    def table(self, level: float = LEVEL) -> pd.DataFrame:
        """``E0*`` [Pa] and ``alpha``: median and central ``level`` interval."""
        rows = []
        for name, label, unit in (("E0", "E0*", "Pa"), ("alpha", "alpha", "-")):
            lo, med, hi = central_band(self.draws[name], level)
            rows.append({"parameter": label, "unit": unit, "median": med, "lo": lo, "hi": hi})
        out = pd.DataFrame(rows)
        out.attrs.update(level=level, t0_s=self.t0, traces=len(self.trace_ids))
        return out


#: Nodes per pooled standard deviation at which the grid stops zooming.
ZOOM_NODES = 3.0


def _log_t(x: np.ndarray, loc: np.ndarray, scale: np.ndarray, nu: int) -> np.ndarray:
    """log Student-t density of ``x`` with location, scale and ``nu`` degrees of freedom."""
    z = (x - loc) / scale
    return (gammaln(0.5 * (nu + 1)) - gammaln(0.5 * nu) - 0.5 * math.log(nu * math.pi)
            - np.log(scale) - 0.5 * (nu + 1) * np.log1p(z * z / nu))


def _surface_rows(fit: RheologyFit, alpha: np.ndarray) -> np.ndarray:
    """(A, FINE) surface nodes at every alpha: the fit's tilted ridge (its grid's centre line,
    extended linearly in alpha) ± 1.5 times its rows' half-width (±9 conditional sd), clipped
    to the surface prior."""
    g = fit.grid
    centre = g.z.mean(axis=1)
    width = float(np.mean(g.z.max(axis=1) - g.z.min(axis=1)))
    slope, icept = np.polyfit(g.theta, centre, 1) if g.theta.size > 1 else (0.0, centre[0])
    mid = icept + slope * alpha
    rows = mid[:, None] + np.linspace(-0.75, 0.75, FINE)[None, :] * width
    return np.clip(rows, fit.data.z_lo, fit.data.z_hi)


def _pooled_log(fits: Sequence[RheologyFit], evaluators: Sequence[NodeEvaluator],
                alpha: np.ndarray, e0: np.ndarray) -> np.ndarray:
    """Σ_i log L_i(E0*, alpha) + log prior on the (alpha × E0*) grid (module docstring)."""
    total = np.zeros((alpha.size, e0.size))
    for f, ev in zip(fits, evaluators, strict=True):
        rows = _surface_rows(f, alpha)
        _, post = ev.logp_rows(alpha, rows)
        H = ev.phi.size
        logp = post.logp.reshape(alpha.size, FINE, H)
        cells = np.stack([np.log(cell_widths(r)) for r in rows])[:, :, None]
        w = logp + cells + np.log(cell_widths(ev.phi))[None, None, :]
        loc = post.beta[..., 0].reshape(alpha.size, FINE, H)
        scale = np.sqrt(post.scale[..., 0, 0]).reshape(alpha.size, FINE, H)
        for a in range(alpha.size):  # one alpha node at a time: (FINE, H, E) stays small
            ok = np.isfinite(w[a])
            lt = _log_t(e0[None, None, :], loc[a][..., None],
                        np.where(ok, scale[a], 1.0)[..., None], post.nu)
            total[a] += logsumexp(np.where(ok[..., None], w[a][..., None] + lt, -np.inf),
                                  axis=(0, 1))
    return total - np.log(e0)[None, :]  # log-uniform prior on E0*


def _grid_moments(alpha, e0, log_mass) -> tuple[float, float, float, float]:
    m = np.exp(log_mass)
    pa, pe = m.sum(axis=1), m.sum(axis=0)
    ma, me = float(pa @ alpha), float(pe @ e0)
    return (ma, math.sqrt(max(float(pa @ (alpha - ma) ** 2), 0.0)), me,
            math.sqrt(max(float(pe @ (e0 - me) ** 2), 0.0)))


#: Log mass below the peak that the zoomed grid keeps inside (edge flag: 10 below the peak).
CONTOUR = 12.0


def _within(nodes: np.ndarray, profile: np.ndarray) -> tuple[float, float]:
    """First and last node whose profile log mass is within :data:`CONTOUR` of the peak."""
    idx = np.flatnonzero(profile > profile.max() - CONTOUR)
    return float(nodes[idx[0]]), float(nodes[idx[-1]])


def pool_rheology(fits: Sequence[RheologyFit], *, n_alpha: int = 41, n_e0: int = 401,
                   n_draws: int = 4000, rng: np.random.Generator | int | None = 0
                   ) -> PooledPowerLaw:
    """Pool power-law fits of one material (module docstring).

    Parameters
    ----------
    fits
        Two or more :func:`~palpbayes.rheology.fit_rheology` results with ``"power-law"`` and
        the same t0.
    n_alpha, n_e0
        Nodes of the pooled grid.
    n_draws
        Posterior draws.
    rng
        Seed or Generator of the draws.

    Raises
    ------
    InputError
        Fewer than two fits, another relaxation model, or different t0.
    """
    if len(fits) < 2:
        raise InputError("pooling takes two or more fits of one material")
    if any(f.rheology != "power-law" for f in fits):
        raise InputError("pooling is for power-law fits (fit_rheology(..., 'power-law'))")
    t0 = fits[0].t0
    if any(f.t0 != t0 for f in fits):
        raise InputError("the fits to pool must share t0")
    med = np.array([[np.median(f.draws["E0"]), np.median(f.draws["alpha"])] for f in fits])
    sd = np.array([[np.std(f.draws["E0"]), np.std(f.draws["alpha"])] for f in fits])
    a_lo = max(0.0, float((med[:, 1] - SPAN_SD * sd[:, 1]).min()))
    a_hi = min(ALPHA_MAX, float((med[:, 1] + SPAN_SD * sd[:, 1]).max()))
    e_lo = max(float((med[:, 0] - 2 * SPAN_SD * sd[:, 0]).min()), 1e-3 * float(med[:, 0].min()))
    e_hi = float((med[:, 0] + 2 * SPAN_SD * sd[:, 0]).max())
    evaluators = [NodeEvaluator(f.data, "power-law", t0, f.grid.drag, f.grid.tilt)  # once each
                  for f in fits]
    for f, ev in zip(fits, evaluators, strict=True):  # phi resolved where each fit found it,
        ev.phi = np.union1d(ev.phi, f.grid.phi)       # the uniform nodes elsewhere
    for _ in range(3):  # zoom until the pooled sd spans >= ZOOM_NODES nodes on both axes
        alpha = np.linspace(a_lo, a_hi, n_alpha)
        e0 = np.linspace(e_lo, e_hi, n_e0)
        total = _pooled_log(fits, evaluators, alpha, e0)
        log_mass = total - logsumexp(total)
        ma, sa, me, se = _grid_moments(alpha, e0, log_mass)
        da, de = alpha[1] - alpha[0], e0[1] - e0[0]
        if sa >= ZOOM_NODES * da and se >= ZOOM_NODES * de:
            break
        # ±SPAN_SD sd: 41 alpha nodes put 3.3 of them in one sd, so one zoom settles; a
        # skewed posterior (alpha piled against its bound 0) keeps its tail: the zoom also
        # spans every node within CONTOUR of the peak, so the new grid's edges are the
        # prior's or carry no mass, and the edge flag below is not raised by the zoom
        a_in, e_in = _within(alpha, log_mass.max(axis=1)), _within(e0, log_mass.max(axis=0))
        a_lo = max(0.0, min(ma - SPAN_SD * sa, a_in[0] - 2 * da))
        a_hi = min(ALPHA_MAX, max(ma + SPAN_SD * sa, a_in[1] + 2 * da))
        e_lo = max(min(me - SPAN_SD * se, e_in[0] - 2 * de), 1e-3 * me)
        e_hi = max(me + SPAN_SD * se, e_in[1] + 2 * de)
    gen = np.random.default_rng(rng)
    p = np.exp(log_mass.ravel())
    pick = gen.choice(p.size, size=n_draws, p=p / p.sum())
    ia, ie = np.unravel_index(pick, log_mass.shape)
    da, de = alpha[1] - alpha[0], e0[1] - e0[0]
    draws = {"alpha": np.clip(alpha[ia] + gen.uniform(-0.5, 0.5, n_draws) * da, 0.0,
                              ALPHA_MAX),
             "E0": e0[ie] + gen.uniform(-0.5, 0.5, n_draws) * de}
    ids = [f.data.trace.trace_id for f in fits]
    pooled = PooledPowerLaw(alpha, e0, log_mass, draws, ids, t0)
    pm = np.array([np.median(draws["E0"]), np.median(draws["alpha"])])
    for i in range(len(fits)):
        z = np.abs(med[i] - pm) / sd[i]
        if (z > DISAGREE_SD).any():
            pooled.flags.append(
                f"{ids[i]}: its own E0* {med[i, 0]:.4g} Pa, alpha {med[i, 1]:.3g} lie "
                f"{z.max():.1f} of its sd from the pooled values: one power law does not "
                "describe it with the others (another material, or rate dependence beyond a "
                "power law)")
    # mass on an edge of the grid that is not a bound of the prior: the traces pull apart
    near = log_mass.max() - 10.0
    by_alpha, by_e0 = log_mass.max(axis=1), log_mass.max(axis=0)
    open_edges = [by_alpha[0] > near and alpha[0] > 0.0,
                  by_alpha[-1] > near and alpha[-1] < ALPHA_MAX,
                  by_e0[0] > near, by_e0[-1] > near]
    if any(open_edges):
        pooled.flags.append("the pooled posterior reaches the edge of its grid: the traces "
                            "disagree too much to pool (see the per-trace flags)")
    return pooled
