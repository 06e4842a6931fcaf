"""Viscoelastic fits in a results folder and their report pages: ``fit_traces`` stores every fit
(``rheology/<trace>_<model>.nc``), :func:`load_rheology_fit` returns the fit's own draws, bands
and attributes, and ``palpbayes report DIR`` draws them from the folder alone, fitting nothing.

One simulated power-law record (3 mm at 100 mm/min, 2 s hold, 200 Hz: 430 block means) is
fitted once with both models (module fixture, the slow part); the report is built once through
the command line with every fitting function patched to raise.
"""

from __future__ import annotations

import contextlib
import io
import re
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import palpbayes.rheology.fit as rfit
import palpbayes.rheology.posterior as rpost
import palpbayes.rheology.results as rresults
from palpbayes.cli import main
from palpbayes.contact.viscoelastic import PowerLawKernel
from palpbayes.errors import DataFileError, InputError
from palpbayes.intervals import central_band
from palpbayes.outputs import rheology_fit_path
from palpbayes.paper import PAPER_TIPS
from palpbayes.plots import plot_cycle_fit, plot_hysteresis, plot_relaxation
from palpbayes.reporting import report as build_pdf
from palpbayes.rheology import (
    STORED_DRAWS,
    clear_rheology_outputs,
    fit_traces,
    load_rheology_fit,
    relaxation_grid,
    rheology_options,
)
from palpbayes.sim import simulate_viscoelastic

KERNEL = PowerLawKernel(60e3, 0.15)
NU = 0.45


def _pdf_pages(path: Path) -> list[str]:
    pypdf = pytest.importorskip("pypdf")
    return [p.extract_text() or "" for p in pypdf.PdfReader(str(path)).pages]


def _plain(text: str) -> str:
    return re.sub(r"\s+", " ", text)


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    """``fit_traces`` of one record with both models; (folder, table, the fits it saved)."""
    rec = simulate_viscoelastic(KERNEL, PAPER_TIPS["paraboloid"], depth=3e-3, speed=100 / 6e4,
                                hold_time=2.0, rate=200.0, rng=3, trace_id="foam")
    out = tmp_path_factory.mktemp("rheology") / "res"
    saved = {}
    real = rresults.save_rheology_fit

    def spy(fit, path, **kw):
        saved[fit.rheology] = fit
        return real(fit, path, **kw)

    with pytest.MonkeyPatch.context() as mp, warnings.catch_warnings():
        warnings.simplefilter("ignore")
        mp.setattr(rresults, "save_rheology_fit", spy)
        table = fit_traces([rec], rheology_options(("power-law", "sls"), nu=NU), out,
                           progress=False)
    return out, table, saved


@pytest.fixture(scope="module")
def report(folder):
    """``palpbayes report DIR`` with every way of fitting or evaluating the model raising."""
    out, _, _ = folder

    def refuse(*_, **__):
        raise AssertionError("the report fitted or evaluated the model")

    buf = io.StringIO()
    with pytest.MonkeyPatch.context() as mp, contextlib.redirect_stdout(buf):
        for module, name in ((rfit, "fit_rheology"), (rresults, "fit_rheology"),
                             (rfit, "grid_posterior"), (rpost, "grid_posterior"),
                             (rfit, "_force_curves"), (rfit, "lee_radok_columns"),
                             (rfit.RheologyFit, "force_curves"),
                             (rfit.RheologyFit, "relaxation")):
            mp.setattr(module, name, refuse)
        rc = main(["report", str(out)])
    assert rc == 0
    return out / "report.pdf", buf.getvalue()


def test_stored_fit_round_trip(folder):
    """The stored draws are the fit's (evenly thinned), the bands and E*(t) the fit's own,
    the attributes the fit's; the stored draws recover the truth and the table's intervals."""
    out, table, saved = folder
    fit = saved["power-law"]
    path = rheology_fit_path(out, "foam", "power-law")
    assert path == out / "rheology" / "foam_power-law.nc" and path.is_file()
    s = load_rheology_fit(path)
    keep = np.linspace(0, len(fit.draws["z_surf"]) - 1, STORED_DRAWS).round().astype(int)
    assert set(s.draws) == set(fit.draws) - {"ess"}
    for name, draws in s.draws.items():
        np.testing.assert_array_equal(draws, fit.draws[name][keep])
    for band, ref in zip(s.band(), central_band(fit.force_curves(200), axis=0), strict=True):
        np.testing.assert_array_equal(band, ref)
    grid = relaxation_grid(fit.data)
    pd.testing.assert_frame_equal(s.relaxation(), fit.relaxation(grid))
    pd.testing.assert_frame_equal(s.relaxation(grid), fit.relaxation(grid))
    for name in ("time", "z", "force", "segment"):
        np.testing.assert_array_equal(getattr(s.data, name), getattr(fit.data, name))
    assert (s.rheology, s.t0, s.nu, s.trace_id, s.tip_kind) == ("power-law", 1.0, NU, "foam",
                                                                "paraboloid")
    assert s.data.segments == ("approach", "hold") and s.model_ok == fit.model_ok
    assert s.flags == tuple(fit.flags) and s.units["E0"] == "Pa" and s.units["alpha"] == "-"
    assert s.z_surf == float(np.median(fit.draws["z_surf"]))
    # the record keeps the retract (not fitted) for the hysteresis
    assert set(np.unique(s.record.segment)) == {0, 1, 2}
    # statistical: the thinned draws recover the truth (E0* within 1 %, alpha within 0.005)
    # and their median and 90 % interval are the table's (all 4000 draws) within sampling error
    row = table[table["rheology"] == "power-law"].iloc[0]
    for name, truth, col, tol in (("E0", 60e3, "E0_star", 600.0), ("alpha", 0.15, "alpha", 5e-3)):
        lo, med, hi = central_band(s.draws[name])
        suffix = "_pa" if name == "E0" else ""
        assert abs(med - truth) < tol, (name, med)
        width = row[f"{col}_hi{suffix}"] - row[f"{col}_lo{suffix}"]
        assert abs(med - row[f"{col}{suffix}"]) < 0.1 * width
        assert abs((hi - lo) / width - 1) < 0.15


def test_the_figures_take_a_stored_fit(folder):
    """What is drawn from a stored fit is its stored numbers: the band's median, E*(t), the
    record of every segment against the depth below the stored surface."""
    out, _, _ = folder
    s = load_rheology_fit(rheology_fit_path(out, "foam", "power-law"))
    ax = plot_cycle_fit(s).axes[0]
    median = next(ln for ln in ax.get_lines() if ln.get_label() == "posterior median")
    np.testing.assert_allclose(median.get_ydata(), s.band()[1])  # drawn in N
    assert ax.get_title().startswith("foam: power law fit, model check ")
    ax = plot_relaxation({"pl": s}).axes[0]
    line = next(ln for ln in ax.get_lines() if ln.get_label().startswith("pl"))
    np.testing.assert_allclose(line.get_ydata(), s.relax["E_star_pa"] * 1e-3)
    ax = plot_hysteresis(s).axes[0]
    lines = {ln.get_label(): ln for ln in ax.get_lines()}
    assert set(lines) == {"approach", "hold", "retract"}
    ret = s.record.segment == 2
    np.testing.assert_allclose(lines["retract"].get_xdata(), (s.z_surf - s.record.z[ret]) * 1e3)


def test_missing_or_corrupt_stored_fit_names_the_file(tmp_path):
    with pytest.raises(InputError, match="foam_sls.nc: no stored viscoelastic fit"):
        load_rheology_fit(tmp_path / "foam_sls.nc")
    bad = tmp_path / "bad.nc"
    bad.write_bytes(b"not a netCDF file")
    with pytest.raises(DataFileError, match="bad.nc: cannot be read as netCDF"):
        load_rheology_fit(bad)


def test_report_pages_carry_the_titles_and_the_tables_numbers(folder, report):
    out, table, saved = folder
    pdf, stdout = report
    pages = [_plain(p) for p in _pdf_pages(pdf)]
    # title, table, one page per trace and model
    assert len(pages) == 4
    assert "palpbayes report" in pages[0] and "Viscoelastic fits" in pages[0]
    assert "Contents" in pages[0]
    assert "Viscoelastic fits (rheology.csv)" in pages[1]
    pl = table.set_index("rheology").loc["power-law"]
    sls = table.set_index("rheology").loc["sls"]
    cells = [f"{pl['E0_star_pa'] / 1e3:.4g} [{pl['E0_star_lo_pa'] / 1e3:.4g}, "
             f"{pl['E0_star_hi_pa'] / 1e3:.4g}]",
             f"{pl['alpha']:.4g} [{pl['alpha_lo']:.4g}, {pl['alpha_hi']:.4g}]",
             f"{sls['tau_s']:.4g} [{sls['tau_lo_s']:.4g}, {sls['tau_hi_s']:.4g}]",
             f"{sls['E1_star_pa'] / 1e3:.4g}", f"{sls['elpd_diff']:.1f} ± "
             f"{sls['elpd_diff_se']:.1f}", "elpd_diff ± se", "Preferred"]
    for cell in cells:
        assert cell in pages[1], cell
    assert "E0* [kPa]" in pages[1] and "tau [s]" in pages[1]
    assert ("passed" if pl["model_ok"] else "FAILED") in pages[1]
    page_pl = next(p for p in pages[2:] if "Viscoelastic fit: foam · power law" in p)
    page_sls = next(p for p in pages[2:] if "Viscoelastic fit: foam · SLS" in p)
    for page in (page_pl, page_sls):
        assert "Viscoelastic fit: foam" in page
        for words in ("Force against time", "Relaxation modulus E*(t)", "hysteresis",
                      "Depth below the fitted surface", "median [90 % interval]"):
            assert words in page, words
    assert f"{pl['E0_pa'] / 1e3:.4g}" in page_pl  # Young's E0 with nu
    assert "PSIS-LOO prefers power law" in page_sls
    # the flags in words, as the fit said them
    for flag in saved["sls"].flags:
        assert _plain(flag)[:40] in page_sls.replace("• ", ""), flag
    if not saved["sls"].flags:
        assert "Flags: none" in page_sls
    assert "2 viscoelastic fit(s)" in stdout and f"wrote {pdf}" in stdout


def test_report_needs_summary_or_rheology_table(tmp_path, capsys):
    (tmp_path / "empty").mkdir()
    with pytest.raises(InputError, match="neither summary.csv .* nor rheology.csv"):
        build_pdf(tmp_path / "empty")
    assert main(["report", str(tmp_path / "empty")]) == 2
    err = capsys.readouterr().err
    assert "rheology.csv" in err and "summary.csv" in err and "Traceback" not in err


def test_a_new_run_removes_the_stored_fits_of_the_last(tmp_path):
    """``fit --rheology --force`` (fit_traces) starts from no table and no stored fits; the
    elastic fit's files and the user's stay."""
    out = tmp_path / "res"
    (out / "rheology").mkdir(parents=True)
    for name in ("rheology/gone_power-law.nc", "rheology.csv", "report.pdf", "summary.csv",
                 "notes.txt"):
        (out / name).write_text("old")

    def unreadable():
        raise DataFileError("missing.csv", "no such file")

    table = fit_traces([("gone", "missing.csv", unreadable)], rheology_options(), out,
                       progress=False)
    assert "no such file" in table.loc[0, "error"]
    assert not list((out / "rheology").glob("*.nc")) and not (out / "report.pdf").exists()
    assert (out / "summary.csv").read_text() == "old" and (out / "notes.txt").is_file()
    assert pd.read_csv(out / "rheology.csv")["trace_id"].tolist() == ["gone"]
    clear_rheology_outputs(out)
    assert not (out / "rheology.csv").exists() and (out / "summary.csv").is_file()
