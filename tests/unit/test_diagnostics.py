"""Convergence figures (palpbayes.bayes.diagnostics)."""

from __future__ import annotations

import math

import numpy as np

from palpbayes.bayes.diagnostics import (
    ESS_MIN,
    RHAT_MAX,
    Diagnostics,
    chain_passes,
    ess_bulk,
    rhat,
)


def _diag(rhat: dict) -> Diagnostics:
    names = list(rhat)
    return Diagnostics(rhat=rhat, ess_bulk=dict.fromkeys(names, 4000.0),
                       ess_tail=dict.fromkeys(names, 4000.0), tau=dict.fromkeys(names, 1.0),
                       acceptance=1.0, n_steps=4000, hit_cap=False)


def test_an_undefined_rhat_is_not_converged_wherever_it_stands():
    """A NaN R-hat makes the fit not converged, first or last among the parameters (the
    builtin max skipped a NaN unless it came first)."""
    assert _diag({"E_star": 1.001, "z_surf": 1.002}).converged
    for r in ({"E_star": math.nan, "z_surf": 1.0}, {"E_star": 1.0, "z_surf": math.nan}):
        d = _diag(r)
        assert math.isnan(d.rhat_max) and not d.converged
        assert d.problems() and "R-hat" in d.problems()[0]


def test_rhat_is_a_guard_at_1_05_not_the_stop():
    """Issue 59: an ensemble's walkers are not independent chains, so R-hat is flagged above
    1.05 (not Vehtari's 1.01); the fit's figures are its ESS and the sampler's own rule."""
    assert _diag({"E_star": 1.03, "z_surf": 1.049, "lp": 1.04}).converged
    d = _diag({"E_star": 1.02, "z_surf": 1.06})
    assert not d.converged and d.problems() == ["R-hat 1.0600 > 1.05 (z_surf)"]


def _ar1(rng, walkers: int, draws: int, phi: float) -> np.ndarray:
    x = np.empty((walkers, draws))
    x[:, 0] = rng.normal(size=walkers)
    e = rng.normal(scale=np.sqrt(1 - phi**2), size=(walkers, draws))
    for t in range(1, draws):
        x[:, t] = phi * x[:, t - 1] + e[:, t]
    return x


def test_chain_passes_on_ess_with_rhat_as_guard():
    """Mixed chains with ESS >= 400 pass; too few draws fail on the ESS; a walker that lags
    in the log posterior fails on its R-hat however well the parameters mix."""
    rng = np.random.default_rng(59)
    chain = np.stack([_ar1(rng, 32, 300, 0.5), _ar1(rng, 32, 300, 0.5)], axis=-1)
    lp = -0.5 * np.sum(chain**2, axis=-1)
    assert chain_passes(chain, lp)
    assert float(ess_bulk(chain[..., 0])) > ESS_MIN
    assert not chain_passes(chain[:4, :40], lp[:4, :40])  # 160 draws: ESS < 400
    stuck = lp.copy()
    stuck[0] -= 50.0  # one walker far below the rest, its parameters as the others'
    assert float(rhat(stuck)) > RHAT_MAX and not chain_passes(chain, stuck)
