"""The stiffness-map GMRF: exact algebra against dense computations, the theta grid, the API."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats
from scipy.sparse.linalg import splu
from scipy.special import k1

from palpbayes.errors import InputError
from palpbayes.flagcodes import flag_level, scoped
from palpbayes.maps import (
    HYPER_NAMES,
    FieldPrior,
    Lattice,
    SpdeModel,
    explore,
    fit_field,
    pad,
    sample_field,
    spde_scales,
    weighted_summary,
)

H = 0.005  # 5 mm


def _small_model(tau_obs_nodes=True):
    """6 × 5 data lattice padded by 2: some empty nodes, one node seen twice."""
    lat = Lattice(0.0, 0.0, H, 6, 5)
    p, index = pad(lat, 2)
    rng = np.random.default_rng(3)
    nodes = np.r_[rng.choice(lat.n_nodes, 20, replace=False), 7]
    nodes[0] = 7  # node 7 observed twice
    y = 11.0 + rng.normal(0, 0.3, nodes.size)
    s = rng.uniform(0.001, 0.02, nodes.size)
    return SpdeModel(p, index[nodes], y, s, m0=float(np.median(y)), v0=2.5**2)


def test_closed_form_log_det_matches_sparse_lu():
    m = _small_model()
    for sig, rng_m in [(0.3, 4 * H), (0.05, 20 * H), (1.0, 1.5 * H)]:
        lu = splu(m.precision(sig, rng_m), permc_spec="MMD_AT_PLUS_A",
                  diag_pivot_thresh=0.0, options={"SymmetricMode": True})
        direct = np.sum(np.log(np.abs(lu.U.diagonal())))
        assert m.log_det_q(sig, rng_m) == pytest.approx(direct, rel=1e-10, abs=1e-8)


@pytest.mark.parametrize("theta", [(0.3, 4 * H, 0.05), (0.1, 12 * H, 0.002), (0.8, 2 * H, 0.2)])
def test_marginal_likelihood_matches_dense_mvn(theta):
    m = _small_model()
    f = m.factor(*theta)
    ll, mean = m.log_marginal(f)
    A = m.A.toarray()
    cov_x = np.zeros((m.n_latent, m.n_latent))
    cov_x[:-1, :-1] = np.linalg.inv(m.precision(theta[0], theta[1]).toarray())
    cov_x[-1, -1] = m.v0
    x0 = np.r_[np.zeros(m.n_nodes), m.m0]
    S = np.diag(m.s**2 + theta[2] ** 2)
    dense = stats.multivariate_normal(A @ x0, A @ cov_x @ A.T + S).logpdf(m.y)
    assert ll == pytest.approx(dense, abs=1e-8)
    # the conditional mean is the Gaussian regression x0 + C Aᵀ (A C Aᵀ + S)⁻¹ (y − A x0)
    gain = cov_x @ A.T @ np.linalg.inv(A @ cov_x @ A.T + S)
    np.testing.assert_allclose(mean, x0 + gain @ (m.y - A @ x0), atol=1e-8)


def test_sampler_covariance_is_the_inverse_posterior_precision():
    lat = Lattice(0.0, 0.0, H, 4, 3)
    m = SpdeModel(lat, [0, 5, 5, 11], [11.0, 11.2, 11.1, 10.9], [0.01, 0.02, 0.01, 0.05],
                  m0=11.0, v0=4.0)
    theta = (0.3, 3 * H, 0.05)
    f = m.factor(*theta)
    P = m.posterior_precision(*theta)[0].toarray()
    cov = np.linalg.inv(P)
    mean = m.log_marginal(f)[1]
    n = 40_000
    x = m.draw(f, np.random.default_rng(11), n)
    # whitened draws: z = Rᵀ(x − mean), P = R Rᵀ, must be iid standard normal
    R = np.linalg.cholesky(P)
    z = R.T @ (x - mean[:, None])
    C = z @ z.T / n
    tol = 5 / np.sqrt(n)  # entries of a sample covariance of N(0, I) have sd ~ 1/sqrt(n)
    assert np.max(np.abs(C - np.eye(m.n_latent))) < 2 * tol
    assert np.max(np.abs(z.mean(axis=1))) < tol
    np.testing.assert_allclose(np.cov(x), cov, atol=3 * tol * np.sqrt(np.outer(
        np.diag(cov), np.diag(cov))).max())


def test_factor_solves_and_log_det_match_the_whole_precision():
    """The field block's LU (fixed order) and beta's Schur complement give P's solves and
    log det."""
    m = _small_model()
    for theta in [(0.3, 4 * H, 0.05), (0.02, 30 * H, 0.001)]:
        f = m.factor(*theta)
        P = m.posterior_precision(*theta)[0].toarray()
        b = np.random.default_rng(4).normal(size=(m.n_latent, 3))
        np.testing.assert_allclose(f.solve(b), np.linalg.solve(P, b), rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(f.solve(b[:, 0]), np.linalg.solve(P, b[:, 0]), rtol=1e-9,
                                   atol=1e-12)
        assert f.log_det() == pytest.approx(np.linalg.slogdet(P)[1], rel=1e-10)


def test_spde_scaling_gives_sigma_and_range_on_an_interior_node():
    """Marginal variance ≈ sigma_f² and Matérn(nu = 1) correlation at the centre of 41 × 41."""
    n, r_steps, sig = 41, 8, 0.5
    lat = Lattice(0.0, 0.0, H, n, n)
    m = SpdeModel(lat, [0], [0.0], [1.0], 0.0, 1.0)
    C = np.linalg.inv(m.precision(sig, r_steps * H).toarray())
    c = lat.index(n // 2, n // 2)
    assert C[c, c] == pytest.approx(sig**2, rel=0.07)  # lattice error O((h/range)^~1)
    kappa = np.sqrt(8) / (r_steps * H)
    for d in (4, 8):
        corr = C[c, lat.index(n // 2 + d, n // 2)] / C[c, c]
        matern = kappa * d * H * k1(kappa * d * H)
        assert corr == pytest.approx(matern, abs=0.025)
    # the free boundary inflates the variance (≈ 2× on an edge): why fit_field pads
    assert C[lat.index(n // 2, 0), lat.index(n // 2, 0)] > 1.8 * sig**2
    kh2, c2 = spde_scales(sig, r_steps * H, H)
    assert kh2 == pytest.approx(8 / r_steps**2) and c2 == pytest.approx(
        1 / (4 * np.pi * kh2 * sig**2))


def test_sample_field_has_the_prior_covariance():
    lat = Lattice(0.0, 0.0, H, 5, 4)
    u = sample_field(lat, 0.4, 3 * H, np.random.default_rng(5), 20_000).reshape(20_000, -1)
    m = SpdeModel(lat, [0], [0.0], [1.0], 0.0, 1.0)
    C = np.linalg.inv(m.precision(0.4, 3 * H).toarray())
    np.testing.assert_allclose(np.cov(u.T), C, atol=5 * C.max() / np.sqrt(20_000) * 2)


# -- the theta grid on known densities ------------------------------------------------------
BOX = np.array([[-10.0, 10.0]] * 3)


def test_explore_recovers_a_gaussian_without_flags():
    mu = np.array([-1.0, 0.5, -3.0])
    Sig = np.array([[0.04, 0.03, 0.0], [0.03, 0.09, -0.01], [0.0, -0.01, 0.25]])
    Qi = np.linalg.inv(Sig)

    def lp(t):
        return -0.5 * (t - mu) @ Qi @ (t - mu)

    grid, flags = explore(lp, np.zeros(3), BOX, grid_points=7, workers=2)
    assert flags == []
    assert grid["weight"].sum() == pytest.approx(1.0)
    T = grid[[f"t_{n}" for n in HYPER_NAMES]]
    summ = weighted_summary(T, grid["weight"].to_numpy()).set_index("parameter")
    np.testing.assert_allclose(summ["mean"], mu, atol=0.01)
    np.testing.assert_allclose(summ["sd"], np.sqrt(np.diag(Sig)), rtol=0.05)
    np.testing.assert_allclose(summ["q95"] - summ["mean"], 1.645 * np.sqrt(np.diag(Sig)),
                               rtol=0.1)
    assert len(grid) < 7**3


def test_explore_flags_a_posterior_piling_up_at_a_bound():
    def lp(t):  # increasing in t[2] up to the search box
        return -0.5 * (t[0] ** 2 + t[1] ** 2) + 3.0 * t[2]

    grid, flags = explore(lp, np.zeros(3), np.array([[-5, 5], [-5, 5], [-5, 1.0]]))
    assert any("search box for tau" in f for f in flags)
    assert any("upper end of the search interval of tau" in f for f in flags)
    grid, flags = explore(lambda t: -0.5 * (t[0] ** 2 + t[1] ** 2)
                          - 0.5 * np.log1p((t[2] / 0.01) ** 2), np.zeros(3), BOX)  # Cauchy tail
    assert any("edge of its integration grid" in f and "tau" in f for f in flags)
    with pytest.raises(InputError, match="odd"):
        explore(lp, np.zeros(3), BOX, grid_points=6)


# -- the fit's interface ------------------------------------------------------------------
@pytest.fixture(scope="module")
def small_fit():
    lat = Lattice(0.01, 0.02, H, 12, 10)
    rng = np.random.default_rng(8)
    p, index = pad(lat, 4)
    u = sample_field(p, 0.3, 4 * H, rng)[0].ravel()[index]
    y = 11.5 + u + rng.normal(0, np.hypot(0.01, 0.05), lat.n_nodes)
    keep = rng.random(lat.n_nodes) > 0.2
    keep[[0, lat.n_nodes - 1]] = True
    fp = fit_field(lat.node_x[keep], lat.node_y[keep], y[keep], np.full(keep.sum(), 0.01),
                   grid_points=5)
    return fp, lat, keep


def test_fit_field_outputs(small_fit):
    fp, lat, keep = small_fit
    got = fp.lattice
    assert (got.nx, got.ny) == (lat.nx, lat.ny)
    assert (got.x0, got.y0, got.step) == pytest.approx((lat.x0, lat.y0, lat.step), rel=1e-9)
    assert fp.n_obs.shape == (10, 12) and fp.n_obs.sum() == keep.sum()
    assert list(fp.hyper.columns) == ["sigma_f", "range_m", "tau", "log_post", "weight"]
    assert fp.hyper["weight"].sum() == pytest.approx(1.0)
    summ = fp.hyper_summary()
    assert list(summ["parameter"]) == list(HYPER_NAMES)
    assert np.all(summ["q05"] < summ["mean"]) and np.all(summ["mean"] < summ["q95"])
    d = fp.draws(np.random.default_rng(1), 60)
    assert d["field"].shape == (60, 10, 12)
    for k in ("beta", *HYPER_NAMES):
        assert d[k].shape == (60,)
    assert set(zip(d["sigma_f"], d["tau"], strict=True)) <= set(
        zip(fp.hyper["sigma_f"], fp.hyper["tau"], strict=True))
    d2 = fp.draws(np.random.default_rng(1), 60)
    np.testing.assert_array_equal(d["field"], d2["field"])  # a seed fixes the draws
    sd = fp.marginal_sd(200)
    assert sd.shape == (10, 12) and np.all(sd > 0)
    # nodes without data are more uncertain than observed ones
    assert np.median(sd[~keep.reshape(10, 12)]) > np.median(sd[keep.reshape(10, 12)])
    big = fp.draws(np.random.default_rng(2), 400)["field"]
    assert np.max(np.abs(big.mean(axis=0) - fp.mean()) / sd) < 0.5


def test_fit_field_input_errors(small_fit):
    fp, lat, keep = small_fit
    x, y = lat.node_x, lat.node_y
    m, s = np.full(x.size, 11.0), np.full(x.size, 0.01)
    with pytest.raises(InputError, match=r"sd\[3\]"):
        fit_field(x, y, m, np.r_[s[:3], 0.0, s[4:]])
    with pytest.raises(InputError, match=r"mean\[0\]"):
        fit_field(x, y, np.r_[np.nan, m[1:]], s)
    with pytest.raises(InputError, match="equal length"):
        fit_field(x, y, m[:-1], s)
    with pytest.raises(InputError, match="grid_points"):
        fit_field(x, y, m, s, grid_points=4)
    with pytest.raises(InputError, match="sigma_0"):
        fit_field(x, y, m, s, prior=FieldPrior(sigma_0=-1.0))
    with pytest.raises(InputError, match="draws"):
        fp.draws(np.random.default_rng(0), 0)


def test_default_prior_follows_lattice_and_data():
    y = np.r_[np.zeros(50), np.ones(50)]
    pr = FieldPrior().resolved(0.004, y)
    assert pr.range_0 == pytest.approx(0.008)
    spread = 1.4826 * 0.5
    assert pr.sigma_0 == pytest.approx(3 * spread) and pr.tau_0 == pytest.approx(2 * spread)
    flat = FieldPrior(range_0=0.01).resolved(0.004, np.zeros(10))
    assert (flat.range_0, flat.sigma_0, flat.tau_0) == (0.01, 0.05, 0.05)


def test_a_map_without_spatial_signal_is_flagged():
    """Pure nugget: sigma_f runs to the bottom of its search interval, range to the top."""
    lat = Lattice(0.0, 0.0, H, 12, 10)
    y = 11.0 + np.random.default_rng(0).normal(0.0, 0.02, lat.n_nodes)
    fp = fit_field(lat.node_x, lat.node_y, y, np.full(lat.n_nodes, 0.01), grid_points=5)
    flat = [f for f in fp.flags if "lower end of the search interval of sigma_f" in f]
    # a flat map is a finding, not a failure: said first in plain words, as information
    assert flat and flat[0].startswith("info: no spatial variation shows"), fp.flags
    assert flag_level(flat[0]) == "info"
    assert scoped("field", flat[0]).startswith("info: field: no spatial variation")
    assert scoped("lump", "radius at its upper bound") == "lump: radius at its upper bound"
    assert fp.hyper_summary().set_index("parameter").loc["sigma_f", "q95"] < 0.05
