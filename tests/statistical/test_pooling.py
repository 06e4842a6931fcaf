"""Hierarchical pooling: marginal likelihood, recovery of mu and tau, coverage, shared budget."""

from __future__ import annotations

import numpy as np
import pytest
from presets import FAST
from scipy import integrate, stats

from palpbayes.bayes import BudgetSpec, SamplerSettings
from palpbayes.errors import FitError, InputError
from palpbayes.fitdata import ModelSpec, prepare
from palpbayes.paper import PAPER_TIPS
from palpbayes.pooling import (
    hierarchical_log_posterior,
    log_normal_summary,
    pool_group,
    sample_hierarchical,
    systematic_factor,
)
from palpbayes.sim import simulate_trace

MU0 = float(np.log(1.2e5))


def _group(rng, n, mu=MU0, tau=0.1):
    s = rng.uniform(0.002, 0.03, n)
    m = rng.normal(rng.normal(mu, tau, n), s)
    return m, s


def test_marginal_likelihood_equals_integral_over_trace_moduli():
    """Π N(m_i | mu, tau² + s_i²) is the integral of Π N(m_i | θ_i, s_i) N(θ_i | mu, tau)."""
    m, s = np.array([11.6, 11.75, 11.5]), np.array([0.02, 0.05, 0.01])
    mu, tau = 11.62, 0.08
    direct = 0.0
    for mi, si in zip(m, s, strict=True):
        val, _ = integrate.quad(lambda th, mi=mi, si=si: stats.norm.pdf(mi, th, si)
                                * stats.norm.pdf(th, mu, tau), mu - 2, mu + 2, points=[mi])
        direct += np.log(val)
    prior = -0.5 * (tau / 0.5) ** 2 + np.log(tau)  # half-normal (unnormalised) + Jacobian
    lp = hierarchical_log_posterior(np.array([mu, np.log(tau)]), m, s, 0.5)[0]
    assert lp == pytest.approx(direct + prior, abs=1e-8)
    assert hierarchical_log_posterior(np.array([[mu, np.log(100.0)]]), m, s)[0] == -np.inf


def test_log_normal_summary_and_validation():
    x = np.exp(np.random.default_rng(0).normal(11.0, 0.02, 5000))
    m, s = log_normal_summary(x)
    assert m == pytest.approx(11.0, abs=1e-3) and s == pytest.approx(0.02, rel=0.05)
    with pytest.raises(FitError):
        log_normal_summary([1.0, -2.0])
    with pytest.raises(InputError):
        sample_hierarchical([1.0, 2.0], [0.1], settings=FAST)
    with pytest.raises(InputError):
        sample_hierarchical([1.0, np.nan], [0.1, 0.1], settings=FAST)


def test_same_seed_same_draws():
    m, s = _group(np.random.default_rng(1), 4)
    a = sample_hierarchical(m, s, seed=7, settings=FAST)
    b = sample_hierarchical(m, s, seed=7, settings=FAST)
    np.testing.assert_array_equal(a.mu, b.mu)
    np.testing.assert_array_equal(a.tau, b.tau)


def test_recovers_mu_and_tau_of_a_large_group():
    rng = np.random.default_rng(2)
    mu, tau = np.log(1.5e5), 0.12
    m, s = _group(rng, 300, mu, tau)
    post = sample_hierarchical(m, s, seed=3)
    assert post.converged
    # posterior sds: tau/sqrt(n) ~ 0.007 for mu, tau/sqrt(2n) ~ 0.005 for tau
    assert abs(np.median(post.mu) - mu) < 3 * np.std(post.mu)
    assert abs(np.median(post.tau) - tau) < 3 * np.std(post.tau)
    assert np.std(post.mu) == pytest.approx(tau / np.sqrt(300), rel=0.2)


def _coverage(n_groups, n, settings, seed):
    rng = np.random.default_rng(seed)
    mu, tau = np.log(1.2e5), 0.1
    hit_mu = hit_tau = 0
    for k in range(n_groups):
        m, s = _group(rng, n, mu, tau)
        post = sample_hierarchical(m, s, seed=k, settings=settings)
        lo, hi = np.quantile(post.mu, [0.05, 0.95])
        hit_mu += lo <= mu <= hi
        lo, hi = np.quantile(post.tau, [0.05, 0.95])
        hit_tau += lo <= tau <= hi
    return hit_mu / n_groups, hit_tau / n_groups


@pytest.mark.slow
def test_interval_coverage_over_simulated_groups_fast():
    """20 groups of 6 traces (tau = 0.1): 90 % intervals of mu and tau cover ~90 %.

    Binomial sd at 20 groups is 6.7 %; the lower bounds are ~3 sd (the slow test is tighter).
    """
    short = SamplerSettings(n_walkers=32, max_steps=600, min_steps=400, check_every=200,
                            progress=False)
    cov_mu, cov_tau = _coverage(20, 6, short, seed=10)
    assert 0.7 <= cov_mu <= 1.0
    assert 0.7 <= cov_tau <= 1.0


@pytest.mark.slow
@pytest.mark.long
def test_interval_coverage_over_simulated_groups():
    """200 groups of 5 traces with the default sampler: coverage 90 % ± 4 % (2 sd)."""
    cov_mu, cov_tau = _coverage(200, 5, None, seed=11)
    assert 0.86 <= cov_mu <= 0.96
    assert 0.84 <= cov_tau <= 0.97


@pytest.fixture(scope="module")
def sphere_data():
    tip = PAPER_TIPS["sphere"]
    trace = simulate_trace(1.1e5, tip, nu=0.3, z_surf=0.1, thickness=0.03, rng=4)
    return prepare(trace, ModelSpec(tip, nu=0.3))


def test_systematic_factor_matches_budget_inputs(sphere_data):
    spec = BudgetSpec()
    f, tab, _ = systematic_factor(sphere_data, 0.1, 1.2e5, spec, 20000, np.random.default_rng(0))
    assert list(tab["input"]) == ["Poisson ratio", "tip radius", "force gain", "compliance"]
    # Poisson ratio Uniform(0.25, 0.35): sd of log(1 - nu²) relative to nu = 0.3
    nu = np.random.default_rng(1).uniform(0.25, 0.35, 200000)
    sd_nu = np.std(np.log1p(-nu**2))
    assert np.sqrt(tab["var_log"].iloc[0]) == pytest.approx(sd_nu, rel=0.03)
    assert np.var(np.log(f)) == pytest.approx(tab["var_log"].sum(), rel=0.05)
    assert np.median(f) == pytest.approx(1.0, abs=0.01)


def test_budget_is_applied_once_to_the_pooled_draws(sphere_data):
    m, s = _group(np.random.default_rng(5), 8)
    bare = pool_group(m, s, seed=1, settings=FAST)
    full = pool_group(m, s, seed=1, settings=FAST, data=sphere_data, z_surf=0.1, estar=1.2e5,
                      budget=BudgetSpec())
    np.testing.assert_array_equal(bare.posterior.mu, full.posterior.mu)  # same stage 2
    np.testing.assert_allclose(full.E, np.exp(full.posterior.mu) * full.factor)
    assert np.all(bare.factor == 1.0)
    var_sys = np.var(np.log(full.factor))
    # log variances add: the budget widens the pooled E by its own variance, not by var/n
    assert np.var(np.log(full.E)) == pytest.approx(np.var(full.posterior.mu) + var_sys,
                                                   rel=0.1)
    assert full.budget["share_pct"].sum() == pytest.approx(100.0)
    assert full.budget["input"].iloc[0] == "mu (pooled posterior)"
    row = full.row()
    assert row["E_lo_pa"] < row["E_pa"] < row["E_hi_pa"]
    assert row["E_new_lo_pa"] < row["E_lo_pa"] and row["E_new_hi_pa"] > row["E_hi_pa"]
    assert row["n_traces"] == 8
    with pytest.raises(InputError):
        pool_group(m, s, settings=FAST, data=sphere_data, budget=BudgetSpec())
