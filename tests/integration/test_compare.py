"""Comparison with the ground truth: z-score and interval columns on hand-computed tables,
the pooling inputs campaign/comparison.py reads, and the text table."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from presets import FAST

import palpbayes.campaign.comparison as comparison
from palpbayes import pooling
from palpbayes.bayes import BudgetSpec
from palpbayes.bayes.diagnostics import import_arviz
from palpbayes.campaign.compare_text import format_comparison
from palpbayes.campaign.comparison import COMPARISON_COLUMNS, _lsq_row, compare
from palpbayes.campaign.reference import gt_columns, new_specimen_sd

Z90 = 1.6448536269514722  # Phi^-1(0.95)
GT = pd.DataFrame({"material": ["White", "Grey"], "n": [5, 5],
                   "E_mean_pa": [100e3, 194e3], "E_sd_pa": [10e3, np.nan]})


# ----------------------------------------------------------------------------- z and interval


def test_new_specimen_sd():
    assert new_specimen_sd(90e3, 150e3) == pytest.approx(60e3 / (2 * Z90), rel=1e-12)
    assert new_specimen_sd(90e3, 150e3, level=0.95) == pytest.approx(60e3 / (2 * 1.959964),
                                                                      rel=1e-6)
    assert math.isnan(new_specimen_sd(np.nan, 150e3))


def test_lsq_row_and_its_z_by_hand():
    """Four traces 100, 110, 120, 130 kPa against GT 100 ± 10 kPa."""
    g = pd.DataFrame({"E_pa": [100e3, 110e3, 120e3, 130e3], "rss_n2": 1.0})
    row = {"method": "lsq", **_lsq_row(g, 0.9)}
    sd = math.sqrt(((15**2 + 5**2) * 2) / 3) * 1e3  # 12.910 kPa
    t = 2.3533634348018264  # t(0.95, 3)
    half_new = t * sd * math.sqrt(1 + 1 / 4)  # 33.97 kPa
    assert row["E_pa"] == pytest.approx(115e3) and row["E_sd_pa"] == pytest.approx(sd)
    assert row["E_new_lo_pa"] == pytest.approx(115e3 - half_new)
    assert row["E_new_hi_pa"] == pytest.approx(115e3 + half_new)
    out = gt_columns(row, GT, "White")
    sd_new = half_new / Z90  # 20.65 kPa
    assert out["gt_z_new"] == pytest.approx(15e3 / math.sqrt(sd_new**2 + 10e3**2), rel=1e-9)
    assert out["gt_z_new"] == pytest.approx(0.654, abs=1e-3)
    assert out["gt_in_new_interval"] is True  # 100 in [81.0, 149.0]
    assert out["rel_err_pct"] == pytest.approx(-15.0)
    assert (out["gt_E_pa"], out["gt_sd_pa"], out["gt_n"]) == (100e3, 10e3, 5)


def test_one_z_definition_for_both_methods():
    """Same E and the same 90 % new-specimen interval give the same z whatever the method and
    whatever sd each method reports (sd over traces; heavy-tailed predictive sd)."""
    common = {"E_pa": 115e3, "E_new_pa": 114e3, "E_new_lo_pa": 90e3, "E_new_hi_pa": 150e3}
    lsq = {"method": "lsq", "E_sd_pa": 8e3, "E_new_sd_pa": 9e3, **common}
    bayes = {"method": "bayes", "E_sd_pa": 3e3, "E_new_sd_pa": 40e3, **common}
    z_lsq = gt_columns(lsq, GT, "White")["gt_z_new"]
    z_bayes = gt_columns(bayes, GT, "White")["gt_z_new"]
    sd_new = 60e3 / (2 * Z90)  # 18.24 kPa
    expected = 15e3 / math.sqrt(sd_new**2 + 10e3**2)
    assert z_lsq == pytest.approx(expected, rel=1e-12)
    assert z_bayes == pytest.approx(expected, rel=1e-12)
    assert expected == pytest.approx(0.7212, abs=1e-4)
    # the old definitions would have given 15/sqrt(8² + 10²) = 1.17 and 15/sqrt(40² + 10²) = 0.36


def test_gt_in_new_interval_and_edge_cases():
    row = {"method": "bayes", "E_pa": 150e3, "E_new_lo_pa": 120e3, "E_new_hi_pa": 180e3}
    out = gt_columns(row, GT, "White")
    assert out["gt_in_new_interval"] is False  # 100 < 120
    assert np.isnan(out["gt_in_E_interval"])  # the row has no E_lo/E_hi: no verdict
    # the material's own interval is tested by its own column, apart from the new-specimen one
    both = gt_columns({**row, "E_new_lo_pa": 95e3, "E_lo_pa": 130e3, "E_hi_pa": 170e3}, GT,
                      "White")
    assert both["gt_in_new_interval"] is True and both["gt_in_E_interval"] is False
    assert gt_columns({**row, "E_lo_pa": 90e3, "E_hi_pa": 170e3}, GT,
                      "White")["gt_in_E_interval"] is True
    assert out["gt_z_new"] == pytest.approx(
        50e3 / math.sqrt((60e3 / (2 * Z90)) ** 2 + 10e3**2), rel=1e-12)
    assert gt_columns({**row, "E_new_lo_pa": 100e3}, GT, "White")["gt_in_new_interval"] is True
    # case-insensitive material match; a missing GT sd counts as zero
    grey = gt_columns({**row, "E_pa": 200e3, "E_new_lo_pa": 150e3, "E_new_hi_pa": 250e3}, GT,
                      "grey")
    assert grey["gt_sd_pa"] == 0.0 and grey["gt_in_new_interval"] is True
    assert grey["gt_z_new"] == pytest.approx(6e3 / (100e3 / (2 * Z90)), rel=1e-12)
    # no interval: GT columns and the error, but no z and no coverage verdict
    bare = gt_columns({"method": "lsq", "E_pa": 110e3, "E_new_lo_pa": np.nan,
                       "E_new_hi_pa": np.nan}, GT, "White")
    assert np.isnan(bare["gt_z_new"]) and np.isnan(bare["gt_in_new_interval"])
    assert bare["rel_err_pct"] == pytest.approx(-10.0)
    assert gt_columns(row, GT, "Pink") == {} and gt_columns(row, None, "White") == {}
    assert set(gt_columns({"method": "lsq", "E_pa": np.nan}, GT, "White")) == {
        "gt_E_pa", "gt_sd_pa", "gt_n"}


# ----------------------------------------------------------------------------- pooling inputs


def _results_folder(root, rng):
    """A results folder: two groups × three traces; the budgeted E_total is 3·E."""
    az = import_arviz()
    post_dir = root / "posterior"
    post_dir.mkdir(parents=True)
    rows, geometry, stat = [], [], {}
    for material, E0 in (("White", 111e3), ("Grey", 194e3)):
        for k in range(3):
            tid = f"{material}_{k}"
            E = np.exp(rng.normal(np.log(E0 * (1 + 0.05 * (k - 1))), 0.01, (2, 300)))
            z = rng.normal(0.1 + 1e-4 * k, 1e-5, (2, 300))
            idata = az.from_dict(posterior={"E": E, "E_total": 3.0 * E * np.exp(
                rng.normal(0, 0.1, E.shape)), "E_star": E / 0.91, "z_surf": z})
            idata.to_netcdf(str(post_dir / f"{tid}.nc"), engine="h5netcdf")
            stat[tid] = (float(np.log(E).mean()), float(np.log(E).std(ddof=1)),
                         float(np.median(z)), float(np.median(E / 0.91)))
            for method, e in (("bayes", float(np.median(E))), ("lsq", float(np.median(E)))):
                rows.append({"trace_id": tid, "method": method, "tip": "sphere",
                             "material": material, "E_pa": e, "converged": True, "notes": ""})
            geometry.append({"trace_id": tid, "material": material, "tip": "sphere",
                             "specimen": f"{material}_S{k}", "radius_m": 0.01,
                             "thickness_m": 0.03})
    pd.DataFrame(rows).to_csv(root / "summary.csv", index=False)
    pd.DataFrame(geometry).to_csv(root / "traces.csv", index=False)
    return stat


def test_compare_pools_the_statistical_E_and_applies_the_budget_once(tmp_path, monkeypatch):
    stat = _results_folder(tmp_path / "res", np.random.default_rng(0))
    calls = []
    sentinel = object()
    real_pool = pooling.pool_group

    def spy(m, s, *, material, tip, data, z_surf, estar, budget, tau_prior_sd, seed,
            settings, p_bonded=None, base_ratio=1.0):
        calls.append({"material": material, "tip": tip, "m": list(m), "s": list(s),
                      "data": data, "z_surf": z_surf, "estar": estar, "budget": budget})
        return real_pool(m, s, material=material, tip=tip, tau_prior_sd=tau_prior_sd,
                         seed=seed, settings=settings)  # stage 2 only: no geometry here

    monkeypatch.setattr(comparison, "pool_group", spy)
    monkeypatch.setattr(comparison, "fitdata_from_posterior", lambda idata, model: sentinel)
    gt_file = tmp_path / "groundtruth_summary.csv"
    GT.to_csv(gt_file, index=False)
    cmp = compare(tmp_path / "res", groundtruth=gt_file, pooling_settings=FAST,
                           tau_prior_sd=0.3, seed=1)
    # one pooling per material × tip, each with the budget (applied there, once)
    assert [(c["material"], c["tip"]) for c in calls] == [("White", "sphere"),
                                                          ("Grey", "sphere")]
    for c in calls:
        ids = [f"{c['material']}_{k}" for k in range(3)]
        # the inputs are the statistical posteriors of E (log E_total is ~log 3 higher)
        np.testing.assert_allclose(c["m"], [stat[i][0] for i in ids], rtol=0, atol=1e-9)
        np.testing.assert_allclose(c["s"], [stat[i][1] for i in ids], rtol=1e-6)
        assert max(c["s"]) < 0.02  # E_total's spread would be ~0.1
        assert isinstance(c["budget"], BudgetSpec) and c["data"] is sentinel
        rep = ids[1]  # the trace whose posterior mean of log E is the group median
        assert (c["z_surf"], c["estar"]) == pytest.approx(stat[rep][2:], rel=1e-9)
    df = cmp.comparison
    assert list(df.columns) == COMPARISON_COLUMNS
    bayes = df[df["method"] == "bayes"].set_index("material")
    assert bayes.loc["White", "E_pa"] == pytest.approx(111e3, rel=0.05)  # not 3 × 111 kPa
    assert (bayes["tau_prior_sd"] == 0.3).all()
    assert df.loc[df["method"] == "lsq", "tau_prior_sd"].isna().all()
    # gt_z_new uses the normal-equivalent sd of the new-specimen interval for both methods
    for _, r in df.iterrows():
        sd_new = (r["E_new_hi_pa"] - r["E_new_lo_pa"]) / (2 * Z90)
        assert r["E_new_sd_eq_pa"] == pytest.approx(sd_new, rel=1e-12)
        gt_sd = 10e3 if r["material"] == "White" else 0.0
        assert r["gt_z_new"] == pytest.approx(
            (r["E_pa"] - r["gt_E_pa"]) / math.sqrt(sd_new**2 + gt_sd**2), rel=1e-12)
    text = cmp.format()
    assert "tau ~ HalfNormal(0.3) on the log-E scale" in text
    lo, hi = bayes.loc["White", "E_new_lo_pa"], bayes.loc["White", "E_new_hi_pa"]
    assert f"[{lo / 1e3:.1f}, {hi / 1e3:.1f}]" in text


# ----------------------------------------------------------------------------- text


def test_text_shows_the_bayesian_interval_and_the_tau_prior():
    df = pd.DataFrame([
        {"material": "White", "tip": "flat", "method": "lsq", "E_pa": 115e3, "E_sd_pa": 12.9e3,
         "E_new_pa": 115e3, "E_new_sd_pa": 14.4e3, "E_new_lo_pa": 81e3, "E_new_hi_pa": 149e3,
         "gt_E_pa": 100e3, "gt_sd_pa": 10e3, "rel_err_pct": -15.0, "gt_in_new_interval": True,
         "paper_E_pa": 119.6e3, "paper_sd_pa": 10.8e3, "converged_all": True, "notes": "",
         "tau_prior_sd": np.nan},
        {"material": "White", "tip": "flat", "method": "bayes", "E_pa": 116e3, "E_sd_pa": 6e3,
         "E_new_pa": 115.5e3, "E_new_sd_pa": 48e3, "E_new_lo_pa": 88.2e3,
         "E_new_hi_pa": 152.7e3, "gt_E_pa": 100e3, "gt_sd_pa": 10e3, "rel_err_pct": -16.0,
         "gt_in_new_interval": True, "paper_E_pa": 119.6e3, "paper_sd_pa": 10.8e3,
         "converged_all": True, "notes": "", "tau_prior_sd": 0.5},
    ])
    text = format_comparison(df, "gt.csv")
    assert "115.5 [88.2, 152.7]" in text and "48.0" not in text  # interval, not ± the tail sd
    assert "115.0 ± 12.9" in text and "100.0 ± 10.0" in text  # LSQ and GT stay mean ± sd
    assert "median [90 % interval]" in text
    assert "tau ~ HalfNormal(0.5) on the log-E scale" in text
    # an older comparison.csv without the column: the prior comes from the argument
    old = df.drop(columns="tau_prior_sd")
    assert "HalfNormal(0.25)" in format_comparison(old, None, tau_prior_sd=0.25)
    assert "scale not recorded" in format_comparison(old, None)
    assert "tau ~" not in format_comparison(df[df["method"] == "lsq"], None)
