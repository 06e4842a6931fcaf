"""The online estimator's full interval (E with the budget), the target on it and the model
checks on the samples so far (issue 46)."""

from __future__ import annotations

import math

import pytest

from palpbayes.errors import InputError
from palpbayes.fitdata import ModelSpec
from palpbayes.online import OnlineEstimator, StoppingRule, chunks, replay
from palpbayes.paper import PAPER_TIPS
from palpbayes.sim import simulate_trace

E_TRUE = 1.25e5
TIP = PAPER_TIPS["paraboloid"]


@pytest.fixture(scope="module")
def trace():
    return simulate_trace(E_TRUE, TIP, thickness=0.03, force_offset=0.05, rng=17, base=None)


def _run(trace, rule, **kw):
    est = OnlineEstimator(ModelSpec(TIP, nu=0.3), rule=rule, **kw)
    states = []
    for t, z, f in chunks(trace, 100, est.limit):
        states.append(est.update(t, z, f))
        if states[-1].should_stop:
            break
    return est, [s for s in states if s.E is not None]


def test_target_on_is_validated():
    with pytest.raises(InputError, match="target_on"):
        StoppingRule(target=0.05, target_on="budget")
    assert StoppingRule(target=0.05).target_on == "stat"  # the library's default is unchanged
    assert StoppingRule(target=0.05, target_on="full").full
    assert not StoppingRule(max_force=1.0, target_on="full").full


def test_the_full_interval_contains_the_statistical_one_and_has_a_floor(trace):
    _, states = _run(trace, StoppingRule(max_depth=1e-3), total=True)
    assert len(states) >= 5
    for s in states:
        T = s.E_total
        assert T.lo < s.E.lo and s.E.hi < T.hi and T.rel_half_width > s.E.rel_half_width
        # the budget alone: ~±3.5 % at nu 0.3 (nu ± 0.05 is most of it), whatever the depth
        assert 0.03 < s.floor < 0.04 and T.rel_half_width >= 0.98 * s.floor
    # without total the estimator does not pay for it
    _, plain = _run(trace, StoppingRule(max_depth=1e-3))
    assert plain[-1].E_total is None and math.isnan(plain[-1].floor)


def test_a_full_target_stops_later_than_a_statistical_one(trace):
    """The statistical ±4 % fires first; on the full interval it waits until the budget's
    interval is within ±4 % too."""
    _, stat = _run(trace, StoppingRule(target=0.04), total=True)
    _, full = _run(trace, StoppingRule(target=0.04, target_on="full"))
    assert stat[-1].stop == full[-1].stop == "target precision"
    assert full[-1].n > stat[-1].n
    assert full[-1].E_total.rel_half_width <= 0.04 < stat[-1].E_total.rel_half_width
    assert all(s.E_total.rel_half_width > 0.04 for s in full[:-1])


def test_a_full_target_below_the_budget_floor_never_fires_and_says_so(trace):
    _, states = _run(trace, StoppingRule(target=0.02, target_on="full"))
    assert not any(s.should_stop for s in states)
    assert "below the ±3.5 % the uncertainty budget alone gives" in states[-1].flags[-1]


def test_model_checks_run_on_the_samples_so_far(trace):
    est, states = _run(trace, StoppingRule(target=0.05, target_on="full"))
    checks = est.model_checks()
    assert [c.name for c in checks] == ["exponent", "residual_structure", "depth_consistency",
                                        "ppc"]
    assert all(c.passed for c in checks)  # the simulated law is the fitted one
    assert abs(checks[0].statistic - 1.5) < 0.05  # the paraboloid's exponent
    assert OnlineEstimator(ModelSpec(TIP)).model_checks() == []  # nothing yet


def test_replay_keeps_the_checks_and_the_full_interval_at_the_stop(trace):
    res = replay(trace, ModelSpec(TIP, nu=0.3), rule=StoppingRule(target=0.05,
                                                                  target_on="full"))
    s = res.at_stop
    assert res.budget_at_stop == s.E_total and len(res.checks_at_stop) == 4
    row = res.row
    assert row["target_on"] == "full" and row["model_ok_stop"] is True
    assert (row["E_total_stop_hi_pa"] - row["E_total_stop_lo_pa"]) / (2 * row["E_stop_pa"]) \
        == pytest.approx(s.E_total.rel_half_width * s.E_total.median / s.E.median)
    h = res.history
    assert h["total_rel_half_width"].notna().all()


def test_fewer_draws_where_the_full_interval_is_only_shown_leave_the_decision_alone(trace):
    """follow shows the full interval from SHOWN_BUDGET_DRAWS draws (the draws cost ~5 ms per
    1,000); where a full target may fire (the statistical interval within it) the update takes
    all BUDGET_DRAWS: the stop and its interval are those of the full run."""
    from palpbayes.online.full_interval import BUDGET_DRAWS, SHOWN_BUDGET_DRAWS

    rule = StoppingRule(target=0.04, target_on="full")
    _, full = _run(trace, rule)
    _, shown = _run(trace, rule, budget_draws=SHOWN_BUDGET_DRAWS)
    assert SHOWN_BUDGET_DRAWS < BUDGET_DRAWS
    assert [s.n for s in shown] == [s.n for s in full]
    assert shown[-1].stop == "target precision"
    assert shown[-1].E_total == full[-1].E_total  # the deciding update: the same draws
    # elsewhere the shown interval is close to the full-draw one (quantiles of 1,000 draws)
    for a, b in zip(shown[:-1], full[:-1], strict=True):
        assert a.E_total.lo == pytest.approx(b.E_total.lo, rel=0.01)
        assert a.E_total.hi == pytest.approx(b.E_total.hi, rel=0.01)
    with pytest.raises(InputError, match="budget_draws"):
        OnlineEstimator(ModelSpec(TIP, nu=0.3), budget_draws=10)
