"""The emcee engine of the viscoelastic fit samples the grid engine's posterior.

Simulated palpations (the paper's paraboloid and flat punch, 50 mm/min, AR(1) noise of 8 mN
with phi = 0.3, an offset of 20 mN) are fitted by both engines, and every marginal of
:func:`palpbayes.rheology.sampler.sample_emcee` is compared with the grid engine's
(:meth:`GridPosterior.draws <palpbayes.rheology.posterior.GridPosterior.draws>`, 20,000
draws):

* medians within 0.2 posterior sd.  Monte Carlo error: emcee's bulk ESS is >= 1,000 here
  (asserted; measured 2,600–5,500), so its median has se <= 1.25/sqrt(1000) = 0.04 sd; the
  grid's 20,000 resampled draws add <= 0.01 sd: 0.2 sd is ~5 se, room left for the grid's
  own quadrature error;
* sds within 10 %: se of an sd is ~1/sqrt(2·ESS) <= 2.2 % for emcee, 0.5 % for the grid,
  so 10 % is ~4.5 se;
* phi is a grid *node* in the grid's draws (nodes around its density, a quarter of its sd
  apart: :meth:`NodeEvaluator.focus_phi <palpbayes.rheology.posterior.NodeEvaluator.
  focus_phi>`), so its mean is compared instead of its median (within 0.2 sd) and its grid
  sd with Sheppard's correction sd² − h²/12;
* R-hat < 1.02 on every parameter and the log posterior; the table's log-likelihood error
  below :data:`~palpbayes.rheology.sampler.TABLE_TOL`.

Fixed seeds: the same numbers every run (asserted by running twice).  The default suite runs
200-block records (power law on the paraboloid, on the flat punch with a tilted baseline; the
standard linear solid on the flat punch; 1.0–1.4 s each here); the full-size records (the
4,100-sample cycle, the retract with a drag term, the SLS on the paraboloid; 1.5–3.5 s each
here) are ``slow``.  Measured over all cases: |Δ median| <= 0.05 sd, phi's mean −0.01…+0.05
sd off the grid's (−0.01…+0.14 when the grid's phi nodes were 0.041 apart, one sd), sd
ratios 0.97–1.05, R-hat <= 1.01, bulk ESS >= 2,700.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy.stats import multivariate_normal

from palpbayes.contact.viscoelastic import PowerLawKernel, standard_linear_solid
from palpbayes.errors import InputError
from palpbayes.paper import PAPER_TIPS
from palpbayes.rheology import prepare_cycle
from palpbayes.rheology.posterior import OFFSET_SD, NodeEvaluator, grid_posterior
from palpbayes.rheology.sampler import TABLE_TOL, ar1_log_likelihood, sample_emcee
from palpbayes.sim import simulate_viscoelastic

#: Tolerances (module docstring).
MEDIAN_SD, SD_RATIO, RHAT, ESS = 0.2, 0.10, 1.02, 1000.0

CASES = {
    # name: (kernel, tip, segments, drag, tilt, max_points)
    "power law, paraboloid, 200 blocks": (PowerLawKernel(80e3, 0.2), "paraboloid",
                                          "approach,hold", False, False, 200),
    "power law, paraboloid, 4,100 samples": (PowerLawKernel(80e3, 0.2), "paraboloid",
                                             "approach,hold", False, False, 800),
    "power law, flat, retract and drag": (PowerLawKernel(60e3, 0.15), "flat",
                                          "approach,hold,retract", True, False, 800),
    "sls, paraboloid": (standard_linear_solid(50e3, 40e3, 1.0), "paraboloid",
                        "approach,hold", False, False, 800),
    "power law, flat, tilted baseline, 200 blocks": (PowerLawKernel(60e3, 0.15), "flat",
                                                     "approach,hold", False, True, 200),
    "sls, flat, 200 blocks": (standard_linear_solid(40e3, 30e3, 0.5), "flat", "approach,hold",
                              False, False, 200),
}
FAST = "power law, paraboloid, 200 blocks"
#: Cases of the default suite (200 blocks: 5-15 s each here); the full-size records take
#: 20-40 s each here (the grid start is most of it) and run with ``-m slow``.
DEFAULT = (FAST, "power law, flat, tilted baseline, 200 blocks", "sls, flat, 200 blocks")


def record(name: str):
    kernel, tip, segments, _, _, max_points = CASES[name]
    trace = simulate_viscoelastic(kernel, PAPER_TIPS[tip],
                                  depth=3e-3 if tip == "paraboloid" else 2e-3,
                                  speed=50 / 6e4, hold_time=1.0, rate=800.0, z_surf=2e-4,
                                  noise_sd=0.008, phi=0.3, offset=0.02, rng=1)
    return prepare_cycle(trace, segments=segments, max_points=max_points)


_RUNS: dict = {}


def run(name: str):
    """(data, grid, emcee result) of a case, computed once per session."""
    if name not in _RUNS:
        data = record(name)
        kernel, _, _, drag, tilt, _ = CASES[name]
        rheology = "power-law" if isinstance(kernel, PowerLawKernel) else "sls"
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            grid = grid_posterior(data, rheology, drag=drag, tilt=tilt)
            _RUNS[name] = (data, grid, sample_emcee(data, rheology, drag=drag, tilt=tilt,
                                                    rng=3, grid=grid))
    return _RUNS[name]


def agreement(grid, result) -> dict[str, dict[str, float]]:
    """Per parameter: the grid's and emcee's centre (median; mean for phi) and sd, and the
    difference in grid sd."""
    g = grid.draws(np.random.default_rng(11), 20_000)
    h = float(np.diff(grid.phi).mean())
    out = {}
    for name, e in result.draws.items():
        centre = np.mean if name == "phi" else np.median
        sd_g = float(np.std(g[name]))
        if name == "phi":
            sd_g = float(np.sqrt(max(sd_g**2 - h**2 / 12, 0.0)))
        out[name] = {"grid": float(centre(g[name])), "emcee": float(centre(e)), "sd_grid": sd_g,
                     "sd_emcee": float(np.std(e)), "rhat": result.rhat[name],
                     "ess": result.ess[name]}
        out[name]["z"] = (out[name]["emcee"] - out[name]["grid"]) / sd_g
    return out


def check(name: str) -> None:
    data, grid, res = run(name)
    # the same parameters (the grid's draws also name their nodes: _theta_node, _z_node)
    params = {k for k in grid.draws(np.random.default_rng(0), 10) if not k.startswith("_")}
    assert set(res.draws) == params - {"ess"}
    assert all(v.shape == (4000,) for v in res.draws.values())
    assert res.table_error < TABLE_TOL, res.table_error
    assert res.rhat["lp"] < RHAT, res.rhat
    for par, row in agreement(grid, res).items():
        assert abs(row["z"]) <= MEDIAN_SD, (par, row)
        assert abs(row["sd_emcee"] / row["sd_grid"] - 1) <= SD_RATIO, (par, row)
        assert row["rhat"] < RHAT, (par, row)
        assert row["ess"] >= ESS, (par, row)


def test_ar1_log_likelihood_is_the_multivariate_normal():
    """The exact AR(1) likelihood equals scipy's multivariate normal with covariance
    sigma²·phi^|i−j|, for several phi (0 included) and a batch of residual vectors."""
    rng = np.random.default_rng(0)
    n = 12
    lag = np.abs(np.subtract.outer(np.arange(n), np.arange(n)))
    for sigma, phi in ((0.01, 0.0), (0.003, 0.45), (2.0, 0.9)):
        r = rng.standard_normal((3, n)) * sigma
        want = multivariate_normal(np.zeros(n), sigma**2 * phi**lag).logpdf(r)
        got = ar1_log_likelihood(r, np.full(3, sigma), np.full(3, phi))
        np.testing.assert_allclose(got, want, rtol=1e-10)


def test_the_sampled_target_is_the_explicit_posterior():
    """The log posterior emcee stored along its chains (column table) matches, up to a
    constant, one written out here from the direct columns, scipy's multivariate normal and
    the grid's priors in the sampled coordinates (flat in log E0*, alpha, z_s, log sigma,
    phi; F0 ~ N(f0, (OFFSET_SD·sigma)²))."""
    data, _, res = run(FAST)
    ev = NodeEvaluator(data, "power-law", 1.0)
    lag = np.abs(np.subtract.outer(np.arange(data.n_points), np.arange(data.n_points)))
    lp = np.asarray(res.idata.sample_stats["lp"])
    got, want = [], []
    for w, i in ((0, 5), (7, 40), (20, 90)):
        p = {k: float(v[w, i]) for k, v in res.chains.items()}
        X = ev.columns(p["alpha"], np.array([p["z_surf"]]))[0]
        mean = p["E0"] * X[:, 0] + p["offset"]
        cov = p["sigma"] ** 2 * p["phi"] ** lag
        want.append(multivariate_normal(mean, cov).logpdf(data.force)
                    + multivariate_normal(data.f0_center, (OFFSET_SD * p["sigma"]) ** 2)
                    .logpdf(p["offset"]))
        got.append(lp[w, i])
    np.testing.assert_allclose(np.diff(got), np.diff(want), atol=1e-3)


@pytest.mark.slow
@pytest.mark.parametrize("name", DEFAULT)
def test_emcee_agrees_with_the_grid_engine(name):
    check(name)


def test_draws_are_deterministic():
    data, grid, res = run(FAST)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        again = sample_emcee(data, "power-law", rng=3, grid=grid)
    for k, v in res.draws.items():
        np.testing.assert_array_equal(again.draws[k], v)
    assert again.diagnostics == res.diagnostics


def test_refusals():
    data, grid, _ = run(FAST)
    with pytest.raises(InputError, match="rheology"):
        sample_emcee(data, "maxwell")
    with pytest.raises(InputError, match="another"):
        sample_emcee(data, "power-law", drag=True, grid=grid)
    with pytest.raises(InputError, match="n_walkers"):
        sample_emcee(data, "power-law", n_walkers=4, grid=grid)
    kernel = standard_linear_solid(50e3, 40e3, 1.0)
    trace = simulate_viscoelastic(kernel, PAPER_TIPS["flat"], depth=2e-3, speed=50 / 6e4,
                                  hold_time=0.5, rng=2)
    with pytest.raises(InputError, match="retract"):
        sample_emcee(prepare_cycle(trace, segments="approach,hold,retract", max_points=100),
                     "sls")


@pytest.mark.slow
@pytest.mark.parametrize("name", [n for n in CASES if n not in DEFAULT])
def test_emcee_agrees_with_the_grid_engine_on_full_records(name):
    check(name)


def test_the_independence_proposal_folded_at_the_bounds_has_the_density_it_claims():
    """The independence move folds a t draw beyond a bound back into the box (phi piles up at
    0.98 on most real records: half the draws used to land beyond it and propose to stay).
    Its Hastings factor needs the folded density, the t summed over every mirror image of x.
    300,000 proposals in a box bounded on both sides in the first coordinate (the t's centre
    near the upper bound) and on one side in the second: the share of each cell of a 6 x 6
    grid over the box matches the integral of that density, normalised by the share of
    draws that moved, within 4 binomial se."""
    from palpbayes.rheology.sampler import _independence_move

    rng = np.random.default_rng(2)
    start = rng.multivariate_normal([0.8, 0.0], [[0.04, 0.018], [0.018, 0.09]], 4000)
    lo, hi = np.array([0.0, -0.5]), np.array([0.95, np.inf])
    move = _independence_move(start, lo, hi)
    n = 300_000
    here = np.tile([0.5, 0.0], (n, 1))
    new, _ = move.get_proposal(here, rng)
    moved = np.any(new != here, axis=1)
    x0 = np.linspace(lo[0], hi[0], 601)
    x1 = np.linspace(lo[1], 4.0, 1201)  # the t's mass beyond 4 is < 1e-4
    X0, X1 = np.meshgrid(x0, x1, indexing="ij")
    dens = np.exp(move.log_density(np.column_stack([X0.ravel(), X1.ravel()])).reshape(X0.shape))
    e0, e1 = np.linspace(lo[0], hi[0], 7), np.r_[np.linspace(lo[1], 2.0, 6), 4.0]
    mass = np.array([[np.trapezoid(np.trapezoid(
        np.where((X0 >= a) & (X0 <= b) & (X1 >= c) & (X1 <= d), dens, 0.0), x1, axis=1), x0)
        for c, d in zip(e1[:-1], e1[1:], strict=True)] for a, b in zip(e0[:-1], e0[1:],
                                                                        strict=True)])
    want = mass / mass.sum() * moved.mean()
    got = np.histogram2d(new[moved, 0], new[moved, 1], bins=[e0, e1])[0] / n
    se = np.sqrt(want * (1 - want) / n)
    assert np.all(np.abs(got - want) <= 4 * se + 2e-4), np.max(np.abs(got - want) / se)


def test_phi_is_resolved_at_the_mode_without_a_climb(monkeypatch):
    """The elastic law has no climb, and a climb that fails falls back to a search from the
    coarse grid's best node.  phi's nodes were then set at that node, where the surface is
    off and the residuals make phi look near its bound: on this record (true phi 0.3 on the
    samples, ~0.05 on the block means) the elastic grid said phi 0.96 ± 0.003 and E* ± 87 Pa,
    emcee ± 3.2 Pa; the power law without its climb put phi's nodes in [0.975, 0.98] and
    alpha's sd 20 times too wide.  The nodes are now checked at the final box's mode and set
    there.  Elastic: grid and emcee agree as in :func:`check`; the power law without its
    climb: the same posterior as with it (medians within 0.2 sd, sds within 10 %)."""
    import palpbayes.rheology.posterior as posterior
    from palpbayes.errors import FitError

    trace = simulate_viscoelastic(PowerLawKernel(80e3, 0.2), PAPER_TIPS["paraboloid"],
                                  depth=3e-3, speed=50 / 6e4, hold_time=1.0, rate=800.0,
                                  z_surf=2e-4, noise_sd=0.0005, phi=0.3, rng=1)
    elastic = simulate_viscoelastic(PowerLawKernel(80e3, 0.0), PAPER_TIPS["paraboloid"],
                                    depth=3e-3, speed=50 / 6e4, hold_time=1.0, rate=800.0,
                                    z_surf=2e-4, noise_sd=0.0005, phi=0.3, rng=1)
    data = prepare_cycle(elastic, segments="approach,hold", max_points=200)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = sample_emcee(data, "elastic", rng=0)
    assert res.rhat["lp"] < RHAT
    for par, row in agreement(res.grid, res).items():
        assert abs(row["z"]) <= MEDIAN_SD, (par, row)
        assert abs(row["sd_emcee"] / row["sd_grid"] - 1) <= SD_RATIO, (par, row)
    data = prepare_cycle(trace, segments="approach,hold", max_points=200)
    draws = [grid_posterior(data, "power-law").draws(np.random.default_rng(0), 20_000)]

    def fails(*args, **kwargs):
        raise FitError("no climb")

    monkeypatch.setattr(posterior, "climb", fails)
    draws.append(grid_posterior(data, "power-law").draws(np.random.default_rng(0), 20_000))
    for name in ("alpha", "z_surf", "sigma", "phi"):
        a, b = (d[name] for d in draws)
        assert abs(np.median(a) - np.median(b)) <= MEDIAN_SD * np.std(a), name
        assert np.std(b) == pytest.approx(np.std(a), rel=SD_RATIO), name
