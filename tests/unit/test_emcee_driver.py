"""The emcee driver's burn-in repair (palpbayes.bayes.sampler): walkers stuck far below the
ensemble are found by their log posterior, moved onto the others and the chain restarted;
a healthy ensemble is left alone."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.special import logsumexp

from palpbayes.bayes import sampler as sampler_module
from palpbayes.bayes.sampler import SamplerSettings, run_emcee, stuck_walkers

SETTINGS = SamplerSettings(n_walkers=16, max_steps=6000, min_steps=500, check_every=100,
                           progress=False)


def _two_modes(theta: np.ndarray) -> np.ndarray:
    """N(0, I) in 2-D, plus a mode at (30, 30) with sd 0.3 and mass e^-50: a walker started
    there proposes jumps of the ensemble's spread (~1) and none lands inside."""
    main = -0.5 * np.sum(theta**2, axis=1)
    far = -50.0 - 0.5 * np.sum(((theta - 30.0) / 0.3) ** 2, axis=1) - 2 * np.log(0.3)
    return logsumexp(np.stack([main, far]), axis=0)


def _start(seed: int) -> np.ndarray:
    p0 = np.random.default_rng(seed).normal(size=(16, 2))
    p0[3] = 30.0  # one walker on the far mode
    return p0


def test_chi2_rule_flags_the_outlier_and_spares_a_healthy_ensemble():
    rng = np.random.default_rng(0)
    ndim, flagged = 5, 0
    for _ in range(2000):  # healthy: lp = -chi2_ndim / 2 over 100 steps of 32 walkers
        lp = -0.5 * rng.chisquare(ndim, size=(100, 32))
        flagged += int(stuck_walkers(lp, ndim).sum())
    assert flagged == 0
    lp = -0.5 * rng.chisquare(ndim, size=(100, 32))
    lp[:, [4, 9]] -= 90.0
    assert np.flatnonzero(stuck_walkers(lp, ndim)).tolist() == [4, 9]
    # with the chain: walker 4 sits still (stuck), walker 9 moves as often as the others do
    # (a broad mode of its own, low in density): only 4 is moved
    chain = np.cumsum(rng.normal(size=(100, 32, ndim)) * (rng.random((100, 32, 1)) < 0.2),
                      axis=0)
    chain[:, 4] = chain[0, 4]
    assert np.flatnonzero(stuck_walkers(lp, ndim, chain)).tolist() == [4]


def test_a_stuck_walker_is_moved_and_the_chain_is_plain_afterwards():
    res = run_emcee(_two_modes, _start(1), SETTINGS, seed=5)
    assert res.moved == 1 and not res.hit_cap
    x = res.samples.reshape(-1, 2)
    assert np.abs(x).max() < 6.0  # nobody left on the far mode
    np.testing.assert_allclose(x.mean(axis=0), 0.0, atol=0.1)
    np.testing.assert_allclose(x.std(axis=0), 1.0, atol=0.08)
    assert res.n_steps >= SETTINGS.min_steps + SETTINGS.check_every  # burn-in counted


def test_without_restarts_the_walker_stays_stuck(monkeypatch):
    """What the repair is for: the same run without it keeps the walker at (30, 30)."""
    monkeypatch.setattr(sampler_module, "MAX_RESTARTS", 0)
    res = run_emcee(_two_modes, _start(1), SETTINGS, seed=5)
    assert res.moved == 0
    assert np.all(np.abs(res.samples[3] - 30.0) < 2.0)  # the chain keeps a wrong walker


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_healthy_ensemble_is_not_touched(seed):
    p0 = np.random.default_rng(seed).normal(scale=3.0, size=(16, 2))
    res = run_emcee(lambda th: -0.5 * np.sum(th**2, axis=1), p0, SETTINGS, seed=seed)
    assert res.moved == 0 and not res.hit_cap


@pytest.mark.parametrize("max_steps", [500, 800, 1100])
def test_no_restart_without_the_budget_for_a_whole_chain(max_steps):
    """A stuck walker found when fewer than min_steps + check_every steps would be left: no
    restart (the run goes on as before the repair: here the stuck walker's chain passes the
    tau rule, which is why fits add the R-hat test), and never a crash or an unchecked chain."""
    settings = SamplerSettings(n_walkers=16, max_steps=max_steps, min_steps=500,
                               check_every=100, progress=False)
    res = run_emcee(_two_modes, _start(1), settings, seed=5)
    assert res.n_steps <= max_steps and res.samples.shape[1] >= 10
    assert res.moved <= (1 if max_steps >= 500 + 500 + 100 else 0)
