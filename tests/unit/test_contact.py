"""Contact laws: MDR general law vs closed forms, exact Sneddon sphere, thickness corrections."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from propbudget import examples

from palpbayes.contact import (
    MAX_TIP_RADIUS_M,
    Tip,
    check_nu,
    check_tip_plausible,
    cone,
    exponent,
    flat,
    force,
    get_law,
    half_angle_from_degrees,
    k_from_modulus,
    mdr,
    modulus_from_k,
    paraboloid,
    shape,
    sphere,
    thickness_factor,
)
from palpbayes.contact.thickness import (
    DIMITRIADIS_CHI_MAX,
    dimitriadis_coefficients,
    dimitriadis_factor,
)
from palpbayes.errors import GeometryError

DEPTHS = np.linspace(1e-6, 3e-3, 500)
TIPS = [
    Tip("flat", radius=0.01),
    Tip("paraboloid", radius=0.0117),
    Tip("sphere", radius=0.01),
    Tip("cone", half_angle=math.radians(70)),
    Tip("power", c=250.0, n=2.5),
]


def rel(a, b):
    return np.max(np.abs(np.asarray(a) / np.asarray(b) - 1))


def test_hess_factor_known_values():
    # kappa_1 = pi/2 (cone), kappa_2 = 2 (paraboloid), kappa_4 = 8/3 (Popov & Hess 2015, tab. 3.1)
    assert mdr.hess_factor(1) == pytest.approx(np.pi / 2, rel=1e-14)
    assert mdr.hess_factor(2) == pytest.approx(2.0, rel=1e-14)
    assert mdr.hess_factor(4) == pytest.approx(8.0 / 3.0, rel=1e-14)


def test_mdr_equals_paraboloid_closed_form():
    R = 0.0117
    assert rel(mdr.shape(DEPTHS, c=1 / (2 * R), n=2), paraboloid.shape(DEPTHS, R)) < 1e-12


def test_mdr_equals_cone_closed_form():
    alpha = math.radians(65)
    assert rel(mdr.shape(DEPTHS, c=1 / math.tan(alpha), n=1), cone.shape(DEPTHS, alpha)) < 1e-12


def test_mdr_tends_to_flat_punch():
    # f = (r/a)^n is a flat punch of radius a as n -> inf; the error falls like ln(n)/n.
    # (with a = 1 length unit so that c = a^-n = 1 does not overflow)
    a = 1.0
    errors = [rel(mdr.shape(DEPTHS, c=1.0, n=n), flat.shape(DEPTHS, a)) for n in
              (1e2, 1e4, 1e6)]
    assert errors[0] > errors[1] > errors[2]
    assert errors[2] < 5e-5  # ~ |ln d|/n with d in units of a
    # and the contact-radius form F = 2n/(n+1)·E*·a·d is exact for every n
    n = 7.0
    c = 3.0e5
    a_n = (DEPTHS / (mdr.hess_factor(n) * c)) ** (1 / n)
    assert rel(mdr.shape(DEPTHS, c, n), 2 * n / (n + 1) * a_n * DEPTHS) < 1e-12


def test_registry_power_laws_match_modules():
    for tip in TIPS:
        law = get_law(tip)
        s = law.shape(DEPTHS, tip)
        if law.exponent is not None:
            assert rel(s, law.prefactor_of(tip) * DEPTHS ** law.exponent_of(tip)) < 1e-12
    assert exponent(Tip("sphere", radius=0.01)) is None


def test_sneddon_parametric_oracle():
    # independent evaluation of Sneddon's parametric form at chosen contact radii
    R = 0.01
    a = np.linspace(0.05, 0.95, 200) * R  # the direct formula cancels below
    log = np.log((R + a) / (R - a))
    d = a / 2 * log
    F = 0.5 * ((R**2 + a**2) * log - 2 * a * R)
    assert rel(sphere.shape(d, R), F) < 1e-10
    assert rel(sphere.contact_radius(d, R), a) < 1e-12


def test_sneddon_against_50_digit_evaluation():
    # Sneddon's parametric form evaluated in 50-digit decimal arithmetic (artanh through ln),
    # from u = a/R = 1e-7 (d/R = 1e-14, where float64 cancels) to u = 0.9999 (d/R ~ 5)
    from decimal import Decimal, getcontext

    getcontext().prec = 50
    us = [Decimal(10) ** Decimal(e / 4) for e in range(-28, 0)] + [Decimal("0.9999")]
    d, s = [], []
    for u in us:
        t = ((1 + u) / (1 - u)).ln() / 2
        d.append(float(u * t))
        s.append(float((1 + u * u) * t - u))
    d, s = np.array(d), np.array(s)
    assert d.min() < 2e-14 and d.max() > 4
    assert rel(sphere.shape(d, 1.0), s) < 1e-13
    assert rel(sphere.contact_radius(d, 1.0), [float(u) for u in us]) < 1e-13


def test_sneddon_tends_to_hertz_and_is_three_percent_below_at_0p3():
    R = 0.01
    ratios = [float(sphere.shape(x * R, R) / paraboloid.shape(x * R, R)) for x in
              (1e-8, 1e-5, 1e-3, 0.1, 0.3)]
    assert abs(ratios[0] - 1) < 1e-8
    assert abs(ratios[1] - 1) < 2e-6
    assert all(np.diff(ratios) < 0)  # the deficit grows with depth
    assert 0.02 < 1 - ratios[-1] < 0.031  # 3.0 % at d/R = 0.3 (docs/design.md §1)


def test_force_zero_for_non_positive_depth_and_vectorised():
    d = np.array([[-1e-3, 0.0], [1e-4, 2e-3]])
    for tip in TIPS:
        F = force(d, 1e5, 0.3, tip)
        assert F.shape == d.shape
        assert F[0, 0] == 0 and F[0, 1] == 0
        assert np.all(F[1] > 0)


@settings(max_examples=examples(40), deadline=None)
@given(
    d1=st.floats(1e-6, 5e-3), d2=st.floats(1e-6, 5e-3),
    E=st.floats(1e2, 1e9), scale=st.floats(1.01, 10.0),
    tip_index=st.integers(0, len(TIPS) - 1),
)
def test_monotone_and_scaling_laws(d1, d2, E, scale, tip_index):
    tip = TIPS[tip_index]
    lo, hi = sorted((d1, d2))
    if hi > lo * (1 + 1e-12):  # depths one ulp apart may round to the same force
        assert force(hi, E, 0.3, tip) > force(lo, E, 0.3, tip)
    assert force(lo, scale * E, 0.3, tip) == pytest.approx(scale * force(lo, E, 0.3, tip),
                                                            rel=1e-12)
    m = exponent(tip)
    if m is not None:  # F ∝ d^m
        assert force(scale * lo, E, 0.3, tip) == pytest.approx(
            scale**m * force(lo, E, 0.3, tip), rel=1e-10)


def test_k_modulus_round_trip_and_paper_sphere_formula():
    R, nu, k = 0.01, 0.3, 1.7e4
    tip = Tip("paraboloid", radius=R)
    assert modulus_from_k(k, nu, tip) == pytest.approx(k * 3 * (1 - nu**2) / (4 * np.sqrt(R)))
    assert k_from_modulus(modulus_from_k(k, nu, tip), nu, tip) == pytest.approx(k, rel=1e-14)
    with pytest.raises(GeometryError, match="no power-law form"):
        modulus_from_k(k, nu, Tip("sphere", radius=R))


@pytest.mark.parametrize("base, expected", [
    ("bonded", [1.133, 1.283, 0.769, -0.0975]),
    ("free", [0.884, 0.781, 0.386, 0.0048]),
])
def test_dimitriadis_nu_half_matches_published_coefficients(base, expected):
    c = dimitriadis_coefficients(0.5, base)
    np.testing.assert_allclose(c[1:], expected, atol=2e-3)
    # the 4·a0²/pi (instead of /pi²) bug would give c2 ≈ 4.03 for the bonded case
    assert c[2] < 1.5


def test_layer_factor_applied_in_shape():
    """shape() on a layer is the half-space shape times thickness_factor (the exact layer
    solution), a 20 mm layer under a 10 mm paraboloid at 2 mm stiffens by > 10 %."""
    tip = Tip("paraboloid", radius=0.01)
    d, h, nu = 2e-3, 0.02, 0.3
    f = thickness_factor(np.array([d]), tip, h, nu, "bonded")[0]
    assert shape(d, tip, thickness_m=h, nu=nu) == pytest.approx(
        f * paraboloid.shape(d, 0.01), rel=1e-14)
    assert f == pytest.approx(dimitriadis_factor(np.array([d]), 0.01, h, nu)[0], rel=0.01)
    assert f > 1.1


@pytest.mark.parametrize("base", ["bonded", "free"])
@pytest.mark.parametrize("nu", [0.0, 0.3, 0.45])
def test_dimitriadis_refuses_chi_above_one(nu, base):
    R, h = 0.01, 0.01
    d_one = (DIMITRIADIS_CHI_MAX * h) ** 2 / R  # chi = 1 exactly
    ok = dimitriadis_factor(np.array([0.0, 0.5 * d_one, d_one]), R, h, nu, base)
    assert np.all(ok >= 1.0) and np.all(np.diff(ok) > 0)  # a stiffening correction up to chi 1
    with pytest.raises(GeometryError, match=r"chi = sqrt\(R\*d\)/h = 1\.1 .*exceeds 1"):
        dimitriadis_factor(np.array([0.5 * d_one, 1.21 * d_one]), R, h, nu, base)
    # the layer solution itself has no such limit: a stiffening factor beyond chi = 1
    tip = Tip("sphere", radius=R)
    f = thickness_factor(np.array([d_one, 1.21 * d_one, 4 * d_one]), tip, h, nu, base)
    assert np.all(np.diff(f) > 0) and f[0] > 1.5


def test_unchecked_dimitriadis_series_goes_negative_where_it_is_now_refused():
    """Why the range check exists: at nu = 0.3 the bonded series is negative at chi = 2.6."""
    c = dimitriadis_coefficients(0.3, "bonded")
    assert np.polyval(c[::-1], 2.6) < 0
    with pytest.raises(GeometryError):
        dimitriadis_factor((2.6 * 0.02) ** 2 / 0.01, 0.01, 0.02, 0.3)


def test_half_angle_from_degrees_reports_degrees():
    assert half_angle_from_degrees(70) == pytest.approx(math.radians(70))
    for bad in (95, 90, 0, -5, float("nan")):
        with pytest.raises(GeometryError, match=r"deg must lie strictly between 0 and 90 deg"):
            half_angle_from_degrees(bad)
    with pytest.raises(GeometryError, match="'steep' deg is not a number"):
        half_angle_from_degrees("steep")


def test_tip_radius_in_mm_given_as_metres_is_caught():
    check_tip_plausible(Tip("sphere", radius=0.01))
    check_tip_plausible(Tip("cone", half_angle=1.0))
    check_tip_plausible(Tip("flat", radius=MAX_TIP_RADIUS_M))
    with pytest.raises(GeometryError, match=r"--radius is in metres.*did you mean 0\.010\?"):
        check_tip_plausible(Tip("sphere", radius=10))
    with pytest.raises(GeometryError, match=r"did you mean 0\.0117\?"):
        check_tip_plausible(Tip("paraboloid", radius=11.7))


@pytest.mark.parametrize("kwargs, match", [
    ({"kind": "wedge", "radius": 1.0}, "unknown tip kind"),
    ({"kind": "sphere"}, "radius.*missing"),
    ({"kind": "flat", "radius": -0.01}, "positive"),
    ({"kind": "flat", "radius": float("nan")}, "positive"),
    ({"kind": "cone", "half_angle": 2.0}, "below pi/2"),
    ({"kind": "power", "c": 1.0}, "exponent n is missing"),
])
def test_tip_validation(kwargs, match):
    with pytest.raises(GeometryError, match=match):
        Tip(**kwargs)


@pytest.mark.parametrize("nu", [-0.1, 0.5001, 0.7, float("nan"), "x"])
def test_poisson_ratio_range(nu):
    with pytest.raises(GeometryError, match="Poisson ratio"):
        check_nu(nu)


def test_poisson_ratio_one_half_is_allowed():
    """nu = 0.5 (incompressible: silicone, gels, tissue) is valid for the half-space laws."""
    assert check_nu(0.5) == 0.5
    assert check_nu(0.0) == 0.0
