"""Grouping and bookkeeping of the pooled table (palpbayes.rheology.campaign), without fits:
which manifest rows form a group, a manifest of one trace per specimen writes the header
only, SLS fits are not pooled, the console lines."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pandas as pd

from palpbayes.outputs import RHEOLOGY_OUTPUTS, RHEOLOGY_POOLED
from palpbayes.rheology.campaign import (
    POOLED_COLUMNS,
    SpeedPools,
    _n_speeds,
    manifest_groups,
    pooled_lines,
)


def _manifest(rows) -> pd.DataFrame:
    base = {"specimen": "", "tip": "paraboloid", "radius_m": 0.0117, "half_angle_deg": np.nan,
            "profile_c": np.nan, "profile_n": np.nan}
    return pd.DataFrame([{**base, **r} for r in rows])


def test_groups_are_material_specimen_and_tip_with_its_size():
    m = _manifest([
        {"trace_id": "a", "material": "W", "specimen": "W1"},
        {"trace_id": "b", "material": "W", "specimen": "W1"},
        {"trace_id": "c", "material": "W", "specimen": "W2"},  # another specimen
        {"trace_id": "d", "material": "W", "specimen": "W1", "radius_m": 0.005},  # another tip
        {"trace_id": "e", "material": "W", "specimen": "W1", "tip": "flat", "radius_m": 0.01},
        {"trace_id": "f", "material": "P"},  # empty specimen: material x tip
        {"trace_id": "g", "material": "P", "specimen": " "},
    ])
    groups = manifest_groups(m)
    assert list(groups.values()) == [["a", "b"], ["c"], ["d"], ["e"], ["f", "g"]]
    key = next(iter(groups))
    assert key == ("W", "W1", "paraboloid", 0.0117, None, None, None)


def test_one_trace_per_specimen_writes_no_table(tmp_path):
    """Issue 58: a header-only table was written (and announced) when nothing pooled."""
    m = _manifest([{"trace_id": t, "material": "W", "specimen": t} for t in "abc"])
    pools = SpeedPools(m)
    for t in "abc":  # never looked at: alone in their groups
        pools.add(SimpleNamespace(trace_id=t), SimpleNamespace(rheology="power-law"))
    table = pools.finish(tmp_path)
    assert table.empty and list(table.columns) == POOLED_COLUMNS
    assert not (tmp_path / RHEOLOGY_POOLED).exists()
    assert pooled_lines(table) == ["no pooled power law: no specimen x tip of the manifest has "
                                   "two fitted power-law traces"]
    assert RHEOLOGY_POOLED in RHEOLOGY_OUTPUTS  # fit --rheology removes a stale table


def test_sls_fits_are_not_pooled(tmp_path):
    m = _manifest([{"trace_id": t, "material": "W"} for t in "ab"])
    pools = SpeedPools(m)
    for t in "ab":  # an SLS fit is dropped before anything else is read
        pools.add(SimpleNamespace(trace_id=t), SimpleNamespace(rheology="sls"))
    assert pools.finish(tmp_path).empty


def test_speeds_count_apart_by_more_than_five_percent():
    assert _n_speeds([5e-4, 5.1e-4, 5e-3]) == 2
    assert _n_speeds([1.0, 1.06, 1.2]) == 3
    assert _n_speeds([2.0]) == 1


def test_console_line_per_group():
    row = dict.fromkeys(POOLED_COLUMNS, np.nan)
    row.update(material="W", specimen="W1", tip="flat", n_traces=2, speeds_mm_min="5;50",
               E0_star_pa=8.1e4, E0_star_lo_pa=7.9e4, E0_star_hi_pa=8.3e4, alpha=0.15,
               alpha_lo=0.14, alpha_hi=0.16, flag_codes="trace_disagrees", error="")
    lines = pooled_lines(pd.DataFrame([row]))
    assert len(lines) == 2 and lines[0].startswith("pooled power law per specimen x tip")
    # issue 58: E0* with the package's prefix (it read "8.1e+04 [7.9e+04, 8.3e+04] Pa")
    assert lines[1] == ("  W/W1 x flat: 2 traces at 5, 50 mm/min: E0* 81 kPa [79 kPa, "
                        "83 kPa], alpha 0.15 [0.14, 0.16]; flagged: trace_disagrees "
                        "(notes in rheology_pooled.csv)")
