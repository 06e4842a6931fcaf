"""Viscoelastic contact (palpbayes.contact.viscoelastic) against the closed forms of DESIGN §9
"Viscoelastic contact" and an independent brute-force quadrature of the Lee–Radok and Ting
integrals."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import brentq
from scipy.special import beta, dawsn, gamma, hyp2f1

from palpbayes.contact.hereditary_steps import Steps, exp_steps, power_steps
from palpbayes.contact.soe import SOE_TOLERANCE, gauss_rule, power_law_soe
from palpbayes.contact.viscoelastic import (
    PowerLawKernel,
    PronyKernel,
    constant_strain_rate_stress,
    hereditary_contact,
    hereditary_force,
    ramp_apparent_modulus,
    standard_linear_solid,
)
from palpbayes.errors import InputError

pytestmark = pytest.mark.filterwarnings("error")  # no overflow or invalid value anywhere

C_PARA = 4 * math.sqrt(0.01) / (3 * (1 - 0.3**2))  # paraboloid R = 10 mm, nu = 0.3 [m^0.5]


def _irregular_axis(t_end: float, n: int, rng, include=()) -> np.ndarray:
    """n random steps (0.3-1.7 x the mean) from 0 to t_end, with the times ``include``."""
    steps = rng.uniform(0.3, 1.7, n)
    t = np.concatenate([[0.0], np.cumsum(steps) / steps.sum() * t_end])
    return np.unique(np.concatenate([t, include]))


# --- closed forms of DESIGN §9 ------------------------------------------------------------


@pytest.mark.parametrize("m", [1.0, 1.5, 2.0])
@pytest.mark.parametrize("alpha", [0.1, 0.4, 0.8])
def test_power_law_ramp_is_beta_closed_form(m, alpha):
    """F = C·E(t)·d^m·m·B(m, 1 - alpha) on d = v·t, at every sample of an irregular axis."""
    kernel = PowerLawKernel(2e5, alpha, t0=0.5)
    t = _irregular_axis(1.5, 600, np.random.default_rng(1))
    d = 2e-3 * t
    F = hereditary_force(t, d, C_PARA, m, kernel)
    ref = C_PARA * kernel(t[1:]) * d[1:] ** m * m * beta(m, 1 - alpha)
    assert F[0] == 0.0
    np.testing.assert_allclose(F[1:], ref, rtol=1e-6, atol=0)
    if m == 1.5:  # the paraboloid's form: (3·sqrt(pi)/4)·Gamma(1 - alpha)/Gamma(5/2 - alpha)
        assert 1.5 * beta(1.5, 1 - alpha) == pytest.approx(
            0.75 * math.sqrt(math.pi) * gamma(1 - alpha) / gamma(2.5 - alpha), rel=1e-14)
    E_app = ramp_apparent_modulus(kernel, 2e-3, d[1:], m)
    np.testing.assert_allclose(C_PARA * E_app * d[1:] ** m, ref, rtol=1e-13)


@pytest.mark.parametrize("alpha", [0.15, 0.5, 0.9])
def test_power_law_ramp_then_hold_is_hypergeometric(alpha):
    """Hold at d0 = v·t_r: F = C·E0·d0^(3/2)·(t/t0)^(-alpha)·2F1(alpha, 3/2; 5/2; t_r/t)."""
    E0, t0, v, t_r = 1e5, 2.0, 1e-3, 0.8
    t = _irregular_axis(3.0, 900, np.random.default_rng(2), include=[t_r])
    d = v * np.minimum(t, t_r)
    F = hereditary_force(t, d, C_PARA, 1.5, PowerLawKernel(E0, alpha, t0))
    hold = t > t_r
    ref = C_PARA * E0 * (v * t_r) ** 1.5 * (t[hold] / t0) ** -alpha * hyp2f1(
        alpha, 1.5, 2.5, t_r / t[hold])
    np.testing.assert_allclose(F[hold], ref, rtol=1e-6, atol=0)
    assert np.all(np.diff(F[hold]) < 0)  # relaxes at constant depth


def test_standard_linear_solid_ramp_and_hold_are_dawson_forms():
    """SLS on a paraboloid: ramp C·[E_inf·(vt)^1.5 + 1.5·E1·(v·tau)^1.5·(sqrt x - D(sqrt x))],
    hold the same relaxed by exp(-(t - t_r)/tau)."""
    E_inf, E1, tau, v, t_r = 3e4, 7e4, 0.3, 2e-3, 1.0
    t = _irregular_axis(2.5, 800, np.random.default_rng(3), include=[t_r])
    d = v * np.minimum(t, t_r)
    F = hereditary_force(t, d, C_PARA, 1.5, standard_linear_solid(E_inf, E1, tau))
    x = np.minimum(t, t_r) / tau
    dawson = np.sqrt(x) - dawsn(np.sqrt(x))
    ref = C_PARA * (E_inf * d**1.5 + 1.5 * E1 * (v * tau) ** 1.5 * dawson
                    * np.exp(-np.maximum(t - t_r, 0) / tau))
    ok = t > 0.02  # sqrt(x) - D(sqrt(x)) loses digits to cancellation below
    np.testing.assert_allclose(F[ok], ref[ok], rtol=1e-6, atol=0)


@pytest.mark.parametrize("alpha", [0.2, 0.6])
@pytest.mark.parametrize("ratio", [1.0, 2.5])
def test_ting_retract_of_a_power_law(alpha, ratio):
    """Approach at v_a, retract at v_r: t1 = t - (1 + v_r/v_a)^(1/(1-alpha))·(t - t_max) and
    F = C·E0·t0^alpha·v_a^m·t^(-alpha)·t1^m·2F1(alpha, m; m+1; t1/t); 0 once t1 < 0."""
    E0, t0, v_a, t_max, m = 1e5, 1.0, 1e-3, 1.0, 1.5
    v_r = ratio * v_a
    t_end = t_max + v_a * t_max / v_r  # back at the surface
    t = _irregular_axis(t_end, 3000, np.random.default_rng(4), include=[t_max])
    d = np.where(t <= t_max, v_a * t, v_a * t_max - v_r * (t - t_max))
    res = hereditary_contact(t, d, C_PARA, m, PowerLawKernel(E0, alpha, t0))
    k = (1 + ratio) ** (1 / (1 - alpha))
    after = t > t_max
    t1 = t - k * (t - t_max)
    assert np.array_equal(res.ting, after)
    on = after & (t1 > 0.02 * t_max)
    np.testing.assert_allclose(res.t1[on], t1[on], rtol=0, atol=1e-7 * t_max)
    ref = C_PARA * E0 * t0**alpha * v_a**m * t[on] ** -alpha * t1[on] ** m * hyp2f1(
        alpha, m, m + 1, t1[on] / t[on])
    np.testing.assert_allclose(res.force[on], ref, rtol=1e-6, atol=0)
    off = after & (t1 < -1e-6 * t_max)
    assert off.sum() > 100 and np.all(res.force[off] == 0) and np.all(np.isnan(res.t1[off]))
    np.testing.assert_allclose(res.t1[~after & (t > 0)], t[~after & (t > 0)], rtol=0, atol=0)


# --- brute-force quadrature on an irregular measured motion --------------------------------


def _measured_motion():
    """Random time steps; approach from above the surface at a varying speed, a hold at the
    maximum, a partial retract to 75 % and a second hold (piecewise linear between samples)."""
    rng = np.random.default_rng(11)
    t = _irregular_axis(1.6, 140, rng)
    x = t / t[-1]
    u = np.clip(x / 0.45, 0, 1)
    d = np.where(x <= 0.45, -0.03 + 1.03 * (0.7 * u + 0.3 * u**2), 1.0)
    d = np.where(x > 0.6, 1.0 - 0.25 * np.clip((x - 0.6) / 0.2, 0, 1), d)
    return t, 2e-3 * d


def _kernel_integral(kernel, tn, a, b, g):
    """∫_a^b E(tn - s)·g(s) ds by adaptive quadrature (the power law's singular factor as an
    algebraic weight when b = tn)."""
    if b <= a:
        return 0.0
    opts = dict(epsabs=0.0, epsrel=1e-12, limit=200)
    if isinstance(kernel, PowerLawKernel) and tn - b <= 1e-14 * tn:
        k = kernel.E0 * kernel.t0**kernel.alpha
        return k * quad(g, a, b, weight="alg", wvar=(0.0, -kernel.alpha), **opts)[0]
    return quad(lambda s: kernel(tn - s) * g(s), a, b, **opts)[0]


def _reference_force(t, d, C, m, kernel, n):
    """Lee–Radok or Ting force at sample n by quadrature over the piecewise-linear depth."""
    steps = []  # contact part [a, b] of each step before t_n, its depth line and slope
    for i in range(n):
        slope = (d[i + 1] - d[i]) / (t[i + 1] - t[i])
        lo, hi = t[i], t[i + 1]
        if d[i] <= 0 < d[i + 1]:
            lo = t[i] - d[i] / slope
        elif d[i + 1] <= 0 < d[i]:
            hi = t[i] - d[i] / slope
        elif d[i] <= 0 and d[i + 1] <= 0:
            continue
        steps.append((lo, hi, d[i], t[i], slope))

    def du(i0, ti, slope):  # d/ds d(s)^m on the step
        return lambda s: m * max(i0 + slope * (s - ti), 0.0) ** (m - 1) * slope

    tn = t[n]
    if d[n] >= d[: n + 1].max():  # contact growing: Lee–Radok
        return C * sum(_kernel_integral(kernel, tn, a, b, du(*rest)) for a, b, *rest in steps)
    kmax = int(np.flatnonzero(d[: n + 1] == d[: n + 1].max())[-1])

    def phi_step(j, start):  # ∫_{max(a, start)}^{b} E(t_n - s)·d'(s) ds on step j
        a, b, _, _, slope = steps[j]
        return slope * _kernel_integral(kernel, tn, max(a, start), b, lambda s: 1.0)

    parts = np.array([phi_step(j, -np.inf) for j in range(len(steps))])
    tail = np.cumsum(parts[::-1])[::-1]  # ∫_{a_j}^{t_n} E·d' ds
    ends = [b for _, b, *_ in steps]
    if tail[0] <= 0:
        return 0.0
    j = max(i for i in range(len(steps)) if tail[i] > 0 and ends[i] <= t[kmax])
    rest = tail[j + 1] if j + 1 < len(steps) else 0.0
    a_j, b_j = steps[j][0], steps[j][1]
    if rest > 0:  # no root before t_max: t1 = t_max
        return C * sum(_kernel_integral(kernel, tn, a, b, du(*r)) for a, b, *r in steps[:j + 1])
    t1 = brentq(lambda s: phi_step(j, s) + rest, a_j, b_j, xtol=1e-15, rtol=1e-15)
    total = sum(_kernel_integral(kernel, tn, a, b, du(*r)) for a, b, *r in steps[:j])
    return C * (total + _kernel_integral(kernel, tn, a_j, t1, du(*steps[j][2:])))


@pytest.mark.parametrize("kernel, m", [
    (PowerLawKernel(1.2e5, 0.35, t0=1.0), 1.5),
    (PowerLawKernel(8e4, 0.7, t0=0.1), 2.0),
    (PronyKernel(2e4, (3e4, 5e4), (0.05, 0.8)), 1.5),
    (PronyKernel(1e4, (6e4,), (0.2,)), 1.0),
], ids=["power-0.35-m1.5", "power-0.7-m2", "prony2-m1.5", "sls-m1"])
def test_measured_motion_matches_quadrature(kernel, m):
    t, d = _measured_motion()
    res = hereditary_contact(t, d, C_PARA, m, kernel)
    assert res.ting.sum() > 40 and (~res.ting & (d > 0)).sum() > 60
    rng = np.random.default_rng(5)
    check = np.concatenate([rng.choice(np.flatnonzero(~res.ting & (d > 0)), 14, replace=False),
                            rng.choice(np.flatnonzero(res.ting), 14, replace=False)])
    ref = np.array([_reference_force(t, d, C_PARA, m, kernel, n) for n in check])
    big = ref > 1e-3 * res.force.max()
    assert big.sum() >= 20 and res.ting[check[big]].sum() >= 6
    np.testing.assert_allclose(res.force[check[big]], ref[big], rtol=1e-6, atol=0)
    np.testing.assert_allclose(res.force[check[~big]], ref[~big], rtol=0,
                               atol=1e-9 * res.force.max())


# --- elastic limit, helpers, the sum of exponentials, bad input ---------------------------


@pytest.mark.parametrize("kernel", [PowerLawKernel(9e4, 0.0), PronyKernel(9e4, (0.0, 0.0),
                                                                           (0.1, 1.0))])
@pytest.mark.parametrize("m", [1.0, 1.5, 2.0])
def test_elastic_limit_is_exact(kernel, m):
    t, d = _measured_motion()
    res = hereditary_contact(t, d, C_PARA, m, kernel)
    np.testing.assert_array_equal(res.force, C_PARA * 9e4 * np.clip(d, 0.0, None) ** m)
    ting = np.flatnonzero(res.ting)  # elastic Ting: d(t1) = d(t) on the approach
    np.testing.assert_allclose(np.interp(res.t1[ting], t, d), d[ting], rtol=1e-12)


def test_apparent_modulus_and_constant_strain_rate_stress():
    power = PowerLawKernel(1e5, 0.25, t0=1.0)
    E_slow, E_fast = ramp_apparent_modulus(power, [1e-3, 4e-3], 2e-3, 1.5)
    assert E_fast / E_slow == pytest.approx(4**0.25, rel=1e-13)  # E_app ∝ v^alpha
    prony = PronyKernel(2e4, (3e4, 5e4), (0.05, 0.8))
    t = np.linspace(0, 2.0, 801)
    F = hereditary_force(t, 1.5e-3 * t, C_PARA, 2.0, prony)
    np.testing.assert_allclose(C_PARA * ramp_apparent_modulus(prony, 1.5e-3, 1.5e-3 * t[1:], 2)
                               * (1.5e-3 * t[1:]) ** 2, F[1:], rtol=1e-10)
    r, ts = 0.01, np.array([0.0, 0.3, 2.0, 30.0])
    np.testing.assert_allclose(constant_strain_rate_stress(power, r, ts),
                               1e5 * r * ts**0.75 / 0.75, rtol=1e-14)
    numeric = [r * quad(prony, 0, x, epsrel=1e-13)[0] for x in ts]
    np.testing.assert_allclose(constant_strain_rate_stress(prony, r, ts), numeric, rtol=1e-11)


def _step_reference(t, d, i, m, rate=None, alpha=None):
    """∫ E(t_i+1 - s)·d/ds[d_+(s)^m] ds over the contact part of step i by quad, E = exp(-rate·
    lag) or lag^(-alpha); the endpoint singularities (contact edge, power law) as weights."""
    slope = (d[i + 1] - d[i]) / (t[i + 1] - t[i])
    if d[i] <= 0 and d[i + 1] <= 0:
        return 0.0
    zero = t[i] - d[i] / slope
    cin, cout = d[i] <= 0 < d[i + 1], d[i + 1] <= 0 < d[i]
    lo, hi = (zero if cin else t[i]), (zero if cout else t[i + 1])
    singular = alpha is not None and not cout  # lag^(-alpha) at s = hi

    def smooth(s):
        edge = abs(slope) ** (m - 1) if cin or cout else (d[i] + slope * (s - t[i])) ** (m - 1)
        lag = t[i + 1] - s
        kern = math.exp(-rate * lag) if alpha is None else (1.0 if singular else lag**-alpha)
        return m * slope * edge * kern

    wvar = (m - 1 if cin else 0.0, (m - 1 if cout else 0.0) - (alpha if singular else 0.0))
    return quad(smooth, lo, hi, weight="alg", wvar=wvar, epsabs=0, epsrel=1e-13)[0]


def test_each_step_kind_is_integrated_exactly():
    """The per-step integrals of exp(-x·lag) and lag^(-alpha) against d[d_+^m] and d[d_+]: the
    contact starting, d tripling, rising 3 %, falling 3 %, the contact ending, out of contact."""
    t = np.array([0.0, 0.4, 1.0, 1.3, 1.7, 2.2, 2.6])
    d = np.array([-1.0, 1.0, 3.0, 3.1, 3.0, -1.0, -0.5]) * 1e-3
    m, alpha, x = 1.5, 0.4, np.array([0.01, 0.7, 5.0, 60.0])
    st = Steps(t, d, m)
    decay, iu, idd = exp_steps(x, st)
    lu, ld = power_steps(alpha, st)
    np.testing.assert_allclose(decay, np.exp(-np.multiply.outer(x, np.diff(t))), atol=1e-15)
    for i in range(t.size - 1):
        for mm, got_exp, got_pow in ((1.0, idd[:, i], ld[i]), (m, iu[:, i], lu[i])):
            ref = [_step_reference(t, d, i, mm, rate=xj) for xj in x]
            np.testing.assert_allclose(got_exp, ref, rtol=1e-10, atol=1e-25)
            if mm == 1.0 or d[i + 1] > 0:  # the d^m one is not needed where the contact ends
                ref = _step_reference(t, d, i, mm, alpha=alpha)
                assert got_pow == pytest.approx(ref, rel=1e-10, abs=1e-25)


@pytest.mark.parametrize("alpha", [0.001, 0.01, 0.3, 0.6, 0.95, 0.999])
@pytest.mark.parametrize("span", [1.0, 3.0, 1e2, 5.7e3, 1e5, 1e8])
def test_sum_of_exponentials_meets_its_tolerance(alpha, span):
    dt = 1e-3
    w, x = power_law_soe(alpha, dt, dt * span)
    s = np.geomspace(dt, dt * span, 4000)
    approx = np.exp(-np.multiply.outer(s, x)) @ w
    assert np.max(np.abs(approx * s**alpha - 1)) < SOE_TOLERANCE
    assert np.all(w > 0) and np.all(x > 0) and w.size < 6 * math.log10(span) + 24


def test_sum_of_exponentials_is_short():
    """The tail's Gauss rule: alpha = 0.3 on [0.875 ms, 5 s] (bench_viscoelastic's cycle) in
    23 terms (34 with the trapezoid's own tail)."""
    assert power_law_soe(0.3, 0.7 / 800, 5.0)[1].size == 23


@pytest.mark.parametrize("alpha", [0.05, 0.3, 0.7, 0.9, 0.99])
def test_the_tails_gauss_rule_keeps_within_its_share_of_the_tolerance(alpha):
    """The trapezoid's slow tail (rates up to x_c, a geometric series) against its 6-point
    Gauss rule, for x_c·t up to soe.TAIL_REACH: within a third of SOE_TOLERANCE of
    t^(-alpha) (the aliasing has the same share)."""
    from palpbayes.contact import soe

    h, _, u, w = soe._tail_rule(alpha)
    j = np.arange(int(80 / (alpha * h)))  # the series to exp(-80)
    uu, ww = np.exp(-h * j), h * alpha / gamma(alpha + 1) * np.exp(-alpha * h * j)
    t = np.geomspace(1e-6, soe.TAIL_REACH, 300)
    series = np.exp(-np.multiply.outer(t, uu)) @ ww
    rule = np.exp(-np.multiply.outer(t, u)) @ w
    assert np.max(np.abs(rule - series) * t**alpha) < SOE_TOLERANCE / 3


def test_gauss_rule_of_a_discrete_measure_integrates_its_moments():
    rng = np.random.default_rng(3)
    u, w = np.sort(rng.uniform(0.0, 1.0, 40)), rng.uniform(0.1, 1.0, 40)
    for n in (1, 3, 6):
        nodes, weights = gauss_rule(u, w, n)
        assert np.all((nodes > u[0]) & (nodes < u[-1]) & (weights > 0))
        for p in range(2 * n):  # exact for degree < 2n, not for 2n
            assert weights @ nodes**p == pytest.approx(w @ u**p, rel=1e-12)
        assert abs(weights @ nodes ** (2 * n) / (w @ u ** (2 * n)) - 1) > 1e-6


def _kw():
    return dict(t=[0.0, 0.1, 0.2, 0.3, 0.4], depth=[0.0, 1e-4, 2e-4, 3e-4, 2e-4], C=1.0,
                m=1.5, kernel=PowerLawKernel(1e5, 0.2))


@pytest.mark.parametrize("change, message", [
    (dict(t=[0.0, 0.1, 0.2, 0.2, 0.4]), r"t\[3\] = 0\.2 s follows t\[2\] = 0\.2"),
    (dict(t=[0.0, 0.1, 0.3, 0.2, 0.4]), r"t\[3\] = 0\.2 s follows t\[2\] = 0\.3"),
    (dict(depth=[0.0, 1e-4, np.nan, 3e-4, 2e-4]), r"depth\[2\] = nan m is not finite"),
    (dict(t=[0.0, 0.1, 0.2, 0.3]), r"shape \(4,\).*shape \(5,\)"),
    (dict(depth=[1e-4, 1e-4, 2e-4, 3e-4, 2e-4]), r"depth\[0\] = 0\.0001 m is positive"),
    (dict(C=-2.0), r"C = -2\.0"),
    (dict(m=0.5), r"m = 0\.5"),
    (dict(kernel="springpot"), r"kernel 'springpot'"),
])
def test_bad_motion_raises_input_error_naming_the_value(change, message):
    with pytest.raises(InputError, match=message):
        hereditary_force(**{**_kw(), **change})


@pytest.mark.parametrize("make, message", [
    (lambda: PowerLawKernel(1e5, -0.1), r"alpha = -0\.1 is outside \[0, 1\)"),
    (lambda: PowerLawKernel(1e5, 1.0), r"alpha = 1\.0 is outside \[0, 1\)"),
    (lambda: PowerLawKernel(1e5, float("nan")), r"alpha = nan"),
    (lambda: PowerLawKernel(-3.0, 0.2), r"E0 = -3\.0 Pa must be finite and > 0"),
    (lambda: PowerLawKernel(1e5, 0.2, t0=0), r"t0 = 0\.0 s must be finite and > 0"),
    (lambda: PronyKernel(1e4, (1e4, 2e4), (0.1,)), r"2 moduli E but 1 times tau"),
    (lambda: PronyKernel(1e4, (1e4,), (-0.5,)), r"tau\[0\] = -0\.5 s must be finite and > 0"),
    (lambda: PronyKernel(1e4, (-1e4,), (0.5,)), r"E\[0\] = -10000\.0 Pa must be finite and >= 0"),
    (lambda: PronyKernel(0.0, (0.0,), (0.5,)), r"every modulus is zero"),
])
def test_bad_kernel_raises_input_error_naming_the_value(make, message):
    with pytest.raises(InputError, match=message):
        make()
