"""One number per quantity (issue 45): what the summary row, the notes, the model's
description and the parameter table say about one fit agree."""

from __future__ import annotations

import re
import warnings

import numpy as np
import pytest

from palpbayes.bayes import fit_bayes
from palpbayes.contact import Tip
from palpbayes.errors import ConvergenceWarning
from palpbayes.fitdata import ModelSpec
from palpbayes.sim import simulate_trace
from palpbayes.units import format_pressure


def _fit(tr, model, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        return fit_bayes(tr, model, engine="exact", seed=1, **kw)


def test_parameter_table_quotes_the_rows_interval():
    """A material misfit (a 20 mm layer fitted as a half-space): the table's E_total interval
    is the row's full interval (the model form's envelope), not the narrower budget one."""
    tip = Tip("paraboloid", radius=0.0117)
    tr = simulate_trace(120e3, tip, thickness=0.02, base="bonded", rng=2)
    res = _fit(tr, ModelSpec(tip, nu=0.3))
    row = res.summary_row()
    assert res.model_form is not None and row["modelform_share_pct"] > 0
    table = res.summary()
    assert (table.loc["E_total", "lo"], table.loc["E_total", "hi"]) == pytest.approx(
        (row["E_lo_pa"], row["E_hi_pa"]), rel=1e-12)
    assert table.loc["E_total", "hi"] - table.loc["E_total", "lo"] > (
        table.loc["E_total", "q95"] - table.loc["E_total", "q05"])
    assert (table.loc["E_star", "lo"], table.loc["E_star", "hi"]) == (
        table.loc["E_star", "q05"], table.loc["E_star", "q95"])


def test_base_note_quotes_the_rows_bonded_and_free_E():
    """A flat punch on a 20 mm layer, base unknown (its curve cannot tell the bases): the note's
    'E is X if bonded, Y if free' are the row's E_bonded_pa and E_free_pa."""
    tip = Tip("flat", radius=0.01)
    tr = simulate_trace(120e3, tip, thickness=0.02, base="free", rng=3)
    row = _fit(tr, ModelSpec(tip, nu=0.3, thickness=0.02)).summary_row()
    note = next(n for n in row["notes"].split("; ") if "base not identified" in n)
    bonded, free = re.search(r"E is (.+?) if the specimen is bonded.*?, (.+?) if it lies",
                             note).groups()
    assert bonded == format_pressure(row["E_bonded_pa"])
    assert free == format_pressure(row["E_free_pa"])


def test_fitted_models_thickness_is_the_rows():
    """--thickness unknown: model_fitted's h and thickness_m are one number."""
    tip = Tip("paraboloid", radius=0.0117)
    tr = simulate_trace(120e3, tip, thickness=0.02, base="bonded", rng=4)
    res = _fit(tr, ModelSpec(tip, nu=0.3, thickness_range=(4e-3, 0.5)), with_model_form=False)
    row = res.summary_row()
    h = float(re.search(r"h=([0-9.]+) mm", row["model_fitted"]).group(1))
    assert row["thickness_m"] * 1e3 == pytest.approx(h, abs=0.051)
    assert row["thickness_lo_m"] <= row["thickness_m"] <= row["thickness_hi_m"]
    assert np.isfinite(row["thickness_m"])


@pytest.mark.parametrize("nu", [0.5, 0.3])
def test_headline_E_is_the_estimate_at_the_stated_inputs_inside_every_interval(nu):
    """Issue 46: at nu 0.5 the budget's nu range is one-sided (0.45..0.5), so the E_total
    draws sit ~3 % above E at the stated nu; the headline was their median, outside its own
    statistical interval.  It is now the estimate at the stated inputs; the budget widens the
    interval around it."""
    tip = Tip("sphere", radius=0.01)
    tr = simulate_trace(20e3, tip, nu=nu, depth=2e-3, rng=4)
    res = _fit(tr, ModelSpec(tip, nu=nu))
    row = res.summary_row()
    assert row["E_pa"] == row["E_stat_pa"]
    assert row["E_stat_lo_pa"] <= row["E_pa"] <= row["E_stat_hi_pa"]
    assert row["E_budget_lo_pa"] <= row["E_stat_lo_pa"] < row["E_stat_hi_pa"] <= (
        row["E_budget_hi_pa"])
    assert row["E_lo_pa"] <= row["E_budget_lo_pa"] and row["E_budget_hi_pa"] <= row["E_hi_pa"]
    table = res.summary()
    assert (table.loc["E_total", "lo"], table.loc["E_total", "hi"]) == (
        row["E_lo_pa"], row["E_hi_pa"])
    shift = np.median(res.draws("E_total")) / row["E_pa"] - 1
    if nu == 0.5:  # the one-sided budget: what the headline used to be
        assert shift > 0.01
        assert np.median(res.draws("E_total")) > row["E_stat_hi_pa"]
    else:
        assert abs(shift) < 0.01


def test_plot_title_quotes_the_rows_E_and_budget_interval():
    """Issue 46 review: the report's posterior plot titled itself with the E_total median, 3 %
    above the row's E_pa at nu 0.5."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib import pyplot as plt

    from palpbayes.plots.posterior import plot_posterior_E

    tip = Tip("sphere", radius=0.01)
    tr = simulate_trace(20e3, tip, nu=0.5, depth=2e-3, rng=4)
    res = _fit(tr, ModelSpec(tip, nu=0.5))
    row = res.summary_row()
    fig = plot_posterior_E(res)
    title = fig.axes[0].get_title()
    plt.close(fig)
    e, lo, hi = (float(v) for v in re.search(
        r"E = ([\d.]+) kPa, 90 % interval \[([\d.]+), ([\d.]+)\]", title).groups())
    assert e == pytest.approx(row["E_pa"] / 1e3, abs=0.051)
    assert (lo, hi) == pytest.approx((row["E_budget_lo_pa"] / 1e3, row["E_budget_hi_pa"] / 1e3),
                                     abs=0.051)


def test_instron_headline_moves_with_the_rows_E():
    """With lubricated platens the compression test reads E itself: E_instron_pa = E_pa, and
    the interval holds it, whatever the budget does to the E_total draws."""
    from palpbayes.bayes.instron import instron_columns

    rng = np.random.default_rng(1)
    stat = rng.normal(100e3, 1e3, 4000)
    total = stat * rng.uniform(1.0, 1.07, stat.size)  # a one-sided budget
    center = np.median(stat) / np.median(total)
    lub = instron_columns(total, 1.15 * total, "lubricated", center=center)
    assert lub["E_instron_pa"] == pytest.approx(np.median(stat), rel=1e-12)
    assert lub["E_instron_lo_pa"] <= lub["E_instron_pa"] <= lub["E_instron_hi_pa"]
    bon = instron_columns(total, 1.15 * total, "bonded", center=center)
    assert bon["E_instron_pa"] == pytest.approx(1.15 * np.median(stat), rel=1e-3)


def test_pooled_headline_is_at_the_stated_inputs_like_a_traces():
    """A group's E_pa and E_new_pa follow the per-trace rule: the median without the budget's
    factor (the sampled base's kept), the interval the budget's, widened to hold it."""
    from palpbayes.pooling.model import PooledEstimate

    rng = np.random.default_rng(2)
    n = 8000
    post = type("P", (), {"mu": np.log(100e3) + rng.normal(0, 0.01, n),
                          "tau": np.full(n, 0.05)})()
    budget = rng.uniform(1.0, 1.07, n)  # one-sided, as nu 0.5's
    base = np.where(rng.random(n) < 0.3, 0.9, 1.0)
    z = rng.standard_normal(n)
    est = PooledEstimate(material="m", tip="t", posterior=post, factor=budget * base,
                         E=np.exp(post.mu) * budget * base,
                         E_new=np.exp(post.mu + post.tau * z) * budget * base,
                         budget=None, base=base)
    h = est.headline()
    assert h["E"] == pytest.approx(np.median(np.exp(post.mu) * base), rel=1e-12)
    assert h["E_new"] == pytest.approx(np.median(np.exp(post.mu + post.tau * z) * base),
                                       rel=1e-12)
    for k in ("E", "E_new"):
        assert h[f"{k}_lo"] <= h[k] <= h[f"{k}_hi"]
    assert np.median(est.E) / h["E"] - 1 > 0.02  # what the headline used to be: shifted


def test_pooled_row_is_the_headline_comparison_csv_quotes():
    """Issue 58: Grey·flat's pooled E read 190.9 kPa in comparison.csv (the median at the stated
    inputs) and 191.9 kPa in pooled.csv (the median of the draws with the budget): pooled.csv's
    row is now the headline, E_mean by the same rule, the sds those of the budget's draws."""
    from palpbayes.pooling.model import PooledEstimate

    rng = np.random.default_rng(3)
    n = 8000
    post = type("P", (), {"mu": np.log(190e3) + rng.normal(0, 0.03, n),
                          "tau": np.abs(rng.normal(0.05, 0.02, n)), "n": 3, "m": np.zeros(3),
                          "s": np.ones(3), "tau_prior_sd": 0.5,
                          "diagnostics": type("D", (), {
                              "rhat_max": 1.0, "ess_min": 1e3, "tau": {"mu": 10.0},
                              "n_steps": 1000, "problems": lambda self: []})(),
                          "converged": True})()
    budget = rng.uniform(0.99, 1.05, n)  # a one-sided budget moves the draws' median
    z = rng.standard_normal(n)
    est = PooledEstimate(material="Grey", tip="flat", posterior=post, factor=budget,
                         E=np.exp(post.mu) * budget,
                         E_new=np.exp(post.mu + post.tau * z) * budget, budget=None)
    row, h = est.row(), est.headline()
    assert abs(np.median(est.E) / h["E"] - 1) > 0.005  # the old pooled.csv E_pa: not it
    for key in ("E", "E_new"):
        assert (row[f"{key}_pa"], row[f"{key}_lo_pa"], row[f"{key}_hi_pa"]) == (
            h[key], h[f"{key}_lo"], h[f"{key}_hi"])
    assert row["E_sd_pa"] == pytest.approx(np.std(est.E, ddof=1), rel=1e-12)
    mean = np.exp(post.mu + 0.5 * post.tau ** 2)  # at the stated inputs, as E
    assert row["E_mean_pa"] == pytest.approx(np.median(mean), rel=1e-12)
    assert row["E_mean_lo_pa"] <= row["E_mean_pa"] <= row["E_mean_hi_pa"]
    assert row["E_mean_pa"] > row["E_pa"]
