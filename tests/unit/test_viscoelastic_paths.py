"""The fast paths of the hereditary integral (contact/hereditary_steps.py, contact/ting_rule.py)
against their plain forms: the blocked scan against the step-by-step recursion, and every
path of hereditary_contact (blocked scan or one scaled cumulative sum, one block of terms or
several, Ting's exponentials as products of cumulative products or directly, 4 or 12
Gauss-Legendre points in the partial step) giving the same force and t1 to rounding."""

from __future__ import annotations

import numpy as np
import pytest

from palpbayes.contact import hereditary_steps, ting_rule, viscoelastic
from palpbayes.contact.hereditary_steps import scan_ordered
from palpbayes.contact.viscoelastic import (
    PowerLawKernel,
    PronyKernel,
    hereditary_contact,
    standard_linear_solid,
)

C_PARA = 4 * np.sqrt(0.01) / (3 * (1 - 0.3**2))


@pytest.mark.parametrize("n", [1, 2, 3, 7, 64, 1000, 4097])
def test_blocked_scan_is_the_recursion(n):
    """H_i = decay_i·H_(i-1) + inc_i from 0, decays from 1e-300 to 1, two streams at once."""
    rng = np.random.default_rng(n)
    decay = np.exp(-rng.choice([0.0, 1e-6, 0.3, 5.0, 700.0], size=(3, n)) * rng.random((3, n)))
    inc = rng.normal(size=(2, 3, n))
    ref, h = np.empty_like(inc), np.zeros((2, 3))
    for i in range(n):
        h = decay[:, i] * h + inc[..., i]
        ref[..., i] = h
    scale = np.abs(inc).sum(axis=-1, keepdims=True)
    np.testing.assert_allclose(scan_ordered(decay, inc), ref, rtol=0, atol=1e-14 * scale.max())


def _noisy_cycle(n=1500, seed=3):
    """800 Hz with ±30 % jitter: approach to 2 mm, a hold creeping 20 um deeper with 1 um noise
    (many running maxima with few rows below each), a retract to 0.5 mm above the surface."""
    rng = np.random.default_rng(seed)
    t = np.concatenate([[0.0], np.cumsum(rng.uniform(0.7, 1.3, n - 1) / 800.0)])
    d = np.interp(t / t[-1], [0.0, 0.4, 0.65, 1.0], [-0.1e-3, 2e-3, 2.02e-3, -0.5e-3])
    hold = (t / t[-1] > 0.4) & (t / t[-1] < 0.65)
    return t, d + np.where(hold, rng.normal(0.0, 1e-6, n), 0.0)


PATHS = {  # module, name, value
    "blocked scan": [(viscoelastic, "_FEW", 0)],
    "blocks of 3 terms": [(viscoelastic, "_FEW", 0), (viscoelastic, "_CHUNK", 3 * 1500)],
    "Ting direct": [(ting_rule, "_FACTOR_ROWS", 0)],
    "Ting factored": [(ting_rule, "_FACTOR_ROWS", 10**9)],
    "12 points": [(ting_rule, "_Q_FEW", 0.0)],
}


@pytest.mark.parametrize("path", list(PATHS))
@pytest.mark.parametrize("kernel, m", [
    (standard_linear_solid(5e4, 5e4, 0.5), 1.5),
    (PronyKernel(2e4, (3e4, 3e4, 3e4), (0.05, 0.5, 5.0)), 2.0),
    (PowerLawKernel(1e5, 0.3), 1.5),
    (PowerLawKernel(8e4, 0.7, 0.1), 1.0),
], ids=["sls", "prony3", "power-0.3", "power-0.7-m1"])
def test_every_path_gives_the_same_force(kernel, m, path, monkeypatch):
    t, d = _noisy_cycle()
    ref = hereditary_contact(t, d, C_PARA, m, kernel)
    kmax = np.maximum.accumulate(np.where(d == np.maximum.accumulate(d), np.arange(t.size), 0))
    groups, rows = np.unique(kmax[ref.ting], return_counts=True)
    assert groups.size > 20 and rows.max() > 500  # many maxima, one (the retract's) with most rows
    for module, name, value in PATHS[path]:
        monkeypatch.setattr(module, name, value)
    res = hereditary_contact(t, d, C_PARA, m, kernel)
    np.testing.assert_array_equal(np.isnan(res.t1), np.isnan(ref.t1))
    np.testing.assert_allclose(res.t1, ref.t1, rtol=0, atol=1e-12 * t[-1])
    np.testing.assert_allclose(res.force, ref.force, rtol=0, atol=1e-11 * ref.force.max())


def test_exp_steps_writes_into_the_given_buffers():
    """The layout copy of the steps (empty places: nothing to integrate) and out= buffers give
    the same decays and increments as the plain call."""
    t, d = _noisy_cycle(200)
    st = hereditary_steps.Steps(t, d, 1.5)
    x = np.array([3e3, 40.0, 0.5, 1e-3])
    decay, iu, idd = hereditary_steps.exp_steps(x, st)
    size, blocks, place = hereditary_steps.block_layout(t.size - 1)
    out = np.full((x.size, size * blocks), np.nan), np.full((2, x.size, size * blocks), np.nan)
    got = hereditary_steps.exp_steps(x, st.placed(place, size * blocks), out)
    assert got[0] is out[0] and got[1].base is out[1] and np.all(np.isfinite(out[1]))
    for a, b in zip((decay, iu, idd), got, strict=True):
        np.testing.assert_allclose(b[:, place], a, rtol=1e-15, atol=0)
    empty = np.setdiff1d(np.arange(size * blocks), place)
    assert np.all(out[1][:, :, empty] == 0)
