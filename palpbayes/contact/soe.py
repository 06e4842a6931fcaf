"""A sum of exponentials for the power law t^(-alpha): Σ w_j·exp(-x_j·t) to a relative
:data:`SOE_TOLERANCE` on [shortest step, duration], the form in which the hereditary integral of
:func:`~palpbayes.contact.viscoelastic.hereditary_contact` runs as recursions
(``../shared/DESIGN.md`` §9).  A helper module: it registers no law.

References: G. Beylkin, L. Monzón, Appl. Comput. Harmon. Anal. 28:131 (2010) (the trapezoidal
rule in ln x); W. Gautschi, Orthogonal Polynomials: Computation and Approximation (2004),
§2.2.3 (the Gauss rule of a discrete measure).
"""

from __future__ import annotations

import functools
import math

import numpy as np
from scipy.linalg import eigh_tridiagonal
from scipy.special import gamma, loggamma

__all__ = ["SOE_TOLERANCE", "TAIL_NODES", "TAIL_REACH", "power_law_soe", "gauss_rule"]

#: Relative accuracy [-] of the power law's sum of exponentials on [shortest step, duration].
SOE_TOLERANCE = 1e-7
#: The trapezoid's nodes at rates x <= TAIL_REACH/duration are replaced by the Gauss rule of
#: TAIL_NODES points of their measure (:func:`power_law_soe`).
TAIL_NODES, TAIL_REACH = 6, 8.0


def power_law_soe(alpha: float, dt_min: float, span: float) -> tuple[np.ndarray, np.ndarray]:
    """Weights w [s^-alpha] and rates x [1/s] with Σ w_j·exp(-x_j·t) ≈ t^(-alpha) to a relative
    :data:`SOE_TOLERANCE` for t [s] in [``dt_min``, ``span``] (0 < ``alpha`` < 1 [-], alpha = 0
    being a constant; the shortest time step and the record's duration, 0 < dt_min <= span),
    all positive.

    Trapezoidal rule in y = ln x of t^(-alpha) = ∫ exp(alpha·y - e^y·t) dy / Gamma(alpha)
    (Beylkin & Monzón 2010): the step h keeps the aliasing error 2|Gamma(alpha + 2·pi·i/h)| /
    Gamma(alpha) below a third of :data:`SOE_TOLERANCE`; the top node is x = ln(3/tol)/dt_min.
    The rule's slow nodes, from x_c <= :data:`TAIL_REACH`/span down (a geometric series), are
    replaced by the :data:`TAIL_NODES`-point Gauss rule of that discrete measure
    (:func:`_tail_rule`): exact for polynomials of degree < 12 in x, it sums exp(-x·t) over
    the tail for x_c·t <= 8 to < 2e-8 relative to t^(-alpha) (under the third of the
    tolerance the aliasing has too; 3e-9 at alpha = 0.3, 2e-8 from 0.8 on: checked
    numerically), with ~10 terms fewer than the rule's own tail (23 for alpha = 0.3 on
    [1 ms, 5 s], where the rule alone took 34).
    """
    h, c, u, w = _tail_rule(alpha)
    y_hi = math.log(math.log(3 / SOE_TOLERANCE) / dt_min)
    n = max(1, math.ceil((y_hi - math.log(TAIL_REACH / span)) / h))
    y = y_hi - h * np.arange(n + 1)  # the trapezoid's nodes, then y_c = y[-1], the tail's top
    return (np.concatenate([c * np.exp(alpha * y[:-1]), w * math.exp(alpha * y[-1])]),
            np.concatenate([np.exp(y[:-1]), u * math.exp(y[-1])]))


@functools.lru_cache(maxsize=128)
def _tail_rule(alpha: float) -> tuple[float, float, np.ndarray, np.ndarray]:
    """(h, c, u, w): the trapezoid's step h in ln x (:func:`power_law_soe`), its weight
    factor c = h·alpha/Gamma(alpha + 1) (node y weighs c·exp(alpha·y)), and the Gauss rule of
    its tail below x_c, nodes u = x/x_c and weights w/x_c^alpha (all depend on alpha only).
    The tail's nodes u = exp(-h·j) down to 1e-12, then the rest lumped into one node with its
    zeroth and first moments (error ~(x·t·u)^2 < 1e-22)."""
    eps = SOE_TOLERANCE
    hs = np.linspace(0.3, 1.5, 121)
    h = hs[2 * np.exp(loggamma(alpha + 2j * np.pi / hs).real - loggamma(alpha)) <= eps / 3][-1]
    c = h * alpha / gamma(alpha + 1)
    j = np.arange(math.ceil(math.log(1e12) / h) + 1)
    u, w = np.exp(-h * j), c * np.exp(-alpha * h * j)
    rest = h * (j[-1] + 1)  # the rest's top, -ln u; its moments sum a geometric series
    s0, s1 = (c * math.exp(-(alpha + k) * rest) / -math.expm1(-(alpha + k) * h) for k in (0, 1))
    nodes, weights = gauss_rule(np.append(u, s1 / s0), np.append(w, s0), TAIL_NODES)
    return float(h), float(c), nodes, weights


def gauss_rule(u: np.ndarray, w: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Nodes and weights of the n-point Gauss rule of the discrete measure Σ w_i·δ(u - u_i)
    (weights w_i > 0 at points u_i, n < their number): Σ weights·nodes^p = Σ w_i·u_i^p for
    p < 2n.  The three-term recurrence of its orthogonal polynomials by the Stieltjes
    procedure, then Golub–Welsch (Gautschi 2004, §2.2.3)."""
    a, b = np.zeros(n), np.zeros(n)
    p_old, p = np.zeros_like(u), np.ones_like(u)
    norm = mass = float(w.sum())
    for k in range(n):
        a[k] = (w @ (u * p * p)) / norm
        if k + 1 < n:
            p_old, p = p, (u - a[k]) * p - b[k] * p_old
            norm_old, norm = norm, float(w @ (p * p))
            b[k + 1] = norm / norm_old
    nodes, vectors = eigh_tridiagonal(a, np.sqrt(b[1:]))
    return nodes, mass * vectors[0] ** 2
