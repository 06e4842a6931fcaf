"""Effect sizes and severity of the model checks (palpbayes.checks.effect).

A failed check says how much its failure moves E; it is material when that exceeds 2 % and the
statistical interval's half width, negligible otherwise, and ``model_ok`` follows material
misfit.  Checked against closed forms (a noise-free power law, the window ratio), against the
E that a refit with the alternative model gives, and on simulated misfit of known size.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from palpbayes import checks as C
from palpbayes.checks.effect import free_exponent_effect
from palpbayes.contact import Tip
from palpbayes.fitdata import ModelSpec
from palpbayes.sim import simulate_trace

PARA = Tip("paraboloid", radius=0.0117)
MODEL = ModelSpec(PARA, nu=0.3)


def _graded(true_tip: Tip, seed: int, fit_model: ModelSpec = MODEL, **kw):
    """run_checks on the least-squares fit (E*, z_surf, F0 free) of a simulated trace."""
    kw.setdefault("base", None)
    tr = simulate_trace(111e3, true_tip, nu=0.3, thickness=0.03, rng=seed, **kw)
    lo = tr.loading_segment()
    z, f = lo.z, lo.force
    dc = C.depth_consistency_check(z, f, fit_model, tr.metadata["z_surf_true"])
    zs, es = dc.details["z_surf_all"], dc.details["estar_all"]
    s = fit_model.shape(zs - z)
    f0 = float(np.mean(f - es * s))
    sigma = float(np.std(f - es * s - f0))
    res = C.run_checks(z, f, fit_model, z_surf=zs, estar=es, f0=f0, sigma=sigma, rng=seed)
    return {c.name: c for c in res}, es, tr


def _check(name, passed, statistic=1.0, **details):
    return C.CheckResult(name, statistic, passed, "" if passed else f"{name} failed", details)


def test_free_exponent_effect_closed_form():
    """Noise-free: a free law that is the fitted law itself (k = E*·s(1 m), m = 1.5, same
    surface) has no effect whatever the offset, as long as both fits carry it; a law fit
    without the 60 mN offset (the paper's) that the free fit carries is off by exactly
    0.06 N / (E*·s(d̄)) at the mean depth; a free surface 10 µm higher changes the effect by
    (d̄ + 10 µm)^1.5/d̄^1.5 − 1."""
    z = np.linspace(0.1005, 0.097, 400)
    zs, estar = 0.1, 1.2e5
    k = estar * MODEL.shape(np.array([1.0]))[0]
    d_bar = float(np.mean(zs - z[z < zs]))
    s_bar = MODEL.shape(np.array([d_bar]))[0]
    same = _check("exponent", True, 1.5, k=k, m=1.5, z_surf_free=zs, F0=0.06)
    assert free_exponent_effect(same, z, MODEL, zs, estar, f0=0.06) == pytest.approx(0, abs=1e-6)
    assert free_exponent_effect(same, z, MODEL, zs, estar, f0=0.0) == pytest.approx(
        0.06 / (estar * s_bar), rel=1e-4)
    high = _check("exponent", True, 1.5, k=k, m=1.5, z_surf_free=zs + 1e-5, F0=0.0)
    assert free_exponent_effect(high, z, MODEL, zs, estar) == pytest.approx(
        ((d_bar + 1e-5) / d_bar) ** 1.5 - 1, rel=1e-4)
    assert math.isnan(free_exponent_effect(_check("exponent", False), z, MODEL, zs, estar))


def test_severity_follows_the_effect_and_the_interval():
    """A depth ratio of 0.96 is negligible against a 2 % limit only when the statistical
    interval is wider than 4 %; a failure whose effect cannot be sized counts as material."""
    z = np.linspace(0.1005, 0.097, 200)
    f = np.zeros_like(z)
    checks = [_check("depth_consistency", False, 0.96, estar_all=1e5, estar_all_se=100.0),
              _check("exponent", True, 1.5)]
    tight = C.grade_checks(checks, z, f, MODEL, z_surf=0.1, estar=1e5, stat_rel_halfwidth=0.01)
    wide = C.grade_checks(checks, z, f, MODEL, z_surf=0.1, estar=1e5, stat_rel_halfwidth=0.05)
    assert tight[0].details["severity"] == "material"
    assert tight[0].details["effect"] == pytest.approx(-0.04)
    assert wide[0].details["severity"] == "negligible"
    assert wide[0].details["effect_limit"] == 0.05
    assert tight[1].details["severity"] == ""  # passed
    assert C.checks_summary(tight)["model_ok"] is False
    assert C.checks_summary(tight)["misfit_effect"] == pytest.approx(-0.04)
    assert C.checks_summary(wide)["model_ok"] is True
    assert C.checks_summary(wide)["flags"][0].startswith("info: depth_consistency check")
    unsized = C.grade_checks([_check("ppc", False, 0.0)], z, f, MODEL, z_surf=0.1, estar=1e5,
                             stat_rel_halfwidth=0.01)
    assert unsized[0].details["severity"] == "material"
    assert math.isnan(C.checks_summary(unsized)["misfit_effect"])  # material, size unknown
    legacy = C.CheckResult("ppc", 0.0, False, "old flag", {})  # saved before grading
    assert C.material(legacy) and C.checks_summary([legacy])["model_ok"] is False


@pytest.mark.parametrize("seed", [1, 2])
def test_a_well_specified_curve_has_no_effect(seed):
    res, _, _ = _graded(PARA, seed)
    for c in res.values():
        assert c.passed and c.details["severity"] == ""
        assert abs(c.details["effect"]) < 0.01  # within noise of 0


@pytest.mark.parametrize("seed", [1, 2])
def test_a_layer_read_as_a_half_space_is_material(seed):
    """3 mm into a 30 mm bonded layer: the shallow half reads ~9 % softer than all depths;
    every failed check carries at least that (the half-space E itself is +34 %, which only
    the layer model recovers: the window effect is a lower bound, not the bias)."""
    res, es, tr = _graded(PARA, seed, base="bonded", depth=3e-3)
    dc = res["depth_consistency"]
    assert dc.details["severity"] == "material"
    assert dc.details["effect"] == pytest.approx(dc.statistic - 1.0)
    assert -0.12 < dc.details["effect"] < -0.06
    for name in ("residual_structure",):
        assert res[name].details["severity"] == "material"
        assert abs(res[name].details["effect"]) >= abs(dc.details["effect"]) - 1e-12
    assert es / tr.metadata["Estar_true"] > 1.25


@pytest.mark.parametrize("seed", [1, 2])
def test_a_cone_read_as_a_paraboloid_is_material(seed):
    """A cone (m = 2) fitted with the paraboloid's 1.5: a large window effect (the shallow
    E* ~0.76 × all) and a free-exponent effect of a few per cent, both signed."""
    cone = Tip("cone", half_angle=math.radians(70))
    res, _, _ = _graded(cone, seed)
    ex, dc = res["exponent"], res["depth_consistency"]
    assert not ex.passed and math.isfinite(ex.details["effect"])
    assert dc.details["severity"] == "material" and dc.details["effect"] < -0.15
    summary = C.checks_summary(list(res.values()))
    assert summary["model_ok"] is False
    assert summary["misfit_effect"] == pytest.approx(
        min(c.details["effect"] for c in res.values() if C.material(c)))
    assert "depth_consistency" in summary["misfit_checks"].split(";")


@pytest.mark.parametrize("drift", [0.01, -0.01])
def test_drift_effect_is_the_linear_baseline_refit(drift):
    """A drifting baseline fitted as constant: the residual check's effect is at least the
    change of E* when the baseline is made linear (recomputed here)."""
    from palpbayes.checks.core import ShapeTable
    from palpbayes.checks.depth import profile_law_fit
    res, _, tr = _graded(PARA, 3, drift=drift)
    rs = res["residual_structure"]
    assert not rs.passed and rs.details["pattern"] == "drift"
    lo = tr.loading_segment()
    zs = res["depth_consistency"].details["z_surf_all"]
    dmax = zs - lo.z.min()
    table = ShapeTable(MODEL, 1.5 * dmax)
    const = profile_law_fit(lo.z, lo.force, table, zs, 0.25 * dmax, "constant",
                             float(lo.z.max()), None)
    line = profile_law_fit(lo.z, lo.force, table, zs, 0.25 * dmax, "linear",
                            float(lo.z.max()), None)
    assert abs(rs.details["effect"]) >= abs(line["estar"] / const["estar"] - 1) - 1e-9
