"""The lump posterior of an active search: closed forms, the profile approximation, recovery
and calibration on data drawn from its own prior."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from scipy import integrate
from scipy.special import logsumexp

from palpbayes.active.posterior import hypotheses, posterior
from palpbayes.errors import InputError
from palpbayes.inclusion import apparent_ratio, sensitivity

A = 0.004837  # the paper's paraboloid at 2 mm [m]
H = 0.02
FOOT = (0.0, 0.042, 0.0, 0.042)


@pytest.fixture(scope="module")
def hyp():
    return hypotheses(FOOT, contact_radius=A, thickness=H)


def _small(hyp):
    """A few hypotheses, to integrate by brute force."""
    taus = hyp.taus[[2, 5, 8]]
    lt = np.log(taus) - 0.5 * (taus / 0.2) ** 2
    return replace(hyp, cx=np.array([0.01, 0.02, 0.03]), cy=np.array([0.02, 0.01, 0.03]),
                   depth_profiles=hyp.depth_profiles[:, [0, 4]], fwhm=hyp.fwhm[[0, 4]],
                   radius=hyp.radius[[0, 4]], cover=hyp.cover[[0, 4]],
                   betas=hyp.betas[[1, 6, 10]], taus=taus, log_tau_prior=lt - logsumexp(lt))


def _brute_log_evidence(hyp, x, y, m, s, alt: bool) -> float:
    """log ∫ p(y | b, h) db (flat b, unit density) summed over the prior of h, by quadrature."""
    terms = []
    centre = range(hyp.cx.size) if alt else [None]
    for c in centre:
        for k in range(hyp.profiles.shape[0] if alt else 1):
            for b_i, beta in enumerate(hyp.betas if alt else [0.0]):
                del b_i
                for t, tau in enumerate(hyp.taus):
                    if alt:
                        d = np.hypot(x - hyp.cx[c], y - hyp.cy[c])
                        mu_ex = beta * np.interp(d, hyp.s_grid, hyp.profiles[k])
                    else:
                        mu_ex = 0.0
                    var = s ** 2 + tau ** 2
                    r = m - mu_ex

                    w = 1.0 / var
                    b0 = float(np.sum(w * r) / np.sum(w))

                    def logf(b, r=r, var=var):
                        return float(np.sum(-0.5 * (r - b) ** 2 / var
                                            - 0.5 * np.log(2 * math.pi * var)))

                    top = logf(b0)
                    val, _ = integrate.quad(lambda b, top=top, f=logf: math.exp(f(b) - top),
                                            b0 - 1, b0 + 1, points=[b0], epsabs=0,
                                            epsrel=1e-11, limit=200)
                    terms.append(math.log(val) + top + hyp.log_tau_prior[t])
    n_alt = (hyp.cx.size * hyp.profiles.shape[0] * hyp.betas.size) if alt else 1
    return float(logsumexp(terms)) - math.log(n_alt)


def test_bayes_factor_equals_quadrature_over_the_background(hyp):
    small = _small(hyp)
    rng = np.random.default_rng(3)
    x, y = rng.uniform(0, 0.042, 12), rng.uniform(0, 0.042, 12)
    m = np.log(5e4) + 0.05 * np.exp(-np.hypot(x - 0.02, y - 0.01) / 0.006) \
        + 0.03 * rng.standard_normal(12)
    s = rng.uniform(0.001, 0.01, 12)
    post = posterior(small, x, y, m, s)
    lbf = (_brute_log_evidence(small, x, y, m, s, True)
           - _brute_log_evidence(small, x, y, m, s, False))
    assert post.log_bayes_factor == pytest.approx(lbf, abs=1e-6)
    assert post.p_lump == pytest.approx(1.0 / (1.0 + math.exp(-lbf)), rel=1e-9)


def test_linear_profile_is_within_its_stated_error_of_the_forward_model(hyp):
    worst = {1.25: 0.0, 1.5: 0.0}
    s = hyp.s_grid[:-1]
    for k in range(hyp.profiles.shape[0]):
        r, c = hyp.radius[k], hyp.cover[k]
        V = sensitivity(s, radius=r, depth=r + c, contact_radius=A, thickness=H)
        for amp in np.linspace(1.03, 1.5, 25):
            g = (1 - 1 / amp) / V[0]
            if g >= 1:  # this sphere cannot look that stiff
                continue
            err = np.abs(-np.log1p(-g * V) - math.log(amp) * hyp.profiles[k][:-1]).max()
            for cap in worst:
                if amp <= cap:
                    worst[cap] = max(worst[cap], err / math.log(amp))
    assert worst[1.25] <= 0.015
    assert worst[1.5] <= 0.035
    assert worst[1.5] > 0.005  # the approximation is not exact: the bound means something


def test_profiles_are_one_at_the_centre_and_fall_to_zero(hyp):
    assert np.allclose(hyp.profiles[:, 0], 1.0)
    assert np.all(hyp.profiles[:, -1] == 0.0)
    assert np.all(np.diff(hyp.profiles, axis=1) <= 1e-12)
    d = np.array([0.0, 0.5 * hyp.fwhm[0], 1.0])
    phi = hyp.profile(d)
    assert phi[0, 0] == pytest.approx(1.0)
    assert phi[0, 1] == pytest.approx(0.5, abs=0.01)
    assert phi[0, 2] == 0.0


def _presses(rng, n, lump, tau=0.03):
    x, y = rng.uniform(0, 0.042, n), rng.uniform(0, 0.042, n)
    if lump is None:
        m = np.log(5e4) + tau * rng.standard_normal(n)
    else:
        cx, cy, depth = lump
        V = sensitivity(np.hypot(x - cx, y - cy), radius=5e-3, depth=depth,
                        contact_radius=A, thickness=H)
        m = np.log(5e4 * apparent_ratio(V, 10.0)) + tau * rng.standard_normal(n)
    return x, y, m, np.full(n, 0.0015)


def test_finds_a_shallow_lump_and_its_centre(hyp):
    rng = np.random.default_rng(11)
    x, y, m, s = _presses(rng, 120, (0.017, 0.026, 5.5e-3))
    post = posterior(hyp, x, y, m, s)
    assert post.p_lump > 0.999
    cx, cy = post.centre
    assert math.hypot(cx - 0.017, cy - 0.026) <= post.centre_radius(0.9)
    assert post.centre_radius(0.9) < 2.5e-3
    assert 1.1 < post.apparent_ratio < 1.3  # forward model: 1.18 at 5.5 mm
    assert 0.008 < post.size < 0.016  # apparent FWHM 10.4 mm
    assert 0.02 < post.tau < 0.045


def test_a_homogeneous_block_lowers_p_lump(hyp):
    rng = np.random.default_rng(12)
    x, y, m, s = _presses(rng, 150, None)
    post = posterior(hyp, x, y, m, s)
    assert post.p_lump < 0.2
    # the same presses over a lump's signature raise it
    x2, y2, m2, s2 = _presses(np.random.default_rng(12), 150, (0.02, 0.02, 6e-3))
    assert posterior(hyp, x2, y2, m2, s2).p_lump > 0.99


@pytest.mark.parametrize("bad", [
    dict(x=[0.01], y=[0.01, 0.02], mean=[1.0], sd=[0.1]),
    dict(x=[np.nan], y=[0.01], mean=[1.0], sd=[0.1]),
    dict(x=[0.01], y=[0.01], mean=[1.0], sd=[0.0]),
    dict(x=[], y=[], mean=[], sd=[]),
])
def test_bad_presses_are_refused(hyp, bad):
    with pytest.raises(InputError, match="presses"):
        posterior(hyp, **bad)


def test_bad_grid_options_are_refused():
    with pytest.raises(InputError, match="footprint"):
        hypotheses((0, 0, 0, 1), contact_radius=A, thickness=H)
    with pytest.raises(InputError, match="min_excess"):
        hypotheses(FOOT, contact_radius=A, thickness=H, min_excess=0.5, max_ratio=1.2)
    with pytest.raises(InputError, match="too thin"):
        hypotheses(FOOT, contact_radius=A, thickness=1e-3)


@pytest.mark.slow
def test_p_lump_and_the_centre_disc_are_calibrated_on_data_from_the_prior(hyp):
    """Draw (lump or not, centre, sphere, beta, tau) from the grid prior, presses at random
    positions from the model itself, and check that P(lump) is calibrated (Brier score and
    bins) and that the 90 % centre disc covers the true centre 90 % of the time."""
    rng = np.random.default_rng(2026)
    probs, truth, covered = [], [], []
    tau_p = np.exp(hyp.log_tau_prior)
    for _ in range(300):
        n = int(rng.integers(20, 80))
        x, y = rng.uniform(0, 0.042, n), rng.uniform(0, 0.042, n)
        tau = hyp.taus[rng.choice(tau_p.size, p=tau_p)]
        lump = rng.random() < 0.5
        mean = 10.0 + tau * rng.standard_normal(n)
        if lump:
            c = int(rng.integers(hyp.cx.size))
            k = int(rng.integers(hyp.profiles.shape[0]))
            beta = hyp.betas[rng.integers(hyp.betas.size)]
            mean += beta * hyp.profile(np.hypot(x - hyp.cx[c], y - hyp.cy[c]))[k]
        s = np.full(n, 0.002)
        mean += s * rng.standard_normal(n)
        post = posterior(hyp, x, y, mean, s)
        probs.append(post.p_lump)
        truth.append(lump)
        if lump:  # the disc is a statement given a lump: calibrated over every lump
            cx, cy = post.centre
            covered.append(math.hypot(cx - hyp.cx[c], cy - hyp.cy[c])
                           <= post.centre_radius(0.9))
    p, t = np.array(probs), np.array(truth, dtype=float)
    # calibration in bins: the mean prediction within 2.5 binomial sd of the frequency
    for lo, hi in ((0.0, 0.05), (0.05, 0.5), (0.5, 0.95), (0.95, 1.0)):
        sel = (p >= lo) & (p < hi) if hi < 1 else (p >= lo)
        if sel.sum() < 15:
            continue
        f, q = t[sel].mean(), p[sel].mean()
        sd = math.sqrt(max(q * (1 - q), 0.01) / sel.sum())
        assert abs(f - q) <= 2.5 * sd + 0.01, (lo, hi, f, q, sel.sum())
    wrong = ((p >= 0.95) & (t == 0)).sum() + ((p <= 0.05) & (t == 1)).sum()
    assert wrong <= 0.05 * ((p >= 0.95) | (p <= 0.05)).sum() + 2
    cov = np.mean(covered)
    print(f"decided {((p >= 0.95) | (p <= 0.05)).sum()}, wrong {wrong}; centre discs "
          f"{len(covered)}, coverage {cov:.3f}")
    assert len(covered) >= 120
    assert 0.85 <= cov <= 0.95, cov
