"""Ting's rule (T. C. T. Ting, J. Appl. Mech. 33:845, 1966) on a measured time axis: the upper
limit t1 of the hereditary integral while the contact shrinks, for
:func:`~palpbayes.contact.viscoelastic.hereditary_contact` (``../shared/DESIGN.md`` §9).  A
helper module: it registers no law.

Below its running maximum at t_max, the force is F(t) = C·∫_0^{t1} E(t - s)·d/ds[d(s)^m] ds with
t1 <= t_max solving ∫_{t1}^{t} E(t - s)·d'(s) ds = 0.  With the kernel as a0 + Σ_j a_j·
exp(-x_j·lag) and the per-term histories H_j(t_k) (the recursions of the caller), the integral
from the start to a sample k is a0·v(t_k) + Σ_j a_j·exp(-x_j·(t - t_k))·H_j(t_k), and t1's step is
found by bisection over the samples, vectorised over the rows (O(rows·K·log N)).

The exponentials exp(-x_j·(t - t_k)) are products of the caller's step decays: for the rows
below one running maximum at sample q (a group; the retract of a cycle is one),
exp(-x_j·(t_r - t_k)) = A_j(r)·P_j(k) with A_j(r) = Π_{i=q}^{r-1} exp(-x_j·dt_i) and
P_j(k) = Π_{i=k}^{q-1} exp(-x_j·dt_i), two cumulative products (O(N·K), nothing divided, so
nothing overflows); each bisection step is then one gather and one dot product per row.  Groups
of few rows (a noisy hold just below its maximum) take exp(-x_j·(t_r - t_k)) directly.
"""

from __future__ import annotations

import numpy as np

from .scratch import scratch

# Gauss-Legendre on [0, 1] in ln(lag) for the partial step [t_k, t1]: 12 points, or 4 where the
# step spans ln(lag) by q <= _Q_FEW away from the contact's first step (error ~ (q/2)^8/8!
# relative: < 1e-17)
_GL = tuple(((x + 1) / 2, w / 2) for x, w in map(np.polynomial.legendre.leggauss, (4, 12)))
_Q_FEW = 0.05

#: A group of rows below one maximum at sample q gets its products when rows·this >= q + 1 -
#: (first contact sample): their O(q·K) cumulative products cost less than exponentials.
_FACTOR_ROWS = 50


class _History:
    """∫_0^{t_k} E(t_r - s) dv(s) = a0·v[k] + Σ_j a_j·exp(-x_j·(t_r - t_k))·H[k, j] for the
    Ting rows r (index ``i`` into them) at samples k < r (lag >= one step: the sum holds)."""

    def __init__(self, t, rows, kmax, lo0, soe, decay):
        a0, a, x = soe[:3]
        self.t, self.rows, self.a0, self.a, self.x = t, rows, a0, a, x
        q = kmax[rows]  # non-decreasing: the groups are runs
        change = np.empty(q.size, dtype=bool)
        change[:1] = True
        np.not_equal(q[1:], q[:-1], out=change[1:])
        first = np.flatnonzero(change)
        count = np.empty_like(first)
        np.subtract(first[1:], first[:-1], out=count[:-1])
        count[-1] = q.size - first[-1]
        groups = q[first]
        big = count * _FACTOR_ROWS >= groups + 1 - lo0
        self.factored = np.repeat(big, count)
        self.all_factored = bool(big.all())
        self.aA = scratch("ting a·A", (rows.size, x.size + 1), zero=not self.all_factored)
        self.aA[:, -1] = a0  # a_j·A_j(r), then a0: the products' last column is v
        self.base = np.zeros(rows.size, dtype=np.intp)  # row of P(k) = base + k
        parts, samples, offset = [], [], 0
        one = int(np.count_nonzero(big)) == 1  # the usual case: one retract, in scratch
        for g, i0, n in zip(groups[big], first[big], count[big], strict=True):
            r = rows[i0:i0 + n]  # rows are sorted and kmax rises: a group is contiguous
            P = scratch("ting P", (g + 1 - lo0, x.size)) if one else np.empty(
                (g + 1 - lo0, x.size))
            P[-1] = 1.0
            np.cumprod(decay[lo0:g][::-1], axis=0, out=P[:-1][::-1])
            A = np.cumprod(decay[g:r[-1]], axis=0, out=scratch("ting A", (r[-1] - g, x.size)))
            np.multiply(a, A[r - g - 1], out=self.aA[i0:i0 + n, :-1])
            self.base[i0:i0 + n] = offset - lo0
            parts.append(P)
            samples.append(np.arange(lo0, g + 1))
            offset += P.shape[0]
        self.P = (parts[0] if one else np.concatenate(parts) if parts
                  else np.zeros((0, x.size)))
        self.sample = np.concatenate(samples) if samples else np.zeros(0, dtype=np.intp)
        # the samples as a slice when they are one run (one group): no gather
        self.span = slice(lo0, lo0 + self.sample.size) if one else self.sample
        self._products: dict[str, np.ndarray] = {}

    def products(self, H, v, name: str) -> np.ndarray:
        """[P(k)·H[k], v[k]] at the factored samples, shape (samples, K + 1), computed once
        per ``name`` (which history H and v are: ``"d"`` or ``"u"``)."""
        out = self._products.get(name)
        if out is None:
            K = self.x.size
            out = self._products[name] = scratch(f"ting P·H {name}", (self.sample.size, K + 1))
            np.multiply(self.P, H[self.span], out=out[:, :K])
            out[:, K] = v[self.span]
        return out

    def __call__(self, H, v, i, k, name: str) -> np.ndarray:
        """∫_0^{t_k} E(t_r - s) dv(s) for rows ``i`` at samples ``k`` (``name`` as in
        :meth:`products`)."""
        if self.all_factored:
            return np.einsum("ij,ij->i", self.aA[i], self.products(H, v, name)[self.base[i] + k])
        out = np.empty(i.size)
        f = self.factored[i]
        fi, fk, ni, nk = i[f], k[f], i[~f], k[~f]
        if fi.size:
            out[f] = np.einsum("ij,ij->i", self.aA[fi],
                               self.products(H, v, name)[self.base[fi] + fk])
        lag = self.t[self.rows[ni]] - self.t[nk]
        out[~f] = self.a0 * v[nk] + np.einsum("ij,ij->i", self.a * np.exp(
            -np.multiply.outer(lag, self.x)), H[nk])
        return out

    def search(self, Hd, dp, g, i, lo, hi) -> None:
        """Bisection over the samples for the rows ``i``, vectorised: ``lo`` and ``hi`` (in
        place) end one sample apart with ∫_{t_lo}^{t} E·d' ds > 0 >= ∫_{t_hi}^{t} E·d' ds
        (``g`` - this function's history of d_+)."""
        f = self.factored[i]
        for sel, fast in ((np.flatnonzero(f), True), (np.flatnonzero(~f), False)):
            if not sel.size:
                continue
            ii = i[sel]
            gg, l, h = g[ii], lo[ii], hi[ii]
            if fast:  # a0·dp[k] as one more term: one gather and one dot product a step
                aA, PH = self.aA[ii], self.products(Hd, dp, "d")
                base = self.base[ii]
                at = scratch("ting search gather", aA.shape)
            for _ in range(int(np.max(h - l, initial=1)).bit_length()):
                mid = (l + h) >> 1  # a finished row (h = l + 1) re-tests l: no change
                if fast:
                    np.take(PH, base + mid, axis=0, out=at)
                    neg = np.einsum("ij,ij->i", aA, at) >= gg
                else:
                    neg = self(Hd, dp, ii, mid, "d") >= gg
                h, l = np.where(neg, mid, h), np.where(neg, l, mid)
            lo[ii], hi[ii] = l, h


# Many parameters: the arrays of one step of Ting's rule, passed as they are: a numerical inner
# loop, where an object per call would cost.
def ting_rule(t, d, dp, u, dt, m, soe, kernel, Hu, Hd, decay, G, rows, force, t1, C) -> None:
    """Ting's rule at the samples ``rows`` (depth below its running maximum), in place.

    Parameters
    ----------
    t, d, dp, u
        [s], [m], [m], [m^m] Times, depths, d_+ = max(d, 0) and d_+^m at every sample.
    dt
        [s] Time steps t[i+1] - t[i].
    m
        Exponent [-] of the elastic law F = C·E·d^m.
    soe
        (a0 [Pa], a [Pa], x [1/s], ...): the kernel as a0 + Σ_j a_j·exp(-x_j·lag).
    kernel
        The relaxation kernel (its exact integral places t1 inside its step).
    Hu, Hd
        [m^m], [m] Per-term histories H_j(t_k) = ∫_0^{t_k} exp(-x_j·(t_k - s)) dv(s) of v = d^m
        and d_+, shape (samples, K).
    decay
        [-] exp(-x_j·dt_i), shape (steps, K).
    G
        [Pa·m] ∫_0^t E(t - s) d[d_+](s) at every sample.
    rows
        Indices of the samples where Ting's rule applies, increasing.
    force, t1
        [N], [s] Outputs, written at ``rows``.
    C
        [N/(Pa·m^m)] Prefactor of the elastic law.
    """
    kc = int(np.argmax(d > 0))  # first sample in contact (d[0] <= 0, so kc >= 1)
    s0 = t[kc - 1] + dt[kc - 1] * -d[kc - 1] / (d[kc] - d[kc - 1])
    kmax = np.maximum.accumulate(np.where(d == np.maximum.accumulate(d), np.arange(t.size), 0))
    hist = _History(t, rows, kmax, kc - 1, soe, decay)
    nu = "d" if m == 1.0 else "u"  # m = 1: d^m is d_+ (the same histories)
    everyone = np.arange(rows.size)
    g, f, tt = G[rows], np.zeros(rows.size), np.full(rows.size, np.nan)
    hi, lo = kmax[rows], np.full(rows.size, kc - 1)
    grow = (g > 0) & (g - hist(Hd, dp, everyone, hi, "d") > 0)  # no root before t_max: t1 = t_max
    act = np.flatnonzero((g > 0) & ~grow & (hi - lo > 1))
    if act.size:
        hist.search(Hd, dp, g, act, lo, hi)
    i = np.flatnonzero(grow)
    tt[i], f[i] = t[hi[i]], C * hist(Hu, u, i, hi[i], nu)
    i = np.flatnonzero((g > 0) & ~grow)
    if i.size:
        r, k = rows[i], hi[i] - 1  # t1 on the step from sample k to k + 1
        b = (d[k + 1] - d[k]) / dt[k]
        w_lo, w_hi = t[r] - t[k + 1], t[r] - np.where(k + 1 == kc, s0, t[k])  # lags
        A_hi = kernel.integral(w_hi)
        with np.errstate(divide="ignore", invalid="ignore"):
            target = A_hi - (g[i] - hist(Hd, dp, i, k, "d")) / b
        # clipped to the step's integrals; NaN (b = 0) takes the lower one: fmax drops NaN
        target = np.fmin(np.fmax(target, kernel.integral(w_lo)), A_hi)
        w1 = np.where(b > 0, kernel._inverse_integral(target, w_lo, w_hi), w_lo)
        q = np.log1p((w_hi - w1) / w1)  # ∫_{start}^{t1} E(t - s)·d/ds[d^m] ds in ln(lag)
        few = (q <= _Q_FEW) & (k + 1 != kc)
        part = np.empty(i.size)
        for sel, (gx, gw) in zip((np.flatnonzero(few), np.flatnonzero(~few)), _GL, strict=True):
            if sel.size:
                w = w1[sel, None] * np.exp(q[sel, None] * gx)
                ds = np.clip(d[k[sel], None] + b[sel, None] * (t[r[sel], None] - w
                                                               - t[k[sel], None]), 0.0, None)
                part[sel] = (kernel(w) * w * m * ds ** (m - 1) * gw).sum(axis=1) * b[
                    sel] * q[sel]
        tt[i], f[i] = t[r] - w1, C * (hist(Hu, u, i, k, nu) + part)
    force[rows], t1[rows] = f, tt
