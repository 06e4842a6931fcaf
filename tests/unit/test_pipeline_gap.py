"""``gap.csv`` in a report's results folder: computed once per package, then written from the
disk cache (issue 58, item 8: ~10 s on one core, the same table on every run)."""

from __future__ import annotations

import numpy as np
import pandas as pd

import palpbayes.gap as gap
from palpbayes import outputs as layout
from palpbayes.campaign.pipeline import write_gap
from palpbayes.twin import cache as twin_cache


def _table() -> pd.DataFrame:
    return pd.DataFrame({"material": ["Pink", "Grey"], "tip": ["flat", "sphere"],
                         "ratio": [1.0 / 3.0, np.nan], "explained": [True, False]})


def test_the_gap_table_is_computed_once_per_package(tmp_path, monkeypatch):
    monkeypatch.setenv("PALPBAYES_CACHE_DIR", str(tmp_path / "cache"))
    calls = []
    monkeypatch.setattr(gap, "gap_table", lambda: calls.append(1) or _table())
    out = tmp_path / "res"
    out.mkdir()
    pd.DataFrame({"material": ["Pink"]}).to_csv(out / layout.SUMMARY, index=False)

    path = write_gap(out)
    first = path.read_bytes()
    assert len(calls) == 1
    # the same bytes as the table written directly (what the report read before)
    direct = tmp_path / "direct.csv"
    _table().to_csv(direct, index=False, float_format="%.6g")
    assert first == direct.read_bytes()

    path.unlink()
    assert write_gap(out).read_bytes() == first
    assert len(calls) == 1  # from the cache: not computed again

    # another package (an edited module: another stamp) computes it again
    monkeypatch.setattr(twin_cache, "package_stamp", lambda: "another package")
    write_gap(out)
    assert len(calls) == 2


def test_without_a_paper_material_there_is_no_gap_table(tmp_path, monkeypatch):
    monkeypatch.setattr(gap, "gap_table", lambda: (_ for _ in ()).throw(AssertionError))
    out = tmp_path / "res"
    out.mkdir()
    pd.DataFrame({"material": ["Foam"]}).to_csv(out / layout.SUMMARY, index=False)
    (out / layout.GAP).write_text("stale\n", encoding="utf-8")
    assert write_gap(out) is None and not (out / layout.GAP).exists()


def test_package_stamp_covers_every_module():
    stamp = twin_cache.package_stamp()
    assert len(stamp) == 32
    twin_cache.package_stamp.cache_clear()
    assert twin_cache.package_stamp() == stamp  # stable
