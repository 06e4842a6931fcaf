"""The compiled core (palpbayes._kernels through palpbayes.shapekernel) against the numpy
expressions it replaced, the contact laws it tabulates, and the samplers made cheaper with it."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from palpbayes.bayes import likelihood as lk
from palpbayes.bayes.exact import exact_posterior, truncated_standard_normal
from palpbayes.bayes.layers import log_evidence
from palpbayes.bayes.priors import PriorSpec
from palpbayes.checks.ppc import posterior_predictive_check
from palpbayes.checks.residuals import binned_residuals
from palpbayes.contact import Tip, touching
from palpbayes.fitdata import ModelSpec, prepare_trace
from palpbayes.shapekernel import compiled_shape, cross_sums, scale_rss
from palpbayes.sim import simulate_trace

HALF_SPACE = {
    "flat": ModelSpec(Tip("flat", radius=5e-3), nu=0.3),
    "paraboloid": ModelSpec(Tip("paraboloid", radius=1e-5), nu=0.5),
    "cone": ModelSpec(Tip("cone", half_angle=0.6), nu=0.4),
}
TABLED = {  # no power law: tabulated; (model, deepest depth [m], bound on |error|/s(d_top))
    "sphere": (ModelSpec(Tip("sphere", radius=1e-5), nu=0.5), 8e-6, 1e-14),
    "paraboloid layer": (ModelSpec(Tip("paraboloid", radius=1e-5), nu=0.5).variant(
        thickness=2.5e-5, base="bonded"), 8e-6, 5e-8),
    "sphere layer": (ModelSpec(Tip("sphere", radius=1e-2), nu=0.3).variant(
        thickness=2.5e-2, base="free"), 3e-3, 5e-8),
    "flat layer": (ModelSpec(Tip("flat", radius=1e-3), nu=0.3).variant(
        thickness=2.5e-2, base="bonded"), 3e-3, 1e-13),
}


@pytest.mark.parametrize("name", list(HALF_SPACE))
def test_power_laws_are_evaluated_exactly(name):
    model = HALF_SPACE[name]
    law = compiled_shape(model, 1e-3)
    assert law.kind == 0
    d = np.random.default_rng(0).random(1000) * 1e-3
    np.testing.assert_allclose(law(d), model.shape(d), rtol=1e-13)
    assert law(np.array([-1e-4, 0.0])).tolist() == [0.0, 0.0]


@pytest.mark.parametrize("name", list(TABLED))
def test_tables_interpolate_the_law_within_their_stated_error(name):
    model, d_max, bound = TABLED[name]
    law = compiled_shape(model, d_max)
    assert law.kind == 1 and d_max <= law.d_top < 1.2 * d_max
    rng = np.random.default_rng(1)
    d = np.r_[rng.random(20000) * law.d_top, rng.random(200) * law.d_top * 1e-4, 0.0]
    err = np.abs(law(d) - model.shape(d)) / model.shape(np.array([law.d_top]))[0]
    assert err.max() < bound
    with pytest.raises(ValueError, match="beyond the shape table"):
        law(np.array([1.01 * law.d_top]))


def _numpy_sums(nodes, z, C, model):
    s = touching(model.shape, nodes[:, None] - z[None, :])
    return (np.einsum("ij,ij->i", s, s), s @ C, np.einsum("ij,ij->i", s[:, 1:], s[:, :-1]),
            s[:, 1:] @ C[:-1], s[:, :-1] @ C[1:], s[:, 0], s[:, -1],
            np.count_nonzero(s > 0, axis=1))


@pytest.mark.parametrize("name", ["paraboloid", "sphere", "paraboloid layer"])
@pytest.mark.parametrize("lag", [False, True])
def test_cross_sums_equal_the_numpy_sums(name, lag):
    model = HALF_SPACE[name] if name in HALF_SPACE else TABLED[name][0]
    rng = np.random.default_rng(2)
    # an approach that turns back (non-monotone z), nodes above, inside and below the samples
    t = np.linspace(0, 1, 3000)
    z = 6e-6 * np.abs(1.2 * t - 0.7) + 2e-8 * rng.standard_normal(t.size)
    C = np.column_stack([np.ones(t.size), z - z.max(), rng.standard_normal(t.size)])
    nodes = np.linspace(-1e-6, 8e-6, 57)
    got = cross_sums(nodes, z, C, model, lag)
    want = _numpy_sums(nodes, z, C, model)
    rtol = 1e-12 if name in HALF_SPACE else 1e-6
    names = ("ss", "sc", "l00", "l0c", "lc0", "s_first", "s_last")
    for key, g, w in zip(names, got, want, strict=False):
        if key in ("l00", "l0c", "lc0") and not lag:
            assert not np.any(g)
            continue
        np.testing.assert_allclose(g, w, rtol=rtol, atol=1e-12 * np.abs(w).max(), err_msg=key)
    np.testing.assert_array_equal(got[7], want[7])


def test_scale_rss_is_the_profile_least_squares():
    model = TABLED["sphere"][0]
    rng = np.random.default_rng(3)
    z = np.linspace(6e-6, -4e-6, 2000)
    f = 2e3 * model.shape(-z) + 1e-9 * rng.standard_normal(z.size)
    nodes = np.linspace(-2e-6, 2e-6, 41)
    rss, estar = scale_rss(nodes, z, f, model)
    s = touching(model.shape, nodes[:, None] - z[None, :])
    e = (s @ f) / np.einsum("ij,ij->i", s, s)
    np.testing.assert_allclose(estar, e, rtol=1e-10)
    np.testing.assert_allclose(rss, ((f[None, :] - e[:, None] * s) ** 2).sum(1), rtol=1e-8)
    # no sample in contact: sum of squares and 0
    rss, estar = scale_rss(np.array([-1e-5]), z, f, model)
    assert estar[0] == 0 and rss[0] == pytest.approx(f @ f)


@pytest.mark.parametrize("noise", ["gaussian", "ar1"])
@pytest.mark.parametrize("baseline", ["constant", "linear"])
def test_likelihood_statistics_equal_the_quadratic_forms(noise, baseline):
    tr = simulate_trace(60e3, Tip("sphere", radius=5e-3), thickness=0.03, noise_pp=0.048, rng=1)
    data = prepare_trace(tr, ModelSpec(Tip("sphere", radius=5e-3), nu=0.3))
    like = lk.TraceLikelihood(data, noise, tabulate=False, baseline=baseline)
    zs = np.linspace(*data.z_prior, 40)
    s = data.model.shape(zs[:, None] - data.z[None, :])
    want = lk._quad_forms(s, like._F, like._u, like._ar1)
    got = like._direct_stats(zs)
    assert got.shape == want.shape
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-14 * np.abs(want).max())


def test_exact_posterior_from_given_nodes_meets_the_same_tolerances():
    """The layer mixture starts each thickness from its neighbour's nodes: the posterior is
    the one refined from the coarse grid (evidence, E* and surface), to quadrature accuracy."""
    tip = Tip("paraboloid", radius=5e-3)
    tr = simulate_trace(60e3, tip, thickness=0.03, noise_pp=0.048, rng=4)
    model = ModelSpec(tip, nu=0.3).variant(thickness=0.03, base="bonded")
    data = prepare_trace(tr, model)
    prior = PriorSpec().for_trace(data, "gaussian", "constant")
    plain = exact_posterior(data, prior)
    near = exact_posterior(prepare_trace(tr, model.variant(thickness=0.027, base="bonded")),
                           prior)
    started = exact_posterior(data, prior, nodes=near.z)
    assert log_evidence(started) == pytest.approx(log_evidence(plain), abs=0.02)
    a, b = plain.estar_summary(), started.estar_summary()
    # the refinement's tolerance (0.5 in log density between nodes) leaves ~1 % of the
    # interval's width to the grid's alignment (a uniform start of 100 nodes instead of 129:
    # -0.4 %); here the width is 0.3 % of E*, so its ends move by ~1e-5 of E*
    for x, y in ((b.median, a.median), (b.lo, a.lo), (b.hi, a.hi)):
        assert x == pytest.approx(y, rel=1e-4)
    assert (b.hi - b.lo) == pytest.approx(a.hi - a.lo, rel=0.02)
    assert started.z_summary().median == pytest.approx(plain.z_summary().median, abs=1e-7)


@pytest.mark.parametrize("a, b", [(-2.0, 1.0), (3.0, 5.0), (-40.0, -35.0), (8.0, np.inf),
                                  (-np.inf, -9.0), (0.5, 0.5001)])
def test_truncated_normal_draws_follow_scipys_truncnorm(a, b):
    rng = np.random.default_rng(5)
    x = truncated_standard_normal(rng, np.full(50000, a), np.full(50000, b))
    assert np.all((x >= a) & (x <= b))
    assert stats.kstest(x, stats.truncnorm(a, b).cdf).pvalue > 1e-3


def test_iid_ppc_replicates_are_the_simulated_chi_square():
    """For iid noise the replicated binned chi² is drawn as chi²(bins): its distribution is
    that of the binned chi² of simulated noise (two-sample KS, fixed seeds)."""
    rng = np.random.default_rng(6)
    z = np.linspace(1e-3, -2e-3, 3000)
    sig = 0.01
    mu = np.zeros((400, z.size))
    res = posterior_predictive_check(z, sig * rng.standard_normal(z.size), mu,
                                     np.full(400, sig), rng=11, z_surf=0.0, max_draws=400)
    e = sig * np.random.default_rng(8).standard_normal((4000, z.size))
    sim = binned_residuals(z, e, 0.0, np.full(4000, sig))["chi2"]
    dof = res.details["dof"]
    assert dof == binned_residuals(z, e[0], 0.0, sig)["dof"] == 15
    assert stats.kstest(sim, stats.chi2(dof).cdf).pvalue > 1e-3  # simulated: chi²(bins)
    rep = np.random.default_rng(11).chisquare(dof, 400)  # what the check drew
    assert stats.ks_2samp(rep, sim).pvalue > 1e-3
    assert 0.05 < res.statistic < 0.999  # a correct model passes


def test_the_kernels_refuse_columns_of_another_length_and_non_finite_depths():
    from palpbayes.errors import InputError

    model = TABLED["sphere"][0]
    z = np.linspace(1e-5, 0.0, 5)
    with pytest.raises(InputError, match="C has 2 rows for 5 heights"):
        cross_sums(np.array([5e-6]), z, np.ones((2, 2)), model, False)
    with pytest.raises(InputError, match="force has 4 rows for 5 heights"):
        scale_rss(np.array([5e-6]), z, np.ones(4), model)
    with pytest.raises(InputError, match="not finite"):
        cross_sums(np.array([np.nan]), z, np.ones((5, 2)), model, False)
    # a depth just past a power of the table's bucket is covered (rounding of the logarithm)
    d = 2.0 ** -20 * (1 + 5e-11)
    assert compiled_shape(model, d).d_top >= d
