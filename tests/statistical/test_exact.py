"""The exact engine against emcee, its coverage, and what it refuses."""

import numpy as np
import pytest

from palpbayes.bayes import BudgetSpec, PriorSpec, fit_bayes
from palpbayes.bayes.diagnostics import import_arviz
from palpbayes.bayes.exact import exact_posterior
from palpbayes.contact import Tip
from palpbayes.errors import ConvergenceWarning, InputError
from palpbayes.fitdata import ModelSpec, prepare_trace
from palpbayes.paper import PAPER_TIPS
from palpbayes.sim import simulate_trace

CASES = {
    "flat": dict(tip="flat"),
    "sphere": dict(tip="sphere"),
    "paraboloid": dict(tip="paraboloid"),
    "paraboloid-ar1": dict(tip="paraboloid", noise="ar1", noise_ar1=0.6),
    "paraboloid-linear": dict(tip="paraboloid", baseline="linear", drift=0.02),
}


@pytest.mark.parametrize("case", list(CASES))
def test_exact_engine_agrees_with_emcee_within_monte_carlo_error(case):
    """Means and sds of E* and z_surf agree within Monte Carlo error, with offsets,
    AR(1) noise and a drifting baseline."""
    c = dict(CASES[case])
    tip = PAPER_TIPS[c.pop("tip")]
    noise, baseline = c.pop("noise", "gaussian"), c.pop("baseline", "constant")
    tr = simulate_trace(140e3, tip, depth=3e-3, force_offset=0.02, rng=21, **c)
    kw = dict(noise=noise, baseline=baseline, budget=BudgetSpec.none(), seed=3)
    mc = fit_bayes(tr, ModelSpec(tip), **kw)
    ex = fit_bayes(tr, ModelSpec(tip), engine="exact", **kw)
    assert mc.diagnostics.converged and ex.converged
    az = import_arviz()
    for name in ("E_star", "z_surf"):
        a, b = mc.draws(name), ex.draws(name)
        mcse = float(az.mcse(mc.idata, var_names=[name])[name])
        mcse_exact = b.std() / np.sqrt(b.size)
        assert abs(a.mean() - b.mean()) < 4 * np.hypot(mcse, mcse_exact), name
        # sd: emcee's ESS >= 400 gives its sd a relative MC error of <= ~4 %
        assert b.std() == pytest.approx(a.std(), rel=0.12), name
    assert ex.idata.posterior.attrs["engine"] == "exact"


@pytest.mark.slow
def test_exact_intervals_cover_the_truth_at_the_nominal_rate():
    """200 traces (random tip, modulus, offset, surface): the 90 % intervals of E* and z_surf
    cover the truth 84-96 % of the time (binomial 99 % range at n = 200)."""
    rng = np.random.default_rng(2026)
    hits = {"E_star": 0, "z_surf": 0}
    n = 200
    for i in range(n):
        kind = ("flat", "sphere", "paraboloid")[i % 3]
        tip = PAPER_TIPS[kind]
        E = float(np.exp(rng.uniform(np.log(5e4), np.log(3e5))))
        z0 = 0.1 + rng.uniform(-1e-3, 1e-3)
        tr = simulate_trace(E, tip, depth=2e-3, z_surf=z0,
                            force_offset=float(rng.normal(0, 0.05)), rng=rng)
        data = prepare_trace(tr, ModelSpec(tip, nu=0.3))
        post = exact_posterior(data, PriorSpec().for_trace(data, "gaussian"))
        es, zs = post.estar_summary(), post.z_summary()
        hits["E_star"] += es.lo <= E / (1 - 0.3**2) <= es.hi
        hits["z_surf"] += zs.lo <= tr.metadata["z_surf_true"] <= zs.hi
    for name, k in hits.items():
        assert 0.84 <= k / n <= 0.96, (name, k / n)


def test_exact_engine_refuses_what_it_does_not_model():
    tip = Tip("paraboloid", radius=0.0117)
    tr = simulate_trace(1e5, tip, depth=3e-3, rng=1)
    with pytest.raises(InputError, match="Student|student|emcee"):
        fit_bayes(tr, engine="exact", noise="student")
    with pytest.raises(InputError, match="soft"):
        fit_bayes(tr, engine="exact", priors=PriorSpec(surface="soft"))
    with pytest.raises(InputError, match="engine"):
        fit_bayes(tr, engine="hmc")


def test_exact_engine_flags_a_posterior_at_the_prior_bound():
    """A prior range that ends below the true E* puts the posterior on its bound: the exact
    engine's result carries the same flag as emcee's and is not reported as converged."""
    tip = PAPER_TIPS["paraboloid"]
    tr = simulate_trace(1.4e5, tip, depth=3e-3, rng=4)
    with pytest.warns(ConvergenceWarning, match="upper prior bound"):
        res = fit_bayes(tr, engine="exact", budget=BudgetSpec.none(),
                        priors=PriorSpec(Estar_bounds=(1.0, 1.3e5)))
    assert any("E* posterior at its upper prior bound" in w for w in res.warnings), res.warnings
    assert not res.converged
