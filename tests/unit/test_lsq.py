"""The paper's least-squares baseline on simulated traces with known truth."""

import math

import numpy as np
import pytest

from palpbayes.contact import Tip
from palpbayes.errors import NoContactError
from palpbayes.fitdata import ModelSpec, prepare
from palpbayes.lsq import fit_lsq, profile_rss
from palpbayes.sim import simulate_trace

TIPS = {
    "flat": Tip("flat", radius=0.010),
    "sphere": Tip("sphere", radius=0.010),
    "paraboloid": Tip("paraboloid", radius=0.0117),
    "cone": Tip("cone", half_angle=math.radians(70)),
    "power": Tip("power", c=300.0, n=2.5),
}
E_TRUE, Z_TRUE = 111e3, 0.1


@pytest.mark.parametrize("kind", list(TIPS))
def test_noise_free_recovery(kind):
    tr = simulate_trace(E_TRUE, TIPS[kind], thickness=0.03, noise_pp=0.0, rng=0, base=None)
    r = fit_lsq(tr, f_unc=48e-3)  # noise-free: no noise spec can be read from the baseline
    assert r.E == pytest.approx(E_TRUE, rel=1e-6)
    assert r.z_surf == pytest.approx(Z_TRUE, abs=1e-6 * 3e-3)  # 1e-6 of the depth
    assert r.rms < 1e-9
    assert not r.constraint_active


@pytest.mark.parametrize("kind", ["sphere", "paraboloid"])
def test_paper_noise_recovery(kind):
    """48 mN p-p: E within 1 % and z_surf within 0.05 mm, over 10 seeds."""
    errs_E, errs_z, cover = [], [], 0
    for seed in range(10):
        tr = simulate_trace(E_TRUE, TIPS[kind], thickness=0.03, rng=seed, base=None)
        r = fit_lsq(tr)
        errs_E.append(r.E / E_TRUE - 1)
        errs_z.append(r.z_surf - tr.metadata["z_surf_true"])
        cover += r.E_lo <= E_TRUE <= r.E_hi
    assert np.max(np.abs(errs_E)) < 0.01
    assert np.max(np.abs(errs_z)) < 0.05e-3
    assert cover >= 7  # the Gauss-Newton 90 % interval is roughly right for iid noise


def test_flat_tip_paper_noise():
    """Flat punch, data past 20 % of the penetration (the paper's rule)."""
    errs = []
    for seed in range(10):
        tr = simulate_trace(E_TRUE, TIPS["flat"], thickness=0.03, rng=seed, base=None)
        r = fit_lsq(tr)
        data = prepare(tr, ModelSpec(tr.tip))
        # the paper's window: only samples past 20 % of the penetration below the onset
        cut = data.z_contact - 0.2 * (data.z_contact - data.z_min)
        assert data.fit_fraction == 0.2 and np.all(data.z <= cut)
        loading = tr.loading_segment()
        assert r.n_points == np.count_nonzero(loading.z <= cut)
        errs.append(r.E / E_TRUE - 1)
    # measured: |error| < 0.1 % — the linear law pins E* and z_surf from the contact part
    assert np.max(np.abs(errs)) < 0.005


def test_constraint_is_respected_when_the_free_optimum_violates_it():
    # Hertz data fitted with the flat-punch law: the best straight line cuts the depth
    # axis below the real surface, where the measured force already exceeds F_unc.
    tr = simulate_trace(E_TRUE, TIPS["paraboloid"], thickness=0.03, rng=3, base=None)
    model = ModelSpec(Tip("flat", radius=0.01))
    data = prepare(tr, model, fit_fraction=0.0)
    r = fit_lsq(tr, model, fit_fraction=0.0)
    assert r.constraint_active
    assert abs(r.force_at_surface) <= data.f_unc + 1e-12
    assert r.z_surf == pytest.approx(data.z_contact, abs=1e-9)
    # the free optimum is lower and has a smaller residual, but is not admissible
    grid = np.linspace(data.z_contact - 1e-3, data.z_top, 4001)
    rss, _ = profile_rss(data, grid)
    z_free = grid[np.argmin(rss)]
    assert z_free < data.z_contact - 1e-5
    assert abs(data.measured_force_at(z_free)) > data.f_unc
    assert rss.min() < r.rss


def test_no_contact_is_a_clear_error():
    tr = simulate_trace(E_TRUE, TIPS["sphere"], thickness=0.03, rng=0, base=None)
    shallow = tr.replace(force=tr.force * 0.0 + 0.001)
    with pytest.raises(NoContactError, match="never leaves"):
        fit_lsq(shallow)


@pytest.mark.parametrize("position_noise", [2e-6, 10e-6])
def test_surface_force_obeys_the_constraint_with_noisy_z(position_noise):
    """Robot position noise makes z locally non-monotone; the contact onset and the reported
    force where the tip passed z_surf are both read on first passage, so they agree.  (Sorting
    the samples by z instead reported up to 77 mN against F_unc = 48 mN.)"""
    model = ModelSpec(Tip("flat", radius=0.01))  # Hertz data, flat law: the constraint binds
    for seed in range(10):
        tr = simulate_trace(E_TRUE, TIPS["paraboloid"], thickness=0.03,
                            position_noise=position_noise, rng=seed, base=None)
        data = prepare(tr, model, fit_fraction=0.0)
        assert float(data.measured_force_at(data.z_contact)) == pytest.approx(data.f_unc)
        r = fit_lsq(tr, model, fit_fraction=0.0)
        assert abs(r.force_at_surface) <= data.f_unc * (1 + 1e-9)
