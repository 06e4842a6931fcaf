"""The recursions of the hereditary integral on a measured time axis, for
:func:`~palpbayes.contact.viscoelastic.hereditary_contact` (``../shared/DESIGN.md`` §9): per time
step, the part in contact and the integrand of d^m (:class:`Steps`); per exponential term
exp(-x·lag) of the kernel, the step's decay exp(-x·dt) and its increments
∫ exp(-x·(t_i+1 - s)) d[d^m] and d[d_+] (:func:`exp_steps`); the power law's last step against
t^(-alpha) (:func:`power_steps`); and the recursion H <- exp(-x·dt)·H + increment for all terms
at once, as a blocked scan on arrays laid out by blocks of steps (:func:`block_layout`,
:func:`blocked_scan`).  A helper module: it registers no law.

References: E. H. Lee, J. R. M. Radok, J. Appl. Mech. 27:438 (1960); M. Abramowitz, I. A. Stegun,
Handbook of Mathematical Functions (1964), 13.2.1 (Kummer's 1F1) and 15.3.1 (Euler's 2F1).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.special import beta, hyp1f1, hyp2f1

from .scratch import scratch

__all__ = ["Steps", "exp_steps", "power_steps", "block_layout", "blocked_scan",
           "scan_ordered"]


def _rule(degree: int):
    """Chebyshev nodes of a step's lag fraction, node values -> monomial coefficients c_k, and
    c_k -> Taylor coefficients in rho of Σ_k c_k·∫_0^1 exp(-rho·s)·s^k ds."""
    nodes = (1 - np.cos((2 * np.arange(degree) + 1) * np.pi / (2 * degree))) / 2
    to_coef = np.linalg.inv(np.vander(nodes, increasing=True)).T
    taylor = np.array([[(-1.0) ** j / ((k + j + 1) * math.factorial(j)) for j in range(12)]
                       for k in range(degree)])
    return nodes, to_coef, taylor


_LINEAR, _CUBIC, _RHO_SERIES = _rule(2), _rule(4), 0.2
# Taylor series in rho <= top: moments (rho^L/L! < 1e-14) and m0 = -expm1(-rho)/rho
# = Σ (-rho)^n/(n+1)! (rho^L/(L+1)! < 1e-17, then exp(-rho) = 1 - rho·m0 to 1e-16); a row's
# count is rounded up to one of _BUCKETS, so that the rows share few Horner loops.
_REACH = np.array([(1e-14 * math.factorial(n)) ** (1 / n) for n in range(1, 13)])
_M0_REACH = np.array([(1e-17 * math.factorial(n + 1)) ** (1 / n) for n in range(1, 14)])
_M0_SERIES = np.array([(-1.0) ** n / math.factorial(n + 1) for n in range(13)])
_BUCKETS = np.array([2, 3, 4, 6, 8, 10, 13])


class Steps:
    """Per time step (sample i to i + 1): its part in contact and the integrand of d^m.

    Where the contact starts or ends, or d grows by over 5 %, d^m is a power of the time from
    the zero of the step's line: integrated in closed form.  Elsewhere in contact,
    f(sigma) = m·(d1 - d0)·d^(m-1) at lag fraction sigma (from the step's end) is a polynomial
    (m = 1, 2) or its cubic interpolant: relative error ~3e-4·z^4 for a relative change z of d
    (< 2e-9 for |z| <= 5 %; larger falls, e.g. noise near the contact start, use it too).
    Its monomial coefficients ``cT`` (degree, steps) and the Taylor coefficients ``sT``
    (12, steps) of :func:`exp_steps` are kept one row per coefficient, for row-wise sums.
    """

    def __init__(self, t: np.ndarray, d: np.ndarray, m: float, u: np.ndarray | None = None):
        self.m, self.dt = m, np.diff(t)
        d0, d1 = d[:-1], d[1:]
        jump, both = d1 - d0, (d0 > 0) & (d1 > 0)
        poly = m in (1.0, 2.0)
        self.cin = np.flatnonzero((d0 <= 0) & (d1 > 0))
        self.cout = np.flatnonzero((d0 > 0) & (d1 <= 0))
        self.rise = np.flatnonzero((d1 > 0) & ((d0 <= 0) | ((jump > 0.05 * d1) & (not poly))))
        with np.errstate(divide="ignore", invalid="ignore"):
            self.L1 = self.dt * d1 / jump  # time from the zero of the step's line to its end
        self.wa, self.ell = np.zeros_like(jump), np.where(both, self.dt, 0.0)
        self.ell[self.cin] = self.L1[self.cin]
        self.wa[self.cout] = self.L1[self.cout]
        self.ell[self.cout] = self.dt[self.cout] - self.wa[self.cout]  # contact: lags wa..+ell
        dp = np.maximum(d, 0.0)
        u = dp**m if u is None else u
        self.u0, self.u1, self.dd = u[:-1], u[1:], np.diff(dp)
        nodes, to_coef, taylor = _LINEAR if poly else _CUBIC
        # f at the nodes, one row per node; zero out of contact and where integrated exactly
        scale = np.where(both, m * jump, 0.0)
        scale[self.rise] = 0.0
        if m == 1.0:
            f = np.broadcast_to(scale, (nodes.size, scale.size))
        else:
            f = np.multiply.outer(nodes, -jump)
            f += d1
            np.maximum(f, 0.0, out=f)
            if m == 1.5:
                np.sqrt(f, out=f)
            elif m != 2.0:
                f **= m - 1
            f *= scale
        self.cT = to_coef.T @ f  # (degree, steps) and (12, steps): rows read one at a time
        self.sT = taylor.T @ self.cT

    def placed(self, pos: np.ndarray, slots: int) -> Steps:
        """The same steps in ``slots`` >= steps places, step i at place pos[i]; the empty places
        are steps of the shortest length out of contact (nothing to integrate)."""
        new = object.__new__(Steps)
        new.m = self.m
        for name in ("dt", "L1", "wa", "ell", "u0", "u1", "dd", "cT", "sT"):
            a = getattr(self, name)
            out = np.full(a.shape[:-1] + (slots,), a.min() if name == "dt" else 0.0)
            out[..., pos] = a
            setattr(new, name, out)
        for name in ("cin", "cout", "rise"):
            setattr(new, name, pos[getattr(self, name)])
        return new


def _series_rows(top: np.ndarray, first: int) -> list[tuple[int, int, int]]:
    """(start, stop, terms) of the rows from ``first`` on, whose largest rho ``top`` decreases:
    runs of equal Taylor length (both series, rounded up to :data:`_BUCKETS`; 13 where
    top > 0.2, the rows whose small rho only use the series)."""
    need = np.maximum(np.searchsorted(_REACH, np.minimum(top, _RHO_SERIES)) + 1,
                      np.searchsorted(_M0_REACH, np.minimum(top, _RHO_SERIES)) + 1)
    terms = _BUCKETS[np.searchsorted(_BUCKETS, need)]
    terms[top > _RHO_SERIES] = _BUCKETS[-1]
    out, j = [], first
    while j < top.size:
        stop = j + int(np.count_nonzero(terms[j:] == terms[j]))
        out.append((j, stop, int(terms[j])))
        j = stop
    return out


def exp_steps(x: np.ndarray, st: Steps, out: tuple[np.ndarray, np.ndarray] | None = None):
    """Decays exp(-x·dt) and increments ∫ exp(-x·(t_i+1 - s)) d[d^m] and ... d[d_+] over the
    steps, shape (len(x), steps) (one array for both when m = 1); written into ``out`` =
    (decays, increments of shape (2 or 1 when m = 1, len(x), steps)) if given.

    With rho = x·dt and m0 = (1 - exp(-rho))/rho: rows whose rho exceed 0.2 somewhere take
    expm1 and the moments ∫_0^1 exp(-rho·s)·s^k ds by their upward recursion; rows (or the
    samples of a row) with rho <= 0.2 take Taylor series in rho, as short as the row's largest
    rho allows (:func:`_series_rows`), for m0, exp(-rho) = 1 - rho·m0 and the moments.  The rows
    are taken by decreasing rate (then put back), so that each kind is a slice; the series are
    evaluated in place (few large temporaries).
    """
    if x.size > 1 and np.any(np.diff(x) > 0):
        order = np.argsort(-x, kind="stable")
        back = np.argsort(order)
        decay, iu, idd = exp_steps(x[order], st)
        return decay[back], (idd[back] if iu is idd else iu[back]), idd[back]
    m, shape = st.m, (x.size, st.dt.size)
    if out is None:
        out = np.empty(shape), np.empty((1 if m == 1.0 else 2,) + shape)
    decay, iu, idd = out[0], out[1][0], out[1][-1]
    rho, m0 = np.multiply.outer(x, st.dt, out=scratch("rho", shape)), scratch("m0", shape)
    n_rec = int(np.count_nonzero(x * st.dt.max() > _RHO_SERIES))  # some rho > 0.2
    n_all = int(np.count_nonzero(x * st.dt.min() > _RHO_SERIES))  # every rho > 0.2
    if n_rec:
        r = rho[:n_rec]
        np.negative(r, out=m0[:n_rec])
        np.expm1(m0[:n_rec], out=m0[:n_rec])
        np.add(m0[:n_rec], 1.0, out=decay[:n_rec])  # exp(-rho) to 1e-16 absolute
        m0[:n_rec] /= r
        np.negative(m0[:n_rec], out=m0[:n_rec])
    groups = _series_rows(x * st.dt.max(), n_all)
    for lo, hi, terms in groups:
        if hi <= n_rec:
            continue
        lo = max(lo, n_rec)
        r, acc, dec = rho[lo:hi], m0[lo:hi], decay[lo:hi]
        acc.fill(_M0_SERIES[terms - 1])
        for c in _M0_SERIES[terms - 2::-1]:
            acc *= r
            acc += c
        np.multiply(r, acc, out=dec)
        np.subtract(1.0, dec, out=dec)
    if m != 1.0:
        if n_rec:
            r, e, acc = rho[:n_rec], decay[:n_rec], iu[:n_rec]
            mk, tmp = scratch("mk", r.shape), scratch("tmp", r.shape)
            mk[...] = m0[:n_rec]
            np.multiply(st.cT[0], mk, out=acc)
            with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
                for k in range(1, st.cT.shape[0]):
                    mk *= k
                    mk -= e
                    mk /= r
                    np.multiply(st.cT[k], mk, out=tmp)
                    acc += tmp
        for lo, hi, terms in groups:
            r, n_terms = rho[lo:hi], min(terms, 12)
            acc = iu[lo:hi] if lo >= n_rec else np.empty_like(r)
            acc[...] = st.sT[n_terms - 1]
            for j in range(n_terms - 2, -1, -1):
                acc *= r
                acc += st.sT[j]
            if lo < n_rec:  # rows with rho on both sides of 0.2
                iu[lo:hi] = np.where(r > _RHO_SERIES, iu[lo:hi], acc)
        c = st.rise  # from the zero of the step's line: d1^m·1F1(1; m+1; -x·L1) - (at d0)
        iu[:, c] = st.u1[c] * hyp1f1(1.0, m + 1.0, -np.multiply.outer(x, st.L1[c]))
        iu[:, c] -= decay[:, c] * st.u0[c] * hyp1f1(1.0, m + 1.0, -np.multiply.outer(
            x, np.maximum(st.L1[c] - st.dt[c], 0.0)))
    np.multiply(st.dd, m0, out=idd)
    for c in (st.cin, st.cout):
        if c.size:
            r = np.multiply.outer(x, st.ell[c])
            lag = np.exp(-np.multiply.outer(x, st.wa[c]))
            idd[:, c] = st.dd[c] * lag * -np.expm1(-r) / r
            if m != 1.0 and c is st.cout:
                iu[:, c] = -st.u0[c] * lag * hyp1f1(m, m + 1.0, -r)
    return decay, iu, idd


def power_steps(alpha: float, st: Steps) -> tuple[np.ndarray, np.ndarray]:
    """∫ (t_i+1 - s)^(-alpha) d[d^m] and ... d[d_+] over each step, exact for the step's
    polynomial or power (Euler: m·B(m, 1 - alpha) and 2F1(alpha, m; m + 1; L0/L1)); the first
    is 0 where the contact ends (never used: Ting's rule holds there)."""
    ell = np.where(st.ell > 0, st.ell, 1.0)
    ld = st.dd * ((st.wa + ell) ** (1 - alpha) - st.wa ** (1 - alpha)) / ((1 - alpha) * ell)
    if st.m == 1.0:
        return ld, ld
    m, c = st.m, st.rise
    lu = ell**-alpha * ((1 / (np.arange(st.cT.shape[0]) + 1 - alpha)) @ st.cT)
    L0 = np.maximum(st.L1[c] - st.dt[c], 0.0)
    lu[c] = st.L1[c] ** -alpha * (st.u1[c] * m * beta(m, 1 - alpha)
                                  - st.u0[c] * hyp2f1(alpha, m, m + 1, L0 / st.L1[c]))
    lu[st.cout] = 0.0
    return lu, ld


def block_layout(n: int) -> tuple[int, int, np.ndarray]:
    """Blocks of n steps: (size, blocks, place) with step i = b·size + s, s < size, kept at
    place s·blocks + b of an array read as (size, blocks): a block's steps along axis 0."""
    size = max(1, min(n, round(n ** (1 / 3))))
    blocks = -(-n // size)
    i = np.arange(n)
    return size, blocks, (i % size) * blocks + i // size


def blocked_scan(decay: np.ndarray, h: np.ndarray, top: bool = False) -> None:
    """In place, for ``h`` of shape (..., rows, size, blocks) and ``decay`` (rows, size, blocks)
    (the steps of :func:`block_layout`): h[s, b] becomes the state after step (b, s) of
    H <- decay·H + h from H = 0.  Blocked scan: a loop over the size steps of every block at
    once, then the blocks' end states by the same scan one level down (O(n^(1/3)) Python
    steps a level, O(n) work a row; only multiplications by decays <= 1: no overflow).
    ``top``: the outer level, whose products of decays take a scratch array."""
    size, blocks = decay.shape[-2:]
    tmp = np.empty(h.shape[:-2] + (blocks,))
    prod = scratch("products", decay.shape) if top else np.empty_like(decay)
    prod[:, 0] = decay[:, 0]  # products of the decays from each block's start
    for s in range(1, size):
        np.multiply(decay[:, s], h[..., s - 1, :], out=tmp)
        h[..., s, :] += tmp
        np.multiply(prod[:, s - 1], decay[:, s], out=prod[:, s])
    if blocks == 1:
        return
    start = np.zeros(h.shape[:-2] + (blocks,))  # state at each block's start
    start[..., 1:] = scan_ordered(prod[:, -1, :-1], h[..., -1, :-1])
    for s in range(size):  # slab by slab: no temporary as large as h
        np.multiply(prod[:, s], start, out=tmp)
        h[..., s, :] += tmp


def scan_ordered(decay: np.ndarray, inc: np.ndarray) -> np.ndarray:
    """States after each step of H <- decay·H + inc from H = 0, for ``decay`` (rows, n) and
    ``inc`` (..., rows, n) in time order (:func:`blocked_scan` on a copy in its layout)."""
    n = decay.shape[-1]
    size, blocks, place = block_layout(n)
    slots = size * blocks
    dec = np.ones(decay.shape[:-1] + (slots,))
    h = np.zeros(inc.shape[:-1] + (slots,))
    dec[..., place], h[..., place] = decay, inc
    blocked_scan(dec.reshape(dec.shape[:-1] + (size, blocks)),
                 h.reshape(h.shape[:-1] + (size, blocks)))
    return h[..., place]
