"""Ting's rule for the retract, as regression columns of the block means (power law).

While the contact shrinks the force is the Lee–Radok integral cut off at t1(t) (Ting 1966;
DESIGN §9):

    F(t) = C·∫_0^{t1} K(t − s)·du/ds ds,   ∫_{t1}^{t} K(t − s)·d'(s) ds = 0,  t1 <= t_max,

u = d^m, d = z_s − z(s) the depth, t_max the time of the deepest point; F = 0 once no t1 after
the contact's start solves the second equation (the tip has left a surface that has not yet
recovered).  With the power law K = E0*·(t/t0)^(−alpha), t1 depends on alpha and on the
motion d'(s) = −z'(s) alone, not on E0* nor on the surface (d' does not depend on z_s, and
d > 0 on [t1, t] while the tip is below the surface), so given (z_s, alpha) the retract's
force is still linear in E0*: the collapsed grid of :mod:`~palpbayes.rheology.posterior`
holds.  (The standard linear solid's t1 depends on E1*/E_inf*: not linear; its retract is
refused.)

On the knots e_k of :mod:`~palpbayes.rheology.design` (z linear between them) the source is
the line of slope r_k plus the bump c_k·b(s) of :func:`~palpbayes.rheology.design.
lee_radok_columns`, so with Φ, Ψ the kernel's first and second integrals

    ∫_{e_k}^{x} K(t − s)·u'(s) ds = r_k·[Φ(t − e_k) − Φ(t − x)]
        + c_k·{Φ(t − e_k)·b'(e_k) − Φ(t − x)·b'(x) − (8/h_k²)·[Ψ(t − e_k) − Ψ(t − x)]},

x = e_{k+1} for a whole step and x = t1 for the step that holds it: two matrices A, B of the
evaluation times × steps per alpha, and the columns r·Aᵀ + c·Bᵀ for every trial surface.  t1
comes from the same integrals of the piecewise-constant d': the knot where
∫_{e_k}^{t} K·d' ds changes sign, then the step's closed-form inverse of Φ.  A block's
value is the mean over :data:`SAMPLES` of its samples, symmetric about its middle
(:func:`symmetric_picks`; :data:`CORNER_SAMPLES` on the first :data:`CORNER_BLOCKS` retract
blocks, where the force bends at the corner).  On the
step where the contact starts u rises linearly from the crossing s_c (not from the step's
start), as in :func:`~palpbayes.rheology.design.onset_correction`, without its bump.  A tip
above the surface at t (d(t) <= 0) has F = 0.
"""

from __future__ import annotations

import numpy as np

from .kernels import double_integrated_kernel, integrated_kernel

__all__ = ["RetractDesign", "ting_columns", "ting_cutoff", "source_coefficients",
           "with_retract", "symmetric_picks", "SAMPLES", "CORNER_BLOCKS", "CORNER_SAMPLES",
           "RETRACT"]

#: Segment code of the retract (:data:`~palpbayes.trace.SEGMENTS`).
RETRACT = 2

#: Most samples per block at which the retract's force is evaluated (evenly spread) ...
SAMPLES = 5
#: ... except on the first retract blocks, where the force bends at the corner: up to
#: :data:`CORNER_SAMPLES`.
CORNER_BLOCKS = 2
CORNER_SAMPLES = 25


def symmetric_picks(n: int, k: int) -> np.ndarray:
    """Indices of ``k`` of ``n`` samples (all of them when k >= n; k + 1 when k is odd and n
    even), evenly spread and symmetric about the block's
    middle (index i picked with n − 1 − i), so that their mean is the block mean of any force
    that is linear in time (rounding the even spread alone can pick 0, 3, 6, 10, 13 of 14:
    a bias of a tenth of a sample's change, a noise sd on a steep retract)."""
    if k >= n:
        return np.arange(n)
    half = np.floor(np.linspace(0, n - 1, k)[: (k + 1) // 2] + 0.5).astype(int)
    if k % 2 and (n - 1) % 2:  # no middle sample: the two around the middle instead
        half = np.r_[half[:-1], (n - 2) // 2]
    return np.unique(np.r_[half, n - 1 - half])


def source_coefficients(z_nodes: np.ndarray, z_edges: np.ndarray, edges: np.ndarray,
                        m: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Depth at the knots (G, K) [m], the line slopes r (G, K − 1) [m^m/s] and the bump
    amplitudes c (G, K − 1) [m^m] of the source u = d^m on every knot step (0 on the step
    where the contact starts), for trial surfaces ``z_nodes`` (G,)."""
    depth = np.asarray(z_nodes, float)[:, None] - np.asarray(z_edges, float)[None, :]
    d = np.clip(depth, 0.0, None)
    u = d**m
    h = np.diff(edges)[None, :]
    r = np.diff(u, axis=1) / h
    c = (0.5 * (d[:, 1:] + d[:, :-1])) ** m - 0.5 * (u[:, 1:] + u[:, :-1])
    c[(depth[:, :-1] <= 0) | (depth[:, 1:] <= 0)] = 0.0
    return depth, r, c


class RetractDesign:
    """Ting's columns of one record's retract blocks, for any surfaces and alpha (module
    docstring).  Built once per record: the evaluation times (at most :data:`SAMPLES` per
    block, :data:`CORNER_SAMPLES` on the first :data:`CORNER_BLOCKS`) and the logarithms of
    their lags to every knot, so that Φ(t − e_k) of every alpha is one ``exp``.

    Parameters
    ----------
    edges, z_edges
        [s], [m] Knots of the motion and the tip height there (the record's, approach to
        retract).
    sample_time
        [s] (R, n) Sample times of each retract block.
    m
        Exponent of the tip's law [-].
    t0
        [s] Reference time of the power law.
    """

    def __init__(self, edges: np.ndarray, z_edges: np.ndarray, sample_time: np.ndarray,
                 m: float, t0: float = 1.0):
        self.e = np.asarray(edges, float)
        self.ze = np.asarray(z_edges, float)
        S = np.asarray(sample_time, float)
        self.R, n = S.shape
        self.m, self.t0 = float(m), float(t0)
        first = min(self.R, CORNER_BLOCKS)  # the corner where the retract starts
        picks = [symmetric_picks(n, k) for k in (CORNER_SAMPLES, SAMPLES)]
        self.groups = [(0, first, picks[0]), (first, self.R, picks[1])]
        self.sample_time = S
        self.t = np.concatenate([S[:first, picks[0]].ravel(), S[first:, picks[1]].ravel()])
        lag = self.t[:, None] - self.e[None, :]
        self.lag = np.clip(lag, 0.0, None)
        with np.errstate(divide="ignore"):
            self.log_lag = np.where(lag > 0, np.log(np.where(lag > 0, lag, 1.0)), -np.inf)
        h = np.diff(self.e)
        self.dp = -np.diff(self.ze) / h  # d' on every step [m/s], the same for every surface
        self.kmax = int(np.argmin(self.ze))
        self.z_t = np.interp(self.t, self.e, self.ze)  # the tip at every evaluation time

    def _phi(self, alpha: float) -> np.ndarray:
        """Φ(t − e_k) (n, K) per unit modulus: t0^alpha·lag^(1−alpha)/(1 − alpha)."""
        return np.exp((1.0 - alpha) * self.log_lag) * (self.t0**alpha / (1.0 - alpha))

    def cutoff(self, alpha: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """t1 (n,) [s], the index j (n,) of the step that holds it (−1: the contact is lost;
        the deepest knot: t1 = t_max) and Φ(t − e_k) (n, K)."""
        e, dp, kmax, t = self.e, self.dp, self.kmax, self.t
        phi = self._phi(alpha)
        P = dp[None, :] * (phi[:, :-1] - phi[:, 1:])  # each step's ∫ (partial at t: Φ(0) = 0)
        G = np.zeros_like(phi)
        G[:, :-1] = np.cumsum(P[:, ::-1], axis=1)[:, ::-1]  # G[:, k] = ∫_{e_k}^{t} K·d' ds
        ok = G[:, : kmax + 1] >= 0.0
        any_ok = ok.any(axis=1)
        j = np.where(any_ok, kmax - np.argmax(ok[:, ::-1], axis=1), -1)
        t1 = np.full(t.size, -np.inf)
        t1[j == kmax] = e[kmax]
        inside = any_ok & (j != kmax)
        if inside.any():
            i = np.flatnonzero(inside)
            k = j[i]
            # Φ(t − t1) = Φ(t − e_{k+1}) − G_{k+1}/d'_k, inverted in closed form
            target = phi[i, k + 1] - G[i, k + 1] / dp[k]
            x = np.clip(target, 0.0, None) * (1.0 - alpha) / self.t0**alpha
            t1[i] = np.clip(t[i] - x ** (1.0 / (1.0 - alpha)), e[k], e[k + 1])
        return t1, j, phi

    def values(self, z_nodes: np.ndarray, alpha: float) -> np.ndarray:
        """Ting's integral per unit modulus (G, n) at the evaluation times.

        The whole steps before t1's telescope into the Lee–Radok knot coefficients a1, a2
        of :func:`~palpbayes.rheology.design.lee_radok_columns` on the knots k <= j(t), so

            V = Σ_{k <= j} [a1_k·Φ(t − e_k) + a2_k·Ψ(t − e_k)]
                − (r_j + c_j·b_j'(t1))·Φ(t − t1) + (8·c_j/h_j²)·Ψ(t − t1),

        two masked products on the knots up to the deepest one (only they can hold t1),
        then the onset step's rise from the crossing."""
        z_nodes = np.atleast_1d(np.asarray(z_nodes, float))
        t, kmax = self.t, self.kmax
        t1, j, phi_all = self.cutoff(alpha)
        live = j >= 0
        if kmax + 1 >= self.e.size or not live.any():  # nothing after the deepest knot
            return np.zeros((z_nodes.size, t.size))
        top = kmax + 2  # the step after the deepest knot enters a1, a2 there (and cancels)
        e, ze = self.e[:top], self.ze[:top]
        h = np.diff(e)
        depth, r, c = source_coefficients(z_nodes, ze, e, self.m)
        a1, a2 = np.zeros((z_nodes.size, top)), np.zeros((z_nodes.size, top))
        b1, b2 = 4.0 * c / h, 8.0 * c / h**2
        a1[:, :-1] += r + b1
        a1[:, 1:] += b1 - r
        a2[:, :-1] -= b2
        a2[:, 1:] += b2
        K = kmax + 1
        mask = np.arange(K)[None, :] <= j[:, None]  # (n, K); a lost contact (j = -1): none
        phi_m = np.where(mask, phi_all[:, :K], 0.0)
        psi_m = phi_m * self.lag[:, :K] / (2.0 - alpha)  # Ψ = Φ·x/(2 − alpha)
        V = a1[:, :K] @ phi_m.T + a2[:, :K] @ psi_m.T
        jj = np.clip(j, 0, top - 2)
        t1s = np.where(live, t1, t)  # any finite time where the contact is lost (masked)
        phi_1 = integrated_kernel(t - t1s, "power-law", alpha, self.t0)
        psi_1 = double_integrated_kernel(t - t1s, "power-law", alpha, self.t0)
        bp = 4.0 * (e[jj + 1] + e[jj] - 2.0 * t1s) / h[jj] ** 2
        V += -(r[:, jj] + c[:, jj] * bp) * phi_1 + (8.0 * c[:, jj] / h[jj] ** 2) * psi_1
        V[:, ~live] = 0.0
        # the step where the contact starts: u rises from the crossing s_c, not from e_k
        onset = (depth[:, :-1] <= 0) & (depth[:, 1:] > 0)
        g = np.flatnonzero(onset.any(axis=1))
        if g.size:
            k = np.argmax(onset[g], axis=1)
            d0, d1 = depth[g, k], depth[g, k + 1]
            sc = e[k] + h[k] * (-d0) / (d1 - d0)  # (Gc,)
            inc = (j[None, :] >= k[:, None]) & live[None, :]
            x = np.where(j[None, :] > k[:, None], e[k + 1][:, None], t1s[None, :])  # (Gc, n)

            def phi(y):
                return integrated_kernel(y, "power-law", alpha, self.t0)

            linear = r[g, k][:, None] * (phi(t[None, :] - e[k][:, None]) - phi(t[None, :] - x))
            slope = d1**self.m / (e[k + 1] - sc)
            exact = np.where(x > sc[:, None], slope[:, None] * (
                phi(t[None, :] - sc[:, None]) - phi(t[None, :] - np.maximum(x, sc[:, None]))),
                0.0)
            V[g] += np.where(inc, exact - linear, 0.0)
        V[z_nodes[:, None] <= self.z_t[None, :]] = 0.0  # the tip above the surface at t
        return np.clip(V, 0.0, None)

    def columns(self, z_nodes: np.ndarray, alpha: float) -> np.ndarray:
        """Block means (G, R) per unit modulus and unit prefactor: multiply by C·E0* for
        the force [N].  The mean of a block's picks, except in the block where the contact
        is lost (:meth:`pull_off_means`)."""
        V = self.values(z_nodes, alpha)
        out = np.empty((V.shape[0], self.R))
        at = 0
        for lo, hi, picks in self.groups:
            if hi > lo:
                n_eval = (hi - lo) * picks.size
                out[:, lo:hi] = V[:, at: at + n_eval].reshape(-1, hi - lo, picks.size).mean(
                    axis=2)
                self.pull_off_means(V, at, lo, hi, picks, out)
                at += n_eval
        return out

    def pull_off_means(self, V: np.ndarray, at: int, lo: int, hi: int, picks: np.ndarray,
                       out: np.ndarray) -> None:
        """Replace in ``out`` (G, R) the means of the blocks ``lo`` ... ``hi`` − 1 (values
        from column ``at`` of ``V`` (G, n), at each block's ``picks``) where the force falls
        to zero between two picks.

        There the force is not linear but a line down to a kink at zero, and the picks'
        mean misses where the kink lies (2 noise sd on a flat punch's pull-off block at
        500 mm/min).  The force is rebuilt at every sample: linear between the picks up to
        the last positive one (value v_a at t_a), then down to zero along the steeper of the
        line from the evaluation before it (the force's slope as it falls) and the chord to
        the next pick (whose value, 0, bounds the crossing), zero after; its mean over the
        block's samples is the block's value."""
        k = picks.size
        Vb = V[:, at: at + (hi - lo) * k].reshape(-1, hi - lo, k)
        # positive: above the rounding of a cancelled integral (1e-14 of the peak seen)
        pos = Vb > 1e-9 * V.max(axis=1)[:, None, None]
        n_pos = pos.sum(axis=2)
        # positive picks, then zero ones: the force falls to zero once, inside the block
        cell = (n_pos > 0) & (n_pos < k) & (np.argmin(pos, axis=2) == n_pos)
        g, b = np.nonzero(cell)
        if g.size == 0:
            return
        c = np.arange(g.size)
        a = n_pos[g, b] - 1  # the last positive pick
        S = self.sample_time[lo + b]  # (c, n)
        tp, v = S[:, picks], Vb[g, b]  # (c, k)
        ta, va, tb = tp[c, a], v[c, a], tp[c, a + 1]
        chord = -va / (tb - ta)
        q = at + b * k + a - 1  # the evaluation before t_a (the previous block's last pick)
        has = q >= 0
        fall = np.full(g.size, -np.inf)
        fall[has] = (va[has] - V[g[has], q[has]]) / (ta[has] - self.t[q[has]])
        slope = np.minimum(fall, chord)
        slope = np.where(np.isfinite(slope), slope, chord)
        rebuilt = np.empty_like(S)
        for i in c:  # the pull-off blocks only: a few cells per evaluation
            rebuilt[i] = np.interp(S[i], tp[i], v[i])
        line = np.clip(va[:, None] + slope[:, None] * (S - ta[:, None]), 0.0, None)
        out[g, lo + b] = np.where(S > ta[:, None], line, rebuilt).mean(axis=1)


def ting_cutoff(t: np.ndarray, edges: np.ndarray, z_edges: np.ndarray, alpha: float,
                t0: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Ting's t1 [s] at times ``t`` (n,) of a shrinking contact, and the index of the knot
    step that holds it (−1: no t1 after the first knot, the contact is lost; the deepest
    knot's index: the contact has not started to shrink, t1 = t_max).

    The motion is the line through the knots ``(edges, z_edges)``; t_max is the deepest
    knot; the kernel is (t/t0)^(−alpha).
    """
    t = np.atleast_1d(np.asarray(t, float))
    design = RetractDesign(edges, z_edges, t[:, None], 1.0, t0)
    t1, j, _ = design.cutoff(alpha)
    return t1, j


def ting_columns(edges: np.ndarray, z_edges: np.ndarray, sample_time: np.ndarray,
                 z_nodes: np.ndarray, m: float, alpha: float, t0: float = 1.0) -> np.ndarray:
    """Block means (G, R) of Ting's ∫_0^{t1} K(t − s)·d/ds[d(s)^m] ds per unit modulus and
    unit prefactor, K = (t/t0)^(−alpha), for the blocks with sample times ``sample_time``
    (R, n) [s] on the retract and trial surfaces ``z_nodes`` (G,) [m]: one
    :class:`RetractDesign` (build that once to evaluate many surfaces and alphas).

    Returns
    -------
    numpy.ndarray
        (G, R) [m^m]: multiply by C·E0* for the force [N].
    """
    return RetractDesign(edges, z_edges, sample_time, m, t0).columns(z_nodes, alpha)


def with_retract(data, columns: np.ndarray, z_nodes: np.ndarray, alpha: float,
                 t0: float = 1.0, design: RetractDesign | None = None) -> np.ndarray:
    """``columns`` (G, B) of a power-law fit's block means (Lee–Radok,
    :func:`~palpbayes.rheology.design.lee_radok_columns`, per unit modulus) with the rows of
    the retract's blocks replaced by Ting's; unchanged without a retract.  ``data`` is the
    :class:`~palpbayes.rheology.cycle.CycleData`; ``design`` its :class:`RetractDesign`
    (built here when None)."""
    ret = data.segment == RETRACT
    if ret.any():
        if design is None:
            design = RetractDesign(data.edges, data.z_edges, data.sample_time[ret], data.m, t0)
        columns[:, ret] = design.columns(z_nodes, alpha)
    return columns
