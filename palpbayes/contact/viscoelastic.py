"""Rigid axisymmetric tip (elastic law F = C·E·d^m) on a linear viscoelastic half-space: the
Lee–Radok and Ting hereditary integrals on a measured time axis, the relaxation kernels
:class:`PowerLawKernel` and :class:`PronyKernel`, and the closed forms of a ramp and of a
constant-strain-rate compression (``../shared/DESIGN.md`` §9 "Viscoelastic contact", whose
closed forms the tests check; "DESIGN §9" below).  A helper module: it registers no law.

References: E. H. Lee, J. R. M. Radok, J. Appl. Mech. 27:438 (1960); T. C. T. Ting, J. Appl.
Mech. 33:845 (1966); G. Beylkin, L. Monzón, Appl. Comput. Harmon. Anal. 28:131 (2010).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.special import beta, gamma, hyp1f1, hyp2f1, loggamma

from ..errors import InputError
from .ting_rule import ting_rule

__all__ = ["PowerLawKernel", "PronyKernel", "standard_linear_solid", "HereditaryContact",
           "hereditary_contact", "hereditary_force", "ramp_apparent_modulus",
           "constant_strain_rate_stress", "SOE_TOLERANCE"]

#: Relative accuracy [-] of the power law's sum of exponentials on [shortest step, duration].
SOE_TOLERANCE = 1e-7


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
# At most _FEW terms whose rates x·(duration) <= 2·_SPREAD: the recursions as cumulative sums
# scaled by exp(±x·t) (|x·t| <= _SPREAD from mid-record: no overflow), fewer Python steps.
_FEW, _SPREAD = 4, 600.0
#: Most numbers [-] in one block of terms' arrays (terms × steps): the memory per array.
_CHUNK = 2_000_000


def _number(name: str, value, unit: str = "", bound: str = "") -> float:
    """``value`` as a finite float, ``bound`` "> 0" or ">= 0" if given, else InputError."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise InputError(f"{name} = {value!r} is not a number") from None
    if not math.isfinite(v) or (bound == "> 0" and v <= 0) or (bound == ">= 0" and v < 0):
        raise InputError(f"{name} = {v!r} {unit} must be finite{' and ' if bound else ''}{bound}")
    return v


@dataclass(frozen=True)
class PowerLawKernel:
    """Springpot relaxation modulus E(t) = E0·(t/t0)^(-alpha) [Pa]: E0 [Pa] > 0 the modulus at
    t0 [s] > 0, 0 <= alpha < 1 (0 elastic, towards 1 a dashpot)."""

    E0: float
    alpha: float
    t0: float = 1.0

    def __post_init__(self) -> None:
        alpha = _number("power-law exponent alpha", self.alpha)
        if not 0.0 <= alpha < 1.0:
            raise InputError(f"power-law exponent alpha = {alpha!r} is outside [0, 1) "
                             "(0: elastic; 1 would be a dashpot with unbounded force)")
        object.__setattr__(self, "E0", _number("power-law modulus E0", self.E0, "Pa", "> 0"))
        object.__setattr__(self, "alpha", alpha)
        object.__setattr__(self, "t0", _number("reference time t0", self.t0, "s", "> 0"))

    def __call__(self, t) -> np.ndarray:
        """E(t) [Pa] at times ``t`` [s] (inf at t = 0 unless alpha = 0)."""
        with np.errstate(divide="ignore"):
            return self.E0 * (np.asarray(t, dtype=float) / self.t0) ** (-self.alpha)

    def integral(self, t) -> np.ndarray:
        """∫_0^t E(s) ds = E0·t0^alpha·t^(1-alpha)/(1-alpha) [Pa·s]."""
        a = self.alpha
        return self.E0 * self.t0**a * np.asarray(t, dtype=float) ** (1 - a) / (1 - a)

    def _inverse_integral(self, target, lo, hi) -> np.ndarray:
        a = self.alpha
        return np.clip((target * (1 - a) / (self.E0 * self.t0**a)) ** (1 / (1 - a)), lo, hi)


@dataclass(frozen=True)
class PronyKernel:
    """Prony series E(t) = E_inf + Σ E_i·exp(-t/tau_i) [Pa]: relaxed modulus E_inf [Pa] >= 0,
    branch moduli ``E`` [Pa] >= 0 and relaxation times ``tau`` [s] > 0 (as many)."""

    E_inf: float
    E: tuple[float, ...] = ()
    tau: tuple[float, ...] = ()

    def __post_init__(self) -> None:
        E, tau = np.atleast_1d(self.E), np.atleast_1d(self.tau)
        if len(E) != len(tau):
            raise InputError(f"Prony series: {len(E)} moduli E but {len(tau)} times tau")
        names = ["relaxed modulus E_inf", *(f"Prony modulus E[{i}]" for i in range(len(E)))]
        E = [_number(n, v, "Pa", ">= 0") for n, v in zip(names, [self.E_inf, *E], strict=True)]
        tau = tuple(_number(f"relaxation time tau[{i}]", v, "s", "> 0") for i, v in enumerate(tau))
        if sum(E) <= 0:
            raise InputError("Prony series: every modulus is zero (E_inf + Σ E_i = 0 Pa)")
        for name, value in (("E_inf", E[0]), ("E", tuple(E[1:])), ("tau", tau)):
            object.__setattr__(self, name, value)

    def __call__(self, t) -> np.ndarray:
        """E(t) [Pa] at times ``t`` [s]."""
        t = np.asarray(t, dtype=float)
        return self.E_inf + sum(e * np.exp(-t / s) for e, s in zip(self.E, self.tau, strict=True))

    def integral(self, t) -> np.ndarray:
        """∫_0^t E(s) ds = E_inf·t + Σ E_i·tau_i·(1 - exp(-t/tau_i)) [Pa·s]."""
        t = np.asarray(t, dtype=float)
        return self.E_inf * t + sum(e * s * -np.expm1(-t / s)
                                    for e, s in zip(self.E, self.tau, strict=True))

    def _inverse_integral(self, target, lo, hi) -> np.ndarray:
        w = np.array(lo, dtype=float)  # Newton from below: the integral is concave
        with np.errstate(divide="ignore", invalid="ignore"):
            for _ in range(100):
                step = np.maximum(np.nan_to_num((target - self.integral(w)) / self(w)), 0.0)
                w, w_old = np.minimum(w + step, hi), w
                if np.all(w - w_old <= 1e-15 * w):
                    break
        return w


def standard_linear_solid(E_inf: float, E1: float, tau: float) -> PronyKernel:
    """Standard linear solid E(t) = E_inf + E1·exp(-t/tau) [Pa] (one-term Prony series)."""
    return PronyKernel(E_inf, (E1,), (tau,))


Kernel = PowerLawKernel | PronyKernel


@dataclass(frozen=True, eq=False)
class HereditaryContact:
    """:func:`hereditary_contact` at every sample: ``force`` [N] (>= 0); ``t1`` [s], the upper
    limit of the hereditary integral (the sample's time while the contact grows, Ting's
    t1 <= t_max while it shrinks, NaN out of contact); ``ting``, where Ting's rule applied."""

    force: np.ndarray
    t1: np.ndarray
    ting: np.ndarray


def _power_soe(alpha: float, dt_min: float, span: float) -> tuple[np.ndarray, np.ndarray]:
    """Weights w and rates x [1/s] with Σ w_j·exp(-x_j·t) ≈ t^(-alpha) on [dt_min, span].

    Trapezoidal rule in y = ln x of t^(-alpha) = ∫ exp(alpha·y - e^y·t) dy / Gamma(alpha)
    (Beylkin & Monzón 2010): the step h keeps the aliasing error 2|Gamma(alpha + 2·pi·i/h)| /
    Gamma(alpha) below a third of :data:`SOE_TOLERANCE`; the top node is x = ln(3/tol)/dt_min;
    the rule's geometric tail of slow nodes is lumped into one exponential with its zeroth and
    first moments, from where that costs (x·t)² < tol/3.
    """
    eps = SOE_TOLERANCE
    hs = np.linspace(0.3, 1.5, 121)
    h = hs[2 * np.exp(loggamma(alpha + 2j * np.pi / hs).real - loggamma(alpha)) <= eps / 3][-1]
    g1 = gamma(alpha + 1)
    c2 = h * alpha / (-math.expm1(-(2 + alpha) * h) * g1)
    y_lo = math.log((2 * eps / (3 * c2)) ** (1 / (2 + alpha)) / span)
    y_hi = math.log(math.log(3 / eps) / dt_min)
    y = y_hi - h * np.arange(max(1, math.ceil((y_hi - y_lo) / h)) + 1)
    y_tail = y[-1] - h
    s0, s1 = (h * alpha * math.exp((alpha + k) * y_tail) / (-math.expm1(-(alpha + k) * h) * g1)
              for k in (0, 1))
    return np.append(h * alpha * np.exp(alpha * y) / g1, s0), np.append(np.exp(y), s1 / s0)


def _soe(kernel: Kernel, dt_min: float, span: float):
    """(a0, a, x, alpha, k): E(t) ≈ a0 + Σ a_j·exp(-x_j·t), the rates x [1/s] decreasing, exact
    for Prony (alpha None); for a power law valid on lags >= the shortest step, the last step
    using k·t^(-alpha)."""
    if isinstance(kernel, PronyKernel):
        E, tau = np.array(kernel.E), np.array(kernel.tau)
        keep = np.flatnonzero(E > 0)
        keep = keep[np.argsort(tau[keep], kind="stable")]
        return kernel.E_inf, E[keep], 1.0 / tau[keep], None, 0.0
    if kernel.alpha == 0.0:
        return kernel.E0, np.zeros(0), np.zeros(0), None, 0.0
    k = kernel.E0 * kernel.t0**kernel.alpha
    w, x = _power_soe(kernel.alpha, dt_min, span)
    order = np.argsort(-x, kind="stable")
    return 0.0, k * w[order], x[order], kernel.alpha, k


class _Steps:
    """Per time step (sample i to i + 1): its part in contact and the integrand of d^m.

    Where the contact starts or ends, or d grows by over 5 %, d^m is a power of the time from
    the zero of the step's line: integrated in closed form.  Elsewhere in contact,
    f(sigma) = m·(d1 - d0)·d^(m-1) at lag fraction sigma (from the step's end) is a polynomial
    (m = 1, 2) or its cubic interpolant: relative error ~3e-4·z^4 for a relative change z of d
    (< 2e-9 for |z| <= 5 %; larger falls, e.g. noise near the contact start, use it too).
    ``coef`` (steps, degree) and ``series`` (steps, 12) are also kept transposed, ``cT`` and
    ``sT``, for the row-wise sums of :func:`_exp_steps`.
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
        dp = np.clip(d, 0, None)
        u = dp**m if u is None else u
        self.u0, self.u1, self.dd = u[:-1], u[1:], np.diff(dp)
        nodes, to_coef, taylor = _LINEAR if poly else _CUBIC
        if m == 1.0:
            f = np.repeat(jump[:, None], nodes.size, axis=1)
        elif m == 2.0:
            f = 2 * jump[:, None] * np.clip(d1[:, None] - jump[:, None] * nodes, 0, None)
        else:
            f = m * jump[:, None] * np.clip(d1[:, None] - jump[:, None] * nodes, 0, None) ** (
                m - 1)
        f[~both] = 0.0
        f[self.rise] = 0.0
        self.coef = f @ to_coef
        self.series = self.coef @ taylor
        self.cT, self.sT = self.coef.T.copy(), self.series.T.copy()

    def placed(self, pos: np.ndarray, slots: int) -> _Steps:
        """The same steps in ``slots`` >= steps places, step i at place pos[i]; the empty places
        are steps of the shortest length out of contact (nothing to integrate)."""
        new = object.__new__(_Steps)
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


def _exp_steps(x: np.ndarray, st: _Steps, out: tuple[np.ndarray, np.ndarray] | None = None):
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
        decay, iu, idd = _exp_steps(x[order], st)
        return decay[back], (idd[back] if iu is idd else iu[back]), idd[back]
    m, shape = st.m, (x.size, st.dt.size)
    if out is None:
        out = np.empty(shape), np.empty((1 if m == 1.0 else 2,) + shape)
    decay, iu, idd = out[0], out[1][0], out[1][-1]
    rho, m0 = np.multiply.outer(x, st.dt), np.empty(shape)
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
            mk, tmp = m0[:n_rec].copy(), np.empty_like(r)
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


def _power_steps(alpha: float, st: _Steps) -> tuple[np.ndarray, np.ndarray]:
    """∫ (t_i+1 - s)^(-alpha) d[d^m] and ... d[d_+] over each step, exact for the step's
    polynomial or power (Euler: m·B(m, 1 - alpha) and 2F1(alpha, m; m + 1; L0/L1)); the first
    is 0 where the contact ends (never used: Ting's rule holds there)."""
    ell = np.where(st.ell > 0, st.ell, 1.0)
    ld = st.dd * ((st.wa + ell) ** (1 - alpha) - st.wa ** (1 - alpha)) / ((1 - alpha) * ell)
    if st.m == 1.0:
        return ld, ld
    m, c = st.m, st.rise
    lu = ell**-alpha * (st.coef @ (1 / (np.arange(st.coef.shape[1]) + 1 - alpha)))
    L0 = np.maximum(st.L1[c] - st.dt[c], 0.0)
    lu[c] = st.L1[c] ** -alpha * (st.u1[c] * m * beta(m, 1 - alpha)
                                  - st.u0[c] * hyp2f1(alpha, m, m + 1, L0 / st.L1[c]))
    lu[st.cout] = 0.0
    return lu, ld


def _layout(n: int) -> tuple[int, int, np.ndarray]:
    """Blocks of n steps: (size, blocks, place) with step i = b·size + s, s < size, kept at
    place s·blocks + b of an array read as (size, blocks): a block's steps along axis 0."""
    size = max(1, min(n, round(n ** (1 / 3))))
    blocks = -(-n // size)
    i = np.arange(n)
    return size, blocks, (i % size) * blocks + i // size


def _scan(decay: np.ndarray, h: np.ndarray) -> None:
    """In place, for ``h`` of shape (..., rows, size, blocks) and ``decay`` (rows, size, blocks)
    (the steps of :func:`_layout`): h[s, b] becomes the state after step (b, s) of
    H <- decay·H + h from H = 0.  Blocked scan: a loop over the size steps of every block at
    once, then the blocks' end states by the same scan one level down (O(n^(1/3)) Python
    steps a level, O(n) work a row; only multiplications by decays <= 1: no overflow)."""
    size, blocks = decay.shape[-2:]
    tmp, prod = np.empty(h.shape[:-2] + (blocks,)), np.empty_like(decay)
    prod[:, 0] = decay[:, 0]  # products of the decays from each block's start
    for s in range(1, size):
        np.multiply(decay[:, s], h[..., s - 1, :], out=tmp)
        h[..., s, :] += tmp
        np.multiply(prod[:, s - 1], decay[:, s], out=prod[:, s])
    if blocks == 1:
        return
    start = np.zeros(h.shape[:-2] + (blocks,))  # state at each block's start
    start[..., 1:] = _scan_ordered(prod[:, -1, :-1], h[..., -1, :-1])
    for s in range(size):  # slab by slab: no temporary as large as h
        np.multiply(prod[:, s], start, out=tmp)
        h[..., s, :] += tmp


def _scan_ordered(decay: np.ndarray, inc: np.ndarray) -> np.ndarray:
    """States after each step of H <- decay·H + inc from H = 0, for ``decay`` (rows, n) and
    ``inc`` (..., rows, n) in time order (:func:`_scan` on a copy in its layout)."""
    n = decay.shape[-1]
    size, blocks, place = _layout(n)
    slots = size * blocks
    dec = np.ones(decay.shape[:-1] + (slots,))
    h = np.zeros(inc.shape[:-1] + (slots,))
    dec[..., place], h[..., place] = decay, inc
    _scan(dec.reshape(dec.shape[:-1] + (size, blocks)), h.reshape(h.shape[:-1] + (size, blocks)))
    return h[..., place]


def _check(t, depth, C, m, kernel) -> tuple[np.ndarray, np.ndarray, float, float]:
    try:
        t, d = np.asarray(t, dtype=float), np.asarray(depth, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InputError(f"time and depth must be numeric arrays ({exc})") from None
    if t.ndim != 1 or t.shape != d.shape or t.size < 2:
        raise InputError(f"time (shape {t.shape}) and depth (shape {d.shape}) must be 1-D "
                         "arrays of the same length, at least 2 samples")
    for name, v, unit, bad in (("time t", t, "s", ~np.isfinite(t)),
                               ("depth", d, "m", ~np.isfinite(d))):
        if bad.any():
            raise InputError(f"{name}[{bad.argmax()}] = {float(v[bad.argmax()])!r} {unit} is "
                             "not finite")
    if np.any(back := np.diff(t) <= 0):
        i = int(back.argmax())
        raise InputError(f"time must increase strictly: t[{i + 1}] = {float(t[i + 1])!r} s "
                         f"follows t[{i}] = {float(t[i])!r} s")
    if d[0] > 0:
        raise InputError(f"depth[0] = {float(d[0])!r} m is positive: the history must begin "
                         "out of contact (start with the approach, or a sample at zero depth)")
    return t, d, _number("prefactor C", C, "N/(Pa·m^m)", "> 0"), _exponent(m, kernel)


def _exponent(m, kernel) -> float:
    if not isinstance(kernel, PowerLawKernel | PronyKernel):
        raise InputError(f"kernel {kernel!r} is neither a PowerLawKernel nor a PronyKernel")
    if (m := _number("exponent m", m)) < 1:
        raise InputError(f"exponent m = {m!r} of F = C·E·d^m must be >= 1")
    return m


def hereditary_contact(t, depth, C: float, m: float, kernel: Kernel) -> HereditaryContact:
    """Force of a rigid tip with elastic law F = C·E·d^m on a linear viscoelastic half-space at
    every sample of a measured depth history (Lee & Radok 1960; Ting 1966; DESIGN §9).

    At its running maximum depth, F(t) = C·∫_0^t E(t - s)·d/ds[d(s)^m] ds; below it,
    F(t) = C·∫_0^{t1} E(t - s)·d/ds[d(s)^m] ds with t1 <= t_max (time of the largest depth so
    far) solving ∫_{t1}^{t} E(t - s)·d'(s) ds = 0, and F = 0 when no t1 after the start of
    contact does (the tip has left the surface).  One loading cycle: contact starts at the
    first d > 0; t1 is a root on [start, t_max] (unique when d rises monotonically to t_max);
    while a contact regrows below the maximum, t1 stays at t_max.

    The depth is linear in time between samples.  d(s)^m is integrated exactly on each step
    (m = 1, 2; where the contact starts or ends; where d rises by over 5 %: Euler/Kummer
    integrals), else against the cubic interpolant of d^(m-1) on the step (relative error
    3e-4·z^4 of the step's increment, z its relative change: < 2e-9 for |z| <= 5 %).  Each
    exponential term (a Prony branch, or one of the K ~ 30-45 of the power law's sum,
    :func:`_power_soe`, accurate to :data:`SOE_TOLERANCE` on [shortest step, duration]) is an
    exact O(N) recursion; the power law's last step is integrated against t^(-alpha) in closed
    form.  Ting's t1: vectorised bisection over the samples (O(N·K·log N)), then the root in
    the step from the kernel's exact integral; that partial step's force by 12-point
    Gauss-Legendre in log-lag.

    Parameters
    ----------
    t
        [s] Sample times, strictly increasing (irregular steps are fine).
    depth
        [m] Indentation depth at each sample; d <= 0 is out of contact; depth[0] <= 0 (the
        material is at rest before the record).
    C
        [N/(Pa·m^m)] Prefactor of the elastic law, e.g. 4·sqrt(R)/(3(1-nu²)).
    m
        Exponent [-] of the elastic law, >= 1 (1.5 paraboloid, 2 cone, 1 flat punch).
    kernel
        Relaxation modulus: :class:`PowerLawKernel` or :class:`PronyKernel`.

    Returns
    -------
    HereditaryContact
        Force [N], Ting's t1 [s] and where Ting's rule applied, at every sample.

    Raises
    ------
    InputError
        Time not strictly increasing or not finite, depth not finite, lengths differ,
        depth[0] > 0, C <= 0, m < 1 or an unknown kernel; the message names the value.
    """
    t, d, C, m = _check(t, depth, C, m, kernel)
    dp = np.clip(d, 0.0, None)
    u = dp if m == 1.0 else dp**m
    st = _Steps(t, d, m, u)
    soe = a0, a, x, alpha, k = _soe(kernel, float(st.dt.min()), float(t[-1] - t[0]))
    n, K = t.size - 1, x.size
    runmax = np.maximum.accumulate(d)
    ting = (d < runmax) & (runmax > 0)
    rows = np.flatnonzero(ting)
    # per term, in time order for Ting's rule: histories of d^m and d_+, and the step decays
    Hu = Hd = np.zeros((n + 1, K))
    decays = np.zeros((n, K))
    fu, fd = np.zeros(n + 1), np.zeros(n + 1)  # ∫_0^t E(t - s) d[d^m], ∫_0^t E(t - s) d[d_+]
    if K and K <= _FEW and x[0] * (t[-1] - t[0]) <= 2 * _SPREAD:
        # few terms, none decaying by over e^1200 on the record: the scan as one cumulative
        # sum, H_i+1 = exp(-x·t'_i+1)·Σ_{j<=i} inc_j·exp(x·t'_j+1), t' = t - mid-record
        decay, iu, idd = _exp_steps(x, st)
        gu = gd = 0.0
        if alpha is not None:
            gu, gd = -(a @ iu), -(a @ idd)
        h = idd[None] if iu is idd else np.stack([iu, idd])
        grow = np.exp(np.multiply.outer(x, t[1:] - 0.5 * (t[0] + t[-1])))
        h *= grow
        np.cumsum(h, axis=-1, out=h)
        h /= grow
        fu[1:], fd[1:] = gu + a @ h[0], gd + a @ h[-1]
        Hu, Hd = np.zeros((n + 1, K)), np.zeros((n + 1, K))
        Hu[1:], Hd[1:], decays = h[0].T, h[-1].T, decay.T
    elif K:
        size, blocks, place = _layout(n)
        sp, gu, gd = st.placed(place, size * blocks), 0.0, 0.0
        if rows.size:  # time order = (blocks, size): one strided copy each, the first row 0
            ordered = np.empty((2 if m != 1.0 else 1, size * blocks + 1, K))
            ordered[:, 0] = 0.0
            Hu, Hd = ordered[0, :n + 1], ordered[-1, :n + 1]
            decays = np.empty((size * blocks, K))
            by_block = ordered[:, 1:].reshape(-1, blocks, size, K), decays.reshape(blocks, size, K)
        chunk = max(1, _CHUNK // (size * blocks))
        for j in range(0, K, chunk):
            sl = slice(j, j + chunk)
            rows_k = len(range(*sl.indices(K)))
            decay, h = np.empty((rows_k, size * blocks)), np.empty(
                (1 if m == 1.0 else 2, rows_k, size * blocks))
            _, iu, idd = _exp_steps(x[sl], sp, (decay, h))
            if alpha is not None:  # the sum holds for lags >= one step: history to the
                gu, gd = gu - a[sl] @ iu, gd - a[sl] @ idd  # previous sample
            h, decay = (v.reshape(v.shape[:-1] + (size, blocks)) for v in (h, decay))
            _scan(decay, h)
            gu, gd = gu + a[sl] @ h[0].reshape(-1, size * blocks), gd + a[sl] @ h[-1].reshape(
                -1, size * blocks)
            if rows.size:
                by_block[0][..., sl] = h.transpose(0, 3, 2, 1)
                by_block[1][..., sl] = decay.transpose(2, 1, 0)
        fu[1:], fd[1:] = gu[place], gd[place]
    if alpha is None:
        fu, fd = fu + a0 * u, fd + a0 * dp
    else:
        lu, ld = _power_steps(alpha, st)
        fu[1:], fd[1:] = fu[1:] + k * lu, fd[1:] + k * ld
    force, t1 = C * fu, np.where(u > 0, t, np.nan)
    if rows.size:
        ting_rule(t, d, dp, u, st.dt, m, soe, kernel, Hu, Hd, decays[:n], fd, rows, force, t1,
                  C)
    if not K:  # elastic: exactly C·E·d^m
        force = C * a0 * u
    return HereditaryContact(np.maximum(force, 0.0), t1, ting)


def hereditary_force(t, depth, C: float, m: float, kernel: Kernel) -> np.ndarray:
    """Contact force [N] at every sample: :func:`hereditary_contact` (equations, accuracy and
    parameters there)."""
    return hereditary_contact(t, depth, C, m, kernel).force


def ramp_apparent_modulus(kernel: Kernel, speed, depth, m: float) -> np.ndarray:
    """Modulus [Pa] an elastic fit F = C·E·d^m reads at ``depth`` [m] on a ramp d = v·t from
    first contact at ``speed`` v [m/s] (> 0, broadcast): F/(C·d^m) at t = d/v (DESIGN §9).

    Power law: E(t)·m·B(m, 1 - alpha), so E_app ∝ v^alpha at a fixed depth.  Prony series,
    term by term: E_inf + Σ E_i·1F1(1; m + 1; -t/tau_i) (= m·∫_0^1 exp(-(t/tau)(1-y))·y^(m-1) dy).
    """
    m = _exponent(m, kernel)
    v, dd = np.asarray(speed, dtype=float), np.asarray(depth, dtype=float)
    for name, x, unit in (("ramp speed", v, "m/s"), ("ramp depth", dd, "m")):
        if not np.all(np.isfinite(x) & (x > 0)):
            raise InputError(f"{name} {x.tolist()!r} {unit} must be positive and finite")
    t = dd / v
    if isinstance(kernel, PowerLawKernel):
        return kernel(t) * m * beta(m, 1 - kernel.alpha)
    return np.full_like(t, kernel.E_inf) + sum(
        e * hyp1f1(1.0, m + 1.0, -t / s) for e, s in zip(kernel.E, kernel.tau, strict=True))


def constant_strain_rate_stress(kernel: Kernel, rate, t) -> np.ndarray:
    """Uniaxial stress [Pa] at time ``t`` [s] of a compression from rest at constant strain rate
    ``rate`` [1/s]: sigma = r·∫_0^t E(s) ds (DESIGN §9); power law
    E0·t0^alpha·r·t^(1-alpha)/(1-alpha), Prony r·(E_inf·t + Σ E_i·tau_i·(1 - exp(-t/tau_i)))."""
    _exponent(1.0, kernel)
    r, tt = np.asarray(rate, dtype=float), np.asarray(t, dtype=float)
    if not (np.all(np.isfinite(r)) and np.all(np.isfinite(tt) & (tt >= 0))):
        raise InputError(f"strain rate {r.tolist()!r} 1/s and time {tt.tolist()!r} s must be "
                         "finite, the time >= 0")
    return r * kernel.integral(tt)
