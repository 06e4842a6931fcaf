"""What ``palpbayes fit`` says on screen: the model check beside E, one line per flag of a fit
that failed it, and the Poisson ratio when it was assumed rather than given."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from palpbayes.campaign.fitjob import FitOptions, nu_source
from palpbayes.cli import main
from palpbayes.cli.console import console_lines, flag_headlines
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
    text = "\n".join(console_lines(summary))
    assert "t1 (bayes): carries a warning on its input" in text
    assert ("  - force scale: the noise before contact is 1,000 times below the declared "
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
    assert "Hertz" in lines[1]
    other = console_lines(pd.DataFrame([_row(E_hertz_pa=float("nan"))]))
    assert "E_hertz" not in other[0] and "Hertz" not in other[1]
