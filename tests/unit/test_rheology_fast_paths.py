"""The fast paths of the viscoelastic fit give the reference numbers (issue 47).

* the constant kernel (the SLS's E_inf*, the elastic law) runs on the knots' lattice by FFT:
  the same columns as the dense K × K products;
* a retract whose blocks start a fraction of a block off the approach's lattice shares a
  finer lattice with it: the same products as the dense path, one FFT group;
* emcee's independence move takes its proposal density over the mirror images in one
  product: the same density as the sum over the images one by one;
* an emcee fit's force curves come from the chain's column table: the direct columns to far
  below the noise.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from scipy.special import logsumexp

from palpbayes.contact.viscoelastic import PowerLawKernel
from palpbayes.paper import PAPER_TIPS
from palpbayes.rheology import fit_rheology
from palpbayes.rheology.cycle import prepare_cycle
from palpbayes.rheology.design import (
    Windows,
    band_corrections,
    knot_products,
    lee_radok_columns,
    step_kernel_means,
)
from palpbayes.rheology.fit import _force_curves
from palpbayes.rheology.lattice import knot_lattice
from palpbayes.rheology.sampler import T_DF, T_INFLATE, _independence_move
from palpbayes.sim import simulate_viscoelastic


@pytest.fixture(scope="module")
def cycle():
    """A 4,081-sample approach – hold – retract cycle (the benchmark's), power law."""
    return simulate_viscoelastic(PowerLawKernel(80e3, 0.2), PAPER_TIPS["paraboloid"],
                                 depth=3e-3, speed=50.0 / 6e4, hold_time=2.0, rate=400.0,
                                 retract=True, z_surf=2e-4, noise_sd=0.008, phi=0.3, rng=1)


def _dense(win: Windows, a1, a2, kernel, theta=0.0):
    D1, D2 = step_kernel_means(win, kernel, theta)
    return a1 @ D1.T + a2 @ D2.T


def test_retract_joins_the_approach_lattice(cycle):
    data = prepare_cycle(cycle, segments=("approach", "hold", "retract"))
    win = data.windows()
    lat = win.lattice
    assert lat is not None and len(lat.groups) == 1  # one FFT, no dense cross terms
    step = float(np.median(np.diff(data.edges)))
    assert lat.groups[0].step == pytest.approx(step / 3, rel=1e-9)
    rng = np.random.default_rng(0)
    a1, a2 = rng.standard_normal((2, 4, data.edges.size))
    for kernel, theta in (("power-law", 0.0), ("power-law", 0.3), ("exponential", 0.7),
                          (None, 0.0)):
        fast = knot_products(win, a1, a2, kernel, theta)
        ref = _dense(win, a1, a2, kernel, theta)
        assert np.max(np.abs(fast - ref)) <= 1e-9 * np.max(np.abs(ref)), kernel


def test_lattice_keeps_a_step_it_cannot_refine():
    """A stretch off the lattice by an irrational fraction of the step starts a group."""
    h = 0.01
    first = np.arange(100) * h
    second = first[-1] + 0.5 + np.sqrt(2) * 1e-3 + np.arange(100) * h
    lat = knot_lattice(np.r_[first, second])
    assert lat is not None and len(lat.groups) == 2
    assert all(g.step == pytest.approx(h) for g in lat.groups)


def test_constant_kernel_columns_match_dense(cycle):
    data = prepare_cycle(cycle)
    win = data.windows()
    assert win.lattice is not None
    z = np.linspace(data.z_lo, data.z_hi, 30)
    fast = lee_radok_columns(win, z, data.z_edges, data.m, None)
    # the same columns from the dense step means: lee_radok_columns on a copy of the windows
    # without a lattice
    dense_win = data.windows()
    dense_win.lattice = None
    ref = lee_radok_columns(dense_win, z, data.z_edges, data.m, None)
    scale = np.max(np.abs(ref), axis=1, keepdims=True) + 1e-300
    assert np.max(np.abs(fast - ref) / scale) <= 1e-8
    assert band_corrections(win, None)[0].shape == win.band.shape


def test_independence_move_density_is_the_sum_over_images():
    rng = np.random.default_rng(3)
    d = 5
    start = rng.standard_normal((400, d)) @ rng.standard_normal((d, d)) * 0.4
    lo = np.array([-np.inf, -1.5, -1.0, -np.inf, -0.8])
    hi = np.array([np.inf, 1.5, np.inf, np.inf, 0.8])
    move = _independence_move(start, lo, hi)
    x = rng.uniform(-1.0, 1.0, (20, d)) * np.array([3.0, 1.4, 0.9, 3.0, 0.79])
    x[0, 1] = 2.0  # outside: -inf
    mu = start.mean(axis=0)
    S = np.cov(start, rowvar=False) * T_INFLATE**2
    L = np.linalg.cholesky(S + 1e-12 * np.trace(S) * np.eye(d))
    options = [[None] + [b for b in (lo[j], hi[j]) if np.isfinite(b)] for j in range(d)]
    ref = np.empty(x.shape[0])
    for w in range(x.shape[0]):
        terms = []
        for combo in itertools.product(*options):
            y = np.array([x[w, j] if b is None else 2 * b - x[w, j]
                          for j, b in enumerate(combo)])
            q = np.linalg.solve(L, y - mu)
            terms.append(-0.5 * (T_DF + d) * np.log1p(q @ q / T_DF))
        inside = np.all((x[w] >= lo) & (x[w] <= hi))
        ref[w] = logsumexp(terms) if inside else -np.inf
    got = move.log_density(x)
    assert np.array_equal(np.isfinite(got), np.isfinite(ref))
    ok = np.isfinite(ref)
    assert np.max(np.abs(got[ok] - ref[ok])) <= 1e-10


def test_emcee_curves_from_the_table(cycle):
    fit = fit_rheology(cycle, "power-law", engine="emcee", n_draws=400, rng=2)
    assert fit.sampler.table is not None
    table = fit.force_curves(50)
    direct = _force_curves(fit.data, "power-law", fit.draws, fit.t0, 50, {})
    sigma = float(np.median(fit.draws["sigma"]))
    assert np.max(np.abs(table - direct)) <= 1e-2 * sigma
