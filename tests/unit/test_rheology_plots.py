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
from palpbayes.units import FORCE_PREFIXES, LENGTH_PREFIXES, PRESSURE_PREFIXES, si_scale

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
    np.testing.assert_allclose(median.get_ydata(), med)  # up to 2 N: drawn in N
    assert ax.get_ylabel() == "Force, F [N]"
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
    assert ax.get_ylabel() == "Relaxation modulus, E*(t) [kPa]"
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
    assert ax.get_xlabel() == "Depth below the fitted surface, d [mm]"


@pytest.mark.parametrize("value, unit, prefixes, expect", [
    (2e-9, "N", FORCE_PREFIXES, (1e9, "nN")), (2e-10, "N", FORCE_PREFIXES, (1e12, "pN")),
    (1.9, "N", FORCE_PREFIXES, (1.0, "N")),
    (0.048, "N", FORCE_PREFIXES, (1e3, "mN")), (7e4, "Pa", PRESSURE_PREFIXES, (1e-3, "kPa")),
    (800.0, "Pa", PRESSURE_PREFIXES, (1.0, "Pa")), (3e-3, "m", LENGTH_PREFIXES, (1e3, "mm")),
    (5e3, "m", LENGTH_PREFIXES, (1.0, "m")), (0.0, "N", FORCE_PREFIXES, (1.0, "N")),
    (float("nan"), "Pa", PRESSURE_PREFIXES, (1.0, "Pa")), (1e-15, "N", FORCE_PREFIXES,
                                                           (1e12, "pN"))])
def test_axes_take_the_unit_that_suits_the_values(value, unit, prefixes, expect):
    """An AFM force of 2 nN is drawn in nN, 0.2 nN in pN, a robot's in N or mN; out of range: the
    nearest prefix."""
    k, label = si_scale(value, unit, prefixes)
    assert label == expect[1] and k == pytest.approx(expect[0])
