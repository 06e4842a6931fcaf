"""Where to press next: three ways to score a candidate press from a lump posterior.

Each criterion takes a :class:`~palpbayes.active.posterior.SearchPosterior` and candidate
positions and returns one score per candidate (higher: press there first).  The predictive
of a new press at q under a kept centre c is Gaussian once b, tau, beta and the sphere are
averaged (moment matched):  y_q | c ~ Normal(mu_c(q), sigma_c(q)²), with
sigma² including the heterogeneity tau² and the new press's own sd; under no lump
y_q ~ Normal(mu_0, sigma_0²).  Under a correlated background (:mod:`~.background`) mu and
sigma² are the field's kriging from the presses: a press beside a soft patch is expected to
read soft, and close to earlier presses it is expected to tell little.

* ``"eig"`` — expected information gain (Lindley 1956, Ann. Math. Statist. 27, 986–1005) on
  the quantity the stopping rule decides on: while P(lump) < p_decide, whether there is a
  lump, I(y_q; lump or not); then where, I(y_q; c | lump).  Each is a mutual information
  H[p(y_q)] − E_g H[p(y_q | g)], the mixtures' entropies by quadrature over y and the
  normal components' in closed form.  It presses where the hypotheses still in play disagree
  most about what the press will read, relative to its noise.  The joint target
  G ∈ {no lump, lump centred at c} (``target="joint"``) is dominated by the centre's
  entropy (about 7.5 nat on a 1 mm grid against at most 0.69 for presence) and chases the
  heterogeneity's bumps on a block without a lump: on the first 8 bench phantoms it left
  3 undecided at 225 presses, the staged target 2 (docs/reference.md, "Active search").
* ``"lse"`` — level-set estimation of {E > k × background} (Gotovos, Casati, Hitz & Krause
  2013, IJCAI; the probabilistic "straddle" of Bryan et al. 2005, NIPS): the candidate
  whose class is most in doubt, min(P_q, 1 − P_q) with P_q = P(E_app(q) > k·E_b); the sum
  of that over the candidate grid is the expected misclassified area, which pressing the
  most doubtful cell reduces most.
* ``"ucb"`` — the upper confidence bound of the lump's log-excess, mean + 2·sd (Srinivas,
  Krause, Kakade & Seeger 2010, ICML): the simple baseline, which chases the stiffest
  place.

``benchmarks/bench_active.py`` compares them with a raster and random presses on simulated
phantoms (docs/reference.md, "Active search").
"""

from __future__ import annotations

import math

import numpy as np

from .background import predictive as background_predictive
from .posterior import SearchPosterior

__all__ = ["CRITERIA", "eig", "lse", "ucb", "predictive", "level_probability"]

_Y_NODES = 48  # fewest quadrature nodes over a press's reading
_Y_NODES_MAX = 4096
_BLOCK = 1 << 22  # elements of the (components, candidates, nodes) temporaries per block


def _phi(post: SearchPosterior, qx: np.ndarray, qy: np.ndarray, depth: int = 0
         ) -> np.ndarray:
    """phi_kj(|q − c|) for kept centres c at depth index j: (K, N_kept, N_q)."""
    hyp = post.hyp
    cx, cy = hyp.cx[post.kept], hyp.cy[post.kept]
    return hyp.profile(np.hypot(cx[:, None] - qx[None, :], cy[:, None] - qy[None, :]), depth)


def predictive(post: SearchPosterior, qx: np.ndarray, qy: np.ndarray, press_sd: float,
               depth: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Group weights (N_kept + 1,) and the predictive mean and sd of log E of a press at each
    candidate (at depth index ``depth``) under each group, (N_kept + 1, N_q): row 0 no lump,
    then the kept centres (under a correlated background,
    :func:`palpbayes.active.background.predictive`: the field kriged from the presses)."""
    if post.background is not None:
        return background_predictive(post, qx, qy, press_sd, depth)
    pc, pkc = post.kept_mix()
    pk = pkc.T[..., None]  # (K, N_kept, 1) P(k | c)
    m = post.moments.transpose(1, 0, 2)[..., None, :]  # (K, N_kept, 1, 6)
    phi = _phi(post, qx, qy, depth)
    mu_ck = m[..., 0] + m[..., 3] * phi
    e2_ck = m[..., 1] + 2 * m[..., 2] * phi + m[..., 4] * phi * phi + m[..., 5]
    mu = (pk * mu_ck).sum(axis=0)
    var = np.maximum((pk * e2_ck).sum(axis=0) - mu * mu, 0.0) + press_sd ** 2
    n0 = post.null_moments
    mu0 = np.full((1, qx.size), n0[0])
    var0 = np.full((1, qx.size), n0[1] - n0[0] ** 2 + n0[2] + press_sd ** 2)
    w = np.concatenate([[1.0 - post.p_lump], post.p_lump * pc])
    return w, np.vstack([mu0, mu]), np.sqrt(np.vstack([var0, var]))


def eig(post: SearchPosterior, qx: np.ndarray, qy: np.ndarray, press_sd: float, *,
        target: str = "auto", p_decide: float = 0.95, depth: int = 0) -> np.ndarray:
    """Expected information gain [nat] of a press at each candidate (module docstring).

    ``target``: ``"presence"`` (lump or not), ``"centre"`` (where, given a lump), ``"joint"``
    (both: G ∈ {no lump, centre c}; by the chain rule the sum of the presence term and
    P(lump) × the centre term), or ``"auto"``: presence while P(lump) < ``p_decide``, then
    the centre — what the stopping rule is waiting for.  ``depth``: the press depth's index.
    """
    if target not in ("auto", "presence", "centre", "joint"):
        raise ValueError(f"target {target!r}: presence, centre, joint or auto")
    if target == "auto":
        target = "presence" if post.p_lump < p_decide else "centre"
    w, mu, sd = predictive(post, qx, qy, press_sd, depth)
    keep = w > 1e-12 * w.max()
    keep[0] = True
    w, mu, sd = w[keep], mu[keep], sd[keep]
    p0 = float(w[0])
    wc = w[1:] / max(w[1:].sum(), 1e-300)  # P(centre | lump)
    h_comp = 0.5 * np.log(2 * math.pi * math.e * sd * sd)  # (G, N_q)
    # quadrature over the reading: nodes at most half the narrowest sd apart over the range
    # the components in play span (a fixed count is far too coarse when tau is small)
    span = slice(1, None) if target == "centre" else slice(None)
    lo_q, hi_q = (mu[span] - 6 * sd[span]).min(axis=0), (mu[span] + 6 * sd[span]).max(axis=0)
    need = np.max((hi_q - lo_q) / (0.5 * sd[span].min(axis=0)))
    nodes = int(np.clip(math.ceil(need) + 1, _Y_NODES, _Y_NODES_MAX))
    chunk = max(1, _BLOCK // (mu.shape[0] * nodes))
    t = np.linspace(0.0, 1.0, nodes)
    out = np.empty(qx.size)
    for j in range(0, qx.size, chunk):
        sl = slice(j, j + chunk)
        m, s = mu[:, sl], sd[:, sl]
        y = lo_q[sl, None] + (hi_q - lo_q)[sl, None] * t[None, :]  # (n, Y)
        z = (y[None, :, :] - m[:, :, None]) / s[:, :, None]
        dens = np.exp(-0.5 * z * z) / (math.sqrt(2 * math.pi) * s[:, :, None])
        p1 = np.einsum("g,gqy->qy", wc, dens[1:])  # the lump's mixture
        if target == "centre":  # I(y; c | lump) = H[p1] − E_c H[N_c]
            out[sl] = _entropy(p1, y) - wc @ h_comp[1:, sl]
            continue
        mix = p0 * dens[0] + (1.0 - p0) * p1
        if target == "presence":  # I(y; lump or not) = H[p] − P0 H[N_0] − P1 H[p1]
            out[sl] = _entropy(mix, y) - p0 * h_comp[0, sl] - (1 - p0) * _entropy(p1, y)
        else:  # joint: H[p] − Σ_g P(g) H[N_g]
            out[sl] = _entropy(mix, y) - p0 * h_comp[0, sl] - (1 - p0) * (wc @ h_comp[1:, sl])
    # a mutual information lies between 0 and the entropy of what it is about
    h_presence = -sum(v * math.log(v) for v in (p0, 1.0 - p0) if v > 0)
    h_centre = float(-(wc[wc > 0] * np.log(wc[wc > 0])).sum())
    top = {"presence": h_presence, "centre": h_centre,
           "joint": h_presence + (1.0 - p0) * h_centre}[target]
    return np.clip(out, 0.0, top)


def _entropy(dens: np.ndarray, y: np.ndarray) -> np.ndarray:
    """−∫ p log p over each row's nodes ``y`` (trapezoid)."""
    f = np.where(dens > 0, -dens * np.log(np.where(dens > 0, dens, 1.0)), 0.0)
    return np.trapezoid(f, y, axis=1)


def level_probability(post: SearchPosterior, qx: np.ndarray, qy: np.ndarray,
                      k: float, depth: int = 0) -> np.ndarray:
    """P(E_app(q) > k·E_b | presses) at each candidate, pressed at depth index ``depth``:
    the lump's log-excess beta·phi above log k (0 without a lump)."""
    if not k > 1.0:
        raise ValueError(f"level k {k!r} must be > 1")
    phi = _phi(post, qx, qy, depth)  # (K, N_kept, N_q)
    betas = post.hyp.betas
    with np.errstate(divide="ignore"):
        thr = math.log(k) / phi
    idx = np.searchsorted(betas, thr, side="left")  # first beta >= threshold
    surv = np.concatenate([post.beta_survival, np.zeros(post.beta_survival.shape[:2] + (1,))],
                          axis=-1)
    K, C = surv.shape[:2]
    p = np.take_along_axis(surv.reshape(K * C, -1), idx.reshape(K * C, -1), axis=1)
    pc, pkc = post.kept_mix()
    w = (pc[:, None] * pkc).T.reshape(K * C, 1)
    return post.p_lump * (w * p).sum(axis=0)


def lse(post: SearchPosterior, qx: np.ndarray, qy: np.ndarray, press_sd: float, *,
        k: float = 1.03, depth: int = 0) -> np.ndarray:
    """Probability that the candidate's class in {E > k·E_b} is wrong, min(P, 1 − P)."""
    p = level_probability(post, qx, qy, k, depth)
    return np.minimum(p, 1.0 - p)


def ucb(post: SearchPosterior, qx: np.ndarray, qy: np.ndarray, press_sd: float, *,
        kappa: float = 2.0, depth: int = 0) -> np.ndarray:
    """Upper confidence bound of the lump's log-excess at each candidate: mean + kappa·sd."""
    phi = _phi(post, qx, qy, depth)
    pc, pkc = post.kept_mix()
    w = (post.p_lump * pc[:, None] * pkc).T[..., None]  # (K, N_kept, 1)
    m = post.moments.transpose(1, 0, 2)
    mean = (w * m[..., 3:4] * phi).sum(axis=(0, 1))
    second = (w * m[..., 4:5] * phi * phi).sum(axis=(0, 1))
    return mean + kappa * np.sqrt(np.maximum(second - mean * mean, 0.0))


#: Criterion name -> (function, one-line description with its reference).
CRITERIA = {
    "eig": (eig, "expected information gain on what the rule decides next: lump or not "
                 "while undecided, then its centre (Lindley 1956)"),
    "lse": (lse, "level-set estimation of {E > k x background}: the most doubtful cell "
                 "(Gotovos et al. 2013; Bryan et al. 2005)"),
    "ucb": (ucb, "upper confidence bound of the lump's excess, mean + 2 sd (Srinivas et al. "
                 "2010): the simple baseline"),
}
