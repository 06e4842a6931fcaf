"""The correlated-background model of the lump posterior (palpbayes.active.background)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from scipy.special import logsumexp

from palpbayes.active import SearchState
from palpbayes.active.background import correlation
from palpbayes.active.criteria import eig, predictive
from palpbayes.active.posterior import hypotheses, posterior
from palpbayes.errors import InputError
from palpbayes.sim.phantom import MapPhantom

FP = (0.0, 0.012, 0.0, 0.012)
A, H = 4.8e-3, 0.02


def _presses(n: int, seed: int = 0, field: float = 0.03):
    rng = np.random.default_rng(seed)
    x, y = rng.uniform(0.0, 0.012, (2, n))
    ph = MapPhantom(field_sd=field, field_length=5e-3, seed=seed)
    s = rng.uniform(0.006, 0.015, n)
    m = 10.8 + ph.background_field(x, y) + 0.03 * rng.standard_normal(n)
    return x, y, m, s


def _brute_lbf(hyp, x, y, m, s) -> float:
    """log Bayes factor by a dense Cholesky per grid point and every hypothesis."""
    n = m.size
    d = np.hypot(hyp.cx[:, None] - x[None, :], hyp.cy[:, None] - y[None, :])
    phi = hyp.profile(d).reshape(-1, n)  # (K N_c, n)
    D = np.hypot(x[:, None] - x[None, :], y[:, None] - y[None, :])
    l0, l1 = [], []
    for ti, tau in enumerate(hyp.taus):
        for si, sf in enumerate(hyp.sigma_fs):
            for li, ell in enumerate(hyp.ells):
                S = sf * sf * correlation(D, ell) + np.diag(s * s + tau * tau)
                Si = np.linalg.inv(S)
                one = np.ones(n)
                s0 = one @ Si @ one
                c = (-0.5 * np.linalg.slogdet(S)[1] - 0.5 * (n - 1) * math.log(2 * math.pi)
                     - 0.5 * math.log(s0) + hyp.log_tau_prior[ti]
                     + hyp.log_field_prior[si, li])
                r = m[None, None, :] - hyp.betas[None, :, None] * phi[:, None, :]
                q = (np.einsum("hbi,ij,hbj->hb", r, Si, r)
                     - (np.einsum("hbi,i->hb", r, Si @ one)) ** 2 / s0)
                l1.append(logsumexp(c - 0.5 * q) - math.log(q.size))
                l0.append(c - 0.5 * (m @ Si @ m - (one @ Si @ m) ** 2 / s0))
    return float(logsumexp(l1) - logsumexp(l0))


def test_correlated_posterior_is_the_dense_marginal_likelihood():
    hyp = hypotheses(FP, contact_radius=A, thickness=H, resolution=3e-3,
                     background="correlated")
    x, y, m, s = _presses(9)
    post = posterior(hyp, x, y, m, s)
    assert post.log_bayes_factor == pytest.approx(_brute_lbf(hyp, x, y, m, s), abs=2e-3)
    assert post.tau_weights.sum() == pytest.approx(1.0)
    assert post.background.field_weights.sum() == pytest.approx(1.0)
    assert post.ck_weights.sum() == pytest.approx(1.0)


def test_without_a_field_the_correlated_model_is_the_white_one():
    white = hypotheses(FP, contact_radius=A, thickness=H, resolution=2e-3)
    none = dataclasses.replace(
        hypotheses(FP, contact_radius=A, thickness=H, resolution=2e-3,
                   background="correlated"),
        sigma_fs=np.array([1e-9]), ells=np.array([A]), log_field_prior=np.zeros((1, 1)))
    x, y, m, s = _presses(15, seed=3)
    m = m + 0.1 * np.exp(-((x - 0.006) ** 2 + (y - 0.005) ** 2) / 2e-3 ** 2 / 2)
    pw, pc = posterior(white, x, y, m, s), posterior(none, x, y, m, s)
    assert pc.log_bayes_factor == pytest.approx(pw.log_bayes_factor, abs=1e-4)
    np.testing.assert_allclose(pc.centre_weights, pw.centre_weights, atol=1e-5)
    np.testing.assert_allclose(pc.tau_weights, pw.tau_weights, atol=1e-6)
    # the predictive (the criteria's input) too
    qx, qy = np.array([0.002, 0.006, 0.011]), np.array([0.003, 0.005, 0.01])
    ww, mw, sw = predictive(pw, qx, qy, 0.01)
    wc, mc, sc = predictive(pc, qx, qy, 0.01)
    np.testing.assert_allclose(mc[0], mw[0], atol=1e-4)  # no lump: same mode of tau or near
    assert wc[0] == pytest.approx(ww[0], abs=1e-5)


def test_the_null_predictive_is_universal_kriging():
    hyp = hypotheses(FP, contact_radius=A, thickness=H, resolution=3e-3,
                     background="correlated")
    x, y, m, s = _presses(20, seed=5, field=0.06)
    post = posterior(hyp, x, y, m, s)
    fit = post.background.null
    qx, qy = np.array([x[0] + 1e-4, 0.006]), np.array([y[0], 0.006])
    _, mu, sd = predictive(post, qx, qy, 0.01)
    # b with a vague normal prior instead of flat: the same conditional in the limit
    pts = np.column_stack([np.r_[x, qx], np.r_[y, qy]])
    D = np.hypot(*(pts[:, None, :] - pts[None, :, :]).transpose(2, 0, 1))
    C = fit.sigma_f ** 2 * correlation(D, fit.ell) + 1e4
    C[np.diag_indices(x.size + 2)] += np.r_[s * s, 0.01 ** 2, 0.01 ** 2] + fit.tau ** 2
    n = x.size
    k = C[:n, n:]
    w = np.linalg.solve(C[:n, :n], k)
    np.testing.assert_allclose(mu[0], w.T @ m, atol=1e-4)
    np.testing.assert_allclose(sd[0] ** 2, np.diag(C[n:, n:] - k.T @ w), rtol=1e-3)
    # beside a press the field is known: the reading is expected near it, sd below the
    # background's
    assert abs(mu[0, 0] - m[0]) < abs(mu[0, 1] - m[0]) + 0.05
    assert sd[0, 0] < sd[0, 1]


def test_search_state_runs_the_correlated_model():
    x, y, m, s = _presses(12, seed=2)
    import pandas as pd

    df = pd.DataFrame({"x_m": x, "y_m": y, "logE_mean": m, "logE_sd": s})
    st = SearchState(df, FP, A, H, resolution=2e-3, background="correlated")
    post = st.posterior()
    assert post.background is not None and 0 < post.p_lump < 1
    qx, qy = st.candidates()
    score = eig(post, qx, qy, 0.01)
    assert score.shape == qx.shape and np.isfinite(score).all() and (score >= 0).all()
    with pytest.raises(InputError, match="background"):
        SearchState(df, FP, A, H, background="pink")


def test_phantom_field_is_off_by_default_and_matern_when_on():
    base = MapPhantom()
    other = MapPhantom(field_length=9e-3)  # field_sd 0: no field drawn, same presses
    np.testing.assert_array_equal(base.press(0.01, 0.02, 3).force,
                                  other.press(0.01, 0.02, 3).force)
    assert base.background_field(0.01, 0.02) == 0.0
    r = np.array([0.0, 5e-3, 20e-3])
    f = np.array([MapPhantom(field_sd=1.0, field_length=5e-3, seed=k).background_field(
        0.01 + r, 0.02) for k in range(300)])
    cov = (f * f[:, :1]).mean(axis=0)
    z = math.sqrt(2.0) * 5e-3 / 5e-3
    from scipy.special import kv

    np.testing.assert_allclose(cov, [1.0, z * kv(1, z), 0.0], atol=0.15)
    with pytest.raises(InputError, match="field_sd"):
        MapPhantom(field_sd=-0.1)


def test_state_folder_keeps_the_background(tmp_path):
    from palpbayes.active.files import init_state, read_state
    from palpbayes.errors import DataFileError

    init_state(tmp_path / "s", footprint=FP, contact_radius=A, thickness=H,
               background="correlated")
    assert read_state(tmp_path / "s").background == "correlated"
    assert read_state(tmp_path / "s", background="white").background == "white"
    with pytest.raises(DataFileError, match="background"):
        init_state(tmp_path / "t", footprint=FP, contact_radius=A, thickness=H,
                   background="pink")
