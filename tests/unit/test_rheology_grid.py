"""The collapsed grid's search finds the mode whatever the last bits of the record.

A standard linear solid pressed at 5 mm/min (the calibration's record sls-1220: 47,000
samples in blocks of 39) has a (tau, z_surf) ridge far narrower than the coarse grid's surface
nodes.  The search used to let theta's moments, which then came from the one row whose
surface node fell nearest the ridge, shrink the box onto that row: the result moved with a
picometre of noise in the record (tau 1.008 or 1.015 s, the grid unsettled), and in one
calibration run this record came out at tau 0.990 s with an sd of 0.0005 s, 55 sd from the
truth (other records of such runs settled up to 32 in log density below the mode).
"""

from __future__ import annotations

import importlib.util
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from palpbayes.rheology import fit_rheology

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def calibration_record():
    """``(model, index) -> (trace, truth)``: a record of tools/rheology_calibration.py."""
    spec = importlib.util.spec_from_file_location("rheology_calibration",
                                                  ROOT / "tools" / "rheology_calibration.py")
    tool = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(tool)
    return lambda model, i: tool.record(model, i)[:2]


@pytest.fixture(scope="module")
def record(calibration_record):
    return calibration_record("sls", 1220)


def test_a_picometre_does_not_move_the_posterior(record):
    """The record as simulated and with 1e-12 m of noise on its heights give the same tau to
    1 % of its sd, each on a settled grid, with the truth within 3 sd."""
    trace, truth = record
    fits = [fit_rheology(trace, "sls", rng=0),
            fit_rheology(replace(trace, z=trace.z + 1e-12 * np.random.default_rng(5)
                                 .standard_normal(trace.z.size)), "sls", rng=0)]
    tau = [fit.draws["tau"] for fit in fits]
    assert all(fit.grid.converged for fit in fits)
    assert abs(np.median(tau[0]) - np.median(tau[1])) < 0.01 * np.std(tau[0])
    assert np.std(tau[1]) == pytest.approx(np.std(tau[0]), rel=0.01)
    assert abs(np.median(tau[0]) - truth["tau"]) < 3 * np.std(tau[0])


@pytest.fixture(scope="module")
def power_law_1058(calibration_record):
    return calibration_record("power-law", 1058)


def test_a_ridge_between_all_nodes_is_climbed(power_law_1058):
    """Calibration record power-law-1058 (a paraboloid at 5 mm/min, 64,000 samples, the
    surface 42 µm below the first sample) has an (alpha, z_surf) ridge ~0.0004 wide in alpha
    and a few µm in z_s, between the coarse grid's alpha nodes (0.059 apart) and surface nodes
    (31 µm).  The box used to cycle between widening and narrowing in z_s, its alpha nodes
    those of the coarse grid, for all its iterations, and reported a mode 255 in log density
    below the truth: E0 17 sd from the truth, the grid unsettled, the predictive check failed.
    The box now starts at the mode climbed on the profile max_z log p: the grid settles
    with the truth within 3 sd."""
    trace, truth = power_law_1058
    from palpbayes.rheology import posterior

    searches = []

    def counted(*args, **kwargs):
        searches.append(posterior_box_search(*args, **kwargs))
        return searches[-1]

    posterior_box_search = posterior.box_search
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(posterior, "box_search", counted)
        fit = fit_rheology(trace, "power-law", rng=0)
    assert [box.converged for box in searches] == [True]  # from the climb, no fallback
    assert fit.grid.converged and fit.ppc.passed
    for name in ("E0", "alpha", "z_surf"):
        d = fit.draws[name]
        assert abs(np.median(d) - truth[name]) < 3 * np.std(d), name
    assert np.std(fit.draws["alpha"]) < 0.002  # the ridge's width, not the coarse spacing


class _TiltedGaussian:
    """A NodeEvaluator stand-in: log p(theta, z) of a Gaussian in theta (sd ``st``) and, on
    each theta, in z (sd ``sz``) around the curve z0 + slope·(theta − t0) + bend·(theta −
    t0)²: the profile max_z log p is theta's Gaussian, its maximum z on the curve."""

    def __init__(self, t0, z0, st, sz, slope, bend=0.0):
        self.t0, self.z0, self.st, self.sz, self.slope = t0, z0, st, sz, slope
        self.bend = bend

    def ridge(self, th):
        return self.z0 + self.slope * (th - self.t0) + self.bend * (th - self.t0) ** 2

    def _lp(self, th, z):
        return -0.5 * (((th - self.t0) / self.st) ** 2 + ((z - self.ridge(th)) / self.sz) ** 2)

    def logp(self, thetas, z):
        return self._lp(np.asarray(thetas)[:, None], np.asarray(z)[None, :]), None

    def logp_rows(self, thetas, z):
        return self._lp(np.asarray(thetas)[:, None], np.asarray(z)), None


def test_climb_finds_the_mode_sd_and_slope_of_a_tilted_ridge():
    """On a Gaussian ridge far narrower than the starting nodes (theta sd 4e-4 against a
    0.06 step, z's conditional sd 1 µm against 31 µm, slope −2.8 mm per unit theta), the climb
    returns the mode, theta's marginal sd, z's conditional sd and the slope (closed forms), and
    the box search from there settles on the same moments."""
    from palpbayes.rheology.grid_search import box_search, climb, log_cells, moments

    ev = _TiltedGaussian(0.2119, 969.9e-6, 4e-4, 1e-6, -2.8e-3)
    bounds = ((0.0, 0.95), (-2e-3, 1.0097e-3))
    (ct, zt), (st, sz), slope = climb(ev, lambda c: c, bounds, (0.2375, 899e-6),
                                      (0.059, 31e-6))
    assert ct == pytest.approx(0.2119, abs=4e-5)
    assert zt == pytest.approx(ev.z0 + ev.slope * (ct - ev.t0), abs=0.2e-6)
    assert st == pytest.approx(4e-4, rel=0.05)
    assert sz == pytest.approx(1e-6, rel=0.2)
    assert slope == pytest.approx(-2.8e-3, rel=0.02)
    box = box_search(ev, lambda c: c, bounds, (ct, zt), (st, sz), slope, 20)
    assert box.converged
    mt, s_t, b, mz, s_z = moments(box.gt, box.gz, box.lp + log_cells(box.gt, box.gz))
    assert (mt, s_t, b, s_z) == pytest.approx((0.2119, 4e-4, -2.8e-3, 1e-6), rel=0.02)


@pytest.mark.parametrize("bend, z0, st_rel", [
    (0.4, 969.9e-6, 0.05),  # the ridge bends 2.3 µm away from its tangent at ±6 theta sd
    (40.0, 969.9e-6, 0.05),  # 0.23 mm: the tangent's 6.7 µm is small beside it
    # the mode half a conditional sd below the surface's bound: a row one sd of theta away
    # has its ridge beyond the bound, so the profile is lower on that side (not a Gaussian)
    (0.0, 1.0097e-3 - 0.5e-6, 0.25),
])
def test_climb_on_a_curved_ridge_and_near_the_surface_bound(bend, z0, st_rel):
    """The climb's mode lies on the ridge within 0.05 conditional sd (the vertex of each row's
    parabola, not its best node), theta within 0.05 sd, theta's sd within ``st_rel`` and the
    slope at the mode within 2 %, on bent ridges and with the mode next to the prior's
    bound (z in metres: ``bend`` [m per unit theta²])."""
    from palpbayes.rheology.grid_search import climb

    ev = _TiltedGaussian(0.2119, z0, 4e-4, 1e-6, -2.8e-3, bend)
    bounds = ((0.0, 0.95), (-2e-3, 1.0097e-3))
    (ct, zt), (st, sz), slope = climb(ev, lambda c: c, bounds, (0.2375, 899e-6),
                                      (0.059, 31e-6))
    assert abs(ct - ev.t0) < 0.05 * ev.st
    assert abs(zt - ev.ridge(ct)) < 0.05 * ev.sz
    assert st == pytest.approx(ev.st, rel=st_rel)
    assert sz == pytest.approx(ev.sz, rel=0.2)
    if z0 < 1e-3:
        assert slope == pytest.approx(-2.8e-3 + 2 * bend * (ct - ev.t0), rel=0.02)


def test_phi_at_its_bound_is_resolved_on_a_real_record(shared_data):
    """afmformats' real stress-relaxation curve (a cell, 12,000 samples in 767 blocks): the
    block means' noise correlation piles up at phi's bound 0.98 with a posterior sd of
    ~1e-4, 400 times finer than the first grid's phi nodes (0.041 apart).  With those nodes
    every grid draw had phi = 0.98 exactly (sd 3e-16), and emcee, started from them, hit its
    6,000-step cap (autocorrelation 45-95 steps).  Near the bound log p rises in phi at a
    rate lambda (its curvature changes it by ~1e-4 over 1/lambda), so the marginal is a density
    cut at the bound: mean 0.98 - 1/lambda, sd 1/lambda.  lambda here is read off the node
    posterior at the grid's mode directly, not from the grid's phi nodes."""
    from palpbayes.bayes.conjugate import node_posterior
    from palpbayes.contact import Tip
    from palpbayes.io.afm import read_afm
    from palpbayes.rheology.posterior import PHI_BOUNDS, NodeEvaluator

    path = shared_data("afm-files/fmt-jpk-sr_cell1-0008.jpk-force")
    trace = read_afm(path, tip=Tip("paraboloid", radius=5e-6), segments="all")[0]
    fit = fit_rheology(trace, "power-law", nu=0.5, rng=0)
    g = fit.grid
    it, iz, _ = np.unravel_index(np.argmax(g.log_mass), g.log_mass.shape)
    ev = NodeEvaluator(fit.data, "power-law", fit.t0, g.drag, g.tilt)
    top, dphi = PHI_BOUNDS[1], 2e-5
    lp = node_posterior(ev.gram(g.theta[[it]], g.z[it, [iz]]), np.array([top - dphi, top]),
                        ev.weights, ev.centers).logp[0]
    lam = (lp[1] - lp[0]) / dphi
    assert 3e3 < lam < 3e4  # the sd is ~1e-4
    phi = g.draws(np.random.default_rng(0), 20_000)["phi"]
    assert np.std(phi) == pytest.approx(1 / lam, rel=0.03)  # measured: 0.7 %
    assert top - np.mean(phi) == pytest.approx(1 / lam, rel=0.03)
    assert 7.5 / lam < np.ptp(g.phi) < 20 / lam  # the nodes span the density, not the prior
    assert any("phi piles up" in f for f in fit.flags)


def test_the_full_box_keeps_the_search_rows_and_adds_the_rows_between():
    """grid_search.refined: the settled 13-row search box at 25 rows evaluates only the 12 new
    rows, and gives the same log density and node posteriors (offset, moduli, their scale,
    S) as evaluating the 25-row box afresh."""
    from palpbayes.contact.viscoelastic import PowerLawKernel
    from palpbayes.paper import PAPER_TIPS
    from palpbayes.rheology.cycle import prepare_cycle
    from palpbayes.rheology.grid_search import FINE, SEARCH_THETA, refined, sheared
    from palpbayes.rheology.posterior import NodeEvaluator
    from palpbayes.sim import simulate_viscoelastic

    trace = simulate_viscoelastic(PowerLawKernel(80e3, 0.2), PAPER_TIPS["paraboloid"],
                                  depth=3e-3, speed=50 / 6e4, hold_time=1.0, rate=800.0,
                                  z_surf=2e-4, noise_sd=0.008, phi=0.3, rng=1)
    ev = NodeEvaluator(prepare_cycle(trace, segments="approach,hold", max_points=200),
                       "power-law", 1.0)
    box = ((0.2, 2e-4), (0.01, 2e-6), -1e-4)
    bounds = ((0.0, 0.95), (ev.data.z_lo, ev.data.z_hi))
    gt, gz = sheared(*box, bounds, SEARCH_THETA)
    search = (gt, gz, *ev.logp_rows(gt, gz))
    n0 = ev.n
    ct, z, lp, post = refined(ev, lambda c: c, box, bounds, search)
    assert ev.n - n0 == (FINE - SEARCH_THETA) * FINE  # only the new rows were evaluated
    ct_f, z_f = sheared(*box, bounds, FINE)
    lp_f, post_f = ev.logp_rows(ct_f, z_f)
    np.testing.assert_allclose(ct, ct_f, rtol=1e-14)
    np.testing.assert_allclose(z, z_f, rtol=1e-12)
    np.testing.assert_allclose(lp, lp_f, rtol=1e-9)
    for name in ("logp", "beta", "scale", "S"):
        np.testing.assert_allclose(getattr(post, name), getattr(post_f, name), rtol=1e-7,
                                   atol=1e-300)


def test_a_search_that_settles_on_its_last_iteration_gets_its_full_box():
    """The settled 13-row search box is refined to 25 rows in one more pass, even when it
    settled on the last allowed iteration (it used to return the 13-row box, unconverged,
    after evaluating the 12 rows between)."""
    from palpbayes.bayes.conjugate import NodePosterior
    from palpbayes.rheology.grid_search import FINE, box_search

    class Gaussian:
        rows = 0

        def logp_rows(self, th, z):
            self.rows += th.size
            lp = (-0.5 * ((th[:, None] - 0.3) / 0.02) ** 2
                  - 0.5 * ((z - 1e-4 - 0.01 * (th[:, None] - 0.3)) / 1e-6) ** 2)
            G = z.size
            return lp, NodePosterior(lp.reshape(G, 1), np.zeros((G, 1, 2)),
                                     np.zeros((G, 1, 2, 2)), np.ones((G, 1)), 5)

    ev = Gaussian()
    box = box_search(ev, lambda c: c, ((0.0, 0.95), (-1e-3, 1e-3)), (0.3, 1e-4),
                     (0.02, 1e-6), 0.01, 1)
    assert box.converged and box.gt.size == FINE and ev.rows == FINE


def test_phi_density_at_the_node_it_last_scanned_is_not_scanned_again():
    """The final box's mode is often the climbed one, where phi's density was scanned: the
    evaluator keeps the last node's answer (one gram less), and a new node is scanned."""
    from palpbayes.contact.viscoelastic import PowerLawKernel
    from palpbayes.paper import PAPER_TIPS
    from palpbayes.rheology.cycle import prepare_cycle
    from palpbayes.rheology.posterior import NodeEvaluator
    from palpbayes.sim import simulate_viscoelastic

    trace = simulate_viscoelastic(PowerLawKernel(80e3, 0.2), PAPER_TIPS["paraboloid"],
                                  depth=3e-3, speed=50 / 6e4, hold_time=1.0, rate=800.0,
                                  z_surf=2e-4, noise_sd=0.008, phi=0.3, rng=1)
    data = prepare_cycle(trace, segments="approach,hold", max_points=200)
    ev, fresh = NodeEvaluator(data, "power-law", 1.0), NodeEvaluator(data, "power-law", 1.0)
    grams = []
    gram = ev.gram
    ev.gram = lambda *a: grams.append(a) or gram(*a)
    first = ev.phi_density(0.2, 2e-4)
    assert ev.phi_density(0.2, 2e-4) is first and len(grams) == 1
    other = ev.phi_density(0.21, 2e-4)
    assert len(grams) == 2
    for got, want in ((first, fresh.phi_density(0.2, 2e-4)),
                      (other, fresh.phi_density(0.21, 2e-4))):
        np.testing.assert_array_equal(got[0], want[0])
        assert got[1:] == want[1:]
