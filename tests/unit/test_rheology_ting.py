"""Ting's rule on the retract (palpbayes.rheology.ting): the columns against the
simulator's hereditary force (Lee–Radok and Ting at sample level, contact/viscoelastic.py),
t1 against its own, and the power-law fit of the whole cycle."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from palpbayes.contact.viscoelastic import PowerLawKernel, hereditary_contact
from palpbayes.errors import InputError
from palpbayes.paper import PAPER_TIPS
from palpbayes.rheology import fit_rheology
from palpbayes.rheology.cycle import prepare_cycle
from palpbayes.rheology.ting import RetractDesign, symmetric_picks, ting_columns, ting_cutoff
from palpbayes.sim import simulate_viscoelastic

CASES = [  # tip, depth [m], alpha, hold [s], speed [mm/min], rate [Hz], tolerance / peak
    ("paraboloid", 3e-3, 0.2, 5.0, 50, 800, 3e-5),
    ("paraboloid", 3e-3, 0.5, 0.0, 50, 800, 3e-4),  # no hold: the corner at the deepest point
    ("flat", 2e-3, 0.1, 3.0, 500, 800, 1e-6),
    ("paraboloid", 3e-3, 0.05, 10.0, 5, 200, 3e-5),
    # holds that are not a whole number of blocks: the corner lies in the unblocked samples
    # between the hold's last block and the retract's first (9e-4 and 6e-4 of the peak, 1.4
    # and 0.8 noise sd, when the model's tip moved on a line across that gap)
    ("paraboloid", 3e-3, 0.3, 7.77, 500, 800, 2e-4),
    ("flat", 2e-3, 0.1, 4.41, 500, 800, 1e-6),
    # a flat punch's pull-off inside a block, between its first and second pick: the picks'
    # mean missed the kink by 8.4e-4 of the peak (2 noise sd), the rebuilt block 3.7e-5
    ("flat", 2e-3, 0.106, 11.38, 500, 800, 1e-4),
]


@pytest.mark.parametrize("tip, depth, alpha, hold, speed, rate, tol", CASES)
def test_columns_are_the_block_means_of_the_hereditary_force(tip, depth, alpha, hold, speed,
                                                             rate, tol):
    """Noise-free records (E0* 80 kPa): C·E0*·(Ting's columns) against the block means of
    the simulator's force on every retract block (measured worst 7.6e-6, 7e-5, 2e-8, 1e-5,
    7.4e-5 and 2e-8 of the peak; a block of the retract is 0.1-0.5 noise sd of the paper's
    sensor at 1e-3), and the same blocks at zero force where the tip has left."""
    tr = simulate_viscoelastic(PowerLawKernel(80e3, alpha), PAPER_TIPS[tip], depth=depth,
                               speed=speed / 6e4, hold_time=hold, rate=rate, z_surf=1e-4,
                               noise_sd=0.0, rng=1)
    data = prepare_cycle(tr, segments=tr.segment_names)
    ret = data.segment == 2
    col = ting_columns(data.edges, data.z_edges, data.sample_time[ret], np.array([1e-4]),
                       data.m, alpha)[0]
    model, truth = data.C * 80e3 * col, data.force[ret]
    peak = data.force.max()
    assert np.abs(model - truth).max() < tol * peak
    gone = truth <= 1e-9 * peak
    assert 5 < gone.sum() < ret.sum()
    np.testing.assert_array_equal(model <= 1e-9 * peak, gone)


def test_cutoff_is_the_simulators_t1():
    """On a sample-level motion (knots at the samples) t1 is the simulator's wherever the
    tip is still in contact (to 1e-7 s; measured 1.9e-8 s, the simulator's sum of
    exponentials); where the simulator's force is zero with the tip below the surface, t1
    lies before the contact started (the tip has left)."""
    tr = simulate_viscoelastic(PowerLawKernel(80e3, 0.25), PAPER_TIPS["paraboloid"],
                               depth=3e-3, speed=50 / 6e4, hold_time=2.0, rate=200.0,
                               z_surf=1e-4, noise_sd=0.0, rng=1)
    depth = 1e-4 - tr.z
    ref = hereditary_contact(tr.time, depth, 1.0, 1.5, PowerLawKernel(1.0, 0.25))
    ret = np.flatnonzero(tr.segment == 2)
    t1, j = ting_cutoff(tr.time[ret], tr.time, tr.z, 0.25)
    live = ref.force[ret] > 0
    assert live.sum() > 20 and (~live).sum() > 20
    np.testing.assert_allclose(t1[live], ref.t1[ret][live], rtol=0, atol=1e-7)
    onset = tr.time[np.argmax(depth > 0)]  # the first sample in contact
    gone = ~live & (depth[ret] > 0)
    assert gone.sum() > 5 and np.all(t1[gone] < onset)


def test_design_is_reused_for_every_surface_and_alpha():
    """One RetractDesign evaluates any (surfaces, alpha) as the one-off function does; a
    surface below the whole motion (never in contact) gives zero."""
    tr = simulate_viscoelastic(PowerLawKernel(80e3, 0.2), PAPER_TIPS["paraboloid"],
                               depth=3e-3, speed=50 / 6e4, hold_time=3.0, rate=400.0,
                               z_surf=1e-4, noise_sd=0.0, rng=1)
    data = prepare_cycle(tr, segments=tr.segment_names)
    ret = data.segment == 2
    design = RetractDesign(data.edges, data.z_edges, data.sample_time[ret], data.m)
    z = np.array([-1.0, 0.0, 1e-4, 3e-4])
    for alpha in (0.0, 0.2, 0.6):
        np.testing.assert_allclose(design.columns(z, alpha), ting_columns(
            data.edges, data.z_edges, data.sample_time[ret], z, data.m, alpha), rtol=1e-12)
    assert not design.columns(z, 0.2)[0].any()


def test_power_law_fit_of_the_whole_cycle():
    """A force-distance curve without a hold (approach and retract only): the approach alone
    does not resolve alpha (0.15), the retract does: E0*, alpha and z_surf within their
    90 % intervals, the model check passes; the SLS refuses the retract."""
    tr = simulate_viscoelastic(PowerLawKernel(60e3, 0.15), PAPER_TIPS["paraboloid"],
                               depth=3e-3, speed=50 / 6e4, hold_time=0.0, rate=400.0,
                               z_surf=2e-4, noise_sd=0.008, phi=0.3, offset=0.02, rng=7)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        whole = fit_rheology(tr, "power-law", segments="approach,retract", rng=1)
        ramp = fit_rheology(tr, "power-law", segments="approach", rng=1)
    tab = whole.table().set_index("parameter")
    for name, truth in (("E0*", 60e3), ("alpha", 0.15), ("z_surf", 2e-4)):
        assert tab.loc[name, "lo"] <= truth <= tab.loc[name, "hi"], (name, tab.loc[name])
    assert whole.model_ok
    w_whole, w_ramp = (np.subtract(*np.percentile(f.draws["alpha"], [95, 5]))
                       for f in (whole, ramp))
    assert w_whole < 0.25 * w_ramp, (w_whole, w_ramp)
    with pytest.raises(InputError, match="power law only"):
        fit_rheology(tr, "sls", segments="approach,retract")


def _within_3_sd(fit, truth: dict) -> None:
    """Each parameter's posterior median within 3 posterior sd of its truth (a single
    record: a 90 % interval misses one parameter in ten)."""
    for name, value in truth.items():
        d = fit.draws[name]
        assert abs(np.median(d) - value) < 3 * np.std(d), (name, np.median(d), np.std(d))


def _record(noise_sd: float = 0.008):
    """The record of the drag, tilt and adhesion tests: a power law (E0* 60 kPa, alpha 0.15)
    pressed 3 mm at 50 mm/min with a 2-s hold and a retract, 400 Hz, 8 mN AR(1) noise."""
    return simulate_viscoelastic(PowerLawKernel(60e3, 0.15), PAPER_TIPS["paraboloid"],
                                 depth=3e-3, speed=50 / 6e4, hold_time=2.0, rate=400.0,
                                 z_surf=2e-4, noise_sd=noise_sd, phi=0.3, rng=21)


@pytest.fixture(scope="module")
def clean_fit():
    """The record and its power-law fit over the whole cycle (drag fitted: the default)."""
    tr = _record()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return tr, fit_rheology(tr, "power-law", segments="approach,hold,retract", rng=1)


@pytest.mark.slow
def test_a_viscous_drag_is_fitted_with_the_retract_and_flagged_without_it(clean_fit):
    """A viscous drag F = b·(−dz/dt) on the probe (b = 6 N·s/m: ±5 mN at 50 mm/min, 0.6
    noise sd of one sample, over 0.4 mm out of contact) puts the approach above the retract.
    Fitted with the retract (the default), b is within 3 sd of 6 and so are E0*, alpha and
    z_surf of theirs; a clean record's b is within 3 sd of 0 and its table has the drag row;
    without the drag term the gap is flagged with b within 25 % and fails the model check."""
    tr, clean = clean_fit
    dragged = tr.replace(force=tr.force - 6.0 * np.gradient(tr.z, tr.time))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fit = fit_rheology(dragged, "power-law", segments="approach,hold,retract", rng=1)
        off = fit_rheology(dragged, "power-law", segments="approach,hold,retract", drag=False,
                           rng=1)
    for f, b in ((clean, 0.0), (fit, 6.0)):
        assert f.table().set_index("parameter").loc["drag", "unit"] == "N·s/m"
        _within_3_sd(f, {"drag": b, "E0": 60e3, "alpha": 0.15, "z_surf": 2e-4})
        assert f.model_ok and not any("viscous drag" in x for x in f.flags), f.flags
    assert "drag" not in off.draws
    (flag,) = [f for f in off.flags if "viscous drag" in f]
    b = float(flag.split("(b = ")[1].split(" N")[0])
    assert b == pytest.approx(6.0, rel=0.25), flag
    assert flag in off.offcontact and not off.model_ok


@pytest.mark.slow
def test_a_tilted_baseline_is_flagged_and_fitted_with_baseline_linear(clean_fit):
    """A baseline that tilts with the height (F1 = 40 N/m: 16 mN, 2 noise sd, over the 0.4 mm
    above the surface) is flagged by a constant-baseline fit and fails its model check; with
    baseline="linear" F1, E0*, alpha and z_surf lie within 3 sd of their truths and the check
    passes."""
    tr = clean_fit[0]
    tilted = tr.replace(force=tr.force + 40.0 * (tr.z - tr.z[0]))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        flat = fit_rheology(tilted, "power-law", segments="approach,hold,retract", rng=1)
        line = fit_rheology(tilted, "power-law", segments="approach,hold,retract",
                            baseline="linear", rng=1)
    (flag,) = [f for f in flat.flags if "tilt with the height" in f]
    assert not flat.model_ok and flag in flat.offcontact
    # the hint was tried (the same fit with baseline="linear") and kept, with what it gives
    assert "--baseline linear: tried, its model check passes, E0* " in flag, flag
    assert float(flag.split("F1 = ")[1].split(" N/m")[0]) == pytest.approx(40.0, rel=0.3)
    assert line.table().set_index("parameter").loc["tilt", "unit"] == "N/m"
    _within_3_sd(line, {"tilt": 40.0, "E0": 60e3, "alpha": 0.15, "z_surf": 2e-4})
    assert line.model_ok and not line.offcontact, line.flags
    with pytest.raises(InputError, match="baseline"):
        fit_rheology(tr, "power-law", baseline="quadratic")


@pytest.mark.slow
def test_adhesion_at_pull_off_is_flagged(clean_fit):
    """A pull-off dip after the contact ends on the retract (−30 mN, 4 noise sd, decaying
    over 0.3 s: the sample holding the tip) is flagged as adhesion and fails the model
    check; the same record without it is not flagged."""
    tr, clean = clean_fit
    ret = tr.segment == 2
    # the tip lets go where the noise-free force of the retract has fallen to zero (Ting's
    # contact ends before the tip is back at the surface)
    free = _record(noise_sd=0.0).force
    t_off = tr.time[ret][np.argmax(free[ret] <= 1e-9)]
    dt = tr.time - t_off
    dip = np.where(ret & (dt >= 0), -0.03 * np.exp(-np.clip(dt, 0, None) / 0.3), 0.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fit = fit_rheology(tr.replace(force=tr.force + dip), "power-law",
                           segments="approach,hold,retract", rng=1)
    assert not any("adhesion" in f for f in clean.flags), clean.flags
    (flag,) = [f for f in fit.flags if "adhesion" in f]
    assert not fit.model_ok and flag in fit.offcontact


@pytest.mark.parametrize("n", [1, 2, 5, 6, 13, 14, 15, 17, 58, 301])
@pytest.mark.parametrize("k", [5, 6, 25])
def test_picks_average_a_linear_force_to_its_block_mean(n, k):
    """The retract's evaluation samples of a block: evenly spread, symmetric about its middle
    (a force linear in time averages to the block mean), all of them when k >= n."""
    picks = symmetric_picks(n, k)
    assert picks.min() >= 0 and picks.max() <= n - 1 and np.all(np.diff(picks) > 0)
    assert picks.size == (n if k >= n else k + (k % 2 and not n % 2))
    np.testing.assert_array_equal(picks, n - 1 - picks[::-1])
    if k < n:  # evenly spread: no gap wider than the even spread's, rounded up, plus one
        assert np.diff(picks).max() <= np.ceil((n - 1) / (k - 1)) + 1
