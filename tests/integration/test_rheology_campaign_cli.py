"""``palpbayes simulate --rheology power-law`` then ``palpbayes fit MANIFEST --rheology
power-law``: one foam palpated at 100, 300 and 900 mm/min, its three power laws pooled into
``rheology_pooled.csv``, whose 90 % intervals cover the truth and are narrower than the widest
single-speed one.  Small and fast: 200 Hz, 1 mm deep, half a second of hold (~45 s of CPU here)."""

from __future__ import annotations

import contextlib
import io

import numpy as np
import pandas as pd
import pytest

from palpbayes.cli import main
from palpbayes.rheology.campaign import POOLED_COLUMNS

#: slow: a simulated three-speed campaign fitted and pooled (~15 s per module fixture)
pytestmark = pytest.mark.slow

SPEEDS = "100,300,900"


@pytest.fixture(scope="module")
def fitted(tmp_path_factory):
    """(campaign folder, results folder, console of the fit)."""
    root = tmp_path_factory.mktemp("visco-campaign")
    camp, out = root / "camp", root / "res"
    said = io.StringIO()
    with contextlib.redirect_stdout(said):
        assert main(["simulate", str(camp), "--rheology", "power-law", "--materials",
                     "Medium", "--tips", "paraboloid", "--speeds", SPEEDS, "--rate", "200",
                     "--hold", "0.5", "--depth", "1e-3", "--seed", "3"]) == 0
        assert main(["fit", str(camp / "manifest.csv"), "--rheology", "power-law", "--out",
                     str(out), "--no-progress"]) == 0
    return camp, out, said.getvalue()


def test_pooled_intervals_cover_the_truth_and_beat_the_widest_single_speed(fitted):
    camp, out, _ = fitted
    truth = pd.read_csv(camp / "truth.csv")
    pooled = pd.read_csv(out / "rheology_pooled.csv")
    assert list(pooled.columns) == POOLED_COLUMNS and len(pooled) == 1
    r = pooled.iloc[0]
    assert (r["material"], r["specimen"], r["tip"], r["radius_m"]) == (
        "Medium", "Medium", "paraboloid", 0.0117)
    assert (r["n_traces"], r["n_speeds"]) == (3, 3)
    assert r["trace_ids"].split(";") == list(truth["trace_id"])
    speeds = np.array(r["speeds_mm_min"].split(";"), dtype=float)
    np.testing.assert_allclose(speeds, truth["speed_mm_min"], rtol=1e-3)  # read from the fits
    E0, alpha = truth["E0_star_pa"].iloc[0], truth["alpha"].iloc[0]
    assert r["E0_star_lo_pa"] < E0 < r["E0_star_hi_pa"]
    assert r["alpha_lo"] < alpha < r["alpha_hi"]
    single = pd.read_csv(out / "rheology.csv")
    assert len(single) == 3 and single["error"].isna().all()
    widest = (single["E0_star_hi_pa"] - single["E0_star_lo_pa"]).max()
    assert r["E0_star_hi_pa"] - r["E0_star_lo_pa"] < widest
    # the manifest's nu reaches both tables: Young's moduli and the compression reading
    assert r["nu"] == 0.3
    assert r["E0_pa"] == pytest.approx(r["E0_star_pa"] * (1 - 0.3**2))
    assert np.isfinite(single["E_compression_pa"]).all()
    np.testing.assert_allclose(single["E_compression_pa"], truth["E_compression_true_pa"],
                               rtol=0.05)
    assert pd.isna(r["flag_codes"]) and pd.isna(r["error"])


def test_console_says_the_pooled_power_law(fitted):
    _, out, said = fitted
    assert "pooled power law per specimen x tip" in said
    line = next(s for s in said.splitlines() if s.startswith("  Medium x paraboloid: "))
    assert line.startswith("  Medium x paraboloid: 3 traces at 100, 300, 900 mm/min: E0* ")
    assert line.endswith("; no flags")
    assert f"wrote {out / 'rheology_pooled.csv'}" in said
