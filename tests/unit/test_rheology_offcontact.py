"""The out-of-contact tilt check (palpbayes.rheology.offcontact.baseline_tilt) on residuals
whose slope is known: recovered within its standard error, never a standard error of zero."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from palpbayes.rheology.offcontact import N_SE, baseline_tilt


def _blocks(span: float, n: int = 40, constant_within: bool = False):
    """n approach blocks then n retract blocks above a surface at 0, spanning ``span`` [m]."""
    z_app = np.full(n, 2 * span) if constant_within else np.linspace(2 * span, span, n)
    z_ret = np.full(n, 1.5 * span) if constant_within else np.linspace(span, 2 * span, n)
    z = np.concatenate([z_app, z_ret])
    segment = np.repeat([0, 2], n)
    return SimpleNamespace(z=z, segment=segment, z_hi=float(z.max()), z_ref=0.0)


@pytest.mark.parametrize("span", [1e-3, 1e-9])
def test_a_known_tilt_is_recovered_within_its_standard_error(span):
    rng = np.random.default_rng(3)
    data = _blocks(span)
    sd = 0.004  # [N]
    slope = 5 * sd / span  # [N/m]: the tilt moves the force 5 sd over the span
    residual = slope * data.z + 0.02 * (data.segment == 2) + rng.normal(0, sd, data.z.size)
    f1, se, got_span = baseline_tilt(data, residual, z_surf=0.0)
    # OLS slope se of one segment's 40 evenly spaced heights over the span, two segments
    x = np.linspace(0, 1, 40)
    want_se = sd / np.sqrt(2 * np.sum((x - x.mean()) ** 2)) / span
    assert got_span == pytest.approx(span)
    assert 0.5 * want_se < se < 2.5 * want_se  # the AR(1) factor of white noise is near 1
    assert abs(f1 - slope) < 3 * se


def test_pure_noise_over_a_nanometre_is_not_a_tilt():
    """Heights spanning a nanometre (a real cell whose surface sits at the first height):
    the standard error scales with 1/span instead of collapsing to zero."""
    rng = np.random.default_rng(4)
    data = _blocks(1e-9)
    f1, se, _ = baseline_tilt(data, rng.normal(0, 0.004, data.z.size), z_surf=0.0)
    assert se > 0 and abs(f1) < N_SE * se


def test_heights_constant_within_each_segment_give_no_slope():
    data = _blocks(1e-6, constant_within=True)
    assert baseline_tilt(data, np.zeros(data.z.size), z_surf=0.0) is None
