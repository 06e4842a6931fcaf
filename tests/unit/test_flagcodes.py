"""A fit's flags as columns a user can filter on: ``notes``, ``flag_codes``, ``flag_level``
(:mod:`palpbayes.flagcodes`), and no column named ``flags`` (``DataFrame.flags`` is pandas')."""

from __future__ import annotations

import pandas as pd
import pytest

from palpbayes.campaign.results import load_results
from palpbayes.flagcodes import (
    POOLED_RHEOLOGY_CODES,
    RHEOLOGY_CODES,
    flag_code,
    flag_columns,
    listed_flag_columns,
    split_flags,
)

# flags as the fits write them (checks, sampler, posterior, least squares, layer notes)
REAL = {
    "free-exponent fit m = 2.04 ± 0.01 vs 1.500 of the paraboloid law: force stiffens with "
    "depth (finite thickness likely) [material: moves E by +12.0 % (free exponent)]":
        "exponent",
    "binned residuals chi² = 88.1 on 15 bins (p = 1e-12), largest bin mean 3.1 sigma: "
    "curvature left (see the exponent check)": "residual_structure",
    "indentation 62 % of the layer thickness: beyond the small strain": "layer",
    "thickness posterior at its lower prior bound (5 mm): widen it": "prior_bound",
    "E* over the shallow half = 1.607 ± 0.006 × E* over all depths: apparent modulus falls "
    "with depth": "depth_consistency",
    "posterior-predictive p = 0": "ppc",
    "info: depth_consistency check fails statistically but is negligible: moves E by 0.2 %, "
    "within ±1.0 %": "depth_consistency",
    "rate dependence: the hold relaxes 12 % -> the material is viscoelastic": "rate",
    "R-hat 1.0600 > 1.05 (z_surf)": "rhat",
    "ESS 210 < 400": "ess",
    "step cap reached (400 steps) before tau was stable": "step_cap",
    "bimodal z_surf: two separated surface heights fit the data": "bimodal_surface",
    "prior-dominated z_surf: the data barely constrain the surface": "prior_dominated_surface",
    "z_surf posterior at its upper prior bound (0.1): widen it": "prior_bound",
    "least squares failed: no contact": "lsq_failed",
    "untared sensor: the pre-contact force is 0.3 N (beyond F_unc = 0.05 N)": "offset",
    "fit failed: file not found": "fit_failed",
    "info: base not identified (P(bonded) = 0.55): E is 50 kPa if bonded": "layer",
    "something new": "other",
}


@pytest.mark.parametrize("text,code", list(REAL.items()))
def test_every_kind_of_flag_gets_its_code(text, code):
    assert flag_code(text) == code


def test_columns_keep_the_words_and_add_codes_and_the_highest_level():
    info = "info: base not identified (P(bonded) = 0.55; P(free) = 0.45): E is 50 kPa"
    warn = "posterior-predictive p = 0"
    assert split_flags(f"{info}; {warn}") == [info, warn]  # "; " inside brackets kept
    cols = flag_columns(f"{info}; {warn}; {warn}")
    assert cols["notes"] == f"{info}; {warn}; {warn}"
    assert cols["flag_codes"] == "layer;ppc" and cols["flag_level"] == "warning"
    assert flag_columns(info)["flag_level"] == "info"
    for empty in ("", None, float("nan")):
        assert flag_columns(empty) == {"notes": "", "flag_codes": "", "flag_level": ""}


def test_a_folder_written_before_the_rename_reads_with_the_new_columns(tmp_path):
    """summary.csv of an older run has ``flags``; it is read as notes, codes and level."""
    old = pd.DataFrame({"trace_id": ["a", "b"], "method": ["bayes", "bayes"],
                        "E_pa": [1e5, 1e5], "converged": [True, False],
                        "flags": ["", "ESS 210 < 400; info: base not identified (x)"]})
    old.to_csv(tmp_path / "summary.csv", index=False)
    s = load_results(tmp_path).summary
    assert "flags" not in s.columns
    assert list(s["flag_codes"]) == ["", "ess;layer"]
    assert list(s["flag_level"]) == ["", "warning"]
    assert s.loc[1, "notes"].startswith("ESS 210")


def test_old_comparison_columns_read_with_the_names_of_the_interval_they_test(tmp_path):
    """comparison.csv of an older run has ``gt_in_interval`` and ``z_score``."""
    old = pd.DataFrame({"material": ["White"], "tip": ["flat"], "method": ["bayes"],
                        "E_pa": [1e5], "gt_in_interval": [False], "z_score": [-0.37]})
    (tmp_path / "summary.csv").write_text("trace_id,method,E_pa\na,bayes,1e5\n")
    old.to_csv(tmp_path / "comparison.csv", index=False)
    c = load_results(tmp_path).comparison
    assert {"gt_in_interval", "z_score"}.isdisjoint(c.columns)
    assert not c.loc[0, "gt_in_new_interval"] and c.loc[0, "gt_z_new"] == pytest.approx(-0.37)


def test_the_viscoelastic_tables_code_their_flags_through_the_same_module():
    """rheology.csv and rheology_pooled.csv: codes by words anywhere, each code once, a level
    as in summary.csv, the flags joined by " | " (their sentences hold "; ")."""
    flags = ["alpha piles up at 0, the lower bound of its prior (P(alpha < 0.01) = 0.4); "
             "the record shows no relaxation", "the grid did not settle in 40 steps",
             "a second grid did not settle", "something new"]
    cols = listed_flag_columns(flags, RHEOLOGY_CODES)
    assert cols["flag_codes"] == "alpha_at_zero;grid;other"
    assert cols["flag_level"] == "warning" and cols["notes"].split(" | ") == flags
    assert listed_flag_columns([], RHEOLOGY_CODES) == {"notes": "", "flag_codes": "",
                                                       "flag_level": ""}
    info = listed_flag_columns(["info: every trace at one speed"], POOLED_RHEOLOGY_CODES)
    assert info["flag_level"] == "info" and info["flag_codes"] == "one_speed"
