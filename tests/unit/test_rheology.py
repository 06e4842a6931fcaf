"""The viscoelastic fit (palpbayes.rheology): the Lee–Radok columns against the exact
hereditary integral, recovery of known relaxation moduli from simulated ramp–hold records
(fixed seeds), the flags and the errors."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from palpbayes.contact import Tip, exponent
from palpbayes.contact.viscoelastic import (
    PowerLawKernel,
    hereditary_force,
    standard_linear_solid,
)
from palpbayes.errors import InputError
from palpbayes.paper import PAPER_TIPS
from palpbayes.rheology import fit_rheology, prepare_cycle
from palpbayes.rheology.design import (
    Windows,
    block_kernel_means,
    knot_products,
    lee_radok_columns,
    window_kernel,
    window_kernels,
)
from palpbayes.rheology.kernels import (
    Lags,
    double_integrated_kernel,
    integrated_kernel,
    triple_integrated_kernel,
)
from palpbayes.rheology.lattice import knot_lattice
from palpbayes.sim import simulate_viscoelastic
from palpbayes.trace import IndentationTrace

PARABOLOID, FLAT = PAPER_TIPS["paraboloid"], PAPER_TIPS["flat"]
CONE = Tip("cone", half_angle=1.0)  # [rad]
SPEED = 50 / 60e3  # 50 mm/min [m/s]


CORNER = 1.0  # [s] where the hold starts, between two samples


def _cycle_axis(n: int = 1500, seed: int = 3, jitter: float = 0.02):
    """Sample times 1 ms apart ± ``jitter``, a 1.5 mm/s ramp from 0.5 mm above the surface
    z = 0 and a hold from :data:`CORNER` on, with the segment codes."""
    rng = np.random.default_rng(seed)
    t = np.cumsum(rng.uniform(1 - jitter, 1 + jitter, n)) * 1e-3
    t -= t[0]
    return t, _height(t), np.where(t < CORNER, 0, 1).astype(np.int8)


def _height(t):
    return 0.5e-3 - 1.5e-3 * np.minimum(t, CORNER)


def _exact_force(t, zs, m, kernel):
    """hereditary_force at ``t`` with the corner of the motion among its knots (it takes the
    depth linear between the samples it is given)."""
    ref = np.sort(np.append(t, CORNER))
    return hereditary_force(ref, zs - _height(ref), 1.0, m, kernel)[ref != CORNER]


@pytest.mark.parametrize("tip", [FLAT, PARABOLOID, CONE], ids=["flat", "paraboloid", "cone"])
@pytest.mark.parametrize("kernel, kind, theta, tol", [
    (PowerLawKernel(1.0, 0.2), "power-law", 0.2, (1e-4, 1e-4)),
    (PowerLawKernel(1.0, 0.6, t0=0.3), "power-law", 0.6, (1e-4, 3e-4)),
    (standard_linear_solid(0.0, 1.0, 0.7), "exponential", 0.7, (1e-4, 1e-4)),
    # tau of five samples: the single samples' linear source shows at the corner (1.4e-3)
    (standard_linear_solid(0.0, 1.0, 0.005), "exponential", 0.005, (3e-4, 3e-3)),
    (standard_linear_solid(1.0, 0.0, 1.0), None, 0.0, (1e-4, 1e-4)),  # the constant kernel
])
@pytest.mark.parametrize("max_points", [100, 1500])
def test_columns_match_block_means_of_the_exact_hereditary_integral(tip, kernel, kind, theta,
                                                                      tol, max_points):
    """The columns are the block means of the force: against hereditary_force (exact per
    step) at 1,500 samples 1 ms ± 2 % apart, in blocks of 15 or single samples (the hold's
    corner between two samples, the contact starting inside a block), to ``tol`` of the peak
    (measured: <= 7e-5 in blocks, 1.2e-4 for tau = 5 samples; single samples 1e-5–1.5e-4,
    1.4e-3 for tau = 5 samples).
    Irregular steps (± 50 %) cost ~1e-3: a block's mean sample time is not its window's
    centre (first order, not modelled)."""
    t, z, seg = _cycle_axis()
    zs, m = 0.2e-3, exponent(tip)
    rec = IndentationTrace(t, z, _exact_force(t, zs, m, kernel), tip=tip, segment=seg)
    d = prepare_cycle(rec, tip, max_points=max_points)
    assert d.block == (15 if max_points == 100 else 1)
    col = lee_radok_columns(d.windows(), np.array([zs]), d.z_edges, m, kind, theta,
                            getattr(kernel, "t0", 1.0))[0]
    assert np.abs(col - d.force).max() < tol[d.block == 1] * d.force.max()


@pytest.mark.parametrize("kind, theta", [("power-law", 0.3), ("exponential", 0.05), (None, 0.0)])
@pytest.mark.parametrize("max_points", [100, 400])
def test_columns_are_continuous_as_the_surface_crosses_a_knot(kind, theta, max_points):
    """A surface a picometre or 0.1 nm above a knot (the contact starts at the very end
    of a step) gives the columns of a surface just below it: the rise's end and its start
    take the same blocks' sample means.  With the knot's own band, the one block where sample
    means and window means swap put an O(1) step over the rise's h², and the columns jumped by
    ~d^(-1/2) (0.6 of a block's value at 1e-12 m in a record), and the fit's density fell by
    1,000 and rose by 9 above the mode within nanometres of a knot (calibration record
    power-law-1105 at 500 mm/min, where the climb found that spike instead of the mode)."""
    t, z, seg = _cycle_axis()
    rec = IndentationTrace(t, z, z * 0, tip=PARABOLOID, segment=seg)
    d = prepare_cycle(rec, PARABOLOID, max_points=max_points)
    win = d.windows()
    ramp = d.z_edges[(d.z_edges < 0.45e-3) & (d.z_edges > 0.0)][::7][:6]
    eps = np.array([-1e-12, 1e-12, 1e-10])
    for zk in ramp:
        col = lee_radok_columns(win, zk + eps, d.z_edges, 1.5, kind, theta)
        scale = np.abs(col).max()
        # smoothly, 1e-10 m moves d^1.5 by at most 1.5·d^0.5·1e-10 ~ 3e-12 m^1.5 (~4e-8 of
        # the scale); measured <= 1.0e-4 of the scale, the step in the block where the
        # contact starts between the band's last block as sample means (the contact from the
        # next step on) and as a window mean (from this step's end); before, 6e-3 to 0.16
        # of the scale at the worst of these knots per case
        assert np.abs(col[1:] - col[0]).max() < 4e-4 * scale, zk


@pytest.mark.parametrize("max_points", [100, 1500])
@pytest.mark.parametrize("kind, theta", [("power-law", 0.2), ("power-law", 0.85),
                                         ("exponential", 0.005), ("exponential", 0.7),
                                         ("exponential", 30.0)])
def test_lattice_products_equal_the_dense_ones(kind, theta, max_points):
    """On a regular sample axis the knots lie on a lattice (one or two knots near the hold's
    corner, between two samples, off it): the FFT convolutions with those knots' rows and
    columns taken directly give the dense products' columns to 1e-7 of the peak (measured
    <= 2e-11, and 2e-8 for tau = 30 s on a 1.5-s record, where Ψ and Ψ₂ of single-sample lags
    cancel to y² and y³, y = 3e-5, in both paths), and the exact block means of the
    hereditary integral to 1e-4 (power law)."""
    t, z, seg = _cycle_axis(jitter=0.0)
    zs, m = 0.2e-3, 1.5
    rec = IndentationTrace(t, z, z * 0, tip=PARABOLOID, segment=seg)
    d = prepare_cycle(rec, PARABOLOID, max_points=max_points)
    win = d.windows()
    # off the lattice: the hold's corner, or the approach's knots when the hold's blocks
    # start on it
    assert win.lattice is not None and len(win.lattice.groups) == 1
    assert 1 <= win.lattice.off.size <= 2
    nodes = np.array([-1e-3, 0.05e-3, zs, 0.45e-3])
    fast = lee_radok_columns(win, nodes, d.z_edges, m, kind, theta)
    win.lattice = None
    dense = lee_radok_columns(win, nodes, d.z_edges, m, kind, theta)
    assert np.abs(fast - dense).max() < 1e-7 * np.abs(dense).max()
    if kind == "power-law" and theta == 0.2:
        exact = _exact_force(t, zs, m, PowerLawKernel(1.0, 0.2))
        d2 = prepare_cycle(IndentationTrace(t, z, exact, tip=PARABOLOID, segment=seg),
                           PARABOLOID, max_points=max_points)
        assert np.abs(fast[2] - d2.force).max() < 1e-4 * d2.force.max()


def test_knot_lattice_or_the_dense_path():
    """A regular axis with a corner has one lattice; jittered steps and too few knots have
    none; a second rate on the same lattice (a hold sampled 4 × faster, windows aligned)
    shares it; one whose windows sit half a fine step off is a second group."""
    e = np.r_[np.arange(200) * 0.01, 1.995]
    lat = knot_lattice(e)
    assert lat is not None and len(lat.groups) == 1 and list(lat.off) == [200]
    assert lat.groups[0].step == pytest.approx(0.01) and list(lat.direct_steps) == [199]
    rng = np.random.default_rng(0)
    assert knot_lattice(np.cumsum(rng.uniform(0.98, 1.02, 200))) is None
    assert knot_lattice(np.arange(40) * 0.01) is None
    two = np.r_[np.arange(100) * 0.01, 0.99 + np.arange(1, 101) * 0.0025]
    lat2 = knot_lattice(two)
    assert lat2 is not None and len(lat2.groups) == 1 and lat2.off.size == 0
    g = lat2.groups[0]
    assert g.step == pytest.approx(0.0025) and g.wide and g.size == 397 + 100
    shifted = np.r_[np.arange(100) * 0.01, 0.99 + 0.00125 + np.arange(100) * 0.0025]
    lat3 = knot_lattice(shifted)
    assert lat3 is not None and [x.members.size for x in lat3.groups] == [100, 100]
    assert list(lat3.direct_steps) == [99]  # the step that joins the two
    # a clock whose step drifts by 1e-7 per step is on no lattice at 1e-9: the dense path
    drift = np.cumsum(0.01 * (1 + 1e-7 * np.arange(300)))
    assert knot_lattice(drift) is None


@pytest.mark.parametrize("kind, theta", [("power-law", 0.3), ("exponential", 0.05)])
def test_knot_products_on_two_rates_and_off_lattice_knots(kind, theta):
    """Steps that span several lattice points (a segment at a quarter of the rate), knots
    off the lattice, and two lattice groups (the second's windows half a step off the
    first's): the lattice path's products equal the dense ones."""
    e = np.r_[np.arange(100) * 0.01, 0.99 + np.arange(1, 101) * 0.0025, 0.5037, 1.1013]
    e.sort()
    win = Windows(e)
    assert win.lattice is not None and win.lattice.groups[0].wide
    assert win.lattice.off.size == 2
    rng = np.random.default_rng(5)
    a1, a2 = rng.normal(size=(3, e.size)), rng.normal(size=(3, e.size)) * 1e2
    fast = knot_products(win, a1, a2, kind, theta)
    win.lattice = None
    dense = knot_products(win, a1, a2, kind, theta)
    assert np.abs(fast - dense).max() < 1e-10 * np.abs(dense).max()
    e2 = np.r_[np.arange(100) * 0.01, 0.99 + 0.00125 + np.arange(100) * 0.0025, 0.3037]
    e2.sort()
    win2 = Windows(e2)
    assert len(win2.lattice.groups) == 2 and win2.lattice.off.size == 1
    a1, a2 = rng.normal(size=(3, e2.size)), rng.normal(size=(3, e2.size)) * 1e2
    fast = knot_products(win2, a1, a2, kind, theta)
    win2.lattice = None
    dense = knot_products(win2, a1, a2, kind, theta)
    assert np.abs(fast - dense).max() < 1e-10 * np.abs(dense).max()


def test_columns_for_many_surfaces_equal_one_at_a_time():
    t, z, seg = _cycle_axis()
    d = prepare_cycle(IndentationTrace(t, z, z * 0, tip=PARABOLOID, segment=seg),
                      max_points=200)
    win = d.windows()
    nodes = np.array([-4e-3, 0.0, 2e-4, 4e-4])  # the first never touches
    many = lee_radok_columns(win, nodes, d.z_edges, 1.5, "power-law", 0.3)
    for i in range(nodes.size):
        one = lee_radok_columns(win, nodes[i:i + 1], d.z_edges, 1.5, "power-law", 0.3)[0]
        np.testing.assert_allclose(many[i], one, rtol=1e-12, atol=1e-18)
    assert not many[0].any() and many[3].max() > many[2].max() > many[1].max() > 0


@pytest.mark.parametrize("kind, theta", [("power-law", 0.0), ("power-law", 0.37),
                                         ("power-law", 0.95), ("exponential", 2e-3),
                                         ("exponential", 0.7), (None, 0.0)])
def test_lag_tables_give_the_kernel_integrals(kind, theta):
    """Phi, Psi and Psi2 from one exponential per lag (Lags.integrals) equal the kernels' own
    functions to 1e-13 relative, any order subset, on lags from -1 s (0) through 1e-9 s (the
    exponential's series) to 50 s; the logarithms given by the caller give the same."""
    x = np.r_[-1.0, 0.0, np.geomspace(1e-9, 50.0, 400)].reshape(2, -1)
    fs = {1: integrated_kernel, 2: double_integrated_kernel, 3: triple_integrated_kernel}
    lags = Lags(x)
    with np.errstate(divide="ignore"):
        given = Lags(np.maximum(x, 0.0), np.log(np.maximum(x, 0.0)))
    for orders in ((1, 2, 3), (3,), (2, 3), (1,)):
        for table in (lags, given):
            for k, got in zip(orders, table.integrals(orders, kind, theta, 2.0), strict=True):
                ref = fs[k](x, kind, theta, 2.0)
                assert got.shape == x.shape and np.all(got[x <= 0] == 0.0)
                np.testing.assert_allclose(got, ref, rtol=1e-13, atol=0)
    with pytest.raises(InputError, match="unknown kernel"):
        lags.integrals((1,), "springpot", 0.3)
    with pytest.raises(InputError, match="alpha = 1.0"):
        lags.integrals((1,), "power-law", 1.0)


def test_the_exponentials_series_meet_the_closed_forms_where_they_hand_over():
    """Psi/tau^2 and Psi2/tau^3 of the exponential: their short series (one each, shared by
    the kernel functions, the lag tables and the dense step means) against the full Taylor
    sums below their thresholds, and against the closed forms at the threshold."""
    from palpbayes.rheology.kernels import PSI2_SERIES, PSI_SERIES, psi2_series, psi_series

    def full(y, first):  # sum over n >= first of (-y)^n / n!, exactly summed
        return math.fsum((-y) ** n / math.factorial(n) for n in range(first, 40))

    for y in np.geomspace(1e-9, PSI_SERIES, 30):
        assert psi_series(y) == pytest.approx(full(y, 2), rel=3e-15)
    for y in np.geomspace(1e-9, PSI2_SERIES, 30):
        assert psi2_series(y) == pytest.approx(-full(y, 3), rel=1.2e-11)
    y = PSI_SERIES
    assert psi_series(y) == pytest.approx(y + math.expm1(-y), rel=1e-9)
    y = PSI2_SERIES
    assert psi2_series(y) == pytest.approx(0.5 * y * y - y - math.expm1(-y), rel=1e-9)


def _window_kernel_reference(win, s, kind, theta, order, side):
    """Block means of Phi (order 1) or Psi (2) of t - s from the kernels' own functions: the
    window mean from the next integral at the window's ends, the BAND + 1 blocks from the
    one holding s as means over their samples."""
    f = double_integrated_kernel if order == 1 else triple_integrated_kernel
    g = integrated_kernel if order == 1 else double_integrated_kernel
    at = f(win.edges[None, :] - s[:, None], kind, theta, 1.0)
    out = (at[:, win.hi] - at[:, win.lo]) / win.width[None, :]
    first = np.searchsorted(win.edges[win.hi], s, side=side)
    for r in range(s.size):
        for o in np.clip(first[r] + np.arange(3), 0, win.lo.size - 1):
            out[r, o] = g(win.samples[o] - s[r], kind, theta, 1.0).mean()
    return out


@pytest.mark.parametrize("kind, theta", [("power-law", 0.3), ("exponential", 0.4)])
def test_window_kernels_share_what_window_kernel_computes(kind, theta):
    """window_kernels' requests (orders 1, 2 on both sides) equal the kernels' own functions
    assembled one block at a time, with the lags of the sources computed or given, for
    sources on knots and between them (the record's knot lags as columns, with their
    logarithms or without)."""
    t, z, seg = _cycle_axis(jitter=0.02)
    d = prepare_cycle(IndentationTrace(t, z, z * 0, tip=PARABOLOID, segment=seg),
                      max_points=100)
    win = d.windows()
    knots = np.array([3, 10, 11, 40])
    requests = ((1, "right"), (2, "left"), (1, "left"), (2, "right"))
    between = 0.3 * win.edges[knots] + 0.7 * win.edges[knots + 1]
    lazy = win.knot_lags.columns(knots)  # before the record's logarithms are computed
    assert np.isneginf(win.knot_lags.log).any()  # now computed (zero lags: -inf)
    for s, given in ((win.edges[knots], win.knot_lags.columns(knots)),
                     (win.edges[knots], lazy), (win.edges[knots], None), (between, None)):
        got = window_kernels(win, s, kind, theta, 1.0, requests, given)
        for (order, side), g in zip(requests, got, strict=True):
            ref = _window_kernel_reference(win, s, kind, theta, order, side)
            np.testing.assert_allclose(g, ref, rtol=1e-12, atol=1e-15 * np.abs(ref).max())
            one = window_kernel(win, s, kind, theta, 1.0, order=order, side=side)
            np.testing.assert_array_equal(one, g)


@pytest.mark.parametrize("jitter, tol", [(0.0, 1e-6), (0.02, 1e-4)])
def test_block_kernel_means_against_sample_means(jitter, tol):
    """Far from a block the window mean stands in for the sample mean (midpoint rule); near
    it the band takes the samples themselves: the assembled means equal brute-force sample
    means of Phi to 1e-6 of the largest on a regular axis (power law, alpha 0.4, blocks of
    15); steps 1 ms ± 2 % cost 3e-5 (a block's mean time is not its window's centre)."""
    t, z, seg = _cycle_axis(jitter=jitter)
    d = prepare_cycle(IndentationTrace(t, z, z * 0, tip=PARABOLOID, segment=seg),
                      max_points=100)
    win = d.windows()
    A1, _ = block_kernel_means(win, "power-law", 0.4)
    brute = integrated_kernel(d.sample_time[:, :, None] - win.edges[None, None, :],
                              "power-law", 0.4).mean(axis=1)
    assert np.abs(A1 - brute).max() < tol * np.abs(brute).max()


def _record(kernel, tip=PARABOLOID, seed=1, **kw):
    opts = dict(depth=3e-3, speed=SPEED, hold_time=8.0, retract=True, rate=800.0,
                z_surf=2e-4, noise_sd=0.008, phi=0.3, offset=0.04, rng=seed)
    opts.update(kw)
    return simulate_viscoelastic(kernel, tip, **opts)


def _inside(fit, name, value, level=0.9):
    lo, hi = np.percentile(fit.draws[name], [50 * (1 - level), 50 * (1 + level)])
    return lo <= value <= hi


def _near(fit, name, value, n_sd=3.0):
    """Within ``n_sd`` posterior sd of the median: one fixed-seed record per test; the 90 %
    intervals' coverage over many records is the slow suite's
    (tests/statistical/test_rheology_calibration.py, measured 0.90–0.97)."""
    d = fit.draws[name]
    return abs(value - np.median(d)) <= n_sd * np.std(d)


@pytest.fixture(scope="module")
def power_fit():
    return fit_rheology(_record(PowerLawKernel(90e3, 0.2)), "power-law", rng=0)


def test_power_law_recovers_its_truth(power_fit):
    """E0*, alpha, z_surf, offset within 3 posterior sd, E0* within 1 %, the block-mean noise
    near its value; the model check passes and nothing is flagged."""
    f = power_fit
    assert _near(f, "E0", 90e3) and _near(f, "alpha", 0.2) and _near(f, "z_surf", 2e-4)
    assert _near(f, "offset", 0.04)
    assert f.data.segments == ("approach", "hold") and f.data.block > 1
    sd_block = 0.008 / np.sqrt(f.data.block)  # AR(1) block means: near, not equal
    assert 0.8 * sd_block < np.median(f.draws["sigma"]) < 2.0 * sd_block
    assert f.model_ok and f.flags == [] and f.grid.converged
    assert abs(np.median(f.draws["E0"]) / 90e3 - 1) < 0.01


def test_power_law_table_relaxation_and_apparent_modulus(power_fit):
    f = power_fit
    tab = f.table()
    assert list(tab["parameter"][:2]) == ["E0*", "alpha"]
    assert (tab["lo"] <= tab["median"]).all() and (tab["median"] <= tab["hi"]).all()
    rel = f.relaxation([0.1, 1.0, 10.0])
    assert rel["E_star_pa"].is_monotonic_decreasing
    assert rel["E_star_lo_pa"].iloc[1] <= 90e3 * 1.02 and rel["E_star_hi_pa"].iloc[1] >= 90e3 / 1.02
    # E*(t) = E0*(t/t0)^-alpha: 10 s over 1 s is 10^-alpha
    assert rel["E_star_pa"].iloc[2] / rel["E_star_pa"].iloc[1] == pytest.approx(10**-0.2, rel=0.02)
    med, lo, hi = f.apparent_modulus(SPEED, 3e-3)
    from palpbayes.contact.viscoelastic import ramp_apparent_modulus
    truth = float(ramp_apparent_modulus(PowerLawKernel(90e3, 0.2), SPEED, 3e-3, 1.5))
    assert lo <= truth * 1.01 and hi >= truth * 0.99 and lo < med < hi
    with pytest.raises(InputError, match="positive"):
        f.relaxation([0.0])


def test_sls_recovers_its_truth():
    f = fit_rheology(_record(standard_linear_solid(50e3, 40e3, 1.5), seed=2), "sls", rng=1,
                     nu=0.45)
    assert _near(f, "E_inf", 50e3) and _near(f, "E1", 40e3) and _near(f, "tau", 1.5)
    assert _near(f, "z_surf", 2e-4)
    assert abs(np.median(f.draws["E_inf"]) / 50e3 - 1) < 0.01
    assert f.model_ok and f.flags == []
    tab = f.table().set_index("parameter")
    assert tab.loc["E_inf", "median"] == pytest.approx(tab.loc["E_inf*", "median"] * (1 - 0.45**2))


def test_the_wrong_relaxation_is_caught():
    """An SLS record (one fast relaxation to a plateau) fitted with the power law fails its
    posterior-predictive check, and the flag says so."""
    f = fit_rheology(_record(standard_linear_solid(50e3, 60e3, 0.8), seed=4, phi=0.0),
                     "power-law", rng=2)
    assert not f.model_ok
    assert any("posterior-predictive" in s or "phi piles up" in s for s in f.flags)


def test_an_elastic_record_flags_alpha_at_zero():
    f = fit_rheology(_record(PowerLawKernel(90e3, 0.0), seed=5), "power-law", rng=3)
    assert any("alpha piles up at 0" in s for s in f.flags)
    assert _near(f, "E0", 90e3)


@pytest.mark.slow
def test_flat_punch_record():
    f = fit_rheology(_record(PowerLawKernel(60e3, 0.3), tip=FLAT, seed=6, depth=2e-3),
                     "power-law", rng=4)
    assert _near(f, "E0", 60e3) and _near(f, "alpha", 0.3) and _near(f, "z_surf", 2e-4)


def test_segments_are_checked():
    rec = _record(PowerLawKernel(90e3, 0.2), hold_time=0.0)
    with pytest.raises(InputError, match="retract is fitted with the power law only"):
        fit_rheology(rec, "sls", segments="approach,retract")
    with pytest.raises(InputError, match="must include the approach"):
        fit_rheology(rec, segments="hold")
    with pytest.raises(InputError, match="asked for the hold segment.*has only approach, "
                       "retract"):
        fit_rheology(rec, segments="approach,hold")
    with pytest.raises(InputError, match="unknown segment 'pause'"):
        prepare_cycle(rec, segments="approach,pause")
    with pytest.raises(InputError, match="unknown rheology 'maxwell'"):
        fit_rheology(rec, "maxwell")


def test_a_tip_without_power_law_is_refused():
    rec = _record(PowerLawKernel(90e3, 0.2))
    with pytest.raises(InputError, match="no power-law form"):
        prepare_cycle(rec, PAPER_TIPS["sphere"])


def test_block_means_and_the_surface_range():
    rec = _record(PowerLawKernel(90e3, 0.2))
    d = prepare_cycle(rec, max_points=300)
    assert d.n_points <= 300 and d.block == -(-rec.segments("approach,hold").n_points // 300)
    assert np.all(np.diff(d.time) > 0) and np.all(np.diff(d.segment) >= 0)
    assert d.z_hi == pytest.approx(d.z[0]) and d.z_lo == pytest.approx(d.z.min())
    assert d.sigma_center == pytest.approx(0.008 / np.sqrt(d.block), rel=0.3)
    with pytest.raises(InputError, match="max_points"):
        prepare_cycle(rec, max_points=10)


def test_a_record_without_segments_gets_them_from_the_motion():
    rec = _record(PowerLawKernel(90e3, 0.2), seed=7)
    bare = IndentationTrace(rec.time, rec.z, rec.force, tip=rec.tip)
    a, b = prepare_cycle(bare), prepare_cycle(rec)
    assert a.segments == b.segments
    assert abs(a.n_points - b.n_points) <= 2


def test_compression_modulus_closed_forms():
    """The compression test's rule on the model's stress-strain curve: the elastic limit
    reads (1 - nu^2)·E* exactly; a power law's reading scales as speed^alpha (the curve's
    shape in strain does not change); the SLS reads E_inf or E_inf + E1 when tau is far
    shorter or longer than the test."""
    from palpbayes.rheology.compression import compression_moduli

    nu, v, h = 0.45, 50 / 60e3, 0.02
    elastic, power = PowerLawKernel(80e3, 0.0), PowerLawKernel(80e3, 0.2)
    slow, fast = compression_moduli([elastic, power], nu, v, h), compression_moduli(
        [elastic, power], nu, 10 * v, h)
    assert slow[0] == pytest.approx(80e3 * (1 - nu**2), rel=1e-12)
    assert fast[0] == pytest.approx(slow[0], rel=1e-12)
    assert fast[1] / slow[1] == pytest.approx(10**0.2, rel=1e-9)
    sls = compression_moduli([standard_linear_solid(40e3, 60e3, 1e-3),
                              standard_linear_solid(40e3, 60e3, 1e4)], nu, v, h)
    np.testing.assert_allclose(sls / (1 - nu**2), [40e3, 100e3], rtol=1e-3)
    with pytest.raises(InputError, match="needs the specimen height"):
        compression_moduli([elastic], nu, v, None)


def test_fit_compression_modulus_brackets_the_truth(power_fit):
    import dataclasses

    from palpbayes.rheology.compression import compression_moduli

    with pytest.raises(InputError, match="fit with nu="):
        power_fit.compression_modulus(0.02)
    f = dataclasses.replace(power_fit, nu=0.45)
    med, lo, hi = f.compression_modulus(0.02)
    truth = compression_moduli([PowerLawKernel(90e3, 0.2)], 0.45, 50 / 60e3, 0.02)[0]
    assert lo < med < hi and abs(med - truth) <= 3 * (hi - lo) / 3.29


def test_pointwise_loglik_is_the_ar1_likelihood(power_fit):
    """The pointwise terms of PSIS-LOO add up to the exact AR(1) Gaussian log-likelihood of
    the block means (stationary, lag-one correlation phi) for each draw."""
    from scipy.stats import multivariate_normal

    from palpbayes.rheology.choice import pointwise_loglik
    from palpbayes.rheology.fit import curve_draws

    f = power_fit
    ll = pointwise_loglik(f, 3)
    idx = curve_draws(len(f.draws["z_surf"]), 3)
    mu = f.force_curves(3)
    n = f.data.n_points
    lag = np.abs(np.subtract.outer(np.arange(n), np.arange(n)))
    for r, i in enumerate(idx):
        s, phi = f.draws["sigma"][i], f.draws["phi"][i]
        exact = multivariate_normal(mu[r], s**2 * phi**lag).logpdf(f.data.force)
        assert ll[r].sum() == pytest.approx(exact, rel=1e-9)


def test_compare_fits_needs_two_fits_on_the_same_blocks(power_fit):
    import dataclasses

    from palpbayes.rheology.choice import compare_rheology

    with pytest.raises(InputError, match="at least two"):
        compare_rheology({"power-law": power_fit})
    other = dataclasses.replace(power_fit, data=prepare_cycle(power_fit.data.trace,
                                                              max_points=300))
    with pytest.raises(InputError, match="same block means"):
        compare_rheology({"a": power_fit, "b": other})


@pytest.mark.slow
def test_pooling_a_fit_with_itself_halves_its_variance(power_fit):
    """The pooled posterior is the product of the traces' likelihoods: a fit pooled with
    itself keeps its centre and its sd shrinks by sqrt(2) (each trace's likelihood is its own
    collapse, re-evaluated on the pooled grid)."""
    from palpbayes.rheology.pool import pool_rheology

    p = pool_rheology([power_fit, power_fit])
    for name in ("E0", "alpha"):
        own, pooled = power_fit.draws[name], p.draws[name]
        assert abs(np.median(pooled) - np.median(own)) < 0.15 * np.std(own)
        assert np.std(pooled) / np.std(own) == pytest.approx(2**-0.5, rel=0.08)
    assert p.flags == [] and list(p.table()["parameter"]) == ["E0*", "alpha"]
    with pytest.raises(InputError, match="two or more"):
        pool_rheology([power_fit])


def test_seed_and_the_exact_engine_are_the_elastic_fits_names(power_fit):
    """``seed=`` and ``engine="exact"`` as :func:`palpbayes.fit` names them: the same fit as
    ``rng=`` and ``engine="grid"`` (issue 57)."""
    f = fit_rheology(_record(PowerLawKernel(90e3, 0.2)), "power-law", seed=0, engine="exact")
    pd.testing.assert_frame_equal(f.table(), power_fit.table())
    with pytest.raises(InputError, match="seed= or rng=, not both"):
        fit_rheology(_record(PowerLawKernel(90e3, 0.2)), "power-law", seed=1, rng=2)
    with pytest.raises(InputError, match="engine 'mcmc'.*grid, emcee.*exact"):
        fit_rheology(_record(PowerLawKernel(90e3, 0.2)), "power-law", engine="mcmc")
