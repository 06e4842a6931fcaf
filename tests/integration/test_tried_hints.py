"""A hint is tried before it is given (issue 46, item 7): a flag that says "try --baseline
linear" keeps the hint, with the E it gives, only when the fit with a linear baseline makes
the flag go away; otherwise it says that the hint was tried and why it does not help."""

from __future__ import annotations

import re

import pytest

from palpbayes import read as read_trace
from palpbayes.bayes.flags import BASELINE_HINT
from palpbayes.campaign.fitjob import FitOptions, fit_trace
from palpbayes.contact import Tip
from palpbayes.sim import simulate_trace


def _bayes_row(trace, **kw):
    return next(r for r in fit_trace(trace, FitOptions(engine="exact", **kw)).rows
                if r["method"] == "bayes")


def test_a_drifting_sensor_keeps_the_hint_with_the_E_it_gives():
    """A sensor drifting 20 N/s: the constant baseline puts the surface at the top of the
    approach and reads E ~50 times too high; the linear one recovers the true 60 kPa."""
    tip = Tip("sphere", radius=0.01)
    tr = simulate_trace(60e3, tip, depth=2e-3, rng=5, drift=20.0, base=None)
    row = _bayes_row(tr, nu=0.3)
    flag = next(f for f in row["notes"].split("; ") if "z_surf posterior at its upper" in f)
    m = re.search(r"try --baseline linear: tried, the flag goes away, E ([\d.]+) kPa, "
                  r"([-+][\d.]+)% against this row", flag)
    assert m, flag
    assert float(m.group(1)) == pytest.approx(60.0, rel=0.02)
    assert float(m.group(2)) < -90  # the row's E is the drift's, not the material's
    assert "was tried" not in row["notes"]


def test_a_clean_trace_has_no_hint_and_no_second_fit(monkeypatch):
    import palpbayes.campaign.fitjob as fitjob

    called = []
    monkeypatch.setattr(fitjob, "tried_baseline_hint",
                        lambda *a, **k: called.append(a) or "")
    tr = simulate_trace(60e3, Tip("sphere", radius=0.01), depth=2e-3, rng=5, base=None)
    row = _bayes_row(tr, nu=0.3)
    assert BASELINE_HINT not in str(row["notes"]) and not called


def test_the_real_stress_relaxation_curve_is_told_the_hint_does_not_help(shared_data):
    """The stress-relaxation cell (issue 46): its elastic fit puts the surface at the top of
    the approach and used to say 'try --baseline linear'; with it the fit does not converge
    and E collapses, so the hint is not given."""
    path = shared_data("afm-files/fmt-jpk-sr_cell1-0008.jpk-force")
    tr = read_trace(path, tip=Tip("paraboloid", radius=5e-6))
    row = _bayes_row(tr, nu=0.5, max_depth=5e-6, model_form=False)
    assert BASELINE_HINT not in row["notes"]
    flag = next(f for f in row["notes"].split("; ") if "z_surf posterior at its upper" in f)
    assert "--baseline linear was tried and does not help" in flag
    assert re.search(r"E [\d.]+ \w?Pa, [-+][\d.]+% against this row", flag)


def test_the_rheology_tilt_hint_is_tried_on_the_real_stress_relaxation_curve(shared_data):
    """The issue's own case: the elastic viscoelastic fit of the stress-relaxation cell flags
    a tilted baseline; with --baseline linear the fit fails ('no posterior draw has positive
    moduli'), so the hint is replaced by that finding."""
    import warnings

    from palpbayes.rheology.fit import fit_rheology
    from palpbayes.rheology.flags import TILT_HINT

    path = shared_data("afm-files/fmt-jpk-sr_cell1-0008.jpk-force")
    tr = read_trace(path, tip=Tip("paraboloid", radius=5e-6))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fit = fit_rheology(tr, "elastic", nu=0.5)
    (flag,) = [f for f in fit.flags if "tilt with the height" in f]
    assert TILT_HINT not in flag
    assert "--baseline linear was tried and its fit fails: no posterior draw" in flag
    assert flag in fit.offcontact and not fit.model_ok
