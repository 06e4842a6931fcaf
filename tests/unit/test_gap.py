"""The paper's robot-vs-Instron gap decomposed (palpbayes.gap), the specimen as tested among
its terms: the physics of every verdict, the count the twin explains, the verdicts' words."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from palpbayes.gap import GAP_COLUMNS, gap_table, gap_verdicts, paper_fit_ratio
from palpbayes.paper import PAPER_MATERIALS, PAPER_TIPS
from palpbayes.twin import Specimen


@pytest.fixture(scope="module")
def table():
    return gap_table()


@pytest.fixture(scope="module")
def white(table):
    return table[table["material"] == "White"].set_index("tip")


def test_columns_and_observed_figures(white):
    assert sorted(white.reset_index().columns) == sorted(GAP_COLUMNS)
    # the published numbers: flat 119.6 kPa against 111 kPa is +7.7 %
    assert white.loc["flat", "observed_pct"] == pytest.approx(100 * (119.6 / 111 - 1))
    assert (white["observed_lo_pct"] < white["observed_pct"]).all()
    assert (white["observed_pct"] < white["observed_hi_pct"]).all()


def test_the_terms_have_their_physical_signs(table, white):
    """A layer only stiffens (bonded more than free); the block's free sides soften it; bonded
    platens make the Instron read stiffer (the ratio lower); Hertz on a sphere reads low, on
    the others it is the law itself; compliance reads low; a flat punch's bias does not depend
    on the window (its factor is depth-free), a curved tip's shrinks in the shallow half."""
    assert (table["thickness_bonded_pct"] > table["thickness_free_pct"]).all()
    assert (table["thickness_free_pct"] > 5).all()
    assert ((table["width_free_pct"] < 0) & (table["width_bonded_pct"] < 0)).all()
    assert (table["width_free_pct"] > -7).all()
    assert ((table["platens_bonded_pct"] < -9) & (table["platens_bonded_pct"] > -15)).all()
    assert -5 < white.loc["sphere", "hertz_pct"] < -1.5
    assert white.loc["flat", "hertz_pct"] == 0 and white.loc["paraboloid", "hertz_pct"] == 0
    assert (white["compliance_pct"] < 0).all() and (white["compliance_pct"] > -2).all()
    flat_twin = 100 * ((1 + white.loc["flat", "thickness_free_pct"] / 100)
                       * (1 + white.loc["flat", "width_free_pct"] / 100) - 1)
    assert white.loc["flat", "window_free_pct"] == pytest.approx(flat_twin, abs=0.2)
    assert white.loc["paraboloid", "window_free_pct"] < white.loc["paraboloid",
                                                                  "thickness_free_pct"]
    assert (table["predicted_lo_pct"] <= table["predicted_hi_pct"]).all()
    # the twin and the platens can only lower the layer's prediction
    assert (table["predicted_lo_pct"] < table["layer_lo_pct"]).all()


def test_a_thicker_block_reads_nearer_the_half_space(table):
    t = table.set_index(["material", "tip"])
    for tip in PAPER_TIPS:
        assert 0 < t.loc[("White", tip), "thickness_free_pct"] < t.loc[("Pink", tip),
                                                                      "thickness_free_pct"]


def test_a_blunter_tip_reads_stiffer_and_a_sharper_one_softer(table):
    """The direction of the paraboloid's verdict, tested on the paper's fit: a tip of twice
    the nominal radius reads stiffer, one of half softer (Hertz: sqrt(R_true/R), +41 % and
    -29 % on a half-space; more on the block, whose bottom effect grows with the contact)."""
    curved = table[table["tip"] != "flat"]
    assert (curved["sharper_tip_pct"] < -25).all() and (curved["blunter_tip_pct"] > 35).all()
    mat, tip = PAPER_MATERIALS["White"], PAPER_TIPS["paraboloid"]
    half = paper_fit_ratio(mat.E_pa, tip, mat.thickness_m, base=None, nu=0.3,
                           true_tip=tip.scaled(0.5))
    assert half == pytest.approx(np.sqrt(0.5), rel=5e-3)
    par = table[table["tip"] == "paraboloid"]
    assert (par["radius_factor"] < 0.7).all()  # the published values need a sharper tip


def test_prediction_matches_a_direct_layer_fit():
    """The thickness term is the paper's least squares on the layer's own curve, the width
    term on the twin's."""
    mat, tip = PAPER_MATERIALS["Pink"], PAPER_TIPS["flat"]
    half = paper_fit_ratio(mat.E_pa, tip, mat.thickness_m, base=None, nu=0.3)
    bonded = paper_fit_ratio(mat.E_pa, tip, mat.thickness_m, base="bonded", nu=0.3)
    assert half == pytest.approx(1.0, abs=1e-3)
    assert bonded == pytest.approx(1.624, abs=0.01)  # Hayes' kappa at a/h = 0.5, nu 0.3
    block = Specimen(mat.thickness_m, length=0.05, width=0.05)
    twin = paper_fit_ratio(mat.E_pa, tip, mat.thickness_m, base="bonded", nu=0.3, block=block)
    assert 0.97 * bonded < twin < bonded


def test_the_twin_explains_more_of_the_papers_values(table):
    """Counted, not tuned: 4 of the 9 published ratios inside the twin's prediction (every
    sphere, the Grey flat punch), against 1 (the White sphere) for the infinite layer with an
    exact Instron; the paraboloids stay outside (they read softer than any elastic block)."""
    assert int(table["explained_layer"].sum()) == 1
    assert int(table["explained"].sum()) == 4
    assert table[table["tip"] == "sphere"]["explained"].all()
    assert not table[table["tip"] == "paraboloid"]["explained"].any()
    assert table["consistent"].all()


def test_verdicts_say_it_tip_by_tip(table):
    v = gap_verdicts(table)
    assert set(v) == {"flat", "sphere", "paraboloid"}
    assert "explains the paper's errors" in v["sphere"]
    assert "sharper than its nominal profile" in v["paraboloid"]
    assert "blunter or wider tip reads stiffer: the wrong way" in v["paraboloid"]
    assert "White and Pink read" in v["flat"] and "below the prediction's lower end" in v["flat"]
    assert all("17 to 25 % nominal strain" in t for t in v.values())


def test_verdicts_follow_the_table_not_the_paper(table):
    """A tip whose softer readings lie inside what an elastic block can read (the prediction
    reaching below 0) gets no 'sharper tip' verdict; values above the prediction are said."""
    par = table[table["tip"] == "paraboloid"].copy()
    par["predicted_lo_pct"] = -5.0  # an elastic block could read softer: not the tip's fault
    par["explained"] = False
    v = gap_verdicts(par)["paraboloid"]
    assert "sharper than its nominal profile" not in v
    assert "White and Pink and Grey read" in v and "below the prediction's lower end" in v
    high = table[table["tip"] == "flat"].copy()
    high["predicted_hi_pct"] = 5.0
    high["predicted_lo_pct"] = -5.0
    high["explained"] = False
    v = gap_verdicts(high)["flat"]
    assert "White and Pink and Grey read" in v and "above the prediction's upper end" in v


# --- the gap at finite strain (issue 56, item 5: palpbayes.gap_strain, the shipped table) -------

SHIPPED = Path(__file__).resolve().parents[2] / "data" / "gap-strain" / "gap_strain.csv"


@pytest.fixture(scope="module")
def strain():
    from palpbayes.gap_strain import FOAMS, STRAIN_COLUMNS

    s = pd.read_csv(SHIPPED)
    assert list(s.columns) == STRAIN_COLUMNS
    assert len(s) == len(PAPER_MATERIALS) * len(PAPER_TIPS) * 2 * len(FOAMS)
    assert np.isfinite(s["strain_factor"]).all()
    return s


def test_a_softening_foam_raises_every_ratio_a_stiffening_one_lowers_it(strain):
    soft = strain[(strain["law"] == "hyperfoam") & (strain["nu0"] < 0.2) & (strain["alpha"] >= 5)]
    assert (soft["strain_factor"] > 1.0).all()  # the Instron's plateau reads softer
    # and the more it softens (larger alpha), the more (per tip, block and base)
    by = soft.pivot_table(index=["material", "tip", "base"], columns="alpha",
                          values="strain_factor")
    assert (by.diff(axis=1).iloc[:, 1:] > 0).all().all()
    nh = strain[strain["law"] == "neo-hookean"]["strain_factor"]
    assert (nh < 1.0).all()  # nominal stress stiffens in compression: the Instron reads stiffer


def test_finite_strain_moves_the_two_curved_tips_together(strain):
    piv = strain.pivot_table(index=["material", "base", "foam"], columns="tip",
                             values="strain_factor")
    ratio = piv["paraboloid"] / piv["sphere"]
    assert ratio.between(0.97, 1.04).all()


def test_the_verdicts_and_their_words(table, strain):
    from palpbayes.gap_strain import strain_verdicts
    from palpbayes.gap_text import strain_paragraph

    v = strain_verdicts(table, strain)
    assert v["explained_linear"] == int(table["explained"].sum()) == 4
    assert v["best_total"] >= 8  # one law per foam (neo-Hookean nu 0.3 on every block)
    assert all(name.startswith("neo-Hookean") for name, _, _ in v["best"].values())
    assert 0.97 < v["paraboloid_over_sphere_min"] <= v["paraboloid_over_sphere_max"] < 1.04
    text = strain_paragraph(v, strain, table)
    assert "raises every ratio" in text and "lowers every ratio" in text
    assert "does not tell the paraboloid from the sphere" in text and "R_true/R = 0.5" in text


@pytest.mark.slow
def test_the_shipped_table_is_what_the_code_computes(strain):
    """Two rows of the shipped table recomputed (the finite elements, coarse: ~20 s)."""
    from palpbayes.gap_strain import FOAMS, strain_row

    for material, tip, base, foam in (("White", "sphere", "free", FOAMS[0]),
                                      ("Grey", "paraboloid", "bonded", FOAMS[3])):
        row = strain_row(material, tip, base, foam)
        shipped = strain[(strain["material"] == material) & (strain["tip"] == tip)
                         & (strain["base"] == base) & (strain["foam"] == foam[0])].iloc[0]
        for col in ("robot_read", "instron_read", "linear_ratio", "strain_factor"):
            assert row[col] == pytest.approx(shipped[col], rel=1e-6), (material, tip, col)
