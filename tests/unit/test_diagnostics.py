"""Convergence figures (palpbayes.bayes.diagnostics)."""

from __future__ import annotations

import math

from palpbayes.bayes.diagnostics import Diagnostics


def _diag(rhat: dict) -> Diagnostics:
    names = list(rhat)
    return Diagnostics(rhat=rhat, ess_bulk=dict.fromkeys(names, 4000.0),
                       ess_tail=dict.fromkeys(names, 4000.0), tau=dict.fromkeys(names, 1.0),
                       acceptance=1.0, n_steps=4000, hit_cap=False)


def test_an_undefined_rhat_is_not_converged_wherever_it_stands():
    """A NaN R-hat makes the fit not converged, first or last among the parameters (the
    builtin max skipped a NaN unless it came first)."""
    assert _diag({"E_star": 1.001, "z_surf": 1.002}).converged
    for rhat in ({"E_star": math.nan, "z_surf": 1.0}, {"E_star": 1.0, "z_surf": math.nan}):
        d = _diag(rhat)
        assert math.isnan(d.rhat_max) and not d.converged
        assert d.problems() and "R-hat" in d.problems()[0]
