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
