"""Is there a lump, and where: a fast grid posterior over one-lump hypotheses.

What an active search decides on, after every press, in well under a second.  The presses so
far are the per-press posteriors of log E (mean y_i, sd s_i at position p_i, as
:mod:`palpbayes.maps.pertrace` or the online estimator give them).  Two hypotheses explain
them:

* **no lump** (H0): y_i ~ Normal(b, s_i² + tau²), a homogeneous block of log modulus b with
  point-to-point heterogeneity tau;
* **one lump** (H1): y_i ~ Normal(b + beta·phi_k(|p_i − c|), s_i² + tau²), a lump centred at
  c whose apparent log-excess at the surface is beta (= log of the apparent peak ratio A) at
  its centre and falls off with distance as the profile phi_k (phi_k(0) = 1).

The profiles are those of :mod:`palpbayes.active.profiles`: the forward model of
:mod:`palpbayes.inclusion` (the Boussinesq-weighted Reuss average) for a set of spheres
(radius R, cover D − R) under the tip's contact radius, one set per press depth: the set
spans the sizes and depths the surface can tell apart, and beta is the apparent peak
log-excess at the first (reference) depth.  A press at another depth j reads
beta·phi_kj(|p − c|): the same lump seen with a wider contact.  The block's log modulus b is
shared by every depth: each press's log E is the modulus of a linear material, the same at any
depth (a material that stiffens with strain needs its presses' E on one footing first).

Priors: P(lump) = ``prior_lump`` (0.5); b flat (it cancels in the Bayes factor, both
hypotheses share it); tau half-normal with scale 0.2 (as :mod:`palpbayes.maps.lump`) on a
log grid; c uniform on a grid over the footprint; the sphere uniform over the set; beta
log-uniform on [log(1 + ``min_excess``), log ``max_ratio``]: a lump is a lump when its
apparent peak excess is at least ``min_excess`` (3 % by default, about one press's
heterogeneity).  b is integrated out in closed form (a Gaussian integral), tau, beta, c and
the sphere by sums over their grids, so the posterior is exact on its grids: no sampler, no
convergence to check.

Reference for the model-choice part: Kass & Raftery (1995), J. Am. Stat. Assoc. 90, 773–795
(Bayes factors).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.special import logsumexp

from ..errors import InputError
from .background import check_background, correlated_posterior, field_grid, lump_probability
from .profiles import A_REF, profile_table

__all__ = ["A_REF", "LumpHypotheses", "SearchPosterior", "hypotheses", "posterior"]

#: Half-normal scale of the heterogeneity tau (as :mod:`palpbayes.maps.lump`).
TAU_SCALE = 0.2
_TAUS = np.geomspace(0.005, 0.4, 10)
_N_BETA = 12


@dataclass(frozen=True)
class LumpHypotheses:
    """The hypothesis grid of one footprint, tip and block (built once, reused every press).

    Attributes
    ----------
    cx, cy
        [m] Lump centres (flattened grid over the footprint, spacing ``resolution``).
    s_grid
        [m] Lateral distances of the tabulated profiles.
    depth_profiles
        (D, K, len(s_grid)) phi_kj(s) at each press depth j (:mod:`~.profiles`);
        :attr:`profiles` is the reference depth's, 1 at s = 0.
    fwhm
        [m] (K,) Full width at half maximum of each profile (the apparent lump diameter).
    radius, cover
        [m] (K,) The sphere of each profile.
    betas
        Grid of beta = log A (log-uniform prior: equal weights).
    taus, log_tau_prior
        Grid of the heterogeneity tau and its log prior weights (normalised).
    contact_radius, thickness
        [m] Tip contact radius a at the reference depth and block thickness H.
    contact_radii
        [m] (D,) The contact radius at each press depth, the reference's first.
    background, sigma_fs, ells, log_field_prior
        ``"white"`` or ``"correlated"`` (:mod:`~.background`), and the correlated field's
        grids of sd (log E) and length [m] with their log prior weights (S, L).
    """

    cx: np.ndarray
    cy: np.ndarray
    s_grid: np.ndarray
    depth_profiles: np.ndarray
    fwhm: np.ndarray
    radius: np.ndarray
    cover: np.ndarray
    betas: np.ndarray
    taus: np.ndarray
    log_tau_prior: np.ndarray
    contact_radius: float
    thickness: float
    resolution: float
    footprint: tuple[float, float, float, float]
    background: str = "white"
    sigma_fs: np.ndarray | None = None
    ells: np.ndarray | None = None
    log_field_prior: np.ndarray | None = None
    contact_radii: tuple[float, ...] = ()

    @property
    def profiles(self) -> np.ndarray:
        """(K, len(s_grid)) phi_k(s) at the reference depth, 1 at s = 0."""
        return self.depth_profiles[0]

    @property
    def n_depths(self) -> int:
        return self.depth_profiles.shape[0]

    def profile(self, d: np.ndarray, depth: int | np.ndarray | None = None) -> np.ndarray:
        """phi_kj at distances ``d`` [m] >= 0 (any shape), linear between the table's nodes
        and 0 beyond it: shape (K, *d.shape).  ``depth``: the press depth's index j (one
        for all, or one per element of ``d``, broadcast); None: the reference depth."""
        u = np.asarray(d, dtype=float) * (1.0 / self.s_grid[1])
        last = self.s_grid.size - 1
        i = np.minimum(u.astype(np.intp), last)
        f = np.minimum(u - i, 1.0)
        i1 = np.minimum(i + 1, last)
        if depth is None or np.ndim(depth) == 0:
            p = self.depth_profiles[0 if depth is None else int(depth)]
            return p[:, i] + f * (p[:, i1] - p[:, i])
        j = np.broadcast_to(np.asarray(depth, dtype=np.intp), u.shape)
        p = self.depth_profiles.transpose(1, 0, 2)  # (K, D, S)
        return p[:, j, i] + f * (p[:, j, i1] - p[:, j, i])


def hypotheses(footprint: tuple[float, float, float, float], *,
               contact_radius: float | tuple[float, ...], thickness: float,
               resolution: float = 1e-3, min_excess: float = 0.03, max_ratio: float = 3.0,
               max_centres: int = 3600, background: str = "white") -> LumpHypotheses:
    """The hypothesis grid (module docstring) over ``footprint`` (x0, x1, y0, y1) [m].

    Parameters
    ----------
    footprint
        [m] The specimen's palpable rectangle; lump centres are placed over it.
    contact_radius, thickness
        [m] The tip's contact radius at the indentation depth
        (:func:`palpbayes.inclusion.contact_radius`), or one per press depth (the reference
        first), and the block thickness.
    resolution
        [m] Spacing of the centre grid (made coarser when the footprint would need more than
        ``max_centres`` centres).
    min_excess
        Smallest apparent peak excess A − 1 that counts as a lump (> 0).
    max_ratio
        Largest apparent peak ratio A of the prior (> 1 + ``min_excess``).
    background
        ``"white"`` (heterogeneity independent press to press) or ``"correlated"`` (with a
        Gaussian random field, :mod:`palpbayes.active.background`).
    """
    radii = tuple(np.atleast_1d(np.asarray(contact_radius, dtype=float)).tolist())
    x0, x1, y0, y1 = (float(v) for v in footprint)
    if not (all(map(math.isfinite, (x0, x1, y0, y1))) and x1 > x0 and y1 > y0):
        raise InputError(f"footprint {footprint!r} must be x0, x1, y0, y1 [m] with x1 > x0 "
                         "and y1 > y0")
    if not (radii and all(math.isfinite(v) and v > 0 for v in radii) and thickness > 0
            and resolution > 0):
        raise InputError("contact radius, thickness and resolution must be > 0 [m]")
    if not (0 < min_excess and max_ratio > 1 + min_excess):
        raise InputError(f"need 0 < min_excess ({min_excess!r}) and max_ratio ({max_ratio!r})"
                         f" > 1 + min_excess")
    check_background(background)
    step = max(float(resolution), math.sqrt((x1 - x0) * (y1 - y0) / max_centres))
    nx = max(2, int(round((x1 - x0) / step)) + 1)
    ny = max(2, int(round((y1 - y0) / step)) + 1)
    X, Y = np.meshgrid(np.linspace(x0, x1, nx), np.linspace(y0, y1, ny))
    s, prof, fwhm, rad, covers = profile_table(radii, float(thickness))
    lt = np.log(_TAUS) - 0.5 * (_TAUS / TAU_SCALE) ** 2  # half-normal × tau (log grid)
    sf, ell, lfp = field_grid(radii[0])
    return LumpHypotheses(
        cx=X.ravel(), cy=Y.ravel(), s_grid=s, depth_profiles=prof, fwhm=fwhm, radius=rad,
        cover=covers,
        betas=np.geomspace(math.log1p(min_excess), math.log(max_ratio), _N_BETA),
        taus=_TAUS.copy(), log_tau_prior=lt - logsumexp(lt), contact_radius=radii[0],
        thickness=float(thickness), resolution=step, footprint=(x0, x1, y0, y1),
        background=background, sigma_fs=sf, ells=ell, log_field_prior=lfp,
        contact_radii=radii)


@dataclass
class SearchPosterior:
    """The posterior of :func:`posterior` on the hypothesis grid.

    Attributes
    ----------
    p_lump
        P(lump | presses).
    log_bayes_factor
        log p(presses | lump) − log p(presses | no lump).
    centre_weights
        (N_c,) P(centre | lump, presses) on ``hyp.cx``, ``hyp.cy``.
    ck_weights
        (N_c, K) P(centre, sphere | lump, presses).
    kept
        Indices of the centres whose predictive moments are kept (:func:`_kept`).
    kept_weights
        (N_kept,) The weight each kept centre carries for P(centre | lump) (sum 1).
    moments
        (N_kept, K, 6) per kept centre and sphere, the posterior means over tau and beta of b̂, b̂²,
        b̂·beta, beta, beta², and of the predictive variance's common part 1/S0 + tau².
    null_moments
        (3,) the same under no lump: E[b̂], E[b̂²], E[1/S0 + tau²].
    beta_weights
        (B,) P(beta | lump, presses) on ``hyp.betas``.
    beta_survival
        (K, N_kept, B) P(beta >= betas[j] | kept centre, sphere, lump, presses).
    tau_weights
        (T,) P(tau | presses) (mixed over both hypotheses).
    background
        The correlated model's part (:class:`~.background.CorrelatedPart`); None when white.
    """

    hyp: LumpHypotheses
    n: int
    p_lump: float
    log_bayes_factor: float
    centre_weights: np.ndarray
    ck_weights: np.ndarray
    kept: np.ndarray
    kept_weights: np.ndarray
    moments: np.ndarray
    null_moments: np.ndarray
    beta_weights: np.ndarray
    beta_survival: np.ndarray
    tau_weights: np.ndarray
    background: object | None = None

    @property
    def centre(self) -> tuple[float, float]:
        """[m] Posterior mean of the centre given a lump."""
        w = self.centre_weights
        return float(w @ self.hyp.cx), float(w @ self.hyp.cy)

    def centre_radius(self, level: float = 0.9) -> float:
        """[m] Radius of the disc about the posterior-mean centre that holds ``level`` of the
        centre's posterior (given a lump), at least half the grid spacing."""
        x, y = self.centre
        d = np.hypot(self.hyp.cx - x, self.hyp.cy - y)
        order = np.argsort(d)
        c = np.cumsum(self.centre_weights[order])
        j = min(int(np.searchsorted(c, level)), d.size - 1)
        return float(max(d[order][j], 0.5 * self.hyp.resolution))

    def size_draws(self) -> tuple[np.ndarray, np.ndarray]:
        """The apparent diameter [m] (FWHM) of each sphere and its posterior weight."""
        return self.hyp.fwhm, self.ck_weights.sum(axis=0)

    @property
    def size(self) -> float:
        """[m] Posterior median of the apparent lump diameter (FWHM) given a lump."""
        v, w = self.size_draws()
        order = np.argsort(v)
        return float(v[order][np.searchsorted(np.cumsum(w[order]), 0.5)])

    @property
    def apparent_ratio(self) -> float:
        """Posterior mean of the apparent peak ratio A = exp(beta) given a lump."""
        return float(self.beta_weights @ np.exp(self.hyp.betas))

    def kept_mix(self) -> tuple[np.ndarray, np.ndarray]:
        """P(centre | lump) carried by each kept centre (N_kept,) and P(sphere | centre,
        lump) (N_kept, K)."""
        ck = self.ck_weights[self.kept]
        s = ck.sum(axis=1)
        return self.kept_weights, ck / np.where(s > 0, s, 1.0)[:, None]

    @property
    def tau(self) -> float:
        """Posterior mean of the heterogeneity tau (sd of log E between presses)."""
        return float(self.tau_weights @ self.hyp.taus)


def posterior(hyp: LumpHypotheses, x: np.ndarray, y: np.ndarray, mean: np.ndarray,
              sd: np.ndarray, *, depth: np.ndarray | None = None, prior_lump: float = 0.5,
              mass: float = 0.999, max_kept: int = 600) -> SearchPosterior:
    """The posterior of the lump hypotheses given presses at (``x``, ``y``) [m] with
    per-press posteriors of log E (``mean``, ``sd``) (module docstring); ``depth``: each
    press's depth index into ``hyp.contact_radii`` (None: all at the reference depth).

    The predictive moments (:attr:`SearchPosterior.moments`) are kept for the heaviest
    centres that hold ``mass`` of the centre's posterior when at most ``max_kept`` do, else
    for a systematic sample of ``max_kept`` draws from it (:func:`_kept`); the candidates of
    :mod:`palpbayes.active.criteria` are scored against these.

    Raises
    ------
    InputError
        No press, arrays of different lengths, a non-finite value or an sd <= 0, a depth
        index out of range, or ``prior_lump`` outside (0, 1).
    """
    x, y, m, s = (np.asarray(v, dtype=float).ravel() for v in (x, y, mean, sd))
    if not (x.size == y.size == m.size == s.size) or x.size == 0:
        raise InputError(f"presses: x, y, mean and sd need one value per press (got {x.size}, "
                         f"{y.size}, {m.size}, {s.size}); at least one press")
    if not (np.isfinite(x).all() and np.isfinite(y).all() and np.isfinite(m).all()
            and np.isfinite(s).all() and (s > 0).all()):
        raise InputError("presses: positions, log E means and sds must be finite, sds > 0")
    if not 0.0 < prior_lump < 1.0:
        raise InputError(f"prior_lump {prior_lump!r} must lie in (0, 1)")
    if depth is not None:
        depth = np.asarray(depth).ravel()
        if depth.size != x.size or not np.all((depth >= 0) & (depth < hyp.n_depths)
                                              & (depth == np.round(depth))):
            raise InputError(f"presses: depth indices must be one per press, integers in "
                             f"[0, {hyp.n_depths}) (the state's depths)")
        depth = depth.astype(np.intp)
        if not depth.any():
            depth = None
    if hyp.background == "correlated":
        return SearchPosterior(**correlated_posterior(
            hyp, x, y, m, s, depth=depth, prior_lump=prior_lump,
            kept=lambda w: _kept(w, mass, max_kept)))
    W = 1.0 / (s[:, None] ** 2 + hyp.taus[None, :] ** 2)  # (n, T)
    wy = W * m[:, None]
    S0, Sy, Syy = W.sum(0), wy.sum(0), (wy * m[:, None]).sum(0)
    # b integrated out: sqrt(2 pi / S0); the shared flat prior on b cancels in the factor
    const = (0.5 * np.log(W).sum(0) - 0.5 * (x.size - 1) * math.log(2 * math.pi)
             - 0.5 * np.log(S0) + hyp.log_tau_prior)  # (T,)
    null_q = Syy - Sy ** 2 / S0
    log_null_t = const - 0.5 * null_q  # (T,)
    log_null = float(logsumexp(log_null_t))

    d = np.hypot(hyp.cx[:, None] - x[None, :], hyp.cy[:, None] - y[None, :])  # (N_c, n)
    phis = hyp.profile(d, None if depth is None else depth[None, :])  # (K, N_c, n)
    K, B, Nc = phis.shape[0], hyp.betas.size, hyp.cx.size
    beta = hyp.betas[None, None, :]
    Sp = phis @ W  # (K, N_c, T)
    Spp = (phis * phis) @ W
    Syp = phis @ wy
    a = Sy[None, None, :, None] - beta * Sp[..., None]  # Sy − beta S_phi: (K, N_c, T, B)
    logL = (const[None, None, :, None] - 0.5 * (
        Syy[None, None, :, None] - 2.0 * beta * Syp[..., None] + beta ** 2 * Spp[..., None]
        - a * a / S0[None, None, :, None]))
    top = float(logL.max())
    w = np.exp(logL - top)  # unnormalised P(k, c, tau, beta | lump)
    z = float(w.sum())
    log_alt = top + math.log(z) - math.log(Nc * K * B)
    lbf = log_alt - log_null
    p_lump = lump_probability(lbf, prior_lump)

    w_kc = w.sum(axis=(2, 3))  # (K, N_c)
    ck = (w_kc / z).T  # (N_c, K)
    centre_w = ck.sum(axis=1)
    keep, kept_w = _kept(centre_w, mass, max_kept)
    wk = w[:, keep]  # (K, N_keep, T, B)
    nk = w_kc[:, keep][..., None, None]
    cond = wk / np.where(nk > 0, nk, 1.0)  # P(tau, beta | c, k, lump)
    bh = a[:, keep] / S0[None, None, :, None]
    cb = cond * bh
    extra = (1.0 / S0 + hyp.taus ** 2)[None, None, :, None]
    mom = np.stack([cb.sum(axis=(2, 3)), (cb * bh).sum(axis=(2, 3)),
                    (cb * beta).sum(axis=(2, 3)), (cond * beta).sum(axis=(2, 3)),
                    (cond * beta ** 2).sum(axis=(2, 3)), (cond * extra).sum(axis=(2, 3))],
                   axis=-1).transpose(1, 0, 2)  # (N_keep, K, 6)
    wn = np.exp(log_null_t - log_null)
    null_mom = np.array([wn @ (Sy / S0), wn @ (Sy / S0) ** 2, wn @ (1.0 / S0 + hyp.taus ** 2)])
    tau_alt = w.sum(axis=(0, 1, 3)) / z
    tau_w = p_lump * tau_alt + (1.0 - p_lump) * wn
    beta_w = w.sum(axis=(0, 1, 2)) / z
    surv = np.cumsum(cond.sum(axis=2)[..., ::-1], axis=-1)[..., ::-1]
    return SearchPosterior(hyp=hyp, n=int(x.size), p_lump=p_lump, log_bayes_factor=lbf,
                           centre_weights=centre_w, ck_weights=ck, kept=keep,
                           kept_weights=kept_w, moments=mom,
                           null_moments=null_mom, beta_weights=beta_w, beta_survival=surv,
                           tau_weights=tau_w)


def _kept(w: np.ndarray, mass: float, most: int) -> tuple[np.ndarray, np.ndarray]:
    """The centres the predictive is computed on, and the weights they carry (sum 1).

    The fewest heaviest centres that hold ``mass`` of ``w`` (normalised), with their own
    weights renormalised, when at most ``most`` do; else (a spread-out posterior, early in a
    search) a systematic sample of ``most`` draws from ``w`` (Kitagawa 1996), each centre
    weighted by how often it was drawn: an unbiased, deterministic, spatially representative
    subset instead of an arbitrary cut of near-ties."""
    order = np.argsort(-w, kind="stable")
    cum = np.cumsum(w[order])
    j = int(np.searchsorted(cum, mass)) + 1
    if j <= most:
        keep = np.sort(order[:max(1, min(j, w.size))])
        return keep, w[keep] / w[keep].sum()
    u = (np.arange(most) + 0.5) / most * cum[-1]
    idx = np.minimum(np.searchsorted(np.cumsum(w), u), w.size - 1)
    keep, counts = np.unique(idx, return_counts=True)
    return keep, counts / counts.sum()
