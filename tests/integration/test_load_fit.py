"""A fit saved by the campaign code comes back equal: ``load_fit`` returns the BayesResult that
was saved, field by field (estimates, intervals, converged, flags, checks, warnings, the
per-trace budget, diagnostics, the fitted data and model).

It used to rebuild the diagnostics from the draws without the sampler's step-cap flag and tau,
to drop the per-trace budget and the checks' details, and to read the tip back from
``traces.csv`` at 10 significant digits, so a flagged fit could come back as converged.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pandas as pd
import pytest
from presets import TINY

import palpbayes.campaign.fitjob as fitjob
from palpbayes.bayes import PriorSpec
from palpbayes.campaign import FitOptions, fit_campaign, load_fit
from palpbayes.contact import Tip
from palpbayes.io.manifest import write_manifest
from palpbayes.io.trace_csv import write_trace
from palpbayes.sim import simulate_trace


def _same(a, b) -> bool:
    """Equal, with NaN equal to NaN, through dicts, lists, tuples and arrays."""
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, list | tuple) and isinstance(b, list | tuple):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        a, b = np.asarray(a), np.asarray(b)
        return a.shape == b.shape and a.dtype == b.dtype and bool(
            np.array_equal(a, b, equal_nan=a.dtype.kind in "fc"))
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return True
    return bool(a == b)


def assert_same_fit(back, saved, *, loading: bool = True) -> None:
    """Every public field of two BayesResults equal (``loading``: also the loading segment)."""
    for name in ("trace_id", "noise", "baseline", "z_ref", "warnings", "converged"):
        assert _same(getattr(back, name), getattr(saved, name)), name
    assert _same(back.summary_row(), saved.summary_row())
    pd.testing.assert_frame_equal(back.summary(), saved.summary())
    assert _same(dataclasses.asdict(back.diagnostics), dataclasses.asdict(saved.diagnostics))
    assert back.diagnostics.problems() == saved.diagnostics.problems()
    assert len(back.checks) == len(saved.checks)
    for b, s in zip(back.checks, saved.checks, strict=True):
        assert _same(dataclasses.asdict(b), dataclasses.asdict(s)), s.name
    assert back.budget is not None
    np.testing.assert_array_equal(back.budget.E, saved.budget.E)
    pd.testing.assert_frame_equal(back.budget.table, saved.budget.table)
    for var in saved.idata.posterior.data_vars:
        np.testing.assert_array_equal(back.draws(var), saved.draws(var))
    d, s = back.data, saved.data
    assert d.model == s.model
    for name in ("z", "force", "z_contact", "z_top", "z_min", "f_unc", "fit_fraction", "tare"):
        assert _same(getattr(d, name), getattr(s, name)), name
    if loading:
        assert d.baseline == s.baseline
        np.testing.assert_array_equal(d.loading.z, s.loading.z)
        np.testing.assert_array_equal(d.loading.force, s.loading.force)
        assert (back.lsq is None) == (saved.lsq is None)
        if saved.lsq is not None:
            assert _same(back.lsq.summary_row(), saved.lsq.summary_row())


def _fit_and_keep(monkeypatch, source, out, options):
    """Fit through fit_campaign (one worker) and keep the BayesResult that was saved."""
    kept = {}
    real = fitjob.fit_trace

    def keep(trace, opts, posterior_dir=None, **kwargs):
        outcome = real(trace, opts, posterior_dir, **kwargs)
        kept[trace.trace_id] = outcome.bayes
        return outcome

    monkeypatch.setattr(fitjob, "fit_trace", keep)
    summary = fit_campaign(source, out, options, workers=1)
    return summary, kept


@pytest.fixture(scope="module")
def layer():
    """A paraboloid 3 mm into a 30 mm layer fitted as a half-space: the model checks fail and
    name finite thickness; the tip radius has more digits than traces.csv keeps."""
    return simulate_trace(136e3, Tip("paraboloid", radius=0.0117 + 1e-13), thickness=0.03,
                          depth=3e-3, base="bonded", rng=3, trace_id="layer")


def test_a_flagged_fit_with_failed_checks_and_a_budget_comes_back_equal(layer, tmp_path,
                                                                        monkeypatch):
    path = write_trace(layer, tmp_path / "layer.csv", float_format="%.17g")
    write_manifest(pd.DataFrame([{
        "trace_id": "layer", "file": str(path), "material": "Pink", "tip": "paraboloid",
        "radius_m": layer.tip.radius, "thickness_m": 0.03}]), tmp_path / "manifest.csv")
    # short chains: the step cap is reached (a diagnostics flag the draws alone do not show)
    opts = FitOptions(seed=1, settings=TINY, layer="off")
    summary, kept = _fit_and_keep(monkeypatch, tmp_path / "manifest.csv", tmp_path / "res",
                                  opts)
    saved = kept["layer"]
    assert not saved.converged and saved.diagnostics.hit_cap
    assert any(not c.passed for c in saved.checks) and saved.budget is not None
    assert not bool(summary["converged"].iloc[0])

    back = load_fit(tmp_path / "res", "layer")
    assert_same_fit(back, saved)
    assert back.summary_row()["notes"] == summary["notes"].iloc[0]


@pytest.mark.slow
def test_a_fit_at_a_prior_bound_comes_back_flagged(tmp_path, monkeypatch):
    """13 samples, the surface above the recorded range: the z_surf posterior sits at its prior
    bound, a warning that alone makes the fit not converged (checks skipped: too few points).
    Fitted from a list of traces: no file to re-read, the stored fitted points are used."""
    tr = simulate_trace(136e3, Tip("sphere", radius=0.01), thickness=0.02, rng=1, rate=5,
                        noise_pp=0.6, approach=5e-5, trace_id="sparse")
    opts = FitOptions(seed=1, f_unc=0.6, priors=PriorSpec(noise_pp=0.6))
    summary, kept = _fit_and_keep(monkeypatch, [tr], tmp_path / "res", opts)
    saved = kept["sparse"]
    assert saved.warnings and saved.diagnostics.converged and not saved.converged

    back = load_fit(tmp_path / "res", "sparse")
    assert_same_fit(back, saved, loading=False)
    assert not back.converged
