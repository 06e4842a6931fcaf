"""Sufficient statistics and the closed-form conditional posterior of the exact engine."""

import numpy as np
import pytest

from palpbayes.bayes.conjugate import Gram, fixed_columns, gram, node_posterior
from palpbayes.bayes.exact import refine_grid
from palpbayes.contact import Tip
from palpbayes.fitdata import ModelSpec

MODEL = ModelSpec(Tip("paraboloid", radius=0.01))


def _data(n=400, phi=0.0, seed=0):
    rng = np.random.default_rng(seed)
    z = np.linspace(0.101, 0.098, n) + 2e-7 * rng.standard_normal(n)
    e = np.zeros(n)
    for t in range(n):
        e[t] = (phi * e[t - 1] if t else 0.0) + 0.01 * rng.standard_normal()
    F = 1.2e5 * MODEL.shape(0.1 - z) + 0.03 + e
    return z, F


@pytest.mark.parametrize("ar1", [False, True])
@pytest.mark.parametrize("linear", [False, True])
def test_sums_added_in_chunks_equal_the_sums_over_all_samples(ar1, linear):
    z, F = _data()
    u = (z - z.max()) if linear else None
    nodes = np.linspace(0.0985, 0.1008, 23)
    whole = gram(z, F, nodes, MODEL, u, ar1)
    C = fixed_columns(F, u)
    parts = Gram.empty(nodes, C.shape[1], ar1)
    for a, b in [(0, 1), (1, 37), (37, 200), (200, 201), (201, 400)]:
        parts.extend(z[a:b], C[a:b], MODEL)
    for name in ("m0", "m1", "first", "last", "n_contact"):
        a, b = getattr(whole, name), getattr(parts, name)
        if a is None:
            assert b is None
            continue
        np.testing.assert_allclose(b, a, rtol=1e-12, atol=1e-300, err_msg=name)
    # the lag-one sums against a direct computation at one node
    if ar1:
        X = np.column_stack([MODEL.shape(nodes[5] - z), C])
        np.testing.assert_allclose(whole.m1[5], X[1:].T @ X[:-1], rtol=1e-12)


@pytest.mark.parametrize("path", ["approach-retract", "starts-in-contact", "ends-in-contact"])
def test_sums_over_the_contact_span_equal_the_sums_over_every_sample(path):
    """The shape is evaluated only on the samples below a node (it is 0 above): the sums, the
    lag-one pairs across the span's ends and the first/last rows equal a direct computation
    over every sample, at every node, added whole or in chunks that start or end out of
    contact."""
    rng = np.random.default_rng(3)
    n = 300
    t = np.linspace(0.0, 1.0, n)
    z = {"approach-retract": 0.1005 - 1e-3 * np.sin(np.pi * t),
         "starts-in-contact": 0.0995 + 1e-3 * t,
         "ends-in-contact": 0.1005 - 1e-3 * t}[path] + 2e-7 * rng.standard_normal(n)
    F = 1.2e5 * MODEL.shape(0.1 - z) + 0.01 * rng.standard_normal(n)
    u = z - z.max()
    C = fixed_columns(F, u)
    nodes = np.linspace(0.0992, 0.1008, 17)
    for chunks in ([(0, n)], [(0, 10), (10, 150), (150, 151), (151, n)]):
        g = Gram.empty(nodes, C.shape[1], True)
        for a, b in chunks:
            g.extend(z[a:b], C[a:b], MODEL)
        for i, zs in enumerate(nodes):
            X = np.column_stack([MODEL.shape(zs - z), C])
            np.testing.assert_allclose(g.m0[i], X.T @ X, rtol=1e-12, atol=1e-300)
            np.testing.assert_allclose(g.m1[i], X[1:].T @ X[:-1], rtol=1e-12, atol=1e-300)
            np.testing.assert_array_equal(g.first[i], X[0])
            np.testing.assert_array_equal(g.last[i], X[-1])
            assert g.n_contact[i] == np.count_nonzero(X[:, 0] > 0)


def test_conditional_posterior_is_the_textbook_regression():
    """At fixed z_s (iid noise): centre = penalised least squares, scale = s²(XᵀX + W)⁻¹ with
    s² = S/nu, S the penalised residual sum of squares (Gelman et al. BDA3 §14.2)."""
    z, F = _data()
    node = 0.1000
    g = gram(z, F, np.array([node]), MODEL, None, False)
    w = np.array([0.25])
    c = np.array([0.02])
    post = node_posterior(g, np.zeros(1), w, c)
    X = np.column_stack([MODEL.shape(node - z), np.ones(z.size)])
    Xp = np.vstack([X, [0.0, np.sqrt(w[0])]])
    yp = np.concatenate([F, [np.sqrt(w[0]) * c[0]]])
    beta, *_ = np.linalg.lstsq(Xp, yp, rcond=None)
    S = float(np.sum((yp - Xp @ beta) ** 2))
    nu = z.size + 1 - 2
    np.testing.assert_allclose(post.beta[0, 0], beta, rtol=1e-9)
    np.testing.assert_allclose(post.S[0, 0], S, rtol=1e-7)
    np.testing.assert_allclose(post.scale[0, 0], S / nu * np.linalg.inv(Xp.T @ Xp), rtol=1e-7)
    assert post.nu == nu


def test_marginal_of_the_surface_matches_brute_force_integration():
    """log p(z_s | data) differences between nodes equal a direct numerical integration of
    the likelihood over E* (flat), F0 and tau on a grid: the closed form is right, constants
    included.  Prior: Jeffreys 1/tau, and F0 | tau ~ N(0, tau²/w) with w -> 0, whose density
    is ∝ 1/tau there (the conjugate form the engine uses)."""
    z, F = _data(n=120)
    nodes = np.array([0.09995, 0.1, 0.10003])
    g = gram(z, F, nodes, MODEL, None, False)
    lp = node_posterior(g, np.zeros(1), np.array([1e-12]), np.zeros(1)).logp[:, 0]
    brute = []
    for zs in nodes:
        X = np.column_stack([MODEL.shape(zs - z), np.ones(z.size)])
        beta, *_ = np.linalg.lstsq(X, F, rcond=None)
        cov = np.linalg.inv(X.T @ X) * np.sum((F - X @ beta) ** 2) / (z.size - 2)
        sd = np.sqrt(np.diag(cov))
        e = beta[0] + sd[0] * np.linspace(-9, 9, 61)
        f0 = beta[1] + sd[1] * np.linspace(-9, 9, 61)
        s_hat = np.sqrt(np.sum((F - X @ beta) ** 2) / z.size)
        tau = s_hat * np.exp(np.linspace(-0.6, 0.6, 81))
        E, F0, T = np.meshgrid(e, f0, tau, indexing="ij")
        r = F[None, None, None, :] - (E[..., None] * X[:, 0] + F0[..., None])
        ll = -z.size * np.log(T) - 0.5 * np.sum(r * r, axis=-1) / T**2 - 2 * np.log(T)
        m = ll.max()
        dens = np.exp(ll - m)
        integral = np.trapezoid(np.trapezoid(np.trapezoid(dens, tau, axis=2), f0, axis=1), e)
        brute.append(m + np.log(integral))
    brute = np.array(brute)
    # a tiny pseudo-weight: its constant (½·ln w) cancels in the differences
    np.testing.assert_allclose(lp - lp[1], brute - brute[1], atol=2e-3)


def test_refinement_resolves_every_mode_of_a_two_peaked_density():
    # the narrow mode spans a fraction of a coarse step (1/128) but shows at its neighbours
    centres, sds = (0.2003, 0.7), (1e-3, 3e-3)

    def logp(x):
        return np.logaddexp(-0.5 * ((x - centres[0]) / sds[0]) ** 2 - np.log(sds[0]),
                            -0.5 * ((x - centres[1]) / sds[1]) ** 2 - np.log(sds[1]))

    nodes, lp, complete = refine_grid(0.0, 1.0, logp, coarse=129)
    assert complete
    w = np.exp(lp - lp.max()) * np.gradient(nodes)
    w /= w.sum()
    # both modes hold half of the mass, and each is resolved (spacing <= its sd near its centre)
    assert w[nodes < 0.45].sum() == pytest.approx(0.5, abs=0.01)
    for c, s in zip(centres, sds, strict=True):
        near = nodes[np.abs(nodes - c) < s]
        assert near.size >= 3
        assert np.diff(near).max() <= 1.1 * s
