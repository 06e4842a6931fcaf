"""Tests of palpbayes.checks: the model-adequacy checks, their calibration and their flags.

Fits here are a plain least squares F = E*·s(z_surf - z) + F0 (grid then Brent over z_surf,
E* and F0 linear), i.e. what the paper's method finds without its surface constraint; posterior
draws for the posterior-predictive check come from the Laplace (Gaussian) approximation around
it.  Seeds are fixed, so every rate below is deterministic.

Measured with the slow test's seeds (40 per tip and noise model, 240 traces at the paper's
8 mN noise, 3,840 points): 2 traces flagged in all (0.8 %): sphere iid 1/40 (ppc), sphere AR(1)
phi = 0.7 1/40 (residual_structure and ppc); paraboloid and flat 0/40 with either noise.  An
independent set of seeds gave 1/40 per cell (residual_structure, with ppc under AR(1)).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import optimize

from palpbayes import checks as C
from palpbayes.contact import Tip
from palpbayes.errors import InputError
from palpbayes.fitdata import ModelSpec
from palpbayes.sim import ar1_noise, simulate_trace

E_WHITE = 111e3
TIPS = {
    "paraboloid": Tip("paraboloid", radius=0.0117),
    "sphere": Tip("sphere", radius=0.01),
    "flat": Tip("flat", radius=0.01),
    "cone": Tip("cone", half_angle=math.radians(70)),
}


# ----------------------------------------------------------------------------- helpers


def _fit(z, f, model):
    """Least squares over z_surf with E*, F0 linear: returns z_surf, E*, F0, sigma."""
    def solve(zs):
        s = model.shape(zs - z)
        X = np.column_stack([s, np.ones_like(z)])
        b = np.linalg.lstsq(X, f, rcond=None)[0]
        r = f - X @ b
        return float(r @ r), b

    span = z.max() - z.min()
    grid = np.linspace(z.min() + 0.02 * span, z.max(), 400)
    g0 = grid[np.argmin([solve(g)[0] for g in grid])]
    step = grid[1] - grid[0]
    zs = optimize.minimize_scalar(lambda x: solve(x)[0], bounds=(g0 - step, g0 + step),
                                  method="bounded", options={"xatol": 1e-10}).x
    rss, b = solve(zs)
    return {"z_surf": float(zs), "estar": float(b[0]), "f0": float(b[1]),
            "sigma": math.sqrt(rss / (z.size - 3))}


def _laplace_draws(z, model, p, phi, rng, n=200):
    """Gaussian approximation of the posterior of (z_surf, E*, F0, sigma[, phi])."""
    zs, es = p["z_surf"], p["estar"]
    J = np.column_stack([es * model.shape_derivative(zs - z), model.shape(zs - z),
                         np.ones_like(z)])
    sc = np.sqrt((J**2).sum(0))
    cov = (np.linalg.inv((J / sc).T @ (J / sc)) / np.outer(sc, sc) * p["sigma"] ** 2
           * (1 + phi) / (1 - phi))
    th = rng.multivariate_normal([zs, es, p["f0"]], cov, size=n)
    sig = p["sigma"] * np.sqrt(rng.chisquare(z.size - 3, n) / (z.size - 3))
    draws = {"z_surf": th[:, 0], "E_star": th[:, 1], "F0": th[:, 2], "sigma": sig}
    if phi:
        draws["phi"] = np.clip(phi + rng.normal(0, math.sqrt((1 - phi**2) / z.size), n),
                               -0.99, 0.99)
    return draws


def _case(true_tip, seed, *, fit_tip=None, phi=0.0, draws=False, **kw):
    kw.setdefault("base", None)  # a half-space unless the case says otherwise
    tr = simulate_trace(E_WHITE, TIPS[true_tip], nu=0.3, thickness=0.03, rng=seed,
                        noise_ar1=phi, **kw)
    lo = tr.loading_segment()
    z, f = lo.z, lo.force
    model = ModelSpec(TIPS[fit_tip or true_tip], nu=0.3)
    p = _fit(z, f, model)
    lag1 = C.noise_lag1(z, f, p["z_surf"])
    d = _laplace_draws(z, model, p, lag1 if phi else 0.0,
                       np.random.default_rng(seed)) if draws else None
    res = C.run_checks(z, f, model, z_surf=p["z_surf"], estar=p["estar"], f0=p["f0"],
                       sigma=p["sigma"], baseline_lag1=lag1, draws=d, rng=seed)
    return {r.name: r for r in res}, p, tr


# ----------------------------------------------------------------------------- pieces


@pytest.mark.parametrize("phi", [0.0, 0.7, -0.3])
def test_ar1_mean_variance_factor(phi):
    for n in (1, 5, 50, 384):
        k = np.arange(n)
        brute = np.sum(phi ** np.abs(k[:, None] - k[None, :])) / n  # n·var(mean)/sigma²
        assert float(C.ar1_mean_variance_factor(n, phi)) == pytest.approx(brute, rel=1e-10)


@pytest.mark.parametrize("m", [1.0, 1.5, 2.0, 2.5])
@pytest.mark.parametrize("baseline", ["constant", "linear"])
def test_free_exponent_fit_recovers_noise_free_power_law(m, baseline):
    z = np.linspace(0.104, 0.097, 3000)
    zs, k, f0, f1 = 0.1003, 2.0e4 * 1e-3 ** (1.5 - m), 0.03, (0.5 if baseline == "linear"
                                                                  else 0.0)
    f = k * np.maximum(zs - z, 0) ** m + f0 + f1 * (z - z.max())
    fit = C.free_exponent_fit(z, f, zs - 2e-5, baseline=baseline, m0=1.5)
    assert fit["m"] == pytest.approx(m, abs=1e-6)
    assert fit["z_surf"] == pytest.approx(zs, abs=1e-10)
    assert fit["k"] == pytest.approx(k, rel=1e-5)
    assert fit["F0"] == pytest.approx(f0, abs=1e-8)
    assert fit["F1"] == pytest.approx(f1, abs=1e-6)
    assert fit["rss"] < 1e-16


def test_law_exponent():
    z = np.linspace(0.101, 0.097, 3200)
    assert C.law_exponent(ModelSpec(TIPS["paraboloid"]), z, 0.1) == 1.5
    assert C.law_exponent(ModelSpec(TIPS["cone"]), z, 0.1) == 2.0
    # exact sphere at d/R = 0.3: softer than Hertz at depth, so a free fit finds m < 1.5
    m_sph = C.law_exponent(ModelSpec(TIPS["sphere"]), z, 0.1)
    assert 1.44 < m_sph < 1.49
    # and a thickness-corrected paraboloid (chi = 0.2 at 3 mm) stiffens: m > 1.5
    m_th = C.law_exponent(ModelSpec(TIPS["paraboloid"], thickness=0.03, bonding="bonded"), z,
                          0.1)
    assert 1.55 < m_th < 1.7


def test_binned_chi2_matches_its_reference_distribution():
    """Pure AR(1) noise as residuals: the AR(1)-aware chi² has mean ~ its degrees of freedom."""
    rng = np.random.default_rng(3)
    z = np.linspace(0.101, 0.097, 3840)
    for phi in (0.0, 0.7):
        chi2 = []
        for _ in range(200):
            e = ar1_noise(z.size, 8e-3, phi, rng.standard_normal(z.size))
            chi2.append(float(C.binned_residuals(z, e, 0.1, 8e-3, phi=phi)["chi2"]))
        dof = 15  # 10 contact + 5 pre-contact bins
        assert np.mean(chi2) == pytest.approx(dof, abs=4 * math.sqrt(2 * dof / 200) + 0.3)


def test_input_errors():
    z = np.linspace(0.101, 0.097, 100)
    with pytest.raises(InputError, match="length"):
        C.residual_structure_check(z, np.zeros(99), 0.1, 8e-3)
    with pytest.raises(InputError, match="20 samples"):
        C.free_exponent_fit(z[:10], z[:10], 0.1)
    with pytest.raises(InputError, match="sigma"):
        C.residual_structure_check(z, np.zeros(100), 0.1, 0.0)
    with pytest.raises(InputError, match="baseline"):
        C.free_exponent_fit(z, np.maximum(0.1 - z, 0), 0.1, baseline="quadratic")


# ----------------------------------------------------------------------------- false alarms


def _false_alarms(n_seeds):
    counts = {}
    for i, tip in enumerate(("paraboloid", "sphere", "flat")):
        for phi in (0.0, 0.7):
            n_fail = 0
            for seed in range(n_seeds):
                res, _, _ = _case(tip, 10_000 * (i + 1) + seed, phi=phi, draws=True)
                n_fail += any(not r.passed for r in res.values())
            counts[(tip, phi)] = n_fail
    return counts


def test_correct_models_rarely_flag():
    counts = _false_alarms(5)  # 30 traces
    assert sum(counts.values()) <= 2, counts


@pytest.mark.slow
def test_false_alarm_rate_40_seeds():
    """40 seeds per tip and noise model: at most 2 flagged traces (5 %) in each cell."""
    counts = _false_alarms(40)
    assert all(c <= 2 for c in counts.values()), counts


# ----------------------------------------------------------------------------- detection


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_finite_thickness_detected(seed):
    """Paraboloid R = 11.7 mm, 3 mm into a 30 mm bonded layer, fitted as a half-space."""
    res, p, tr = _case("paraboloid", seed, base="bonded")
    assert p["estar"] / tr.metadata["Estar_true"] > 1.2  # the bias the checks must explain
    named = [r for r in (res["exponent"], res["depth_consistency"])
             if not r.passed and "finite thickness" in r.flag]
    assert named, [r.flag for r in res.values()]
    assert res["exponent"].details["delta_m"] > 0.05
    assert res["depth_consistency"].statistic < 0.95


@pytest.mark.parametrize("seed", [1, 2])
def test_cone_fitted_as_paraboloid_names_wrong_tip(seed):
    res, _, _ = _case("cone", seed, fit_tip="paraboloid")
    ex = res["exponent"]
    assert not ex.passed
    assert ex.statistic == pytest.approx(2.0, abs=0.05)
    assert ex.flag.index("wrong tip") < ex.flag.index("finite thickness")
    assert "cone" in ex.flag


@pytest.mark.parametrize("phi", [0.0, 0.7])
@pytest.mark.parametrize("seed", [1, 2])
def test_gradual_onset_named(seed, phi):
    res, _, _ = _case("paraboloid", seed, phi=phi, onset_force=0.02, onset_length=0.2e-3)
    rs = res["residual_structure"]
    assert not rs.passed and "onset" in rs.flag and rs.details["pattern"] == "onset"


def test_adhesion_named():
    res, _, _ = _case("paraboloid", 4, onset_force=-0.02, onset_length=0.1e-3)
    rs = res["residual_structure"]
    assert not rs.passed and "adhesion" in rs.flag


@pytest.mark.parametrize("drift", [0.01, -0.01, 0.005])
@pytest.mark.parametrize("seed", [1, 2])
def test_drift_named(seed, drift):
    """Linear drift [N/s] (0.5-1 × the sensor's 48 mN p-p over the trace), constant baseline."""
    res, _, _ = _case("paraboloid", seed, drift=drift)
    rs = res["residual_structure"]
    assert not rs.passed and "drift" in rs.flag and rs.details["pattern"] == "drift"


def test_ppc_fails_for_wrong_law_passes_for_right_one():
    good, _, _ = _case("paraboloid", 7, draws=True)
    assert good["ppc"].passed and good["ppc"].statistic > 0.01
    bad, _, _ = _case("paraboloid", 7, draws=True, base="bonded")
    assert not bad["ppc"].passed and bad["ppc"].statistic < 0.01
    assert "posterior-predictive" in bad["ppc"].flag


def test_run_checks_on_16000_points():
    """A long trace passes every check (timing: benchmarks/bench_real.py)."""
    tr = simulate_trace(E_WHITE, TIPS["sphere"], nu=0.3, thickness=0.03, rng=1, rate=3333.3,
                        base=None)
    lo = tr.loading_segment()
    z, f = lo.z, lo.force
    assert z.size == 16000
    model = ModelSpec(TIPS["sphere"], nu=0.3)
    p = _fit(z, f, model)
    draws = _laplace_draws(z, model, p, 0.0, np.random.default_rng(0))
    kw = dict(z_surf=p["z_surf"], estar=p["estar"], f0=p["f0"], sigma=p["sigma"])
    res = C.run_checks(z, f, model, draws=draws, rng=0, **kw)
    assert [r.name for r in res] == ["exponent", "residual_structure", "depth_consistency",
                                     "ppc"]
    assert all(r.passed for r in res), [r.flag for r in res]
