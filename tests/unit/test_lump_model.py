"""The lump model's pieces: the prior on the sampled coordinates, map_from_points with gaps."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from palpbayes.inclusion import contact_radius
from palpbayes.maps.lump import RATIO_MAX, _Problem, lump_table
from palpbayes.maps.pertrace import POINT_COLUMNS
from palpbayes.maps.run import MapOptions, map_from_points
from palpbayes.paper import PAPER_TIPS

H, STEP = 0.02, 3e-3
A = contact_radius(PAPER_TIPS["paraboloid"], 2e-3)


@pytest.fixture(scope="module")
def table():
    return lump_table(A, H, STEP, 0.03)


@pytest.mark.parametrize("radius, cover", [(4e-3, 0.5e-3), (6e-3, 2e-3), (3e-3, 5e-3)])
def test_the_apparent_ratio_coordinate_carries_a_log_uniform_ratio_prior(table, radius, cover):
    """With no information in the data, exp(log prior) integrated over log A is the measure of
    log rho, ln(RATIO_MAX): the Jacobian 1/((1 − g)·A·V(0)) is right and complete."""
    x = np.linspace(0, 0.03, 5)
    p = _Problem(x=x, y=x, obs=np.zeros(5), var=np.full(5, 1e16), table=table, thickness=H,
                 box=(-0.01, 0.04, -0.01, 0.04), log_r=(math.log(1.5e-3), math.log(9e-3)),
                 log_eb=(-10.0, 10.0))
    v0 = float(table(np.zeros(1), radius, radius + cover)[0])
    log_a_max = -math.log1p(-v0 * (1 - 1 / RATIO_MAX))  # g = 1 − 1/RATIO_MAX
    la = np.linspace(0.0, log_a_max, 20001)[:-1]
    tau = 0.05
    theta = np.column_stack([np.zeros_like(la), np.full_like(la, 0.015), np.full_like(la, 0.015),
                             np.full_like(la, math.log(radius)), np.full_like(la, cover), la,
                             np.full_like(la, math.log(tau))])
    lp, g = p.batch(theta)
    assert np.all(np.isfinite(lp))
    const = (-math.log(H - 2 * radius) - 0.5 * (tau / 0.2) ** 2 + math.log(tau)
             - 0.5 * 5 * math.log(1e16 + tau * tau))
    mass = np.trapezoid(np.exp(lp - const), la)
    assert mass == pytest.approx(math.log(RATIO_MAX), rel=2e-3)
    np.testing.assert_allclose(1 / (1 - g), 1 / (1 - (1 - np.exp(-la)) / v0), rtol=1e-12)
    # beyond the bound (rho > RATIO_MAX) and below A = 1: outside the support
    out = theta[:2].copy()
    out[0, 5], out[1, 5] = log_a_max * 1.001, -1e-6
    assert np.all(np.isneginf(p.batch(out)[0]))


def _points(n=12, seed=0):
    rng = np.random.default_rng(seed)
    ix, iy = np.meshgrid(np.arange(n), np.arange(n))
    x, y = ix.ravel() * STEP, iy.ravel() * STEP
    logE = np.log(50e3) + 0.03 * rng.standard_normal(x.size)
    pts = pd.DataFrame({c: np.nan for c in POINT_COLUMNS}, index=range(x.size))
    return pts.assign(trace_id=[f"p{k}" for k in range(x.size)], x_m=x, y_m=y, logE_mean=logE,
                      logE_sd=0.002, E_median_pa=np.exp(logE), E_lo_pa=np.exp(logE) * 0.99,
                      E_hi_pa=np.exp(logE) * 1.01, E_lsq_pa=np.exp(logE), depth_m=2e-3,
                      notes="", flag_codes="", flag_level="", error="")


def test_failed_traces_keep_their_nodes_on_the_map():
    """A whole edge row and a few inner points fail: the lattice is unchanged (12 × 12), those
    nodes have no data (wider intervals, n_traces 0) and a flag counts them."""
    pts = _points()
    bad = (pts["y_m"] == pts["y_m"].max()) | pts.index.isin([30, 31, 77])
    pts.loc[bad, ["logE_mean", "logE_sd"]] = np.nan
    pts.loc[bad, "error"] = "no contact"
    res = map_from_points(pts, tip=PAPER_TIPS["paraboloid"], thickness=None,
                          options=MapOptions(field_draws=400))
    n = res.nodes
    assert (res.field.lattice.nx, res.field.lattice.ny) == (12, 12) and len(n) == 144
    assert (n.loc[bad.to_numpy(), "n_traces"] == 0).all()
    assert (n.loc[~bad.to_numpy(), "n_traces"] == 1).all()
    assert np.isnan(n.loc[bad.to_numpy(), "E_point_pa"]).all()
    width = np.log(n["E_hi_pa"] / n["E_lo_pa"])
    assert width[bad.to_numpy()].mean() > 1.1 * width[~bad.to_numpy()].mean()
    assert any(f.startswith(f"{int(bad.sum())} of 144 traces could not be fitted")
               for f in res.flags)
    assert any("block thickness" in f for f in res.flags) and res.lump is None


def test_repeated_positions_share_a_node():
    pts = _points(10)
    extra = pts.iloc[[0, 55]].assign(trace_id=["again0", "again55"])
    res = map_from_points(pd.concat([pts, extra], ignore_index=True),
                          tip=PAPER_TIPS["paraboloid"], thickness=None,
                          options=MapOptions(field_draws=200, lump=False))
    assert len(res.nodes) == 100
    assert res.nodes.set_index(["ix", "iy"]).loc[[(0, 0), (5, 5)], "n_traces"].tolist() == [2, 2]
    assert "info: lump model off (--no-lump; the default for an AFM map)" in res.flags
