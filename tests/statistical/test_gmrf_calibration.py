"""Stiffness maps by simulation: recovery of a model field and of a bump, and calibration.

The default suite recovers one field simulated from the model itself and one smooth bump (a
few seconds each); ``pytest -m slow`` adds the coverage of the field's 90 % intervals over
datasets whose truth is drawn from the prior the model is fitted with, and times a 100 × 100
map (printed, not asserted).
"""

from __future__ import annotations

import resource
import time

import numpy as np
import pytest

from palpbayes.intervals import LEVEL
from palpbayes.maps import FieldPrior, Lattice, default_margin, fit_field, pad, sample_field

H = 0.005  # 5 mm lattice step
BETA = float(np.log(1.2e5))


def _simulate(n, sigma_f, range_steps, tau, rng, s=0.01, beta=BETA):
    """A field from the model (simulated on the padded lattice fit_field uses) and its data."""
    lat = Lattice(0.0, 0.0, H, n, n)
    padded, index = pad(lat, default_margin(lat))
    mu = beta + sample_field(padded, sigma_f, range_steps * H, rng)[0].ravel()[index]
    s = np.broadcast_to(s, mu.shape)
    y = mu + rng.normal(0.0, np.sqrt(s**2 + tau**2))
    return lat, mu.reshape(n, n), y, np.asarray(s, dtype=float)


def _coverage(field_draws, truth, level=LEVEL):
    a = (1 - level) / 2
    lo, hi = np.quantile(field_draws, [a, 1 - a], axis=0)
    return float(np.mean((truth >= lo) & (truth <= hi)))


def test_recovers_a_field_simulated_from_the_model():
    truth = {"sigma_f": 0.3, "range_m": 8 * H, "tau": 0.05}
    rng = np.random.default_rng(2024)
    lat, mu, y, s = _simulate(30, truth["sigma_f"], 8, truth["tau"], rng)
    fp = fit_field(lat.node_x, lat.node_y, y, s)
    assert fp.flags == []
    summ = fp.hyper_summary().set_index("parameter")
    for name, value in truth.items():
        row = summ.loc[name]
        assert abs(row["mean"] - value) < 3 * row["sd"], (name, row.to_dict())
        assert row["q05"] / 1.5 < value < 1.5 * row["q95"], (name, row.to_dict())
    d = fp.draws(np.random.default_rng(1), 500)
    assert 0.8 <= _coverage(d["field"], mu) <= 0.97
    assert abs(d["beta"].mean() - BETA) < 3 * d["beta"].std()
    # the exact mixture mean agrees with the draws
    assert np.max(np.abs(fp.mean() - d["field"].mean(axis=0))) < 0.2 * d["field"].std(
        axis=0).min() + 1e-3


def test_recovers_a_smooth_bump_and_detects_it():
    """A Gaussian bump (height 1.0 in log E, sd 3 steps) on a flat background, nugget 0.05.

    Under the stationary Matérn prior a sharp peak is pulled towards its surroundings by about
    one posterior sd (0.02–0.04 here, over seeds), on top of the local noise, hence 3 sd.
    """
    n, tau = 30, 0.05
    lat = Lattice(0.0, 0.0, H, n, n)
    rng = np.random.default_rng(8)
    dx = (lat.node_x - 15 * H) / H
    dy = (lat.node_y - 15 * H) / H
    mu = BETA + 1.0 * np.exp(-(dx**2 + dy**2) / (2 * 3.0**2))
    s = rng.uniform(0.001, 0.02, mu.size)
    y = mu + rng.normal(0.0, np.sqrt(s**2 + tau**2))
    fp = fit_field(lat.node_x, lat.node_y, y, s)
    assert fp.flags == []
    d = fp.draws(np.random.default_rng(3), 500)["field"].reshape(500, -1)
    peak = lat.index(15, 15)
    m, sd = d[:, peak].mean(), d[:, peak].std()
    assert abs(m - mu[peak]) < 3 * sd
    stiffer = d - np.median(d, axis=1, keepdims=True) > np.log(2)
    p = stiffer.mean(axis=0)
    assert p[peak] > 0.9
    far = np.hypot(dx, dy) > 12
    assert p[far].max() < 0.05
    # the nugget is recovered (the bump is smooth enough for the Matérn field)
    tau_row = fp.hyper_summary().set_index("parameter").loc["tau"]
    assert tau_row["q05"] / 1.5 < tau < 1.5 * tau_row["q95"]


PRIOR = FieldPrior(range_0=2 * H, sigma_0=0.5, tau_0=0.1)
N_DATASETS = 20


def _draw_theta(rng, prior=PRIOR):
    c = -np.log(prior.alpha)
    return {"sigma_f": rng.exponential(prior.sigma_0 / c),
            "range_m": c * prior.range_0 / rng.exponential(),
            "tau": rng.exponential(prior.tau_0 / c)}


@pytest.mark.slow
def test_field_intervals_are_calibrated_over_prior_draws():
    """Truth drawn from the prior the model is fitted with: the field's 90 % intervals cover
    ~90 % of the nodes, and the hyperparameters' 90 % intervals ~90 % of the truths."""
    rng = np.random.default_rng(99)
    cover, hyper_in, flagged = [], [], 0
    for _ in range(N_DATASETS):
        th = _draw_theta(rng)
        lat, mu, y, s = _simulate(25, th["sigma_f"], th["range_m"] / H, th["tau"], rng)
        fp = fit_field(lat.node_x, lat.node_y, y, s, prior=PRIOR)
        flagged += bool(fp.flags)
        cover.append(_coverage(fp.draws(rng, 400)["field"], mu))
        summ = fp.hyper_summary().set_index("parameter")
        hyper_in += [summ.loc[k, "q05"] <= v <= summ.loc[k, "q95"] for k, v in th.items()]
    print(f"\nfield coverage per dataset: {np.round(cover, 3)}; mean {np.mean(cover):.3f}; "
          f"hyperparameter coverage {np.mean(hyper_in):.3f} of {len(hyper_in)}; "
          f"{flagged} fits flagged")
    assert 0.85 <= np.mean(cover) <= 0.95
    assert np.mean(hyper_in) >= 0.75


@pytest.mark.slow
@pytest.mark.long  # ~5 min on 2 cores; run by hand (docs/reference.md)
def test_a_100_by_100_map_is_calibrated():
    """At n = 10,000 the field's 90 % intervals still cover the truth (wall time, theta grid
    size, time per factorisation and peak memory are printed; bench_map.py measures them)."""
    rng = np.random.default_rng(5)
    lat, mu, y, s = _simulate(100, 0.3, 10, 0.05, rng)
    t0 = time.perf_counter()
    fp = fit_field(lat.node_x, lat.node_y, y, s)
    t_fit = time.perf_counter() - t0
    h = fp.hyper.iloc[int(np.argmax(fp.hyper["weight"]))]
    t0 = time.perf_counter()
    for _ in range(3):
        fp._model.factor(h.sigma_f, h.range_m, h.tau)
    t_lu = (time.perf_counter() - t0) / 3
    t0 = time.perf_counter()
    d = fp.draws(np.random.default_rng(0), 200)
    t_draw = time.perf_counter() - t0
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    cov = _coverage(d["field"], mu)
    print(f"\n100 × 100 map: fit {t_fit:.1f} s, {len(fp.hyper)} theta points, "
          f"{t_lu:.3f} s per factorisation ({fp._model.n_latent} latent), 200 draws "
          f"{t_draw:.1f} s, peak RSS {rss:.0f} MB, coverage {cov:.3f}, "
          f"flags {fp.flags}")
    assert 0.8 <= cov <= 0.97  # 10,000 correlated nodes: the band of the 30 × 30 test
