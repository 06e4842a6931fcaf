"""Bayesian engine: recovery, an independent grid oracle, likelihood tabulation, persistence."""

import math

import numpy as np
import pytest

from palpbayes.bayes import BudgetSpec, SamplerSettings, TraceLikelihood, fit_bayes
from palpbayes.bayes.diagnostics import import_arviz
from palpbayes.contact import Tip
from palpbayes.errors import ConvergenceError, ConvergenceWarning
from palpbayes.fitdata import ModelSpec, prepare
from palpbayes.lsq import fit_lsq_data
from palpbayes.sim import simulate_trace

E_TRUE = 136e3
TIPS = {
    "flat": Tip("flat", radius=0.010),
    "sphere": Tip("sphere", radius=0.010),
    "paraboloid": Tip("paraboloid", radius=0.0117),
}


@pytest.mark.parametrize("kind", list(TIPS))
def test_recovery_at_paper_noise(kind):
    tr = simulate_trace(E_TRUE, TIPS[kind], depth=2e-3, rng=11)
    res = fit_bayes(tr, seed=5, budget=BudgetSpec.none())
    E = res.draws("E")
    lo, hi = np.quantile(E, [0.05, 0.95])
    assert lo <= E_TRUE <= hi
    assert np.median(E) == pytest.approx(E_TRUE, rel=0.01)
    z = res.draws("z_surf")
    assert abs(np.median(z) - tr.metadata["z_surf_true"]) < 4 * z.std() + 1e-7
    assert res.diagnostics.converged, res.diagnostics.problems()
    # the budget-free total equals the statistical E
    np.testing.assert_allclose(res.draws("E_total"), E)


@pytest.mark.parametrize("noise", ["gaussian", "ar1"])
def test_tabulated_likelihood_matches_direct_sum(noise):
    tr = simulate_trace(E_TRUE, TIPS["paraboloid"], depth=2e-3, noise_ar1=0.5, rng=2)
    data = prepare(tr, ModelSpec(tr.tip))
    lsq = fit_lsq_data(data)
    like = TraceLikelihood(data, noise, z_center=lsq.z_surf, z_scale=lsq.z_surf_sd)
    rng = np.random.default_rng(0)
    n = 200
    theta = np.column_stack([
        np.log(lsq.Estar) + 3 * lsq.Estar_sd / lsq.Estar * rng.standard_normal(n),
        lsq.z_surf + 5 * lsq.z_surf_sd * rng.standard_normal(n),
        np.log(lsq.rms) + 0.05 * rng.standard_normal(n),
        0.003 * rng.standard_normal(n),
    ] + ([rng.uniform(-0.9, 0.9, n)] if noise == "ar1" else []))
    theta[:, 1] = np.clip(theta[:, 1], *like.z_bounds)
    np.testing.assert_allclose(like(theta), like(theta, direct=True), rtol=0, atol=1e-3)
    # anywhere in the admissible range (mostly coarse grid, log L up to ~1e7 below its
    # maximum) the error is small relative to the distance from the maximum: such walkers are
    # rejected either way
    far = theta.copy()
    far[:, 1] = rng.uniform(*like.z_bounds, n)
    direct = like(far, direct=True)
    gap = like(theta).max() - direct
    assert np.all(np.abs(like(far) - direct) < 1e-3 + 1e-4 * gap)


def _grid_oracle(data, priors):
    """Brute-force posterior on a (log E*, z_s, F0) grid, sigma integrated on a 1-D grid.

    Written independently of the package's likelihood: residuals are summed directly.
    ``priors`` is the trace's prior (centres and scales read from its data).
    """
    lsq = fit_lsq_data(data)
    n_g = 31
    le = np.log(lsq.Estar) + np.linspace(-7, 7, n_g) * lsq.Estar_sd / lsq.Estar
    zs = lsq.z_surf + np.linspace(-7, 7, n_g) * lsq.z_surf_sd
    f0_sd = lsq.rms / np.sqrt(data.n_points) * 6
    f0 = np.linspace(-7, 7, n_g) * f0_sd
    ls = np.log(lsq.rms) + np.linspace(-0.15, 0.15, 121)
    logp = np.empty((n_g, n_g, n_g))
    sig = np.exp(ls)
    for j, z in enumerate(zs):
        s = data.model.shape(z - data.z)
        r = data.force[None, None, :] - np.exp(le)[:, None, None] * s - f0[None, :, None]
        rss = np.einsum("abn,abn->ab", r, r)
        # log p(rss | sigma) + log prior(sigma), summed over the sigma grid (log-sum-exp)
        ll = (-data.n_points * ls[None, None, :] - rss[..., None] / (2 * sig**2)
              - 0.5 * ((ls - np.log(priors.sigma_center)) / priors.spec.log_sigma_sd) ** 2)
        mx = ll.max(axis=-1, keepdims=True)
        logp[:, j, :] = (mx[..., 0] + np.log(np.exp(ll - mx).sum(axis=-1))
                         - 0.5 * ((f0[None, :] - priors.f0_center) / priors.f0_sd) ** 2)
    w = np.exp(logp - logp.max())
    w /= w.sum()
    E_grid = np.exp(le)[:, None, None]
    Z_grid = zs[None, :, None]
    out = {}
    for name, g in (("E_star", E_grid), ("z_surf", Z_grid)):
        mean = float((w * g).sum())
        out[name] = (mean, float(np.sqrt((w * (g - mean) ** 2).sum())))
    return out


def test_posterior_matches_grid_oracle():
    tr = simulate_trace(E_TRUE, TIPS["paraboloid"], depth=2e-3, rng=7)
    res = fit_bayes(tr, seed=3, budget=BudgetSpec.none())
    from palpbayes.bayes import PriorSpec

    oracle = _grid_oracle(res.data, PriorSpec().for_trace(res.data, "gaussian"))
    for name in ("E_star", "z_surf"):
        x = res.draws(name)
        ess = res.diagnostics.ess_bulk[name]
        mean, sd = oracle[name]
        assert abs(x.mean() - mean) < 4 * sd / np.sqrt(ess), name
        assert x.std() == pytest.approx(sd, rel=0.08), name


def test_summary_netcdf_and_predictive(tmp_path):
    tr = simulate_trace(E_TRUE, TIPS["sphere"], depth=2e-3, rng=1)
    res = fit_bayes(tr, seed=1)
    table = res.summary()
    assert {"E_total", "E", "E_star", "z_surf", "sigma", "F0"} <= set(table.index)
    assert table.loc["E", "q05"] < table.loc["E", "median"] < table.loc["E", "q95"]
    assert table.loc["sigma", "median"] == pytest.approx(8e-3, rel=0.1)  # 48 mN p-p / 6
    # the budget widens the interval: E_total is wider than E
    assert table.loc["E_total", "sd"] > 5 * table.loc["E", "sd"]
    shares = res.budget.table["share_pct"]
    assert shares.sum() == pytest.approx(100.0)
    path = res.to_netcdf(tmp_path / "post.nc")
    az = import_arviz()
    idata = az.from_netcdf(str(path))
    np.testing.assert_allclose(np.asarray(idata.posterior["E"]).ravel(), res.draws("E"))
    assert idata.attrs["tip"] == "sphere"
    band = res.predictive(n_draws=100)
    assert np.all(band["lo_n"] <= band["median_n"]) and np.all(band["median_n"] <= band["hi_n"])
    noisy = res.predictive(n_draws=300, noise=True)
    resid = res.data.force - noisy["median_n"]
    inside = (res.data.force >= noisy["lo_n"]) & (res.data.force <= noisy["hi_n"])
    assert 0.85 < inside.mean() < 0.95  # 90 % predictive band holds ~90 % of the data
    assert abs(resid.mean()) < 1e-3


def test_seed_reproducible_and_step_cap_is_flagged():
    tr = simulate_trace(E_TRUE, TIPS["paraboloid"], depth=2e-3, noise_ar1=0.6, rng=4)
    kw = dict(noise="ar1", seed=9, settings=SamplerSettings(min_steps=250, max_steps=400))
    with pytest.warns(ConvergenceWarning, match="step cap reached"):
        a = fit_bayes(tr, **kw)
    with pytest.warns(ConvergenceWarning):
        b = fit_bayes(tr, **kw)
    np.testing.assert_array_equal(a.draws("E_star"), b.draws("E_star"))
    row = a.summary_row()
    assert row["converged"] is False and "step cap" in row["notes"]
    with pytest.raises(ConvergenceError, match="not converged"):
        fit_bayes(tr, strict=True, **kw)
    # even the short chain locates the AR(1) coefficient
    assert abs(np.median(a.draws("phi")) - 0.6) < 0.05
    assert math.isfinite(a.diagnostics.rhat_max)


def test_bimodality_detector():
    from palpbayes.bayes.fit import is_bimodal

    rng = np.random.default_rng(0)
    one = rng.normal(0, 1e-6, 4000)
    two = np.concatenate([rng.normal(0, 1e-6, 3000), rng.normal(50e-6, 1e-6, 1000)])
    heavy = rng.standard_t(3, 4000) * 1e-6
    assert not is_bimodal(one)
    assert is_bimodal(two)
    assert not is_bimodal(heavy)  # heavy tails are not a second mode
    assert not is_bimodal(np.concatenate([one, [1.0]]))  # a lone outlier is not a mode


def test_log_posterior_rhat_catches_a_walker_off_a_thin_ridge():
    """A walker displaced across a long thin ridge (the flat punch's z_surf-F0 ridge) leaves every
    parameter's marginal unchanged, so parameter R-hat and ESS pass; the log posterior shows it."""
    from palpbayes.bayes.diagnostics import chain_passes

    rng = np.random.default_rng(1)
    along = rng.standard_normal((24, 600))
    across = 0.01 * rng.standard_normal((24, 600))

    def xy(c):
        return np.stack([(along + c) / np.sqrt(2), (along - c) / np.sqrt(2)], axis=-1)

    def lp(c):
        return -0.5 * (along**2 + (c / 0.01) ** 2)

    assert chain_passes(xy(across), lp(across))
    off = across.copy()
    off[3] += 5 * 0.01  # one walker five narrow-direction sd off the ridge
    assert chain_passes(xy(off))  # the parameters alone do not see it
    assert not chain_passes(xy(off), lp(off))


def test_diagnostics_include_log_posterior_and_moves_are_selectable():
    from palpbayes.bayes.sampler import MOVES

    tr = simulate_trace(E_TRUE, TIPS["paraboloid"], depth=2e-3, rng=3)
    res = fit_bayes(tr, seed=2, budget=BudgetSpec.none(),
                    settings=SamplerSettings(moves="de-snooker"))
    assert "lp" in res.diagnostics.rhat
    assert res.diagnostics.rhat_max >= res.diagnostics.rhat["lp"]
    assert res.diagnostics.converged, res.diagnostics.problems()
    assert set(MOVES) == {"de", "de-snooker", "stretch"}
    from palpbayes.errors import InputError

    with pytest.raises(InputError, match="unknown moves"):
        SamplerSettings(moves="walk")
    with pytest.raises(InputError, match="max_steps"):
        SamplerSettings(max_steps=0)


def test_cell_scale_indentation_in_si():
    """The E* prior is scale-free: an AFM-like indentation of a cell (E = 2 kPa, 5 um bead,
    1 um deep, nN forces, 0.3 nN p-p noise) fits with the same code once the noise spec and
    F_unc are given in newtons."""
    from palpbayes.bayes import PriorSpec

    E, nu, pp = 2e3, 0.45, 0.3e-9
    tr = simulate_trace(E, Tip("paraboloid", radius=5e-6), nu=nu, z_surf=20e-6, depth=1e-6,
                        approach=0.5e-6, speed=2e-6, rate=2000.0, noise_pp=pp, rng=8)
    assert 5e-9 < tr.force.max() < 1e-8  # nanonewtons
    res = fit_bayes(tr, ModelSpec(tr.tip, nu=nu), f_unc=pp, priors=PriorSpec(noise_pp=pp),
                    budget=BudgetSpec.none(), seed=4)
    E_draws = res.draws("E")
    lo, hi = np.quantile(E_draws, [0.05, 0.95])
    assert lo <= E <= hi
    assert np.median(E_draws) == pytest.approx(E, rel=0.02)
    assert np.median(res.draws("sigma")) == pytest.approx(pp / 6, rel=0.1)
    assert res.diagnostics.converged, res.diagnostics.problems()
