"""What ``palpbayes fit`` says on screen: the model check beside E, one line per flag of a fit
that failed it, and the Poisson ratio when it was assumed rather than given."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from palpbayes.campaign.fitjob import FitOptions, nu_source
from palpbayes.cli import main
from palpbayes.cli.console import console_lines, flag_headlines, short_ids
from palpbayes.contact import DEFAULT_NU, Tip
from palpbayes.io.trace_csv import write_trace
from palpbayes.sim import simulate_trace

# a flag text as summary.csv holds it: messages joined by "; ", with "; " inside brackets
FLAGS = ("free-exponent fit m = 2.04 ± 0.01 vs 1.500 of the paraboloid law: force stiffens "
         "with depth (finite thickness likely; or a stiffer base) [material: moves E by "
         "+12.0 % (free exponent at the mean depth)]; binned residuals chi² = 88.1 on 15 bins "
         "(p = 1e-12), largest at the onset; posterior-predictive p = 0.001")


def test_flag_headlines_split_only_between_messages_and_drop_the_explanations():
    assert flag_headlines(FLAGS) == [
        "free-exponent fit m = 2.04 ± 0.01 vs 1.500 of the paraboloid law: force stiffens "
        "with depth",
        "binned residuals chi² = 88.1 on 15 bins",
        "posterior-predictive p = 0.001"]
    assert flag_headlines("") == []
    long = flag_headlines("x" * 300, width=50)
    assert len(long) == 1 and len(long[0]) == 50 and long[0].endswith("...")


def _row(**kw):
    base = {"trace_id": "t1", "method": "bayes", "E_pa": 5e4, "E_sd_pa": 1e3, "E_lo_pa": 4.8e4,
            "E_hi_pa": 5.2e4, "converged": True, "model_ok": True, "notes": "",
            "nu_source": "option", "misfit_checks": ""}
    return {**base, **kw}


def test_console_names_each_failed_check_and_the_assumed_nu():
    summary = pd.DataFrame([_row(), _row(trace_id="t2", model_ok=False, notes=FLAGS,
                                         misfit_checks="exponent;ppc", nu_source="default")])
    text = "\n".join(console_lines(summary))
    table = text.splitlines()[0]
    assert "model_ok" in table and "converged" in table
    assert "t2 (bayes): failed a model check" in text and "t1 (bayes)" not in text
    assert "  - free-exponent fit m = 2.04 ± 0.01 vs 1.500" in text
    assert "  - posterior-predictive p = 0.001" in text
    assert "90 % interval" in text
    assert "nu = 0.3 assumed" in text and "silicone" in text
    quiet = "\n".join(console_lines(pd.DataFrame([_row()])))
    assert "failed" not in quiet and "assumed" not in quiet and "warning" not in quiet


def test_a_fit_that_did_not_converge_is_said_so():
    summary = pd.DataFrame([_row(converged=False, notes="z_surf posterior at its upper prior "
                                 "bound (widen the prior)")])
    text = "\n".join(console_lines(summary))
    assert "t1 (bayes): did not converge" in text
    assert "  - z_surf posterior at its upper prior bound" in text


def test_nu_source_says_where_the_ratio_came_from():
    trace = simulate_trace(60e3, Tip("sphere", radius=0.01), depth=2e-3, rng=3, trace_id="a")
    assert nu_source(trace, FitOptions()) == "default"
    assert nu_source(trace, FitOptions(nu=0.45)) == "option"
    trace.metadata["nu"] = 0.49
    assert nu_source(trace, FitOptions(nu=0.45)) == "manifest"


@pytest.mark.parametrize("nu", [None, 0.45])
def test_fit_without_nu_says_so_on_screen_and_in_the_summary(tmp_path, capsys, nu):
    """A custom robot CSV fitted as a new user would: without --nu the default is printed and
    recorded, and E uses it; with --nu neither note nor default."""
    trace = simulate_trace(60e3, Tip("sphere", radius=0.01), nu=0.45, depth=2e-3, rng=3,
                           trace_id="block")
    path = tmp_path / "block.csv"
    write_trace(trace, path)
    args = ["fit", str(path), "--out", str(tmp_path / "out"), "--tip", "sphere", "--radius",
            "0.01", "--engine", "exact", "--no-progress"]
    rc = main(args + ([] if nu is None else ["--nu", str(nu)]))
    out = capsys.readouterr().out
    assert rc == 0
    summary = pd.read_csv(tmp_path / "out" / "summary.csv")
    row = summary[summary["method"] == "bayes"].iloc[0]
    if nu is None:
        assert row["nu_source"] == "default" and row["nu"] == DEFAULT_NU
        assert "note: Poisson ratio not given: nu = 0.3 assumed" in out
    else:
        assert row["nu_source"] == "option" and row["nu"] == nu
        assert "Poisson ratio not given" not in out
    # E = E*(1 - nu^2) with the ratio the row reports
    np.testing.assert_allclose(row["E_pa"], row["Estar_pa"] * (1 - row["nu"]**2),
                               rtol=0.02)


def test_a_warning_on_the_input_is_printed_even_when_the_checks_pass():
    # issue 46: a force in the wrong unit fitted with model_ok True printed nothing
    flag = ("force scale: the noise before contact is 1,000 times below the declared "
            "--noise-pp, check --force-unit (the sensor noise: 48 µN peak-to-peak)")
    summary = pd.DataFrame([_row(notes=flag, flag_codes="force_scale")])
    text = " ".join(ln.strip() for ln in console_lines(summary))  # wrapped at 100
    assert "t1 (bayes): carries a warning on its input" in text
    assert ("- force scale: the noise before contact is 1,000 times below the declared "
            "--noise-pp, check --force-unit") in text
    assert "warning: 1 fit(s)" in text


def test_least_squares_row_says_converged_n_a_and_a_sphere_shows_its_hertz_e():
    # issue 46: "converged NaN" on the least-squares row; E_hertz was missing from the console
    summary = pd.DataFrame([_row(E_hertz_pa=4.85e4),
                            _row(method="lsq", converged=float("nan"), E_sd_pa=float("nan"),
                                 E_hertz_pa=4.8e4)])
    lines = console_lines(summary)
    header, bayes, lsq = lines[0].splitlines()
    assert "E_hertz" in header and "48.5 kPa" in bayes and "48 kPa" in lsq
    assert lsq.split()[-2:] == ["n/a", "True"] and bayes.split()[-2:] == ["True", "True"]
    assert "NaN" not in lines[0] and "nan" not in lines[0]
    assert "Hertz" in " ".join(lines[1:])
    other = console_lines(pd.DataFrame([_row(E_hertz_pa=float("nan"))]))
    assert "E_hertz" not in other[0] and "Hertz" not in " ".join(other[1:])


# ---------------------------------------------------------------- issue 58: 100 columns

LONG = "block_A_silicone_ecoflex30_sphere10mm_press_{}_long_identifier"


def _layered_rows(tid: str) -> list[dict]:
    """A layered fit's two rows (the numbers of a 20 mm block fitted with --thickness 0.02
    --method both), the Bayesian one with a material misfit and the specimen's twin."""
    bayes = _row(trace_id=tid, E_pa=59.9e3, E_sd_pa=2.1e3, E_lo_pa=41.2e3, E_hi_pa=63.2e3,
                 E_stat_lo_pa=59.8e3, E_stat_hi_pa=60.0e3, E_budget_lo_pa=56.6e3,
                 E_budget_hi_pa=63.2e3, E_hertz_pa=58.5e3, model_ok=False, notes=FLAGS,
                 misfit_checks="exponent;residual_structure;depth_consistency;ppc",
                 layer="60 × 60 × 20 mm block, base unknown", E_halfspace_pa=70.1e3,
                 E_bonded_pa=55.8e3, E_free_pa=59.9e3, platens="unknown",
                 E_instron_pa=79e3, E_instron_lo_pa=58e3, E_instron_hi_pa=136e3)
    lsq = _row(trace_id=tid, method="lsq", E_pa=73.4e3, E_sd_pa=82.7, E_lo_pa=73.2e3,
               E_hi_pa=73.5e3, E_hertz_pa=71.7e3, converged=float("nan"),
               layer="half-space (the paper's)", E_halfspace_pa=73.4e3, E_bonded_pa=58.6e3,
               E_free_pa=62.8e3, E_instron_pa=float("nan"))
    return [bayes, lsq]


def test_every_line_fits_in_100_columns_with_long_ids_a_layer_and_both_methods():
    """Issue 58: the table was ~220 characters wide with a long trace id (and the sentences
    under it up to 190): it wrapped in a terminal.  Every line now fits in 100, a long id is
    cut in its middle, and the rows of two ids stay told apart."""
    summary = pd.DataFrame(_layered_rows(LONG.format("03")) + _layered_rows(LONG.format("04")))
    lines = "\n".join(console_lines(summary)).splitlines()
    assert max(len(ln) for ln in lines) <= 100, max(lines, key=len)
    header, *rows = lines[:5]
    assert header.split() == ["trace_id", "method", "E", "E_lo", "E_hi", "E_sd", "E_hertz",
                              "converged", "model_ok"]
    ids = [r.split()[0] for r in rows]
    assert ids[0] == ids[1] != ids[2] == ids[3] and "…" in ids[0]  # cut where they agree
    assert ids[0].startswith("block_A") and ids[0].endswith("3_long_identifier")
    assert [r.split()[1] for r in rows] == ["bayes", "lsq"] * 2
    assert "59.9 kPa 41.2 kPa 63.2 kPa 2.1 kPa 58.5 kPa" in rows[0]


def test_ids_that_would_read_the_same_get_numbers_and_a_key():
    ids = ["x" * 60 + "a" + "y" * 60, "x" * 60 + "b" + "y" * 60]
    shown, key = short_ids(ids, 30)
    assert shown == {ids[0]: "trace 1", ids[1]: "trace 2"}
    assert key == ["trace ids:", f"  trace 1 = {ids[0]}", f"  trace 2 = {ids[1]}"]
    assert short_ids(["a", "b"], 30) == ({"a": "a", "b": "b"}, [])


def test_a_layered_fit_shows_e_read_as_a_half_space():
    """Issue 58: with --thickness, E_halfspace_pa (and the bonded and free readings) were in
    summary.csv but not on the console."""
    text = " ".join(ln.strip() for ln in console_lines(pd.DataFrame(_layered_rows("t1"))))
    assert ("t1 bayes [60 × 60 × 20 mm block, base unknown]: half-space 70.1 kPa, bonded "
            "55.8 kPa, free 59.9 kPa") in text
    assert "t1 lsq [half-space (the paper's)]: half-space 73.4 kPa" in text
    assert "half-space" not in "\n".join(console_lines(pd.DataFrame([_row()])))


def test_the_legend_says_which_interval_e_sd_belongs_to():
    """Issue 58: an E_sd of 454 Pa sat beside [15.1, 34.5] kPa on spot3 with the legend "E_sd
    its sd": it is the sd of the statistical + budget draws (summary.csv E_sd_pa), and the
    interval beside it adds the model form."""
    text = " ".join(ln.strip() for ln in console_lines(pd.DataFrame(_layered_rows("t1"))))
    assert ("E_sd: bayes, the sd of E with the budget, i.e. of the statistical + budget part "
            "of E_lo..E_hi (summary.csv E_sd_pa; the model form, an envelope, has no sd); "
            "lsq, its standard error") in text
    assert "t1: statistical -0.2/+0.2 %, + budget -5.5/+5.5 %, + model form -31.2/+5.5 %" \
        in text


def test_fit_prints_a_layered_fit_of_a_long_id_in_100_columns(tmp_path, capsys):
    """The command as a user runs it: --thickness, --method both, a 60-character id."""
    trace = simulate_trace(60e3, Tip("sphere", radius=0.01), nu=0.45, depth=2e-3, rng=3,
                           thickness=0.02, trace_id="t")
    path = tmp_path / f"{LONG.format('03')}.csv"
    write_trace(trace, path)
    assert main(["fit", str(path), "--out", str(tmp_path / "out"), "--tip", "sphere",
                 "--radius", "0.01", "--nu", "0.45", "--thickness", "0.02", "--method", "both",
                 "--engine", "exact", "--no-progress"]) == 0
    out = capsys.readouterr().out.splitlines()
    said = [ln for ln in out if not ln.startswith("wrote ")]
    assert max(len(ln) for ln in said) <= 100, max(said, key=len)
    assert any(ln.startswith("  block_A_silicon…ong_identifier bayes [h=20 mm, base "
                             "unknown]: half-space ") for ln in said), out
