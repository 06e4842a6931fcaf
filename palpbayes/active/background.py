"""A spatially correlated background for the lump posterior: the field integrated out.

The white model of :mod:`palpbayes.active.posterior` lets each press's heterogeneity be
independent of its neighbours'; a real specimen's is spatially correlated, and under the white
model a soft or stiff patch several presses wide reads as evidence of a lump.  The correlated
model adds a Gaussian random field f to log E::

    y = b·1 + beta·phi_h + f + e,   f ~ GP(0, sigma_f²·k(·; ell)),   e ~ N(0, diag(s_i² + tau²))

with k the Matérn-3/2 correlation k(r) = (1 + √3 r/ell)·exp(−√3 r/ell) (Rasmussen & Williams
2006, eq. 4.17).  Given the lump hypothesis h = (centre, sphere, beta) the model is
linear-Gaussian, so b (flat, as in the white model) and f integrate out in closed form::

    log p(y | h, g) = −(n − 1)/2·log 2π − ½ log|Σ| − ½ log S0 − ½ (q0 − 2 beta u + beta² v)

Σ = diag(s² + tau²) + sigma_f²·K, S0 = 1ᵀΣ⁻¹1, q0 = yᵀΣ⁻¹y − (1ᵀΣ⁻¹y)²/S0, u and v the same
restricted (REML-style) products of y and phi_h with phi_h: the white model's formula with Σ⁻¹
for W, equal to it at sigma_f = 0, so the Bayes factor is the white one's with the field
added.  g = (tau, sigma_f, ell) is summed over a grid.

Cost.  With E = diag(s_i² − min s²), Σ = (min s² + tau²)·I + (E + sigma_f²·K): one symmetric
eigendecomposition E + sigma_f² K = Q Λ Qᵀ per (sigma_f, ell) serves every tau
(Σ⁻¹ = Q diag(1/(d_tau + Λ)) Qᵀ), and phi_h'Σ⁻¹phi_h for all hypotheses is one product
(Φ Q)² · 1/(d + Λ) (in single precision: a sum of squares).  Grid points g whose bound on
the lump's likelihood (its maximum over beta in the prior's range, per hypothesis) cannot
reach e⁻³⁰ of the best are skipped, exact to that tolerance.

Priors: sigma_f half-normal with scale :data:`FIELD_SCALE` (as tau) on the log grid
:data:`SIGMA_FS`; ell uniform on ``ELL_FACTORS`` × the contact radius: a field shorter than
the contact radius is averaged by the press into the nugget tau, one longer than a few lump
widths into the level b; between them it competes with a lump (FWHM 8–18 mm for a 5 mm
contact radius), which is the point.

What a new press will read (:func:`predictive`) is the universal-kriging conditional of the
field given the presses, at the mode of g under each hypothesis (the field's hyperparameters
are plugged in for choosing the next press; the decision sums over them).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.linalg import cho_factor, cho_solve, solve_triangular
from scipy.special import logsumexp

from ..errors import InputError

__all__ = ["BACKGROUNDS", "ELL_FACTORS", "FIELD_SCALE", "SIGMA_FS", "BackgroundFit",
           "CorrelatedPart", "check_background", "correlation", "field_grid", "lump_probability",
           "correlated_posterior", "correlated_terms", "sum_lump", "predictive"]

#: Models of the background: independent press to press, or with a correlated field.
BACKGROUNDS = ("white", "correlated")
#: Half-normal scale of the field's sd sigma_f (as the white heterogeneity tau's).
FIELD_SCALE = 0.2
#: Grid of sigma_f (sd of log E).
SIGMA_FS = (0.01, 0.02, 0.04, 0.08)
#: Grid of the correlation length ell, in contact radii.
ELL_FACTORS = (1.0, 2.0, 4.0)
_PRUNE = 30.0  # nat: grid points whose bound is this far below the best are skipped


def correlation(d: np.ndarray, ell: float) -> np.ndarray:
    """The Matérn-3/2 correlation at distances ``d`` [m] for length ``ell`` [m]."""
    r = math.sqrt(3.0) * np.asarray(d, dtype=float) / ell
    return (1.0 + r) * np.exp(-r)


def lump_probability(log_bayes_factor: float, prior_lump: float) -> float:
    """P(lump | presses) from the log Bayes factor lump : no lump and the prior P(lump)
    (the logistic of the posterior log odds, written with tanh: no overflow at decisive
    evidence); both background models use it."""
    logit = log_bayes_factor + math.log(prior_lump) - math.log1p(-prior_lump)
    return float(0.5 * (1.0 + math.tanh(0.5 * logit)))


def check_background(name: str) -> str:
    """``name`` if it is one of :data:`BACKGROUNDS`, else an InputError."""
    if name not in BACKGROUNDS:
        raise InputError(f"background {name!r}: choose one of {', '.join(BACKGROUNDS)}")
    return name


def field_grid(contact_radius: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """sigma_f grid, ell grid [m] and their log prior weights (S, L), normalised."""
    if not contact_radius > 0:
        raise InputError(f"contact radius {contact_radius!r} must be > 0 [m]")
    sf = np.array(SIGMA_FS)
    ell = contact_radius * np.array(ELL_FACTORS)
    lp = np.log(sf) - 0.5 * (sf / FIELD_SCALE) ** 2  # half-normal × sigma_f (log grid)
    lp = lp[:, None] - math.log(ell.size) + np.zeros(ell.size)[None, :]
    return sf, ell, lp - np.log(np.exp(lp - lp.max()).sum()) - lp.max()


@dataclass
class BackgroundFit:
    """The background at one grid point g, conditioned on the presses (for the predictive).

    Attributes
    ----------
    tau, sigma_f, ell
        The grid point (sd of log E, sd of log E, [m]).
    xy
        [m] (n, 2) press positions.
    chol
        Cholesky factor of Σ (lower, :func:`scipy.linalg.cho_factor`).
    v1
        Σ⁻¹1.
    s0, b0
        1ᵀΣ⁻¹1 and the level's estimate 1ᵀΣ⁻¹y / S0 (no lump).
    alpha
        Σ⁻¹(y − b0·1).
    """

    tau: float
    sigma_f: float
    ell: float
    xy: np.ndarray
    chol: tuple
    v1: np.ndarray
    s0: float
    b0: float
    alpha: np.ndarray

    @classmethod
    def at(cls, xy: np.ndarray, m: np.ndarray, s: np.ndarray, tau: float, sigma_f: float,
           ell: float) -> BackgroundFit:
        d = np.hypot(*(xy[:, None, :] - xy[None, :, :]).transpose(2, 0, 1))
        S = sigma_f ** 2 * correlation(d, ell)
        S[np.diag_indices_from(S)] += s * s + tau * tau
        c = cho_factor(S, lower=True)
        v1 = cho_solve(c, np.ones(m.size))
        s0 = float(v1.sum())
        b0 = float(v1 @ m) / s0
        return cls(tau, sigma_f, ell, xy, c, v1, s0, b0, cho_solve(c, m - b0))

    def cross(self, qx: np.ndarray, qy: np.ndarray) -> np.ndarray:
        """sigma_f²·k(press, q): (n, N_q)."""
        d = np.hypot(self.xy[:, 0:1] - qx[None, :], self.xy[:, 1:2] - qy[None, :])
        return self.sigma_f ** 2 * correlation(d, self.ell)

    def krige(self, kq: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """For cross covariances ``kq`` (n, N_q): the level-free mean A(q) = b0 + kqᵀα,
        1 − 1ᵀΣ⁻¹kq, and the variance of log E at q without the press's own sd (universal
        kriging with a flat level: sigma_f² + tau² − kqᵀΣ⁻¹kq + (1 − 1ᵀΣ⁻¹kq)²/S0)."""
        one_minus = 1.0 - self.v1 @ kq
        z = solve_triangular(self.chol[0], kq, lower=True)
        var = (self.sigma_f ** 2 + self.tau ** 2 - (z * z).sum(axis=0)
               + one_minus ** 2 / self.s0)
        return self.b0 + self.alpha @ kq, one_minus, np.maximum(var, 0.0)


@dataclass
class CorrelatedPart:
    """What the correlated model adds to a :class:`~.posterior.SearchPosterior`.

    Attributes
    ----------
    null, lump
        The background at the mode of g given no lump, and given a lump
        (:class:`BackgroundFit`).
    phi_solve
        (K, N_kept, n) phi_h(presses)ᵀΣ⁻¹ at the lump's mode, per sphere and kept centre.
    b1
        (K, N_kept) phi_hᵀΣ⁻¹1 / S0 there (the level's shift per unit beta).
    field_weights
        (S, L) P(sigma_f, ell | presses) on ``hyp.sigma_fs`` × ``hyp.ells`` (both hypotheses
        mixed).
    evaluated
        Grid points g whose lump likelihood was summed (the others were bounded away).
    """

    null: BackgroundFit
    lump: BackgroundFit
    phi_solve: np.ndarray
    b1: np.ndarray
    field_weights: np.ndarray
    evaluated: int


def correlated_terms(hyp, phis: np.ndarray, xy: np.ndarray, m: np.ndarray, s: np.ndarray
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The log likelihood's parts on the grid g = (tau, sigma_f, ell) (module docstring).

    Returns ``L0`` (G,) log p(y | no lump, g) + log prior(g); the grid's (tau, sigma_f, ell)
    indices (G, 3); the rows ``rows`` of g whose lump terms were computed and per hypothesis
    ``u``, ``v`` (len(rows), K·N_c) so that log p(y | h, g) + log prior(g) = L0 + beta·u −
    ½ beta²·v.  A (sigma_f, ell) whose every g has L0 + ½ q0 (a bound of the lump's
    likelihood) below the null's evidence − :data:`_PRUNE` − log(K·N_c·B) is not computed.
    """
    n = m.size
    KN = phis.shape[0] * phis.shape[1]
    T = hyp.taus.size
    s2 = s * s
    dtau = s2.min() + hyp.taus ** 2  # (T,)
    E = np.diag(s2 - s2.min())
    D = np.hypot(*(xy[:, None, :] - xy[None, :, :]).transpose(2, 0, 1))
    blocks, L0, bound, idx = [], [], [], []
    for li, ell in enumerate(hyp.ells):
        R = correlation(D, ell)
        for si, sf in enumerate(hyp.sigma_fs):
            lam, Q = np.linalg.eigh(sf * sf * R + E)
            lam = np.maximum(lam, 0.0)
            inv = 1.0 / (dtau[:, None] + lam[None, :])  # (T, n)
            q1, qy = Q.T @ np.ones(n), Q.T @ m
            S0, Sy, Syy = inv @ (q1 * q1), inv @ (q1 * qy), inv @ (qy * qy)
            const = (-0.5 * np.log(dtau[:, None] + lam[None, :]).sum(1)
                     - 0.5 * (n - 1) * math.log(2 * math.pi) - 0.5 * np.log(S0)
                     + hyp.log_tau_prior + hyp.log_field_prior[si, li])
            L0.append(const - 0.5 * (Syy - Sy * Sy / S0))
            bound.append(const.max())
            blocks.append((Q, inv, q1, qy, S0, Sy))
            idx += [(t, si, li) for t in range(T)]
    L0 = np.concatenate(L0)
    floor = float(logsumexp(L0)) - _PRUNE - math.log(KN * hyp.betas.size)
    Phi = phis.reshape(KN, n)
    Phi32 = Phi.astype(np.float32)
    live = [b for b in range(len(blocks)) if bound[b] >= floor]
    # phi'Σ⁻¹1 and phi'Σ⁻¹y of every live g in one product
    SpSy = Phi @ np.hstack([blocks[b][0] @ (blocks[b][1] * blocks[b][w]).T
                            for b in live for w in (2, 3)])
    rows, U, V = [], [], []
    for j, b in enumerate(live):
        Q, inv, q1, qy, S0, Sy = blocks[b]
        P = Phi32 @ Q.astype(np.float32)
        P *= P
        Spp = P @ inv.T.astype(np.float32)  # (KN, T)
        Sp, Syp = SpSy[:, 2 * j * T:(2 * j + 1) * T], SpSy[:, (2 * j + 1) * T:(2 * j + 2) * T]
        U.append((Syp - Sp * (Sy / S0)).T)
        V.append((Spp - Sp * Sp / S0).T)
        rows.append(np.arange(b * T, (b + 1) * T))
    return (L0, np.array(idx), np.concatenate(rows), np.vstack(U).astype(np.float32),
            np.vstack(V).astype(np.float32))


def sum_lump(L0: np.ndarray, U: np.ndarray, V: np.ndarray, betas: np.ndarray
             ) -> tuple[float, np.ndarray, np.ndarray]:
    """Σ over g of exp(log p(y | h, g) + log prior(g)) per hypothesis and beta (the rows of
    :func:`correlated_terms`, ``L0`` theirs), skipping the g that cannot matter: (reference
    log r, A (K·N_c, B) the sums / e^r, per-g log mass (−inf when skipped)).

    A g is skipped when B·Σ_h exp(its bound) (the likelihood's maximum over beta in the
    prior's range, per h) is below e^−:data:`_PRUNE` of the mass summed so far; the g are
    taken in decreasing order of that bound."""
    bmin, bmax = float(betas[0]), float(betas[-1])
    bstar = np.clip(U / np.where(V > 0, V, np.inf), bmin, bmax)
    gbound = logsumexp(bstar * (U - 0.5 * bstar * V), axis=1) + L0 + math.log(betas.size)
    order = np.argsort(-gbound)
    ref, A, lg, total = -np.inf, None, np.full(L0.size, -np.inf), -np.inf
    b32 = betas.astype(np.float32)
    half = np.float32(-0.5) * b32
    for g in order:
        if gbound[g] < total - _PRUNE:
            break
        t = np.multiply.outer(V[g], half)
        t += U[g][:, None]
        t *= b32
        top = float(L0[g]) + float(t.max())
        if top > ref:
            if A is not None:
                A *= np.float32(math.exp(ref - top))
            ref = top
        t += np.float32(L0[g] - ref)
        np.exp(t, out=t)
        if A is None:
            A = t
        else:
            A += t
        lg[g] = ref + math.log(float(t.sum(dtype=np.float64)))
        total = float(np.logaddexp(total, lg[g]))
    return ref, A, lg


def predictive(post, qx: np.ndarray, qy: np.ndarray, press_sd: float, depth: int = 0
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """As :func:`palpbayes.active.criteria.predictive` under the correlated model: the
    kriging of the field given the presses, at the mode of g of each hypothesis (a press
    at depth index ``depth``).

    Under a kept centre c and sphere k the reading's mean is A(q) + beta·B_ck(q) with
    B_ck(q) = phi_ck(q) − b1_ck·(1 − 1ᵀΣ⁻¹k_q) − phi_ckᵀΣ⁻¹k_q; its second moment takes
    E[beta], E[beta²] given (c, k) at the mode, and the spheres are mixed by moments.
    """
    bg: CorrelatedPart = post.background
    hyp = post.hyp
    pc, pkc = post.kept_mix()
    kq0 = bg.null.cross(qx, qy)
    a0, _, var0 = bg.null.krige(kq0)
    kq1 = kq0 if bg.lump is bg.null else bg.lump.cross(qx, qy)
    a1, om1, var1 = bg.lump.krige(kq1)
    cx, cy = hyp.cx[post.kept], hyp.cy[post.kept]
    phi = hyp.profile(np.hypot(cx[:, None] - qx[None, :], cy[:, None] - qy[None, :]), depth)
    B = phi - bg.b1[..., None] * om1[None, None, :] - bg.phi_solve @ kq1  # (K, N_kept, N_q)
    mom = post.moments.transpose(1, 0, 2)  # (K, N_kept, 6)
    eb, eb2 = mom[..., 3:4], mom[..., 4:5]
    mu_ck = a1[None, None, :] + eb * B
    e2_ck = a1 * a1 + 2.0 * a1 * eb * B + eb2 * B * B + var1
    pk = pkc.T[..., None]
    mu = (pk * mu_ck).sum(axis=0)
    var = np.maximum((pk * e2_ck).sum(axis=0) - mu * mu, 0.0) + press_sd ** 2
    w = np.concatenate([[1.0 - post.p_lump], post.p_lump * pc])
    return (w, np.vstack([a0[None, :], mu]),
            np.sqrt(np.vstack([(var0 + press_sd ** 2)[None, :], var])))


def correlated_posterior(hyp, x: np.ndarray, y: np.ndarray, m: np.ndarray, s: np.ndarray, *,
                         prior_lump: float, kept, depth: np.ndarray | None = None) -> dict:
    """The fields of :class:`~palpbayes.active.posterior.SearchPosterior` under the
    correlated model (inputs checked by :func:`~palpbayes.active.posterior.posterior`;
    ``kept(centre_weights)`` chooses the kept centres).  The predictive moments
    (``moments``, ``null_moments``) are at the mode of g given a lump and given none;
    ``beta_survival`` and the weights sum over g.  ``depth``: each press's depth index (None:
    the reference depth)."""
    n = m.size
    xy = np.column_stack([x, y])
    phis = hyp.profile(np.hypot(hyp.cx[:, None] - x[None, :], hyp.cy[:, None] - y[None, :]),
                       None if depth is None else depth[None, :])
    K, Nc, B = phis.shape[0], hyp.cx.size, hyp.betas.size
    L0, gi, rows_g, U, V = correlated_terms(hyp, phis, xy, m, s)
    log_null = float(logsumexp(L0))
    ref, A, lg_rows = sum_lump(L0[rows_g], U, V, hyp.betas)
    lg = np.full(L0.size, -np.inf)
    lg[rows_g] = lg_rows
    A = A.astype(float)
    z = float(A.sum())
    lbf = ref + math.log(z) - math.log(Nc * K * B) - log_null
    p_lump = lump_probability(lbf, prior_lump)

    A3 = A.reshape(K, Nc, B)
    w_kc = A3.sum(axis=2)
    ck = (w_kc / z).T  # (N_c, K)
    centre_w = ck.sum(axis=1)
    keep, kept_w = kept(centre_w)
    nk = w_kc[:, keep][..., None]
    cond = A3[:, keep] / np.where(nk > 0, nk, 1.0)  # P(beta | c, k, lump), g summed
    surv = np.cumsum(cond[..., ::-1], axis=-1)[..., ::-1]

    wn = np.exp(L0 - log_null)
    wa = np.exp(lg - logsumexp(lg))
    wg = p_lump * wa + (1.0 - p_lump) * wn
    field_w = np.zeros(hyp.log_field_prior.shape)
    np.add.at(field_w, (gi[:, 1], gi[:, 2]), wg)

    def fit(g: int) -> BackgroundFit:
        t, si, li = gi[g]
        return BackgroundFit.at(xy, m, s, float(hyp.taus[t]), float(hyp.sigma_fs[si]),
                                float(hyp.ells[li]))

    g0, g1 = int(np.argmax(L0)), int(np.argmax(lg))
    null = fit(g0)
    lump = null if g1 == g0 else fit(g1)
    rows = np.arange(K)[:, None] * Nc + keep[None, :]  # (K, N_kept)
    bet = hyp.betas
    r1 = int(np.flatnonzero(rows_g == g1)[0])
    u1, v1 = U[r1][rows][..., None].astype(float), V[r1][rows][..., None].astype(float)
    ll = bet * (u1 - 0.5 * bet * v1)
    cw = np.exp(ll - ll.max(axis=-1, keepdims=True))
    cw /= cw.sum(axis=-1, keepdims=True)
    eb, eb2 = cw @ bet, cw @ (bet * bet)
    ph = phis[:, keep]  # (K, N_kept, n)
    phi_solve = cho_solve(lump.chol, ph.reshape(-1, n).T).T.reshape(ph.shape)
    b1 = (ph @ lump.v1) / lump.s0
    b0 = lump.b0
    extra = 1.0 / lump.s0 + lump.tau ** 2 + lump.sigma_f ** 2
    mom = np.stack([b0 - eb * b1, b0 * b0 - 2 * b0 * b1 * eb + b1 * b1 * eb2,
                    b0 * eb - b1 * eb2, eb, eb2, np.full(eb.shape, extra)],
                   axis=-1).transpose(1, 0, 2)  # (N_kept, K, 6)
    null_mom = np.array([null.b0, null.b0 ** 2,
                         1.0 / null.s0 + null.tau ** 2 + null.sigma_f ** 2])
    part = CorrelatedPart(null=null, lump=lump, phi_solve=phi_solve, b1=b1,
                          field_weights=field_w, evaluated=int(np.isfinite(lg).sum()))
    return dict(
        hyp=hyp, n=int(n), p_lump=p_lump, log_bayes_factor=lbf, centre_weights=centre_w,
        ck_weights=ck, kept=keep, kept_weights=kept_w, moments=mom, null_moments=null_mom,
        beta_weights=A3.sum(axis=(0, 1)) / z, beta_survival=surv,
        tau_weights=np.bincount(gi[:, 0], wg, minlength=hyp.taus.size), background=part)
