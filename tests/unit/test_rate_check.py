"""The rate-dependence check (palpbayes.checks.rate): an elastic fit of a cycle whose hold
relaxes or whose retract lies below the approach is flagged, with the option to use.

Statistical: 24 elastic cycles (two tips, hold and retract, AR(1) noise) pass; viscoelastic
cycles fail with the relaxation the noise-free hereditary force gives; a creep hold (constant
force, growing depth) reads as relaxation; the flag reaches model_ok, the summary row and the
CLI, without widening the elastic interval by the depth windows of the model form.
"""

from __future__ import annotations

import warnings

import numpy as np
import pandas as pd
import pytest

from palpbayes.bayes import fit_bayes
from palpbayes.checks import THRESHOLDS, checks_summary
from palpbayes.checks.rate import rate_dependence_check
from palpbayes.contact import Tip
from palpbayes.contact.viscoelastic import PowerLawKernel, standard_linear_solid
from palpbayes.errors import InputError
from palpbayes.fitdata import ModelSpec, prepare
from palpbayes.paper import PAPER_TIPS
from palpbayes.sim import simulate_trace, simulate_viscoelastic

PARA = PAPER_TIPS["paraboloid"]


def _fit(trace, seed=1):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return fit_bayes(trace, ModelSpec(trace.tip, nu=0.3), engine="exact", seed=seed)


def _rate(res):
    return next((c for c in res.checks if c.name == "rate"), None)


@pytest.mark.parametrize("tip", ["paraboloid", "flat"])
def test_elastic_cycles_pass(tip):
    """Twelve elastic ramp-hold-retract cycles per tip (seeds 0-11, AR(1) noise phi 0.5):
    no rate flag; the relaxation and the retract ratio are within 4 se of zero."""
    for seed in range(12):
        tr = simulate_trace(50e3, PAPER_TIPS[tip], nu=0.3, depth=3e-3 if tip != "flat" else 2e-3,
                            hold=4.0, retract=True, noise_ar1=0.5, rng=seed)
        c = _rate(_fit(tr, seed))
        assert c is not None and c.passed, (seed, c.details)
        d = c.details
        assert abs(d["relaxation"]) < 4 * d["relaxation_se"]
        assert abs(d["retract_ratio"]) < 4 * d["retract_se"]


def test_power_law_cycle_is_flagged_with_its_relaxation():
    """A power-law material (E0* 60 kPa, alpha 0.05): the check's relaxation is the noise-free
    hereditary force's over the same hold windows (to 3 se), the retract reads E* below the
    approach, the flag names the option, and model_ok is False."""
    kernel = PowerLawKernel(60e3, 0.05)
    kw = dict(depth=3e-3, speed=50 / 6e4, hold_time=5.0, rate=800.0)
    tr = simulate_viscoelastic(kernel, PARA, rng=2, **kw)
    clean = simulate_viscoelastic(kernel, PARA, rng=2, noise_sd=0.0, **kw)
    res = _fit(tr)
    c = _rate(res)
    assert not c.passed and c.details["severity"] == "material"
    hold = np.flatnonzero(clean.segment == 1)
    w = hold.size // 10
    f = clean.force
    expect = (f[hold[:w]].mean() - f[hold[-w:]].mean()) / f[hold[:w]].mean()
    assert c.details["relaxation"] == pytest.approx(expect, abs=3 * c.details["relaxation_se"])
    assert 0.05 < expect < 0.1
    assert c.details["retract_ratio"] < -0.1
    assert "--rheology power-law,sls" in c.flag and "hold" in c.flag and "retract" in c.flag
    summary = checks_summary(res.checks)
    assert summary["model_ok"] is False and "rate" in summary["misfit_checks"].split(";")
    assert c.details["effect"] == pytest.approx(c.details["retract_ratio"])


def test_rate_alone_does_not_widen_the_interval_by_depth_windows():
    """A weakly relaxing material (alpha 0.01) whose loading the elastic law fits: only the
    rate check fails, the model form (depth windows) is not applied, the row says why."""
    tr = simulate_viscoelastic(PowerLawKernel(60e3, 0.01), PARA, depth=3e-3, speed=50 / 6e4,
                               hold_time=5.0, rng=4)
    res = _fit(tr)
    summary = checks_summary(res.checks)
    assert summary["misfit_checks"] == "rate"
    assert res.model_form is None
    row = res.summary_row()
    assert row["model_ok"] is False or row["model_ok"] == 0
    assert "rate dependence" in row["notes"]


def test_sls_and_creep_are_flagged():
    """The SLS cycle relaxes; a creep hold (force held, the tip sinks 5 %) relaxes against
    the elastic law at its depth by about 1.05^1.5 - 1 of the force."""
    sls = simulate_viscoelastic(standard_linear_solid(40e3, 30e3, 1.0), PARA, depth=3e-3,
                                speed=50 / 6e4, hold_time=5.0, rng=3)
    assert not _rate(_fit(sls)).passed
    el = simulate_trace(50e3, PARA, nu=0.3, depth=3e-3, hold=4.0, retract=False,
                        noise_pp=0.0, rng=0)
    z, f = el.z.copy(), el.force.copy()
    hold = np.flatnonzero(np.arange(z.size) > np.argmin(z))
    zs = el.metadata["z_surf_true"]
    d0 = zs - z[hold[0]]
    z[hold] = zs - d0 * np.linspace(1.0, 1.05, hold.size)  # sinks at a constant force
    seg = np.zeros(z.size, dtype=int)
    seg[hold] = 1  # a creep hold is told by its label (as AFM files record it), not by z
    creep = el.replace(z=z, force=f, segment=seg)
    model = ModelSpec(PARA, nu=0.3)
    estar = 50e3 / (1 - 0.3**2)
    c = rate_dependence_check(creep, model, z_surf=zs, estar=estar, sigma=1e-3)
    w = hold.size // 10
    grow = np.linspace(1.0, 1.05, hold.size) ** 1.5
    expect = np.mean(grow[-w:]) / np.mean(grow[:w]) - 1
    assert c.details["relaxation"] == pytest.approx(expect, rel=0.05)
    assert not c.passed and "relaxation or creep" in c.flag


def test_no_hold_no_retract_no_check_and_bad_input():
    """A loading alone carries no rate check; prepare keeps the cycle only when the record
    goes on past the loading; sigma and E* are checked."""
    ramp = simulate_trace(50e3, PARA, nu=0.3, depth=3e-3, rng=0)
    assert prepare(ramp, ModelSpec(PARA)).cycle is None
    assert _rate(_fit(ramp)) is None
    cyc = simulate_trace(50e3, PARA, nu=0.3, depth=3e-3, hold=2.0, retract=True, rng=0)
    data = prepare(cyc, ModelSpec(PARA))
    assert data.cycle is not None and data.cycle.n_points == cyc.n_points
    zs = cyc.metadata["z_surf_true"]
    with pytest.raises(InputError, match="sigma"):
        rate_dependence_check(cyc, ModelSpec(PARA), z_surf=zs, estar=5e4, sigma=0.0)
    with pytest.raises(InputError, match="E\\*"):
        rate_dependence_check(cyc, ModelSpec(PARA), z_surf=zs, estar=float("nan"), sigma=1.0)
    assert THRESHOLDS["rate_n_se"] == 5.0


def test_recorded_segments_end_the_loading_within_the_approach():
    """A tip that sinks on during a hold (creep) does not take the hold into the loading
    when the trace records its segments."""
    tr = simulate_viscoelastic(PowerLawKernel(60e3, 0.1), PARA, depth=3e-3, speed=50 / 6e4,
                               hold_time=2.0, rng=1)
    z = tr.z.copy()
    hold = tr.segment == 1
    z[hold] -= np.linspace(0.0, 1e-4, int(hold.sum()))
    sunk = tr.replace(z=z)
    last_approach = int(np.flatnonzero(tr.segment == 0)[-1])
    assert sunk.loading_segment().n_points == last_approach + 1
    assert sunk.replace(segment=None).loading_segment().n_points > last_approach + 1


def test_cli_fit_of_a_viscoelastic_cycle_says_rate(tmp_path, capsys):
    """palpbayes fit of a ramp-hold-retract CSV of a power-law material: summary.csv has
    model_ok False, 'rate' among the misfit checks and the option in its flags."""
    from palpbayes.cli import main
    from palpbayes.io.trace_csv import write_trace

    tr = simulate_viscoelastic(PowerLawKernel(60e3, 0.1), PARA, depth=3e-3, speed=50 / 6e4,
                               hold_time=3.0, rng=5)
    path = write_trace(tr, tmp_path / "cycle.csv", float_format="%.12g")
    assert main(["fit", str(path), "--tip", "paraboloid", "--radius", "0.0117", "--nu", "0.3",
                 "--out", str(tmp_path / "out"), "--engine", "exact", "--method", "bayes",
                 "--no-progress"]) == 0
    row = pd.read_csv(tmp_path / "out" / "summary.csv").iloc[0]
    assert not bool(row["model_ok"])
    assert "rate" in str(row["misfit_checks"]).split(";")
    assert "--rheology power-law,sls" in str(row["notes"])


REAL = {"fmt-jpk-sr_cell1-0008.jpk-force": ("hold", 0.45, 0.60),
        "fmt-jpk-cc_pr14-brain-2021.06.30.jpk-force": ("hold", 0.12, 0.20),
        "fmt-jpk-cc_pr14-polymergel-2021.06.30.jpk-force": ("hold", 0.12, 0.20),
        "fmt-jpk-fd_spot3-0192.jpk-force": ("retract", 0.08, 0.20)}


@pytest.mark.parametrize("name", [
    # the two creep curves take ~10 s each: in the slow suite
    pytest.param(n, marks=pytest.mark.slow) if "cc_pr14" in n else n for n in sorted(REAL)])
def test_real_afm_cycles_are_flagged_rate_dependent(shared_data, name):
    """Real AFM cycles (afmformats' test files, MIT; paraboloid R = 5 µm, nu 0.5), read with
    every segment: the stress-relaxation cell loses about half its force over the 30 s hold
    (measured 53 %), the two creep curves 16-17 % against the elastic law at their growing
    depth, the force-distance curve's retract reads E* 13 % below its approach.  The
    approach's elastic fit is the one the approach alone gives."""
    from palpbayes.io.afm import read_afm

    path = shared_data("afm-files", files=[name]) / name
    kind, lo, hi = REAL[name]
    tip = Tip("paraboloid", radius=5e-6)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        (full,) = read_afm(path, segments="all", tip=tip)
        (approach,) = read_afm(path, tip=tip)
        res = fit_bayes(full, ModelSpec(tip, nu=0.5), engine="exact", seed=1)
        alone = fit_bayes(approach, ModelSpec(tip, nu=0.5), engine="exact", seed=1)
    c = _rate(res)
    assert not c.passed and c.details["severity"] == "material"
    value = c.details["relaxation"] if kind == "hold" else -c.details["retract_ratio"]
    assert lo < value < hi, c.details
    assert res.summary_row()["E_pa"] == pytest.approx(alone.summary_row()["E_pa"], rel=1e-9)
    assert _rate(alone) is None
