"""Calibration of E's full interval (statistical + budget + model form) under misfit the user
did not model: 50 traces of each of an unmodelled bonded and free layer of 20-30 mm, strain
stiffening, a gradual onset and a blunted paraboloid apex, and 200 well-specified traces, all
with the budget's inputs drawn (palpbayes.sim.misfit), fitted as a half-space by the exact
engine.  Runs tools/modelform_calibration.py (the same numbers docs/reference.md quotes)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest

ROOT = Path(__file__).resolve().parents[2]
MISFITS = ("layer_bonded", "layer_free", "stiffening", "onset", "blunt")


@pytest.fixture(scope="module")
def calibration(tmp_path_factory) -> pd.DataFrame:
    out = tmp_path_factory.mktemp("modelform") / "calibration.csv"
    subprocess.run([sys.executable, str(ROOT / "tools" / "modelform_calibration.py"),
                    "--n", "50", "--n-well", "200", "--workers", "2", "--csv", str(out)],
                   check=True, cwd=ROOT, capture_output=True, text=True)
    df = pd.read_csv(out)
    t = df["E_true_pa"]
    df["cov_full"] = (df["E_lo_pa"] <= t) & (t <= df["E_hi_pa"])
    df["cov_budget"] = (df["E_budget_lo_pa"] <= t) & (t <= df["E_budget_hi_pa"])
    return df


@pytest.mark.slow
@pytest.mark.parametrize("scenario", MISFITS)
@pytest.mark.long
def test_full_interval_covers_under_unmodelled_misfit(calibration, scenario):
    df = calibration[calibration["scenario"] == scenario]
    assert len(df) == 50
    # the budget interval alone misses these (the bias is the model's, not the noise's; a
    # blunted apex moves E by ~1.4 %, which the budget covers in most traces) ...
    assert df["cov_budget"].mean() < (0.8 if scenario == "blunt" else 0.5)
    # ... the full interval covers the true E in >= 85 % of the traces
    assert df["cov_full"].mean() >= 0.85, df["cov_full"].mean()


@pytest.mark.slow
@pytest.mark.long
def test_well_specified_coverage_and_width(calibration):
    df = calibration[calibration["scenario"] == "well"]
    assert len(df) == 200
    assert 0.86 <= df["cov_full"].mean() <= 0.94, df["cov_full"].mean()
    widen = ((df["E_hi_pa"] - df["E_lo_pa"]).sum()
             / (df["E_budget_hi_pa"] - df["E_budget_lo_pa"]).sum())
    assert widen <= 1.10, widen
