"""The E* marginal of the exact engine: a Student-t mixture summarised on a grid."""

import numpy as np
import pytest
from scipy import stats

from palpbayes.bayes.exact import phi_grid
from palpbayes.bayes.mixture import tilted_mixture
from palpbayes.errors import InputError
from palpbayes.fitdata import ModelSpec
from palpbayes.online import OnlineEstimator
from palpbayes.paper import PAPER_TIPS

BOUNDS = (1.0, 1e12)


def test_one_node_gives_the_student_t_quantiles():
    s = tilted_mixture(np.zeros(1), np.array([1e5]), np.array([50.0]), 30, BOUNDS, tilt=False)
    q = stats.t.ppf([0.05, 0.95], 30, loc=1e5, scale=50.0)
    assert s.lo == pytest.approx(q[0], abs=0.05) and s.hi == pytest.approx(q[1], abs=0.05)
    assert s.sd == pytest.approx(50.0 * np.sqrt(30 / 28), rel=1e-3)


@pytest.mark.parametrize("far", [2e5, 5e5, 5e6])
def test_a_remote_node_of_negligible_mass_does_not_blur_the_peak(far):
    """A minor node (1e-7 of the mass) far away once stretched the grid so that the main peak
    was sampled by a few points: sd 23 instead of 50, or an interval 9x too wide."""
    one = tilted_mixture(np.zeros(1), np.array([1e5]), np.array([50.0]), 1e6, BOUNDS)
    two = tilted_mixture(np.log([1.0, 1e-7]), np.array([1e5, far]), np.array([50.0, 50.0]),
                         1e6, BOUNDS)
    assert two.sd == pytest.approx(one.sd, rel=1e-3)
    assert two.lo == pytest.approx(one.lo, rel=1e-6) and two.hi == pytest.approx(one.hi, rel=1e-6)


def test_two_real_modes_are_both_resolved():
    w = np.array([0.7, 0.3])
    s = tilted_mixture(np.log(w), np.array([1e5, 5e5]), np.array([50.0, 80.0]), 1e6, BOUNDS,
                       tilt=False)
    assert s.mean == pytest.approx(0.7 * 1e5 + 0.3 * 5e5, rel=3e-4)
    assert s.lo == pytest.approx(stats.norm.ppf(0.05 / 0.7, 1e5, 50.0), abs=0.05 * 50.0)


def test_phi_grid_covers_the_whole_prior():
    g = phi_grid((-0.99, 0.99))
    assert g[0] == -0.99 and g[-1] == 0.99 and np.all(np.diff(g) > 0)


@pytest.mark.parametrize("kw, match", [
    (dict(noise_pp=-0.01), "noise_pp"), (dict(noise_pp=0.0), "noise_pp"),
    (dict(f_unc=float("nan")), "f_unc"), (dict(persist=0), "persist"), (dict(level=1.5), "level"),
])
def test_online_options_are_checked(kw, match):
    with pytest.raises(InputError, match=match):
        OnlineEstimator(ModelSpec(PAPER_TIPS["flat"]), **kw)


def test_an_empty_first_chunk_is_no_error():
    est = OnlineEstimator(ModelSpec(PAPER_TIPS["flat"]))
    state = est.update([], [], [])
    assert state.n == 0 and not state.in_contact and not state.should_stop
