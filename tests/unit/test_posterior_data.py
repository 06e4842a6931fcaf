"""A fit's InferenceData groups as numpy arrays (palpbayes.bayes.posterior_data) and its
diagnostics with arviz-stats (palpbayes.bayes.diagnostics): the same InferenceData, the same
file, the same figures as with arviz (issue 59)."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from palpbayes.bayes.diagnostics import (
    compute_diagnostics,
    ess_bulk,
    ess_tail,
    hdi,
    import_arviz,
    rhat,
)
from palpbayes.bayes.posterior_data import PosteriorData
from palpbayes.errors import InputError
from palpbayes.io.atomic import write_netcdf_atomic

az = import_arviz()


def _groups(seed: int = 0) -> PosteriorData:
    rng = np.random.default_rng(seed)
    out = PosteriorData.from_dicts(
        posterior={"E_star": rng.lognormal(8, 0.1, (4, 60)), "z_surf": rng.normal(0, 1, (4, 60)),
                   "w": rng.normal(0, 1, (4, 60, 3)),
                   "bonded": np.where(rng.random((4, 60)) < 0.1, np.nan, 1.0)},
        sample_stats={"lp": rng.normal(0, 1, (4, 60))},
        observed_data={"force": rng.normal(0, 1, 25)}, constant_data={"z": np.linspace(0, 1, 25)},
        attrs={"trace_id": "t1", "model": "sphere R=10 µm", "nu": 0.45, "seed": 3,
               "z_prior_m": [0.1, 0.2], "lsq_E_pa": np.nan, "modes_weight": [1.0]})
    out.posterior.attrs.update({"engine": "exact", "log_bf_bonded": 1.5})
    return out


def _same(a, b) -> bool:
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return (type(a) is type(b) and a.dtype == b.dtype
                and np.array_equal(a, b, equal_nan=a.dtype.kind == "f"))
    return type(a) is type(b) and (a == b or (a != a and b != b))


def test_the_inference_data_is_what_from_dict_makes():
    g = _groups()
    idata = g.to_inference_data()
    ref = az.from_dict(posterior=dict(g.posterior.data), sample_stats=dict(g.sample_stats.data),
                       observed_data=dict(g.observed_data.data),
                       constant_data=dict(g.constant_data.data), attrs=dict(g.attrs))
    assert idata.groups() == ref.groups() == g.group_names()
    for name in ref.groups():
        ours, theirs = getattr(idata, name), getattr(ref, name)
        xr.testing.assert_equal(ours, theirs)
        assert {k: v for k, v in ours.attrs.items() if k not in g.posterior.attrs} == {
            **theirs.attrs, "created_at": g.created_at}
    assert idata.posterior.attrs["engine"] == "exact" and idata.posterior.attrs[
        "log_bf_bonded"] == 1.5
    assert dict(idata.attrs) == g.attrs


def test_the_file_is_the_one_arviz_writes(tmp_path):
    """Written with h5netcdf, read by arviz: the groups, arrays, dimensions, coordinates,
    encodings and attributes (with their types) of ``InferenceData.to_netcdf``'s file."""
    g = _groups()
    ours = az.from_netcdf(str(g.to_netcdf(tmp_path / "ours.nc")))
    theirs = az.from_netcdf(str(write_netcdf_atomic(g.to_inference_data(),
                                                    tmp_path / "theirs.nc")))
    assert ours.groups() == theirs.groups() == g.group_names()
    assert list(ours.attrs) == list(theirs.attrs)
    assert all(_same(ours.attrs[k], theirs.attrs[k]) for k in theirs.attrs)
    for name in theirs.groups():
        a, b = getattr(ours, name), getattr(theirs, name)
        xr.testing.assert_identical(a, b)
        assert list(a.attrs) == list(b.attrs)
        assert all(_same(a.attrs[k], b.attrs[k]) for k in b.attrs)
        for var in b.variables:
            assert a[var].dtype == b[var].dtype
            enc = ("dtype", "zlib", "complevel", "shuffle", "chunksizes")
            assert {k: a[var].encoding.get(k) for k in enc} == {
                k: b[var].encoding.get(k) for k in enc}


def test_draws_need_chain_and_draw_axes():
    with pytest.raises(InputError, match="axes"):
        PosteriorData.from_dicts(posterior={"E": np.ones(10)})


def test_a_fit_keeps_numpy_draws_and_makes_the_inference_data_once(tmp_path):
    """BayesResult.idata is made on first access and kept; a result whose idata was made (and
    perhaps changed) is written from it."""
    from palpbayes import Tip
    from palpbayes.bayes import fit_bayes
    from palpbayes.sim import simulate_trace

    tr = simulate_trace(120e3, Tip("sphere", radius=0.01), nu=0.45, rng=6, depth=2e-3)
    res = fit_bayes(tr, engine="exact", with_model_form=False)
    assert isinstance(res.groups, PosteriorData) and res._idata is None
    idata = res.idata
    assert res.idata is idata and idata.posterior.attrs["engine"] == "exact"
    np.testing.assert_array_equal(np.asarray(idata.posterior["E"]), res.groups.posterior["E"])
    idata.posterior.attrs["note"] = "mine"
    back = az.from_netcdf(str(res.to_netcdf(tmp_path / "r.nc")))
    assert back.posterior.attrs["note"] == "mine"
    assert back.posterior.attrs["palpbayes_result"] == res.groups.posterior.attrs[
        "palpbayes_result"]


def _ar1(rng, chains: int, draws: int, rho: float) -> np.ndarray:
    x = np.zeros((chains, draws))
    e = rng.standard_normal((chains, draws))
    x[:, 0] = e[:, 0]
    for t in range(1, draws):
        x[:, t] = rho * x[:, t - 1] + e[:, t]
    return x + rng.normal(0, 0.2, (chains, 1))


def test_the_figures_are_arviz_figures():
    """R-hat and bulk ESS equal arviz's; tail ESS is the same definition, its quantile from
    numpy instead of scipy's mquantiles (within 1 %); the HDI equals arviz's."""
    rng = np.random.default_rng(3)
    for chains, draws, rho in ((4, 1000, 0.0), (24, 300, 0.9), (8, 50, 0.5), (32, 2000, 0.95)):
        x = np.exp(_ar1(rng, chains, draws, rho))
        assert float(rhat(x)) == pytest.approx(float(az.rhat(x)), rel=1e-12)
        assert float(ess_bulk(x)) == pytest.approx(float(az.ess(x, method="bulk")), rel=1e-12)
        assert float(ess_tail(x)) == pytest.approx(float(az.ess(x, method="tail")), rel=0.01)
        lo, hi = hdi(x, 0.9)
        np.testing.assert_allclose((lo, hi), np.asarray(az.hdi(x.ravel(), hdi_prob=0.9)))
    g = _groups()
    d = compute_diagnostics(g, ["E_star", "z_surf", "w"], np.ones(3), 0.5, 100, False)
    ref = g.to_inference_data()
    assert d.rhat["lp"] == pytest.approx(float(az.rhat(np.asarray(g.sample_stats["lp"]))))
    assert d.rhat["w"] == pytest.approx(float(az.rhat(ref, var_names=["w"])["w"].max()))
    assert d.ess_bulk["w"] == pytest.approx(float(az.ess(ref, var_names=["w"])["w"].min()))
    assert compute_diagnostics(ref, ["E_star", "z_surf", "w"], np.ones(3), 0.5, 100,
                               False) == d
