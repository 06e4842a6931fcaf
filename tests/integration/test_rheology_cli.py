"""``palpbayes fit --rheology power-law|sls``: the viscoelastic fit from the command line on a
trace CSV with segments, a manifest (one trace that cannot be fitted keeps its row) and a real
stress-relaxation AFM file; the table, the console and the one-line errors."""

from __future__ import annotations

import re
import warnings

import numpy as np
import pandas as pd
import pytest

from palpbayes.cli import main
from palpbayes.contact.viscoelastic import PowerLawKernel
from palpbayes.io.manifest import write_manifest
from palpbayes.io.trace_csv import write_trace
from palpbayes.paper import PAPER_TIPS
from palpbayes.rheology.compression import compression_moduli
from palpbayes.sim import simulate_viscoelastic

PARA = ["--tip", "paraboloid", "--radius", "0.0117", "--no-progress"]
SR = "fmt-jpk-sr_cell1-0008.jpk-force"


@pytest.fixture(scope="module")
def record_csv(tmp_path_factory):
    rec = simulate_viscoelastic(PowerLawKernel(80e3, 0.2), PAPER_TIPS["paraboloid"],
                                depth=3e-3, speed=50 / 6e4, hold_time=6.0, rate=400.0,
                                z_surf=2e-4, noise_sd=0.008, phi=0.2, rng=11, trace_id="pl")
    return write_trace(rec, tmp_path_factory.mktemp("rec") / "pl.csv", float_format="%.12g")


def test_fit_rheology_writes_one_row_with_intervals_and_says_what_it_checked(
        record_csv, tmp_path, capsys):
    out = tmp_path / "res"
    assert main(["fit", str(record_csv), "--rheology", "power-law", "--nu", "0.45",
                 "--thickness", "0.02", "--out", str(out), *PARA]) == 0
    text = " ".join(ln.strip() for ln in capsys.readouterr().out.splitlines())  # wrapped
    assert "pl: E0* " in text and "alpha " in text and "model check passed" in text
    assert "a compression test at 50 mm/min would read E " in text
    assert "takes a half-space" in text  # 3 mm into 20 mm: said, not modelled
    row = pd.read_csv(out / "rheology.csv").iloc[0]
    assert row["rheology"] == "power-law" and row["segments"] == "approach,hold"
    assert row["E0_star_lo_pa"] < 80e3 < row["E0_star_hi_pa"]
    assert row["alpha_lo"] < 0.2 < row["alpha_hi"]
    assert row["E0_pa"] == pytest.approx(row["E0_star_pa"] * (1 - 0.45**2))
    assert bool(row["model_ok"]) and row["block"] >= 1 and row["t0_s"] == 1.0
    assert row["flag_codes"] == "thickness" and row["compression_height_m"] == 0.02
    assert row["E_compression_lo_pa"] < row["E_compression_pa"] < row["E_compression_hi_pa"]
    truth = compression_moduli([PowerLawKernel(80e3, 0.2)], 0.45, 50 / 60e3, 0.02)[0]
    assert row["E_compression_lo_pa"] < truth < row["E_compression_hi_pa"]
    # the same seed, the same table
    assert main(["fit", str(record_csv), "--rheology", "power-law", "--nu", "0.45",
                 "--thickness", "0.02", "--out", str(out), "--force", *PARA]) == 0
    again = pd.read_csv(out / "rheology.csv").iloc[0]
    assert again["E0_star_pa"] == row["E0_star_pa"] and again["alpha_hi"] == row["alpha_hi"]


def test_the_retract_by_tings_rule(record_csv, tmp_path, capsys):
    """--segments approach,hold,retract: the whole cycle, the retract by Ting's rule; the
    truth inside the intervals and the row names its segments."""
    out = tmp_path / "cycle"
    assert main(["fit", str(record_csv), "--rheology", "power-law", "--segments",
                 "approach,hold,retract", "--out", str(out), *PARA]) == 0
    assert "model check passed" in capsys.readouterr().out
    row = pd.read_csv(out / "rheology.csv").iloc[0]
    assert row["segments"] == "approach,hold,retract"
    assert row["E0_star_lo_pa"] < 80e3 < row["E0_star_hi_pa"]
    assert row["alpha_lo"] < 0.2 < row["alpha_hi"]


@pytest.mark.slow
def test_three_models_and_which_one_the_record_prefers(record_csv, tmp_path, capsys):
    """A power-law record fitted by the elastic law, the power law and the SLS on the same
    block means: the power law is preferred by PSIS-LOO, by many standard errors over each;
    every row carries the comparison; the elastic row has E* and fails its model check."""
    out = tmp_path / "all"
    assert main(["fit", str(record_csv), "--rheology", "elastic,power-law,sls", "--out",
                 str(out), *PARA]) == 0
    text = capsys.readouterr().out
    assert "pl (power-law): E0* " in text and "pl (sls): E_inf* " in text
    assert "pl (elastic): E* " in text
    assert "pl: prefers power-law: elpd_loo higher than elastic by " in text
    tab = pd.read_csv(out / "rheology.csv").set_index("rheology")
    assert list(tab.index) == ["elastic", "power-law", "sls"]
    assert bool(tab.loc["power-law", "preferred"]) and not tab.loc[["elastic", "sls"],
                                                                  "preferred"].any()
    assert tab.loc["power-law", "elpd_diff"] == 0.0
    for other in ("elastic", "sls"):
        assert -tab.loc[other, "elpd_diff"] > 5 * tab.loc[other, "elpd_diff_se"]
    assert tab.loc["elastic", "E_star_pa"] > 0 and not tab.loc["elastic", "model_ok"]
    assert 4 < tab.loc["power-law", "p_loo"] < 9  # E0, alpha, z_surf, offset, sigma, phi


@pytest.mark.slow
def test_the_emcee_engine_from_the_command_line(record_csv, tmp_path):
    """--rheology-engine emcee: the row says so, with converged chains (R-hat <= 1.05, ESS >=
    400) and the truth inside the intervals, as the grid engine's."""
    out = tmp_path / "emcee"
    assert main(["fit", str(record_csv), "--rheology", "power-law", "--rheology-engine",
                 "emcee", "--out", str(out), *PARA]) == 0
    row = pd.read_csv(out / "rheology.csv").iloc[0]
    assert row["engine"] == "emcee" and bool(row["converged"]) and bool(row["model_ok"])
    assert row["rhat_max"] <= 1.05 and row["ess_min"] >= 400
    assert row["E0_star_lo_pa"] < 80e3 < row["E0_star_hi_pa"]
    assert row["alpha_lo"] < 0.2 < row["alpha_hi"]


@pytest.mark.slow
def test_a_manifest_keeps_the_row_of_a_trace_that_cannot_be_fitted(record_csv, tmp_path,
                                                                    capsys):
    flat = tmp_path / "flat.csv"
    pd.DataFrame({"time_s": np.arange(100) * 0.01, "z_m": np.zeros(100),
                  "force_n": np.zeros(100)}).to_csv(flat, index=False)
    manifest = write_manifest(pd.DataFrame({
        "trace_id": ["good", "still"], "file": [str(record_csv), str(flat)],
        "material": ["silicone"] * 2, "tip": ["paraboloid"] * 2,
        "radius_m": [0.0117] * 2}), tmp_path / "manifest.csv")
    assert main(["fit", str(manifest), "--rheology", "sls", "--out", str(tmp_path / "res"),
                 "--no-progress"]) == 0
    tab = pd.read_csv(tmp_path / "res" / "rheology.csv").set_index("trace_id")
    assert list(tab.index) == ["good", "still"]
    assert np.isfinite(tab.loc["good", "tau_s"]) and tab.loc["good", "E_inf_star_pa"] > 0
    assert "never moves down" in tab.loc["still", "error"] or "segment" in tab.loc["still",
                                                                                    "error"]
    assert "still: not fitted:" in capsys.readouterr().out


@pytest.mark.parametrize("extra, message", [
    (["--method", "lsq"], "--method lsq is for the elastic fit"),
    (["--resume"], "--resume is for elastic campaigns"),
    (["--nu-range", "0.3", "0.4"], "--nu-range is for the elastic fit"),
    (["--t0", "0"], "--t0 0.0 must be a positive time"),
    (["--rheology", "power-law,sls", "--segments", "approach,hold,retract"],
     "with the power law only"),
    (["--compression-speed", "-5"], "--compression-speed -5.0 must be a positive"),
    (["--rheology", "maxwell"], "unknown model 'maxwell'"),
    (["--engine", "exact"], "--engine is an option of the elastic fit"),
    (["--tare"], "--tare is an option of the elastic fit"),
    (["--peer-compatible", "pyfmrheo", "--segments", "approach,retract"],
     "--peer-compatible pyfmrheo sets --segments as the peer does"),
    (["--peer-compatible", "pyfmrheo", "--drag", "on"], "sets --drag as the peer does"),
    (["--peer-compatible", "nanite"], "invalid choice: 'nanite'"),
    (["--peer-compatible", "pyfmrheo", "--rheology", "sls"], "fits the retract by Ting's rule"),
])
def test_options_that_do_not_apply_are_one_line_errors(record_csv, tmp_path, capsys, extra,
                                                       message):
    try:
        rc = main(["fit", str(record_csv), "--rheology", "power-law", "--out",
                   str(tmp_path / "r"), *PARA, *extra])
    except SystemExit as exc:  # argparse's own usage errors
        rc = exc.code
    err = capsys.readouterr().err
    assert rc == 2 and message in err and "Traceback" not in err


def test_segments_without_rheology_and_an_existing_table(record_csv, tmp_path, capsys):
    assert main(["fit", str(record_csv), "--segments", "approach,hold", "--out",
                 str(tmp_path / "e"), *PARA]) == 2
    assert "--segments is an option of --rheology" in capsys.readouterr().err
    assert main(["fit", str(record_csv), "--compression-speed", "10", "--out",
                 str(tmp_path / "e"), *PARA]) == 2
    assert "--compression-speed is an option of --rheology" in capsys.readouterr().err
    out = tmp_path / "res"
    (out).mkdir()
    (out / "rheology.csv").write_text("trace_id\n")
    assert main(["fit", str(record_csv), "--rheology", "sls", "--out", str(out), *PARA]) == 2
    assert "exists; pass --force" in capsys.readouterr().err


def test_a_real_stress_relaxation_file_end_to_end(shared_data, tmp_path, capsys):
    """afmformats' JPK stress-relaxation curve (a cell; 2 µm approach, 30 s hold): read with
    its segments, fitted, and its misfit named in the table and on the console."""
    path = shared_data("afm-files", files=[SR]) / SR
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # afmformats' own warnings about JPK metadata
        rc = main(["fit", str(path), "--rheology", "power-law", "--tip", "paraboloid",
                   "--radius", "5e-6", "--nu", "0.5", "--out", str(tmp_path / "sr"),
                   "--no-progress"])
    assert rc == 0, capsys.readouterr().err
    row = pd.read_csv(tmp_path / "sr" / "rheology.csv").iloc[0]
    assert row["segments"] == "approach,hold" and not isinstance(row["error"], str)
    assert 300 < row["E0_star_pa"] < 3000 and 0.05 < row["alpha"] < 0.5
    text = capsys.readouterr().out
    if row["model_ok"]:
        assert "model check passed" in text
    else:  # what fails is said, with its code in the table
        assert "model check FAILED" in text and row["flag_codes"]


def test_the_console_says_its_intervals_are_statistical_in_the_packages_units(tmp_path, capsys):
    """Issue 58, on a simulated one-trace campaign (E0* 35 kPa, alpha 0.25): the console gave
    'E0* 3.49e+04 [3.481e+04, 3.499e+04] Pa' with no word on what the intervals hold (the
    truth sat just outside), then 'no pooled power law' and 'wrote rheology_pooled.csv', a
    header-only table.  Now kPa with the digits that tell the ends apart, the intervals said
    to be statistical only, and no empty table written or announced."""
    camp, out = tmp_path / "camp", tmp_path / "res"
    assert main(["simulate", str(camp), "--rheology", "power-law", "--materials", "Soft",
                 "--tips", "paraboloid", "--speeds", "50", "--seed", "0"]) == 0
    capsys.readouterr()
    assert main(["fit", str(camp / "manifest.csv"), "--rheology", "power-law", "--nu", "0.3",
                 "--out", str(out), "--no-progress"]) == 0
    said = capsys.readouterr().out
    lines = said.splitlines()
    text = " ".join(ln.strip() for ln in lines)
    assert "the intervals are statistical only" in text and "no model form" in text
    assert "e+0" not in said and " kPa [" in text, said
    row = pd.read_csv(out / "rheology.csv").iloc[0]
    E0 = re.search(r"E0\* ([\d.]+) kPa \[([\d.]+) kPa, ([\d.]+) kPa\]", text)
    assert E0 is not None, said
    lo, hi = (float(v) * 1e3 for v in E0.groups()[1:])
    assert (lo, hi) == pytest.approx((row["E0_star_lo_pa"], row["E0_star_hi_pa"]), abs=5.1)
    assert lo != hi  # narrow intervals keep the digits that tell their ends apart
    assert max(len(ln) for ln in lines if not ln.startswith("wrote ")) <= 100
    assert "no pooled power law" in said and "rheology_pooled.csv" not in said
    assert not (out / "rheology_pooled.csv").exists()
