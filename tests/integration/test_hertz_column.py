"""The paper's Hertz fit of sphere traces (summary.csv ``E_hertz_pa``, ``E_hertz_rel_diff``).

Tip ``sphere`` is the exact Sneddon law; the paper fitted its sphere with Hertz (docs/design.md §1).
On traces simulated with Sneddon's law, least squares with the paraboloid law at the sphere's
radius must give an E a few per cent *below* the Sneddon E, more so the deeper the indentation.
"""

from __future__ import annotations

import math

import pytest

from palpbayes.campaign.fitjob import SUMMARY_COLUMNS, FitOptions, fit_trace
from palpbayes.contact import Tip
from palpbayes.sim import simulate_trace

E_TRUE = 111e3
R = 0.01
SPHERE = Tip("sphere", radius=R)


def _lsq_row(depth: float, tip: Tip = SPHERE, rng: int = 3) -> dict:
    tr = simulate_trace(E_TRUE, tip, thickness=0.03, depth=depth, rng=rng, trace_id="t",
                        base=None)
    (row,) = fit_trace(tr, FitOptions(method="lsq")).rows
    return row


def test_columns_are_in_the_summary_layout():
    i = SUMMARY_COLUMNS.index("E_hertz_pa")
    assert SUMMARY_COLUMNS[i:i + 2] == ["E_hertz_pa", "E_hertz_rel_diff"]


@pytest.mark.parametrize(("depth", "lo", "hi"), [(2e-3, -0.032, -0.017),   # d/R = 0.2
                                                 (3e-3, -0.045, -0.028)])  # d/R = 0.3 (paper)
def test_hertz_fit_of_a_sneddon_sphere_is_a_few_percent_low(depth, lo, hi):
    row = _lsq_row(depth)
    assert row["E_pa"] == pytest.approx(E_TRUE, rel=0.01)  # Sneddon fit recovers the truth
    assert row["E_hertz_pa"] < row["E_pa"]                  # Hertz: more force per E -> lower E
    rel = row["E_hertz_rel_diff"]
    assert rel == pytest.approx((row["E_hertz_pa"] - row["E_pa"]) / row["E_pa"], rel=1e-12)
    assert lo < rel < hi


def test_deeper_indentation_widens_the_gap():
    assert _lsq_row(3e-3)["E_hertz_rel_diff"] < _lsq_row(1.5e-3)["E_hertz_rel_diff"] < 0


def test_other_tips_get_nan():
    row = _lsq_row(2e-3, tip=Tip("paraboloid", radius=0.0117))
    assert math.isnan(row["E_hertz_pa"]) and math.isnan(row["E_hertz_rel_diff"])


def test_an_untared_offset_does_not_pose_as_the_hertz_gap():
    """The paper's least squares has no offset: on an untared trace (+0.3 N) its E moves, but
    the Hertz gap is taken on the tared force and stays that of the tared trace (before: the
    untared ratio read -5.1 % for -3.6 %, and the Bayesian row compared its own E with the
    biased least-squares Hertz E); the Bayesian row gets its own E times the ratio."""
    def rows(offset):
        tr = simulate_trace(E_TRUE, SPHERE, thickness=0.03, depth=3e-3, rng=3, trace_id="t",
                            base=None, force_offset=offset)
        return {r["method"]: r for r in fit_trace(
            tr, FitOptions(method="both", engine="exact", seed=1)).rows}

    tared, untared = rows(0.0), rows(0.3)
    gap = tared["lsq"]["E_hertz_rel_diff"]
    assert -0.06 < gap < -0.01
    # the offset moves the least-squares E itself, not the gap
    assert abs(untared["lsq"]["E_pa"] / tared["lsq"]["E_pa"] - 1) > 0.02
    assert untared["lsq"]["E_hertz_rel_diff"] == pytest.approx(gap, abs=0.01)
    b = untared["bayes"]
    assert b["E_hertz_rel_diff"] == untared["lsq"]["E_hertz_rel_diff"]
    assert b["E_hertz_pa"] == pytest.approx(b["E_pa"] * (1 + b["E_hertz_rel_diff"]), rel=1e-12)
