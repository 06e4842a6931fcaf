"""Model-form uncertainty (palpbayes.bayes.modelform) and the simulator's blunted apex."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy import integrate, optimize

from palpbayes.bayes import fit_bayes
from palpbayes.bayes.modelform import (
    Alternative,
    ModelForm,
    interval_parts,
    layer_alternative,
    model_form,
    window_alternatives,
)
from palpbayes.bayes.result import BayesResult
from palpbayes.checks import CheckResult
from palpbayes.contact import Tip, shape
from palpbayes.errors import ConvergenceWarning, GeometryError, InputError
from palpbayes.fitdata import ModelSpec, prepare_trace
from palpbayes.sim import simulate_trace
from palpbayes.sim.force import blunted_paraboloid_shape, true_force
from palpbayes.sim.misfit import MISFIT_NU, MISFIT_SCENARIOS, misfit_trace

PARA = Tip("paraboloid", radius=0.0117)


# ------------------------------------------------------------------ the blunted apex
def _mdr_numeric(d: float, R: float, b: float) -> float:
    """F/E* of the profile max(0, r² − b²)/2R by the MDR with g(x) from quadrature."""
    def g(x):
        if x <= b:
            return 0.0
        # g(x) = x ∫_b^x f'(r)/sqrt(x² − r²) dr, f' = r/R; substitute r = x·sin(t)
        t0 = np.arcsin(b / x)
        val, _ = integrate.quad(lambda t: x * np.sin(t) / R, t0, np.pi / 2, epsabs=0,
                                epsrel=1e-12)
        return x * val
    a = optimize.brentq(lambda x: g(x) - d, b + 1e-12, b + 10 * np.sqrt(d * R) + 1e-3,
                        xtol=1e-15, rtol=1e-14)
    val, _ = integrate.quad(lambda x: d - g(x), 0.0, a, points=[b], limit=200, epsabs=0,
                            epsrel=1e-11)
    return 2.0 * val


@pytest.mark.parametrize("b", [0.5e-3, 2e-3])
@pytest.mark.parametrize("d", [1e-5, 5e-4, 3e-3])
def test_blunted_apex_matches_mdr_quadrature(b, d):
    assert blunted_paraboloid_shape(d, 0.0117, b) == pytest.approx(
        _mdr_numeric(d, 0.0117, b), rel=1e-6)


def test_blunted_apex_limits():
    d = np.array([1e-6, 1e-4, 3e-3])
    # b = 0: Hertz exactly; d << b²/R: the flat punch 2·b·d
    np.testing.assert_allclose(blunted_paraboloid_shape(d, 0.0117, 0.0), shape(d, PARA),
                               rtol=1e-12)
    assert blunted_paraboloid_shape(1e-9, 0.0117, 2e-3) == pytest.approx(2 * 2e-3 * 1e-9,
                                                                           rel=1e-3)
    # stiffer than the sharp tip at every depth, the excess fading with depth
    ratio = blunted_paraboloid_shape(d, 0.0117, 2e-3) / shape(d, PARA)
    assert np.all(ratio > 1) and np.all(np.diff(ratio) < 0)


def test_blunted_apex_knob_in_the_simulator():
    kw = {"depth": 3e-3, "rng": 3}
    plain = simulate_trace(50e3, PARA, **kw)
    off = simulate_trace(50e3, PARA, apex_flat_radius=0.0, **kw)
    np.testing.assert_array_equal(plain.force, off.force)  # off: bit for bit
    blunt = simulate_trace(50e3, PARA, apex_flat_radius=2e-3, **kw)
    assert blunt.metadata["apex_flat_radius_true"] == 2e-3
    assert blunt.force.max() > plain.force.max()
    with pytest.raises(GeometryError, match="paraboloid"):
        true_force(1e-3, 50e3, 0.45, Tip("sphere", radius=0.01), apex_flat_radius=1e-3)
    with pytest.raises(InputError, match="apex flat radius"):
        simulate_trace(50e3, PARA, apex_flat_radius=-1e-3, **kw)


def test_misfit_traces_are_reproducible_and_named():
    for s in MISFIT_SCENARIOS:
        a, tip = misfit_trace(s, 3)
        b, _ = misfit_trace(s, 3)
        np.testing.assert_array_equal(a.force, b.force)
        assert a.thickness is None and a.metadata["scenario"] == s
        assert a.metadata["E_true"] == 50e3 and tip.kind in ("paraboloid", "sphere")
    assert not np.array_equal(misfit_trace("onset", 1)[0].force,
                              misfit_trace("onset", 2)[0].force)
    with pytest.raises(InputError, match="unknown misfit scenario"):
        misfit_trace("wobble", 0)


# ------------------------------------------------------------------ the envelope
def _check(name, severity, **details):
    return CheckResult(name, 1.0, severity == "", "", {"severity": severity, **details})


def test_no_material_misfit_no_model_form():
    E = np.full(1000, 50e3)
    checks = [_check("exponent", ""), _check("residual_structure", "negligible")]
    assert model_form(E, checks, np.random.default_rng(0)) is None


def test_envelope_keeps_plausible_alternatives_only():
    rng = np.random.default_rng(1)
    E = 50e3 * np.exp(0.02 * rng.standard_normal(4000))
    depth = _check("depth_consistency", "material", ratio=0.8, estar_all=100.0,
                   estar_shallow=80.0, estar_shallow_se=0.4, estar_deep=110.0,
                   estar_deep_se=1.1)
    bad = Alternative("layer, thickness unknown", 20e3, 18e3, 22e3, False,
                      "its own checks fail")
    form = model_form(E, [depth], np.random.default_rng(2), lambda: bad)
    names = [a.name for a in form.alternatives]
    assert names == ["as fitted", "shallow half", "deep half", "layer, thickness unknown"]
    shallow, deep = form.alternatives[1], form.alternatives[2]
    assert shallow.E_pa == pytest.approx(40e3, rel=0.01)
    assert deep.E_pa == pytest.approx(55e3, rel=0.01)
    # the implausible layer does not widen the envelope; the windows do
    assert form.lo_pa == pytest.approx(shallow.lo_pa) and form.hi_pa == pytest.approx(deep.hi_pa)
    assert form.lo_pa > 22e3
    cols = form.columns()
    assert 0 < cols["modelform_share_pct"] < 100
    assert "left out: its own checks fail" in cols["modelform_models"]
    assert ModelForm.from_state(form.to_state()) == form


def test_layer_alternative_only_where_the_modulus_rises_with_depth():
    E = np.full(1000, 50e3)
    calls = []

    def fit_layer():
        calls.append(1)
        return Alternative("layer, thickness unknown", 40e3, 38e3, 42e3)

    falls = _check("depth_consistency", "material", ratio=1.2, estar_all=100.0,
                   estar_shallow=120.0, estar_shallow_se=1.0)
    form = model_form(E, [falls], np.random.default_rng(0), fit_layer)
    assert calls == [] and [a.name for a in form.alternatives] == ["as fitted", "shallow half"]
    steeper = _check("exponent", "negligible", m=2.1, m_law=1.5)  # the direction counts
    form = model_form(E, [falls, steeper], np.random.default_rng(0), fit_layer)
    assert calls == [1] and form.lo_pa == 38e3


def test_no_finite_interval_gives_a_nan_envelope_not_an_error():
    E = np.full(100, np.nan)
    form = model_form(E, [_check("ppc", "material")], np.random.default_rng(0))
    assert np.isnan(form.lo_pa) and np.isnan(form.hi_pa) and form.share() == 0.0
    failed = Alternative("layer, thickness unknown", np.nan, np.nan, np.nan, False,
                         "not fitted: singular matrix")
    assert failed.describe() == "layer, thickness unknown (left out: not fitted: singular matrix)"


def test_a_numerical_failure_of_the_layer_fit_is_an_implausible_alternative():
    trace, tip = misfit_trace("layer_bonded", 1)
    data = prepare_trace(trace, ModelSpec(tip, nu=MISFIT_NU))

    def broken_fit(*args, **kwargs):
        raise np.linalg.LinAlgError("singular matrix")

    alt = layer_alternative(broken_fit, data, float(data.z.max()) - 1e-3)
    assert not alt.plausible and "singular matrix" in alt.note


def test_window_alternative_spread_follows_its_standard_error():
    E = np.full(20000, 50e3)
    alts = window_alternatives(E, {"estar_all": 100.0, "estar_shallow": 90.0,
                                   "estar_shallow_se": 4.5}, np.random.default_rng(0))
    assert [a.name for a in alts] == ["shallow half"]  # no deep window in the details
    (a,) = alts
    # log-normal with sd 0.05: 90 % interval exp(±1.645·0.05)
    assert a.lo_pa / a.E_pa == pytest.approx(np.exp(-1.645 * 0.05), rel=0.01)
    assert a.hi_pa / a.E_pa == pytest.approx(np.exp(1.645 * 0.05), rel=0.01)
    alts = window_alternatives(E, {"estar_all": 100.0, "estar_shallow": 90.0,
                                   "estar_shallow_se": 4.5, "estar_deep": np.nan,
                                   "estar_deep_se": np.nan}, np.random.default_rng(0))
    assert [(a.name, a.plausible) for a in alts] == [("shallow half", True),
                                                     ("deep half", False)]
    assert "search bound" in alts[1].describe()


def test_interval_parts_text():
    text = interval_parts(100.0, (99.0, 101.0), (95.0, 105.0), (70.0, 105.0))
    assert text == ("statistical -1.0/+1.0 %, + budget -5.0/+5.0 %, + model form "
                    "-30.0/+5.0 %")
    assert "model form" not in interval_parts(100.0, (99.0, 101.0), (95.0, 105.0),
                                              (95.0, 105.0))
    assert interval_parts(float("nan"), (1, 2), (1, 2), (1, 2)) == ""


# ------------------------------------------------------------------ in a fit
def _fit(trace, tip, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        return fit_bayes(trace, ModelSpec(tip, nu=MISFIT_NU), engine="exact", seed=0, **kw)


def test_onset_misfit_interval_reaches_the_truth(tmp_path):
    """A gradual onset read by the half-space law: E ~7 % low, outside the budget interval;
    the deep-half alternative brings the truth into the full interval, and the saved fit
    reads back the same columns."""
    trace, tip = misfit_trace("onset", 5)
    res = _fit(trace, tip)
    row = res.summary_row()
    E = trace.metadata["E_true"]
    assert not row["model_ok"]
    assert not row["E_budget_lo_pa"] <= E <= row["E_budget_hi_pa"]
    assert row["E_lo_pa"] <= E <= row["E_hi_pa"]
    assert row["E_lo_pa"] <= row["E_budget_lo_pa"] and row["E_hi_pa"] >= row["E_budget_hi_pa"]
    assert row["modelform_share_pct"] > 30
    assert "deep half" in row["modelform_models"]
    deep = next(a for a in res.model_form.alternatives if a.name == "deep half")
    assert deep.E_pa == pytest.approx(E, rel=0.04)
    path = res.to_netcdf(tmp_path / "fit.nc")
    import arviz as az
    back = BayesResult.from_idata(az.from_netcdf(path), res.data, res.lsq)
    again = back.summary_row()
    for k in ("E_lo_pa", "E_hi_pa", "E_budget_lo_pa", "modelform_share_pct",
              "modelform_models"):
        assert again[k] == row[k]
    plain = _fit(trace, tip, with_model_form=False).summary_row()
    assert (plain["E_lo_pa"], plain["E_hi_pa"]) == (row["E_budget_lo_pa"], row["E_budget_hi_pa"])


def test_layer_alternative_explains_an_unmodelled_layer():
    trace, tip = misfit_trace("layer_bonded", 0)
    res = _fit(trace, tip)
    row = res.summary_row()
    E = trace.metadata["E_true"]
    assert row["E_pa"] > 1.2 * E  # the half-space reading
    assert row["E_lo_pa"] <= E <= row["E_hi_pa"]
    layer = next(a for a in res.model_form.alternatives if a.name.startswith("layer"))
    assert layer.plausible and layer.lo_pa <= E <= layer.hi_pa


def test_well_specified_fit_has_no_model_form():
    trace, tip = misfit_trace("well", 0)
    res = _fit(trace, tip)
    row = res.summary_row()
    assert res.model_form is None and row["model_ok"]
    assert (row["E_lo_pa"], row["E_hi_pa"]) == (row["E_budget_lo_pa"], row["E_budget_hi_pa"])
    assert row["modelform_share_pct"] == 0.0 and row["modelform_models"] == ""


def test_deep_window_recovers_e_under_an_onset():
    trace, tip = misfit_trace("onset", 2)
    res = _fit(trace, tip, with_model_form=False)
    dc = next(c for c in res.checks if c.name == "depth_consistency").details
    et = trace.metadata["Estar_true"]
    assert abs(dc["estar_all"] / et - 1) > 0.04
    assert dc["estar_deep"] / et == pytest.approx(1.0, abs=0.03)
    assert dc["estar_deep_se"] > 0


def test_a_flagged_layer_fit_is_left_out_with_the_flag_named():
    """A layer fit whose chains converge but whose posterior is flagged (its thickness at the
    prior's lower bound, as on real AFM curves) is left out with that flag's headline as the
    reason, not as "not converged"."""
    from dataclasses import replace

    from palpbayes.bayes.fit import fit_bayes_data

    trace, tip = misfit_trace("layer_bonded", 1)
    data = prepare_trace(trace, ModelSpec(tip, nu=MISFIT_NU))
    flag = ("thickness posterior at its lower prior bound (722 nm): the layer's thickness "
            "piles up at the thinnest the prior allows; more words")

    def flagged_fit(*args, **kwargs):
        res = fit_bayes_data(*args, **kwargs)
        assert res.diagnostics.converged
        return replace(res, warnings=[flag])

    alt = layer_alternative(flagged_fit, data, float(data.z.max()) - 1e-3)
    assert not alt.plausible
    assert alt.note.split("; ")[0] == "thickness posterior at its lower prior bound (722 nm)"
    assert "not converged" not in alt.note
