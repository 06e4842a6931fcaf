"""Figures of a viscoelastic fit (palpbayes.plots.rheology): what is drawn is the fit's own
numbers (the median force curve, E*(t) and its band, the segments of the record)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from matplotlib.figure import Figure

from palpbayes.contact.viscoelastic import PowerLawKernel
from palpbayes.intervals import central_band
from palpbayes.paper import PAPER_TIPS
from palpbayes.plots import plot_cycle_fit, plot_hysteresis, plot_relaxation
from palpbayes.plots.rheology import SEGMENT_COLORS
from palpbayes.rheology import fit_rheology
from palpbayes.sim import simulate_viscoelastic

KERNEL = PowerLawKernel(70e3, 0.15)


@pytest.fixture(scope="module")
def fitted():
    tr = simulate_viscoelastic(KERNEL, PAPER_TIPS["paraboloid"], depth=3e-3, speed=50 / 6e4,
                               hold_time=4.0, rate=200.0, rng=8, trace_id="foam")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return tr, fit_rheology(tr, "power-law", rng=0)


def test_cycle_fit_draws_the_median_force_and_names_the_check(fitted):
    _, fit = fitted
    fig = plot_cycle_fit(fit, n_draws=100)
    assert isinstance(fig, Figure)
    ax = fig.axes[0]
    median = next(ln for ln in ax.get_lines() if ln.get_label() == "posterior median")
    _, med, _ = central_band(fit.force_curves(100), axis=0)
    np.testing.assert_allclose(median.get_ydata(), med * 1e3)
    np.testing.assert_allclose(median.get_xdata(), fit.data.time)
    assert ax.get_title() == ("foam: power law fit, model check "
                              + ("passed" if fit.model_ok else "FAILED"))
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert {"approach", "hold", "power law, 90 % band"} <= set(labels)


def test_relaxation_draws_the_band_and_the_truth_on_log_axes(fitted):
    _, fit = fitted
    times = np.geomspace(0.01, 10.0, 30)
    fig = plot_relaxation({"foam": fit}, times=times, truth=KERNEL)
    ax = fig.axes[0]
    assert ax.get_xscale() == "log" and ax.get_yscale() == "log"
    tab = fit.relaxation(times)
    line = next(ln for ln in ax.get_lines() if ln.get_label().startswith("foam"))
    np.testing.assert_allclose(line.get_ydata(), tab["E_star_pa"] * 1e-3)
    truth = next(ln for ln in ax.get_lines() if ln.get_label() == "true E*(t)")
    np.testing.assert_allclose(truth.get_ydata(), KERNEL(times) * 1e-3)
    # the recovered E*(t) is the truth's within 3 % at 1 s
    assert float(fit.relaxation([1.0])["E_star_pa"].iloc[0]) == pytest.approx(70e3, rel=0.03)


def test_hysteresis_colours_each_segment(fitted):
    tr, fit = fitted
    zs = float(np.median(fit.draws["z_surf"]))
    fig = plot_hysteresis(tr, z_surf=zs)
    ax = fig.axes[0]
    lines = {ln.get_label(): ln for ln in ax.get_lines()}
    assert set(lines) == {"approach", "hold", "retract"}
    for name, ln in lines.items():
        assert ln.get_color() == SEGMENT_COLORS[name]
    ret = lines["retract"]
    np.testing.assert_allclose(ret.get_xdata(), (zs - tr.z[tr.segment == 2]) * 1e3)
    assert "Depth" in ax.get_xlabel()
