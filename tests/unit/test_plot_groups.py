"""The campaign figures' shared layout: one column per material × tip, in the report's order,
each material's Instron band behind its columns."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from palpbayes.plots import plot_halfspace_vs_layer, plot_specimen_as_tested


def _comparison() -> pd.DataFrame:
    rows = []
    for mat, gt in (("Grey", 214e3), ("White", 124e3)):  # out of the report's order on purpose
        for tip in ("sphere", "flat"):
            base = {"material": mat, "tip": tip, "gt_E_pa": gt, "gt_sd_pa": 0.1 * gt}
            rows.append({**base, "method": "lsq", "E_pa": 1.3 * gt, "E_free_pa": 1.1 * gt,
                         "E_bonded_pa": 1.0 * gt})
            rows.append({**base, "method": "bayes", "E_new_pa": gt, "E_new_lo_pa": 0.8 * gt,
                         "E_new_hi_pa": 1.2 * gt, "E_instron_pa": 1.1 * gt,
                         "E_instron_new_lo_pa": 0.9 * gt, "E_instron_new_hi_pa": 1.3 * gt})
    return pd.DataFrame(rows)


@pytest.mark.parametrize("plot, per_column", [(plot_specimen_as_tested, 2),
                                              (plot_halfspace_vs_layer, 1)])
def test_columns_bands_and_intervals(plot, per_column):
    fig = plot(_comparison())
    ax = fig.axes[0]
    labels = [t.get_text() for t in ax.get_xticklabels()]
    assert labels == ["White\nflat", "White\nsphere", "Grey\nflat", "Grey\nsphere"]
    np.testing.assert_allclose(ax.get_xticks(), [0.0, 1.0, 2.5, 3.5])
    # one Instron line per material, at its mean, spanning its columns
    lines = [c for c in ax.collections if c.__class__.__name__ == "LineCollection"
             and len(c.get_segments()) == 1 and c.get_segments()[0][0][1] ==
             c.get_segments()[0][1][1]]
    levels = sorted(seg[0][1] for c in lines for seg in c.get_segments())
    assert levels[:1] == [pytest.approx(124.0)] and pytest.approx(214.0) in levels
    # a 90 % interval per column (the Bayesian one, and on the twin figure E_instron's)
    assert len(ax.containers) == per_column * 4
    tops = sorted(max(seg[1][1] for seg in c.lines[2][0].get_segments())
                  for c in ax.containers)
    assert pytest.approx(1.2 * 214.0) in tops
