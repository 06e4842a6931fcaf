"""The inclusion forward model: closed forms, limits, monotonicity, quadrature, the fast table."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from palpbayes.contact import ContactLaw, Tip
from palpbayes.contact.registry import register, unregister
from palpbayes.errors import InputError
from palpbayes.inclusion import (
    Inclusion,
    _disk_fraction,
    apparent_modulus,
    apparent_ratio,
    contact_radius,
    depth_weight,
    sensitivity,
)
from palpbayes.inclusion_table import SensitivityTable
from palpbayes.paper import PAPER_TIPS

A = math.sqrt(0.0117 * 2e-3)  # the paper's paraboloid at 2 mm: a = 4.84 mm
H = 0.02
GEO = {"contact_radius": A, "thickness": H}


@pytest.fixture(scope="module")
def table():
    return SensitivityTable(A, H)


def test_centred_disk_closed_form():
    """L(0, ρ, z) = 1 − h³/(h² + ρ²)^(3/2), and ∫∫ K dA → 1 for a huge disk."""
    rho = np.array([1e-4, 1e-3, 3e-3, 6e-3, 2e-2, 1e3])
    h = np.full(rho.size, A + 2e-3)
    exact = 1.0 - h**3 / (h * h + rho * rho) ** 1.5
    assert _disk_fraction(np.zeros(rho.size), rho, h, 48) == pytest.approx(exact, abs=1e-13)
    assert exact[-1] == pytest.approx(1.0, abs=1e-12)


@pytest.mark.parametrize("s", [0.0, 1.5e-3, 2.9e-3, 3.0e-3, 3.1e-3, 6e-3, 2e-2])
def test_off_centre_disk_against_brute_force(s):
    """The semi-analytic disk integral (axis inside or outside the disk) against a fine
    Cartesian midpoint sum of K over the disk."""
    rho, h, n = 3e-3, A + 1e-3, 1200
    g = (np.arange(n) + 0.5) / n * 2 * rho - rho
    X, Y = np.meshgrid(g, g)
    r2 = (X + s) ** 2 + Y**2
    K = 3 * h**3 / (2 * np.pi * (h * h + r2) ** 2.5)
    brute = np.sum(K * (X * X + Y * Y <= rho * rho)) * (2 * rho / n) ** 2
    got = _disk_fraction(np.array([s]), np.array([rho]), np.array([h]), 48)[0]
    assert got == pytest.approx(brute, rel=2e-3, abs=2e-5)


def test_depth_weight_normalised():
    x, w = np.polynomial.legendre.leggauss(200)
    z = 0.5 * H * (x + 1)
    assert np.sum(0.5 * H * w * depth_weight(z, **GEO)) == pytest.approx(1.0, abs=1e-9)
    assert depth_weight(np.array([-1e-3, H + 1e-3]), **GEO).tolist() == [0.0, 0.0]


def test_huge_inclusion_sees_everything():
    """A sphere far wider than the tip, touching the surface and spanning the whole weighted
    depth: V(0) -> 1 (and nearby too)."""
    V = sensitivity(np.array([0.0, 5e-3]), radius=10.0, depth=10.0, **GEO)
    assert np.all(V > 0.999) and np.all(V <= 1.0)


def test_small_sphere_limit():
    """A tiny sphere acts as a point: V = (4/3)πR³·ω(D)·K(s, D), off-centre too."""
    R, D = 0.2e-3, 6e-3
    s = np.array([0.0, 3e-3, 8e-3, 15e-3])
    h = D + A
    point = (4 / 3 * np.pi * R**3 * depth_weight(D, **GEO)
             * 3 * h**3 / (2 * np.pi * (h * h + s * s) ** 2.5))
    assert sensitivity(s, radius=R, depth=D, **GEO) == pytest.approx(point, rel=2e-3)


def test_homogeneous_block_is_exact():
    """ratio = 1 (or no inclusion) reads exactly E_b, and E_app/E_b = 1 for every V."""
    x = np.linspace(0, 0.03, 7)
    lump = Inclusion(x=0.012, y=0.01, depth=6e-3, radius=5e-3, ratio=1.0)
    for inc in (lump, None):
        E = apparent_modulus(x, 0.01, E_background=50e3, inclusion=inc, **GEO)
        assert np.all(E == 50e3)
    V = np.random.default_rng(0).uniform(0, 1, 100)
    assert np.all(apparent_ratio(V, 1.0) == 1.0)


def test_monotone_in_distance_and_depth():
    s = np.linspace(0, 0.05, 101)
    V = sensitivity(s, radius=5e-3, depth=8e-3, **GEO)
    assert np.all(np.diff(V) < 0)
    peaks = [sensitivity(np.zeros(1), radius=5e-3, depth=d, **GEO)[0]
             for d in (5e-3, 7e-3, 9e-3, 12e-3, 15e-3)]
    assert np.all(np.diff(peaks) < 0)


def test_vanishes_far_away_and_below_the_block():
    assert sensitivity(np.array([1.0]), radius=5e-3, depth=8e-3, **GEO)[0] < 1e-9
    assert sensitivity(np.array([0.0]), radius=5e-3, depth=H + 5e-3, **GEO)[0] == 0.0


def test_deeper_lump_smaller_peak_apparent_ratio():
    peak = [apparent_modulus(0.0, 0.0, E_background=1.0, **GEO,
                             inclusion=Inclusion(0.0, 0.0, depth=d, radius=4e-3, ratio=5.0))
            for d in (4e-3, 6e-3, 9e-3, 13e-3)]
    assert np.all(np.diff(peak) < 0) and peak[-1] > 1.0


def test_rigid_limit_saturates():
    """ratio -> ∞: E_app/E_b -> 1/(1 − V), reached from below; a soft lump reads < 1."""
    V = np.array([0.0, 0.05, 0.3, 0.9])
    sat = 1.0 / (1.0 - V)
    assert apparent_ratio(V, np.inf) == pytest.approx(sat, rel=1e-15)
    assert apparent_ratio(V, 1e9) == pytest.approx(sat, rel=1e-8)
    ratios = [apparent_ratio(V, r) for r in (2.0, 10.0, 100.0)]
    assert np.all(np.diff(ratios, axis=0) >= 0) and np.all(ratios[-1] <= sat)
    assert np.all(apparent_ratio(V[1:], 0.2) < 1.0)


@pytest.mark.parametrize("a, R, D", [(A, 5e-3, 8e-3), (0.5e-3, 5e-3, 5e-3),
                                     (0.01, 2e-3, 15e-3), (A, 10e-3, 10e-3)])
def test_quadrature_converges(a, R, D):
    """Doubling the nodes changes V by < 1e-4 (at the default, < 1e-6)."""
    s = np.array([0.0, 2e-3, R, R + 1e-4, 8e-3, 20e-3])
    geo = {"radius": R, "depth": D, "contact_radius": a, "thickness": H}
    v24, v48, v96 = (sensitivity(s, nodes=n, **geo) for n in (24, 48, 96))
    assert np.max(np.abs(v24 - v96)) < 1e-3
    assert np.max(np.abs(v48 - v96)) < 1e-6


def test_table_matches_exact(table):
    """Random spheres over the table's whole domain, distances out into the tail."""
    rng = np.random.default_rng(42)
    lo, hi = table.radius_range
    worst = 0.0
    for k in range(60):
        R = math.exp(rng.uniform(math.log(lo), math.log(hi)))
        m = H * rng.uniform(0, 1) ** (2 if k % 2 else 1)
        ell = R + m + A
        s = np.concatenate([rng.uniform(0, 1.5 * ell, 12), rng.uniform(0, 6 * ell, 4)])
        exact = sensitivity(s, radius=R, depth=R + m, **GEO)
        fast = table(s, R, R + m)
        worst = max(worst, float(np.max(np.abs(fast - exact))))
        # the array path gives the same numbers as the scalar fast path
        assert table(s, np.full(s.size, R), R + m) == pytest.approx(fast, abs=1e-12)
    assert worst <= 2e-3
    assert worst <= 5e-4  # what the docstring promises for this tip


def test_table_edges(table):
    lo, hi = table.radius_range
    assert table(np.array([0.0, 0.01]), 5e-3, 5e-3 + H).tolist() == [0.0, 0.0]  # below
    assert table(-0.004, 5e-3, 8e-3) == pytest.approx(float(table(0.004, 5e-3, 8e-3)))
    with pytest.raises(InputError, match="radius_range"):
        table(0.0, 2 * hi, 3 * hi)
    with pytest.raises(InputError, match="depth"):
        table(0.0, 5e-3, 4e-3)
    wide = SensitivityTable(A, H, radius_range=(0.5 * lo, hi), n_radius=6, n_margin=6, n_s=8)
    assert np.isfinite(wide(0.0, 0.6 * lo, lo))


def test_contact_radius():
    assert contact_radius(PAPER_TIPS["flat"], 2e-3) == 0.010
    assert contact_radius(PAPER_TIPS["paraboloid"], 2e-3) == pytest.approx(A, rel=1e-15)
    R, d = 0.010, 2e-3
    a = contact_radius(PAPER_TIPS["sphere"], d)  # Sneddon: d = (a/2)·ln((R + a)/(R − a))
    assert 0.5 * a * math.log((R + a) / (R - a)) == pytest.approx(d, rel=1e-9)
    assert a == pytest.approx(math.sqrt(R * d), rel=0.04)
    # every tip whose law has a contact radius, a cone among them: a = 2·d·tan(alpha)/pi
    assert contact_radius(Tip("cone", half_angle=1.2), 2e-3) == pytest.approx(
        2 * 2e-3 * math.tan(1.2) / math.pi, rel=1e-12)
    with pytest.raises(InputError, match="depth"):
        contact_radius(PAPER_TIPS["flat"], 0.0)


def test_a_tip_kind_registered_later_is_asked_not_named():
    """The inclusion model asks the contact-law registry (issue 57: it switched on the kind,
    so a new tip was refused by maps and the active search until this file was edited)."""
    law = register(ContactLaw(
        kind="wedge9", parameters=("radius",), shape=lambda d, tip: np.clip(d, 0, None) * 0.0,
        exponent=1.0, prefactor=lambda tip: 0.0, reference="a toy law of this test",
        name="wedge", label="wedge", summary="toy", describe=lambda tip: "wedge9",
        contact_radius=lambda d, tip: np.full(np.shape(d), 3.0 * tip.radius),
        profile_exponent=lambda tip: 2.0))
    try:
        assert contact_radius(Tip("wedge9", radius=0.002), 1e-3) == pytest.approx(0.006)
        unregister("wedge9")
        register(dataclasses.replace(law, contact_radius=None, profile_exponent=None))
        with pytest.raises(InputError, match="needs a tip with a contact radius"):
            contact_radius(Tip("wedge9", radius=0.002), 1e-3)
    finally:
        unregister("wedge9")


@pytest.mark.parametrize("kwargs, match", [
    ({"radius": 0.0}, "radius"),
    ({"depth": 3e-3}, "stick out"),
    ({"ratio": -2.0}, "ratio"),
    ({"x": math.nan}, "centre x"),
])
def test_inclusion_validation(kwargs, match):
    good = {"x": 0.0, "y": 0.0, "depth": 8e-3, "radius": 5e-3, "ratio": 5.0}
    with pytest.raises(InputError, match=match):
        Inclusion(**{**good, **kwargs})
    with pytest.raises(InputError, match="s \\[m\\]"):
        sensitivity(np.array([-1.0]), radius=5e-3, depth=8e-3, **GEO)


def test_batch_equals_scalar_calls(table):
    rng = np.random.default_rng(3)
    lo, hi = table.radius_range
    R = rng.uniform(lo, min(hi, 0.4 * H), 12)
    D = R + rng.uniform(0.0, 0.5 * H, 12) * np.r_[0.0, np.ones(11)]  # one touching the surface
    D[-1] = R[-1] + 1.5 * H  # one below the block: V = 0
    s = rng.uniform(0.0, 0.08, (12, 40))
    got = table.batch(s, R, D)
    want = np.array([table(s[k], R[k], D[k]) for k in range(12)])
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-12)
    assert np.all(got[-1] == 0.0)
