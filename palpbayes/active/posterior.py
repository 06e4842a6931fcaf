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

The profiles are those of the forward model of :mod:`palpbayes.inclusion` (the
Boussinesq-weighted Reuss average that :mod:`palpbayes.maps.lump` and the map simulator use)
for a set of spheres (radius R, cover D − R) under the tip's contact radius: the set spans the
sizes and depths the surface can tell apart.  phi_k is the log-excess profile of sphere k at
the reference apparent ratio :data:`A_REF`, divided by log A_REF; at other amplitudes the
shape is kept (linear in beta).  Against the forward model's own profile the error is at
most 1.5 % of the peak log-excess for A <= 1.25 and 3.5 % for A <= 1.5
(``tests/unit/test_active_posterior.py``); beyond, the model is a shape approximation.

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
from functools import lru_cache

import numpy as np
from scipy.special import logsumexp

from ..errors import InputError
from ..inclusion import sensitivity
from .background import check_background, correlated_posterior, field_grid, lump_probability

__all__ = ["A_REF", "LumpHypotheses", "SearchPosterior", "hypotheses", "posterior"]

#: Apparent peak ratio at which the profile shapes are taken.
A_REF = 1.15
#: Sphere radii [m] and covers (depth of the top below the surface) [m] of the profile set.
RADII = (2.5e-3, 4e-3, 6e-3, 9e-3)
COVERS = (0.0, 3e-3, 6e-3)
#: Half-normal scale of the heterogeneity tau (as :mod:`palpbayes.maps.lump`).
TAU_SCALE = 0.2
_TAUS = np.geomspace(0.005, 0.4, 10)
_N_BETA = 12
_S_MAX_FACTOR = 8.0  # profiles tabulated out to this × (R + cover + a); zero beyond


@dataclass(frozen=True)
class LumpHypotheses:
    """The hypothesis grid of one footprint, tip and block (built once, reused every press).

    Attributes
    ----------
    cx, cy
        [m] Lump centres (flattened grid over the footprint, spacing ``resolution``).
    s_grid
        [m] Lateral distances of the tabulated profiles.
    profiles
        (K, len(s_grid)) phi_k(s), 1 at s = 0.
    fwhm
        [m] (K,) Full width at half maximum of each profile (the apparent lump diameter).
    radius, cover
        [m] (K,) The sphere of each profile.
    betas
        Grid of beta = log A (log-uniform prior: equal weights).
    taus, log_tau_prior
        Grid of the heterogeneity tau and its log prior weights (normalised).
    contact_radius, thickness
        [m] Tip contact radius a and block thickness H.
    background, sigma_fs, ells, log_field_prior
        ``"white"`` or ``"correlated"`` (:mod:`~.background`), and the correlated field's
        grids of sd (log E) and length [m] with their log prior weights (S, L).
    """

    cx: np.ndarray
    cy: np.ndarray
    s_grid: np.ndarray
    profiles: np.ndarray
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

    def profile(self, d: np.ndarray) -> np.ndarray:
        """phi_k at distances ``d`` [m] >= 0 (any shape), linear between the table's nodes
        and 0 beyond it: shape (K, *d.shape)."""
        u = np.asarray(d, dtype=float) * (1.0 / self.s_grid[1])
        last = self.s_grid.size - 1
        i = np.minimum(u.astype(np.intp), last)
        f = np.minimum(u - i, 1.0)
        p = self.profiles
        return p[:, i] + f * (p[:, np.minimum(i + 1, last)] - p[:, i])


@lru_cache(maxsize=8)
def _profiles(a: float, thickness: float) -> tuple[np.ndarray, np.ndarray, np.ndarray,
                                                   np.ndarray, np.ndarray]:
    """phi_k on a common distance grid for every sphere of :data:`RADII` × :data:`COVERS`
    that fits in the block; their FWHM, radii and covers."""
    reach = max(RADII) + max(COVERS) + a
    s = np.linspace(0.0, _S_MAX_FACTOR * reach, 481)  # uniform: LumpHypotheses.profile
    rows, fwhm, radii, covers = [], [], [], []
    s = np.append(s, s[-1] + s[1])  # a last node of zeros: 0 beyond the table
    for r in RADII:
        for cover in COVERS:
            if cover + 2.0 * r > thickness:
                continue
            V = sensitivity(s, radius=r, depth=r + cover, contact_radius=a,
                            thickness=thickness)
            if not V[0] > 1e-4:
                continue
            g = (1.0 - 1.0 / A_REF) / V[0]
            if g >= 1.0:  # this sphere cannot look A_REF stiff: the linear shape is V's own
                phi = V / V[0]
            else:
                phi = -np.log1p(-g * V) / math.log(A_REF)
            j = int(np.argmax(phi <= 0.5))
            half = s[j - 1] + (0.5 - phi[j - 1]) * (s[j] - s[j - 1]) / (phi[j] - phi[j - 1])
            phi[-1] = 0.0
            rows.append(phi)
            fwhm.append(2.0 * half)
            radii.append(r)
            covers.append(cover)
    if not rows:
        raise InputError(f"the block ({thickness:g} m) is too thin for any lump of the set "
                         f"(radii {RADII} m)")
    return s, np.array(rows), np.array(fwhm), np.array(radii), np.array(covers)


def hypotheses(footprint: tuple[float, float, float, float], *, contact_radius: float,
               thickness: float, resolution: float = 1e-3, min_excess: float = 0.03,
               max_ratio: float = 3.0, max_centres: int = 3600,
               background: str = "white") -> LumpHypotheses:
    """The hypothesis grid (module docstring) over ``footprint`` (x0, x1, y0, y1) [m].

    Parameters
    ----------
    footprint
        [m] The specimen's palpable rectangle; lump centres are placed over it.
    contact_radius, thickness
        [m] The tip's contact radius at the indentation depth
        (:func:`palpbayes.inclusion.contact_radius`) and the block thickness.
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
    x0, x1, y0, y1 = (float(v) for v in footprint)
    if not (all(map(math.isfinite, (x0, x1, y0, y1))) and x1 > x0 and y1 > y0):
        raise InputError(f"footprint {footprint!r} must be x0, x1, y0, y1 [m] with x1 > x0 "
                         "and y1 > y0")
    if not (contact_radius > 0 and thickness > 0 and resolution > 0):
        raise InputError("contact radius, thickness and resolution must be > 0 [m]")
    if not (0 < min_excess and max_ratio > 1 + min_excess):
        raise InputError(f"need 0 < min_excess ({min_excess!r}) and max_ratio ({max_ratio!r})"
                         f" > 1 + min_excess")
    check_background(background)
    step = max(float(resolution), math.sqrt((x1 - x0) * (y1 - y0) / max_centres))
    nx = max(2, int(round((x1 - x0) / step)) + 1)
    ny = max(2, int(round((y1 - y0) / step)) + 1)
    X, Y = np.meshgrid(np.linspace(x0, x1, nx), np.linspace(y0, y1, ny))
    s, prof, fwhm, radii, covers = _profiles(float(contact_radius), float(thickness))
    lt = np.log(_TAUS) - 0.5 * (_TAUS / TAU_SCALE) ** 2  # half-normal × tau (log grid)
    sf, ell, lfp = field_grid(float(contact_radius))
    return LumpHypotheses(
        cx=X.ravel(), cy=Y.ravel(), s_grid=s, profiles=prof, fwhm=fwhm, radius=radii,
        cover=covers,
        betas=np.geomspace(math.log1p(min_excess), math.log(max_ratio), _N_BETA),
        taus=_TAUS.copy(), log_tau_prior=lt - logsumexp(lt), contact_radius=float(contact_radius),
        thickness=float(thickness), resolution=step, footprint=(x0, x1, y0, y1),
        background=background, sigma_fs=sf, ells=ell, log_field_prior=lfp)


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
              sd: np.ndarray, *, prior_lump: float = 0.5, mass: float = 0.999,
              max_kept: int = 600) -> SearchPosterior:
    """The posterior of the lump hypotheses given presses at (``x``, ``y``) [m] with
    per-press posteriors of log E (``mean``, ``sd``) (module docstring).

    The predictive moments (:attr:`SearchPosterior.moments`) are kept for the heaviest
    centres that hold ``mass`` of the centre's posterior when at most ``max_kept`` do, else
    for a systematic sample of ``max_kept`` draws from it (:func:`_kept`); the candidates of
    :mod:`palpbayes.active.criteria` are scored against these.

    Raises
    ------
    InputError
        No press, arrays of different lengths, a non-finite value or an sd <= 0, or
        ``prior_lump`` outside (0, 1).
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
    if hyp.background == "correlated":
        return SearchPosterior(**correlated_posterior(
            hyp, x, y, m, s, prior_lump=prior_lump, kept=lambda w: _kept(w, mass, max_kept)))
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
    phis = hyp.profile(d)  # (K, N_c, n)
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
