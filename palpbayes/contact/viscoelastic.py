"""Rigid axisymmetric tip (elastic law F = C·E·d^m) on a linear viscoelastic half-space: the
Lee–Radok and Ting hereditary integrals on a measured time axis, the relaxation kernels
:class:`PowerLawKernel` and :class:`PronyKernel`, and the closed forms of a ramp and of a
constant-strain-rate compression (``../shared/DESIGN.md`` §9 "Viscoelastic contact", whose
closed forms the tests check; "DESIGN §9" below).  Ting's rule on the retract is in
:mod:`~palpbayes.contact.ting_rule`.  A helper module: it registers no law.

References: E. H. Lee, J. R. M. Radok, J. Appl. Mech. 27:438 (1960); T. C. T. Ting, J. Appl.
Mech. 33:845 (1966).  The power law's sum of exponentials is in :mod:`~palpbayes.contact.soe`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.special import beta, hyp1f1

from ..errors import InputError
from .hereditary_steps import Steps, block_layout, blocked_scan, exp_steps, power_steps
from .scratch import scratch
from .soe import power_law_soe
from .ting_rule import ting_rule

__all__ = ["PowerLawKernel", "PronyKernel", "standard_linear_solid", "HereditaryContact",
           "hereditary_contact", "hereditary_force", "ramp_apparent_modulus",
           "constant_strain_rate_stress"]


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

    def _value_and_integral(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """E(t) [Pa] and ∫_0^t E(s) ds [Pa·s] (exp for E: 1 + expm1 would round a branch
        to 0 beyond ~37 tau, and with E_inf = 0 the Newton step to 0/0)."""
        value, integral = np.full(t.shape, self.E_inf), self.E_inf * t
        for e, s in zip(self.E, self.tau, strict=True):
            y = -t / s
            value += e * np.exp(y)
            integral -= (e * s) * np.expm1(y)
        return value, integral

    def _inverse_integral(self, target, lo, hi) -> np.ndarray:
        # Newton from below (the integral is concave), from where the tangent at hi reaches
        # the target (below the root: a concave function lies under its tangents); fmax and
        # fmin clip to [lo, hi] and take a NaN step (0/0 where E underflows to 0) as none
        target, lo, hi = (np.asarray(v, dtype=float) for v in (target, lo, hi))
        with np.errstate(divide="ignore", invalid="ignore"):
            value, integral = self._value_and_integral(hi)
            w = np.fmin(np.fmax(hi - (integral - target) / value, lo), hi)
            for _ in range(100):
                value, integral = self._value_and_integral(w)
                w, w_old = np.fmin(w + np.fmax((target - integral) / value, 0.0), hi), w
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
    w, x = power_law_soe(kernel.alpha, dt_min, span)
    order = np.argsort(-x, kind="stable")
    return 0.0, k * w[order], x[order], kernel.alpha, k


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
    exponential term (a Prony branch, or one of the K ~ 17-45 of the power law's sum,
    :func:`~palpbayes.contact.soe.power_law_soe`, accurate to
    :data:`~palpbayes.contact.soe.SOE_TOLERANCE` = 1e-7 relative on [shortest step, duration])
    is an exact O(N) recursion H <- exp(-x·dt)·H + increment, run for all terms at once as a blocked
    scan (:func:`~palpbayes.contact.hereditary_steps.blocked_scan`, O(N^(1/3)) Python steps; up to 4
    Prony terms as one cumulative sum);
    the power law's last step is integrated against t^(-alpha) in closed form.  Ting's t1
    (:func:`~palpbayes.contact.ting_rule.ting_rule`): vectorised bisection over the samples
    (O(rows·K·log N), the exponentials as products of cumulative products of the step decays),
    then the root in the step from the kernel's exact integral; that partial step's force by
    12-point Gauss-Legendre in log-lag (4 points where the step spans ln(lag) by <= 0.05).
    Its cost per call: ``benchmarks/bench_viscoelastic.py``.

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
    dp = np.maximum(d, 0.0)
    u = dp if m == 1.0 else dp * np.sqrt(dp) if m == 1.5 else dp**m  # sqrt: 3x faster
    st = Steps(t, d, m, u)
    soe = a0, a, x, alpha, k = _soe(kernel, float(st.dt.min()), float(t[-1] - t[0]))
    n, K = t.size - 1, x.size
    runmax = np.maximum.accumulate(d)
    ting = (d < runmax) & (runmax > 0)
    rows = np.flatnonzero(ting)
    # per term, in time order for Ting's rule: histories of d^m and d_+, and the step decays;
    # empty here (no terms: an elastic kernel), set by the branches below where Ting reads them
    Hu = Hd = np.zeros((n + 1, 0))
    decays = np.zeros((n, 0))
    fu, fd = np.zeros(n + 1), np.zeros(n + 1)  # ∫_0^t E(t - s) d[d^m], ∫_0^t E(t - s) d[d_+]
    if K and K <= _FEW and x[0] * (t[-1] - t[0]) <= 2 * _SPREAD:
        # few terms, none decaying by over e^1200 on the record: the scan as one cumulative
        # sum, H_i+1 = exp(-x·t'_i+1)·Σ_{j<=i} inc_j·exp(x·t'_j+1), t' = t - mid-record
        decay, iu, idd = exp_steps(x, st)
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
        size, blocks, place = block_layout(n)
        sp, gu, gd = st.placed(place, size * blocks), 0.0, 0.0
        if rows.size:  # time order = (blocks, size): one strided copy each, the first row 0
            ordered = scratch("ordered", (2 if m != 1.0 else 1, size * blocks + 1, K))
            ordered[:, 0] = 0.0
            Hu, Hd = ordered[0, :n + 1], ordered[-1, :n + 1]
            decays = scratch("decays", (size * blocks, K))
            by_block = ordered[:, 1:].reshape(-1, blocks, size, K), decays.reshape(blocks, size, K)
        chunk = max(1, _CHUNK // (size * blocks))
        for j in range(0, K, chunk):
            sl = slice(j, j + chunk)
            rows_k = len(range(*sl.indices(K)))
            decay, h = scratch("decay", (rows_k, size * blocks)), scratch(
                "increments", (1 if m == 1.0 else 2, rows_k, size * blocks))
            _, iu, idd = exp_steps(x[sl], sp, (decay, h))
            if alpha is not None:  # the sum holds for lags >= one step: history to the
                gu, gd = gu - a[sl] @ iu, gd - a[sl] @ idd  # previous sample
            h, decay = (v.reshape(v.shape[:-1] + (size, blocks)) for v in (h, decay))
            blocked_scan(decay, h, top=True)
            gu, gd = gu + a[sl] @ h[0].reshape(-1, size * blocks), gd + a[sl] @ h[-1].reshape(
                -1, size * blocks)
            if rows.size:
                by_block[0][..., sl] = h.transpose(0, 3, 2, 1)
                by_block[1][..., sl] = decay.transpose(2, 1, 0)
        fu[1:], fd[1:] = gu[place], gd[place]
    if alpha is None:
        fu, fd = fu + a0 * u, fd + a0 * dp
    else:
        lu, ld = power_steps(alpha, st)
        fu[1:], fd[1:] = fu[1:] + k * lu, fd[1:] + k * ld
    force, t1 = C * fu, np.where(u > 0, t, np.nan)
    if rows.size:
        ting_rule(t, d, dp, u, st.dt, m, soe, kernel, Hu, Hd, decays[:n], fd, rows, force, t1,
                  C)
    if not K:  # elastic: exactly C·E·d^m
        force = C * a0 * dp**m
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
