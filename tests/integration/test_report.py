"""The PDF report, its CLI and the plotting functions.

A small synthetic campaign (2 foams × 1 tip × 2 repetitions, 2 compression tests per foam) is
fitted once through ``palpbayes report CAMPAIGN`` (module fixture, ~20 s); the tests read the
PDF back (pypdf when installed) and check what a reader would look for: page titles, units on
the axes, bands that contain their medians.
"""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from matplotlib.collections import PolyCollection
from matplotlib.figure import Figure
from matplotlib.patches import Rectangle

from palpbayes import plots
from palpbayes.campaign.results import ResultsFolder
from palpbayes.cli import main
from palpbayes.paper import PAPER_MATERIALS, PAPER_TIPS
from palpbayes.reporting import (
    BUDGET_GROUPS_PER_PAGE,
    CHART_GROUPS_PER_PAGE,
    REPORT_NAME,
    TABLE_ROWS_PER_PAGE,
    load_fit,
    load_results,
    report,
    summary_table,
)
from palpbayes.reporting.format import fmt_range, shown_path
from palpbayes.reporting.methods import methods_lines
from palpbayes.reporting.pages_title import _settings_lines
from palpbayes.sim import simulate

GROUP_TITLES = ["White · sphere", "Pink · sphere"]
FIXED_TITLES = ["Summary: ground truth vs least squares vs Bayes",
                "Comparison per material and tip", "Convergence diagnostics",
                "Uncertainty budget", "Methods", "Finite thickness: half-space and layer",
                "Why does the robot read stiffer than the Instron?",
                "The gap at finite strain: foams that soften or stiffen",
                "The specimen as tested: palpation and compression like for like"]


def _pdf_pages(path: Path) -> list[str]:
    """Text of each page (pypdf), or empty strings counted from the page objects."""
    try:
        import pypdf
    except ImportError:
        raw = path.read_bytes()
        n = len(re.findall(rb"/Type\s*/Page[^s]", raw))
        return [""] * n
    reader = pypdf.PdfReader(str(path))
    return [p.extract_text() or "" for p in reader.pages]


@pytest.fixture(scope="module")
def campaign(tmp_path_factory) -> Path:
    root = tmp_path_factory.mktemp("campaign")
    return simulate(
        root / "camp", seed=5, repetitions=2, gt_specimens=2,
        materials={k: PAPER_MATERIALS[k] for k in ("White", "Pink")},
        tips={"sphere": PAPER_TIPS["sphere"]})


#: The layout of the fixture's pages, as the layout check saw them before they were saved
#: (:func:`palpbayes.reporting.layout_check.watch_pages`): problems, and page -> its text.
_LAYOUT: dict = {}


@pytest.fixture(scope="module")
def fitted(campaign, tmp_path_factory):
    """``palpbayes report CAMPAIGN --out RES -o PDF`` run once, every page's layout checked
    (:data:`_LAYOUT`); (results dir, pdf, stdout)."""
    out = tmp_path_factory.mktemp("results") / "res"
    pdf = out.parent / "campaign-report.pdf"
    import contextlib
    import io

    from palpbayes.reporting.layout_check import page_observers, text_boxes, watch_pages

    texts: dict[str, str] = {}

    def keep(title, fig) -> None:
        texts[title] = " ".join(b.text for b in text_boxes(fig))  # the painted texts

    buf = io.StringIO()
    page_observers.append(keep)
    try:
        with watch_pages() as problems, contextlib.redirect_stdout(buf):
            rc = main(["report", str(campaign), "--out", str(out), "-o", str(pdf),
                       "--workers", "1", "--seed", "3"])
    finally:
        page_observers.remove(keep)
    assert rc == 0
    _LAYOUT.update(problems=list(problems), texts=texts)
    return out, pdf, buf.getvalue()


def test_campaign_report_pages_do_not_overprint_or_clip(fitted):
    """Issue 46: no text over text, off the page or wider than its table cell, on every page
    of the campaign report (title, summary, comparison, layer, gap, twin, group, diagnostics,
    walkers, budget, indentation, methods); the single-fit, rheology and map reports are
    checked in test_report_layout.py."""
    problems, texts = _LAYOUT["problems"], _LAYOUT["texts"]
    assert len(texts) >= 12, list(texts)
    assert not problems, "\n".join(map(str, problems))


def test_campaign_diagnostics_count_only_what_failed(fitted):
    diag = re.sub(r"\s+", " ", " ".join(t for name, t in _LAYOUT["texts"].items()
                                        if "Convergence diagnostics" in name))
    assert "All 4 Bayesian fits converged" in diag and "NOT converge" not in diag


# ----------------------------------------------------------------------------- report


def test_campaign_report_pipeline_writes_every_table(fitted, campaign):
    out, pdf, stdout = fitted
    for name in ("summary.csv", "comparison.csv", "pooled.csv", "budget.csv",
                 "groundtruth.csv", "groundtruth_summary.csv", "settings.json"):
        assert (out / name).is_file(), name
    assert len(list((out / "posterior").glob("*.nc"))) == 4
    comp = pd.read_csv(out / "comparison.csv")
    assert set(comp["method"]) == {"lsq", "bayes"}
    # sphere traces: the paper's Hertz fit beside every row, a few per cent below E
    summ = pd.read_csv(out / "summary.csv")
    assert summ["E_hertz_pa"].notna().all()
    lsq = summ[summ["method"] == "lsq"]  # (the Bayesian rows model the layer, Hertz does not)
    assert ((lsq["E_hertz_rel_diff"] < 0) & (lsq["E_hertz_rel_diff"] > -0.06)).all()
    assert comp["gt_E_pa"].notna().all()
    # the blocks' footprints reach the fits (their twins) and the comparison sets their
    # compression reading beside the Instron's, like for like (the GT blocks were tested
    # between bonded platens; the run's platens are unknown: the interval spans both)
    bayes = summ[summ["method"] == "bayes"]
    assert bayes["layer"].str.contains("50 × 50 × (?:30|20) mm block").all()
    # platens unknown: the interval runs from E's own lower end (lubricated) to the bonded
    # draws' upper end, c = 1.07-1.22 above E's (the blocks' twins at nu 0.25-0.35)
    np.testing.assert_allclose(bayes["E_instron_lo_pa"], bayes["E_lo_pa"], rtol=1e-12)
    assert (bayes["E_instron_hi_pa"] / bayes["E_hi_pa"]).between(1.07, 1.22).all()
    truth = pd.read_csv(campaign / "truth.csv").set_index("trace_id")
    t = truth.loc[bayes["trace_id"]]
    assert (bayes["E_instron_lo_pa"].to_numpy() <= t["E_instron_true_pa"].to_numpy()).all()
    assert (t["E_instron_true_pa"].to_numpy() <= bayes["E_instron_hi_pa"].to_numpy()).all()
    cb = comp[comp["method"] == "bayes"]
    assert (cb["platens"] == "unknown").all() and cb["gt_in_instron_interval"].all()
    assert "like for like" in stdout and "covers the Instron in 2/2" in stdout
    assert pdf.is_file()
    assert f"wrote {pdf}" in stdout
    assert "report: " in stdout and "pages" in stdout


def test_pdf_pages_and_titles(fitted):
    out, pdf, _ = fitted
    pages = _pdf_pages(pdf)
    # title, summary, comparison, finite thickness, the paper's gap, the gap at finite strain,
    # the specimen as tested, 2 groups, diagnostics, walkers, budget, methods (1-2 pages)
    assert 13 <= len(pages) <= 15
    if not any(pages):
        pytest.skip("pypdf not installed: page count checked, titles not")
    text = "\n".join(pages)
    assert "palpbayes report" in pages[0] and "Contents" in pages[0]
    for title in FIXED_TITLES:
        assert title in text, title
    for title in GROUP_TITLES:
        mat, tip = title.split(" · ")
        assert any(mat in p and tip in p and "Representative trace" in p for p in pages), title
    # the summary table is a real table with the numbers of comparison.csv (kPa)
    comp = pd.read_csv(out / "comparison.csv")
    r = comp[(comp["material"] == "White") & (comp["method"] == "bayes")].iloc[0]
    assert f"{r['E_pa'] / 1e3:.1f} ± {r['E_sd_pa'] / 1e3:.1f}" in pages[1]
    assert f"{r['gt_E_pa'] / 1e3:.1f} ± {r['gt_sd_pa'] / 1e3:.1f}" in pages[1]
    # every page has its number; methods page states the priors table
    assert all(f"page {i} / {len(pages)}" in p for i, p in enumerate(pages, 1))
    assert "log_Estar" in text and "Uniform" in text
    assert "All 4 Bayesian fits converged" in text and "NOT converged" not in text


def test_one_number_per_quantity_in_the_tables_pages_and_console(fitted):
    """Issue 58: Grey·flat's pooled E read 190.9 kPa in comparison.csv, on the console and the
    summary page, 191.9 kPa in pooled.csv and on its group page (the median at the stated
    inputs against the median with the budget); White·paraboloid's new-specimen interval read
    [65, 179] on the summary page and [64.8, 178.1] on its group page.  One computation,
    copied; one printed form (0.1 kPa) everywhere."""
    from palpbayes.campaign.comparison import POOLED_SHARED

    out, _, stdout = fitted
    comp = pd.read_csv(out / "comparison.csv")
    bayes = comp[comp["method"] == "bayes"].set_index(["material", "tip"])
    pooled = pd.read_csv(out / "pooled.csv").set_index(["material", "tip"]).loc[bayes.index]
    for col in POOLED_SHARED:
        np.testing.assert_array_equal(bayes[col].to_numpy(), pooled[col].to_numpy(), col)
    texts = _LAYOUT["texts"]
    summary = " ".join(t for name, t in texts.items() if ": Summary" in name)  # "page 2: ..."
    for (mat, tip), r in bayes.iterrows():
        e = f"{r['E_pa'] / 1e3:.1f}"
        new = f"[{r['E_new_lo_pa'] / 1e3:.1f}, {r['E_new_hi_pa'] / 1e3:.1f}]"
        assert f"{e} ± {r['E_sd_pa'] / 1e3:.1f}" in summary and new in summary
        assert new in stdout  # the console's table
        page = next(t for name, t in texts.items() if name.endswith(f": {mat} · {tip}"))
        assert f"E = {e} kPa" in page and f"new specimen {new} kPa" in page, page


def test_report_from_results_folder_cli(fitted, tmp_path, capsys):
    out, _, _ = fitted
    pdf = tmp_path / "again.pdf"
    assert main(["report", str(out), "-o", str(pdf)]) == 0
    assert pdf.is_file() and pdf.stat().st_size < 3_000_000
    assert f"wrote {pdf}" in capsys.readouterr().out
    # default name inside the results folder
    info = report(out)
    assert info.path == out / REPORT_NAME and info.path.is_file()
    assert info.titles[1].startswith("Summary") and info.n_traces == 4
    # continued pages are numbered 2/n, 3/n (not 'continued 2' on the second page)
    methods = [t for t in info.titles if t.startswith("Methods")]
    assert methods[0] == "Methods" and len(methods) >= 2
    assert methods[1:] == [f"Methods (continued, {k}/{len(methods)})"
                           for k in range(2, len(methods) + 1)]
    assert info.results_shown == shown_path(out)


@pytest.mark.slow
def test_rerun_on_the_same_campaign_reuses_the_fits(fitted, campaign, tmp_path):
    out, _, _ = fitted
    before = {p.name: p.stat().st_mtime_ns for p in (out / "posterior").glob("*.nc")}
    assert main(["report", str(campaign), "--out", str(out), "-o", str(tmp_path / "r.pdf"),
                 "--workers", "1", "--seed", "3"]) == 0
    after = {p.name: p.stat().st_mtime_ns for p in (out / "posterior").glob("*.nc")}
    assert before == after
    # an edited trace, other options or another version: tests/integration/test_report_rerun.py


def test_report_input_errors(tmp_path, capsys, monkeypatch, fitted):
    assert main(["report", str(tmp_path / "missing")]) == 2
    assert "no such file" in capsys.readouterr().err
    (tmp_path / "empty").mkdir()
    assert main(["report", str(tmp_path / "empty")]) == 2
    assert "neither a results folder" in capsys.readouterr().err
    out, _, _ = fitted
    assert main(["report", str(out), "-o", str(tmp_path / "r.txt")]) == 2
    assert main(["report", str(out), "--out", str(tmp_path / "x")]) == 2
    # no INPUT and no shipped example (e.g. an installed wheel): a clear input error
    import palpbayes

    monkeypatch.setattr(palpbayes, "__file__", str(tmp_path / "site" / "palpbayes" /
                                                   "__init__.py"))
    assert main(["report"]) == 2
    assert "shipped example campaign is not at" in capsys.readouterr().err


def test_summary_table_without_comparison(fitted, tmp_path):
    out, _, _ = fitted
    res = load_results(out)
    res.comparison = None
    tab = summary_table(res)
    assert list(tab["Material"]) == ["White", "Pink"]
    assert "Bayes mean E ± sd over traces [kPa]" in tab.columns
    full = summary_table(load_results(out))
    # units in the headers; the two Bayes quantities labelled apart
    assert {"GT E ± sd [kPa]", "LS E ± sd [kPa]", "Bayes material E ± sd [kPa]",
            "Bayes new specimen 90 % [kPa]", "Bayes covers GT", "Paper E ± sd [kPa]",
            "Paper err [%] (vs paper's GT)", "Hertz LS E [kPa] (Δ vs LS)"} <= set(full.columns)
    assert set(full["Bayes covers GT"]) <= {"yes", "NO"}
    # sphere groups: the paper's Hertz fit, a few per cent below the Sneddon LS E
    for cell in full["Hertz LS E [kPa] (Δ vs LS)"]:
        delta = float(re.search(r"\(([-+]\d+\.\d) %\)", cell).group(1))
        assert -6.0 < delta < 0.0


def test_compare_cli_says_what_its_bayes_cells_are(fitted, tmp_path, capsys):
    import shutil

    out, _, _ = fitted
    copy = tmp_path / "res"
    shutil.copytree(out, copy)
    assert main(["compare", str(copy)]) == 0
    text = capsys.readouterr().out
    assert "NEW SPECIMEN" in text and "'Bayes material E ± sd'" in text
    assert "E_new_lo_pa, E_new_hi_pa" in text and "E_new_sd_pa" not in text  # as printed
    assert "none found" not in text  # the campaign's ground truth was found and analysed


def test_summary_page_states_coverage_and_paper_error_basis(fitted):
    _, pdf, stdout = fitted
    pages = _pdf_pages(pdf)
    if not any(pages):
        pytest.skip("pypdf not installed")
    comp = pd.read_csv(fitted[0] / "comparison.csv")
    k = int(comp[comp["method"] == "bayes"]["gt_in_new_interval"].sum())
    summary = " ".join(pages[1].split())
    assert f"Bayes: {k}/2" in summary and "LS: " in summary
    assert "relative to the PAPER's own Instron ground truth" in summary
    assert "not to the GT column" in summary
    assert "covers the ground truth: Bayes" in stdout
    # sphere pages name the paper's Hertz fit of the same traces
    groups = [p for p in pages if "Representative trace" in p]
    assert groups and all("Paper's Hertz fit of the same" in " ".join(p.split())
                          for p in groups)


def test_methods_text_is_built_from_the_settings(fitted):
    import copy

    out, _, _ = fitted
    res = load_results(out)

    def text(r) -> str:
        return " ".join(t for _, t in methods_lines(r))

    base = text(res)
    smp = res.settings["options_fields"]["settings"]
    assert f"longer than {smp['tau_factor']:g} × the integrated autocorrelation time" in base
    assert "100 autocorrelation" not in base and "first 20 % of a flat punch" in base
    assert "HalfNormal(0.5)" in base  # tau prior scale read from pooled.csv
    changed = copy.deepcopy(res.settings)
    changed["options_fields"]["settings"].update(
        tau_factor=37, check_every=123, min_steps=456, max_steps=7890, tau_rtol=0.02,
        n_walkers=24, moves="de-snooker")
    changed["options_fields"]["fit_fraction"] = 0.1
    res.settings = changed
    res.pooled = res.pooled.assign(tau_prior_sd=0.25)
    new = text(res)
    for frag in ("emcee, 24 walkers", "80 % DEMove + 20 % DESnookerMove",
                 "every 123 steps after 456", "longer than 37 × the integrated",
                 "less than 2 % since the last check",
                 "bulk and tail ESS ≥ 400 for every parameter, with max R-hat ≤ 1.05 over "
                 "every parameter and the log posterior as a guard",
                 "or at 7890 steps (then flagged)",
                 "Burn-in 2·max tau, thinning floor(min tau / 2)", "the first 10 % of the",
                 "HalfNormal(0.25)"):
        assert frag in new, frag
    assert "50 ×" not in new.split("Pooling")[0] and "HalfNormal(0.5)" not in new
    changed["options_fields"]["settings"]["moves"] = "de"
    assert "DEMove) only" in text(res)



def test_settings_and_methods_print_forces_and_depths_with_a_prefix(fitted):
    """Force and depth settings are printed with an SI prefix chosen from their size, so
    AFM-scale settings read as pN and µm, not as '0 mN'."""
    import copy

    out, _, _ = fitted
    res = load_results(out)

    def text(lines) -> str:
        return " ".join(t for _, t in lines)

    # the fixture gives no noise spec: it is read from each trace's baseline, and said so
    auto = "read from each trace's pre-contact baseline (6 sd)"
    assert f"(F_unc = {auto};" in text(methods_lines(res))
    base = text(_settings_lines(res))
    assert f"F_unc = {auto};" in base and f"sensor noise {auto} peak-to-peak" in base
    changed = copy.deepcopy(res.settings)
    opts = changed["options_fields"]
    opts.update(f_unc=3e-10, max_depth=2e-6)
    opts["priors"] = {**(opts.get("priors") or {}), "noise_pp": 2.5e-10}
    res.settings = changed
    methods, settings = text(methods_lines(res)), text(_settings_lines(res))
    assert "(F_unc = 300 pN;" in methods
    assert "Only samples shallower than 2 µm are fitted." in methods
    assert "F_unc = 300 pN; fit fraction" in settings and "max depth 2 µm" in settings
    assert "sensor noise 250 pN peak-to-peak" in settings
    assert " mN" not in methods.split("Bayesian model")[0] and " mN" not in settings


def test_methods_priors_table_matches_the_priors_module():
    """The priors on the methods page are written out in palpbayes.reporting.methods; they must
    name every sampled parameter and state PriorSpec's default numbers."""
    import math

    from palpbayes.bayes.priors import NOISE_MODELS, PriorSpec, param_names
    from palpbayes.reporting.methods import PRIORS_TABLE

    rows = {ln.split()[0] for ln in PRIORS_TABLE if ln.strip() and not ln.startswith(" ")}
    for noise in NOISE_MODELS:
        assert set(param_names(noise, "linear")) <= rows, noise
    text = " ".join(PRIORS_TABLE)
    spec = PriorSpec()
    lo, hi = spec.Estar_bounds
    assert f"[ln {lo:g} Pa, ln 1e{round(math.log10(hi))} Pa]" in text
    assert f"Normal(ln(pp/6), {spec.log_sigma_sd:g})" in text
    assert f"Uniform(−{-spec.phi_bounds[0]:g}, {spec.phi_bounds[1]:g})" in text
    assert f"Uniform(ln {spec.nu_t_bounds[0]:g}, ln {spec.nu_t_bounds[1]:g})" in text

def _replicated(res: ResultsFolder, path: Path, materials: list[str], tips: list[str]
                ) -> ResultsFolder:
    """The tables of one fitted group copied to materials × tips groups (no posteriors: the
    group pages say so, nothing is fitted)."""
    mat0, tip0 = res.groups()[0]

    def rep(df: pd.DataFrame | None) -> pd.DataFrame | None:
        if df is None:
            return None
        src = df[(df["material"].astype(str) == mat0) & (df["tip"].astype(str) == tip0)]
        parts = []
        for m in materials:
            for t in tips:
                part = src.copy()
                part["material"], part["tip"] = m, t
                if "trace_id" in part:
                    part["trace_id"] = part["trace_id"].str.replace(f"{mat0}_{tip0}", f"{m}_{t}")
                parts.append(part)
        return pd.concat(parts, ignore_index=True)

    return ResultsFolder(path=path, summary=rep(res.summary), settings=res.settings,
                         comparison=rep(res.comparison), pooled=rep(res.pooled),
                         budget=rep(res.budget))


@pytest.mark.slow
def test_many_groups_paginate_tables_and_split_charts(fitted, tmp_path):
    out, _, _ = fitted
    res = load_results(out)
    (tmp_path / "many").mkdir()
    materials = [f"Foam{i}" for i in range(1, 10)]
    tips = ["flat", "sphere", "paraboloid"]
    many = report(_replicated(res, tmp_path / "many", materials, tips),
                        tmp_path / "many.pdf")
    few = report(_replicated(res, tmp_path / "many", materials[:1], tips),
                       tmp_path / "few.pdf")
    assert len(_pdf_pages(many.path)) == many.n_pages
    assert max(many.table_rows) <= TABLE_ROWS_PER_PAGE

    def rows_of(info, prefix):
        return [r for t, r in zip(info.titles, info.table_rows, strict=True)
                if t.startswith(prefix)]

    assert rows_of(many, "Summary") == [14, 13]
    assert rows_of(many, "Comparison") == [9, 9, 9]  # whole materials, spread evenly
    assert max(rows_of(many, "Comparison")) <= CHART_GROUPS_PER_PAGE
    assert rows_of(many, "Uncertainty budget") == [9, 9, 9]
    assert max(rows_of(many, "Uncertainty budget")) <= BUDGET_GROUPS_PER_PAGE
    assert rows_of(many, "Convergence diagnostics") == [14, 13]
    assert "Summary: ground truth vs least squares vs Bayes (continued, 2/2)" in many.titles
    # 24 more group pages, one more summary and diagnostics page, two more of each chart
    assert many.n_pages - few.n_pages == 24 + 1 + 1 + 2 + 2
    assert rows_of(few, "Summary") == [3]


def test_small_formatting_helpers(tmp_path, monkeypatch):
    assert fmt_range(1500, 1500) == "1500" and fmt_range(1250, 2000) == "1250–2000"
    (tmp_path / "work").mkdir()
    monkeypatch.chdir(tmp_path / "work")
    assert shown_path(tmp_path / "work" / "res") == "res"
    assert shown_path(tmp_path / "rep") == str(Path("..") / "rep")
    assert shown_path("/") == "/"


def test_plotting_modules_do_not_use_pyplot():
    code = ("import sys, palpbayes.plots, palpbayes.reporting, palpbayes.cli.report; "
            "print('matplotlib.pyplot' in sys.modules)")
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert res.stdout.strip() == "False"


# ----------------------------------------------------------------------------- plots


@pytest.fixture(scope="module")
def fit(fitted):
    out, _, _ = fitted
    return load_fit(out, "White_sphere_r01")


def _band_contains(ax, band_label: str, line_label: str) -> None:
    coll = [c for c in ax.collections
            if isinstance(c, PolyCollection) and band_label in str(c.get_label())]
    line = [ln for ln in ax.lines if ln.get_label() == line_label]
    assert coll and line, (band_label, line_label)
    verts = coll[0].get_paths()[0].vertices
    x, y = line[0].get_xdata(), line[0].get_ydata()
    for xi, yi in list(zip(x, y, strict=True))[::15]:
        at = verts[np.isclose(verts[:, 0], xi, rtol=0, atol=1e-12), 1]
        assert at.size >= 2
        assert at.min() - 1e-12 <= yi <= at.max() + 1e-12


def test_force_depth_plot_units_and_band(fit):
    fig = plots.plot_force_depth(fit)
    assert isinstance(fig, Figure)
    ax = fig.axes[0]
    assert "[mm]" in ax.get_xlabel() and "Depth" in ax.get_xlabel()
    assert ax.get_ylabel() == "Force, F [N]"
    labels = ax.get_legend_handles_labels()[1]
    assert "least squares" in labels and "Bayes posterior median" in labels
    _band_contains(ax, "credible band", "Bayes posterior median")
    _band_contains(ax, "predictive", "Bayes posterior median")
    # the force-depth data are plotted in mm and N: the deepest point is ~3 mm (White: 30 mm)
    data = [ln for ln in ax.lines if str(ln.get_label()).startswith("data")][0]
    assert 2.0 < np.max(data.get_xdata()) < 4.0
    assert np.max(data.get_ydata()) == pytest.approx(fit.data.force.max())
    assert len(ax.child_axes) == 1  # the zoom on the contact onset
    inset = ax.child_axes[0]
    assert inset.get_xlim()[0] < 0 < inset.get_xlim()[1]
    # neither the inset nor the legend covers the data or the fitted curves
    assert _points_inside(ax, inset, data) == 0
    assert _points_inside(ax, ax.get_legend(), data) == 0
    median = [ln for ln in ax.lines if ln.get_label() == "Bayes posterior median"][0]
    assert _points_inside(ax, inset, median) == 0
    assert _points_inside(ax, ax.get_legend(), median) == 0


def _points_inside(ax, artist, line) -> int:
    """How many points of ``line`` (on ``ax``) fall inside ``artist``'s drawn box."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    fig = ax.figure
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    box = artist.get_window_extent(canvas.get_renderer())
    xy = ax.transData.transform(np.column_stack([line.get_xdata(), line.get_ydata()]))
    inside = ((xy[:, 0] >= box.x0) & (xy[:, 0] <= box.x1)
              & (xy[:, 1] >= box.y0) & (xy[:, 1] <= box.y1))
    return int(inside.sum())


def test_plots_draw_on_a_given_axes(fit):
    fig = Figure()
    ax = fig.add_subplot()
    assert plots.plot_residuals(fit, ax=ax) is fig
    assert ax.get_ylabel().endswith("[mN]") and "[mm]" in ax.get_xlabel()
    # the legend sits in the band kept free below the residuals
    points = [ln for ln in ax.lines if ln.get_label() == "Bayes residuals"][0]
    assert _points_inside(ax, ax.get_legend(), points) == 0


def test_posterior_plots(fit):
    fig = plots.plot_posterior(fit, truth={"E": 110e3})
    ax_e, ax_z, ax_pair = fig.axes[:3]
    assert ax_e.get_xlabel() == "Young's modulus, E [kPa]"
    assert "[µm]" in ax_z.get_xlabel() and "[µm]" in ax_pair.get_xlabel()
    assert "[kPa]" in ax_pair.get_ylabel()
    # the posterior median line lies inside the shaded central 90 % interval, in kPa
    # (the row's numbers: E at the stated inputs, the budget interval around it)
    row = fit.summary_row()
    med = row["E_pa"] / 1e3
    assert any(np.allclose(ln.get_xdata(), med) for ln in ax_e.lines)
    lo, hi = row["E_budget_lo_pa"] / 1e3, row["E_budget_hi_pa"] / 1e3
    spans = [p for p in ax_e.patches if isinstance(p, Rectangle)]
    assert any(np.isclose(p.get_x(), lo) and np.isclose(p.get_x() + p.get_width(), hi)
               for p in spans)
    assert lo < med < hi
    # z_surf relative to its median: the posterior is centred on 0 µm
    z = (fit.draws("z_surf") - np.median(fit.draws("z_surf"))) * 1e6
    assert abs(np.median(z)) < 1e-9


def test_walkers_plot(fit):
    fig = plots.plot_walkers(fit)
    axes = fig.axes
    assert len(axes) == 4
    units = [a.get_ylabel() for a in axes]
    assert units[0] == "E* [kPa]" and units[2] == "sigma [mN]" and units[3] == "F0 [mN]"
    n_walkers = fit.idata.posterior.sizes["chain"]
    assert all(len(a.lines) == n_walkers for a in axes)
    assert "Sampler step" in axes[-1].get_xlabel()
    assert re.search(r"R-hat \d\.\d{4},", axes[0].get_title(loc="left"))  # as the tables


def test_budget_plots(fitted):
    out, _, _ = fitted
    budget = pd.read_csv(out / "budget.csv")
    fig = plots.plot_budget(budget)
    ax = fig.axes[0]
    assert "[%]" in ax.get_xlabel()
    # stacked bars: the shares of each group add up to 100 %
    widths: dict[float, float] = {}
    for p in ax.patches:
        widths[round(p.get_y(), 6)] = widths.get(round(p.get_y(), 6), 0.0) + p.get_width()
    assert len(widths) == 2
    assert all(w == pytest.approx(100.0, abs=1e-6) for w in widths.values())
    one = budget[budget["material"] == "White"].drop(columns=["material", "tip"])
    fig1 = plots.plot_budget(one)
    assert [t.get_text() for t in fig1.axes[0].get_yticklabels()] == list(one["input"])


def test_comparison_and_forest_plots(fitted):
    out, _, _ = fitted
    comp = pd.read_csv(out / "comparison.csv")
    fig = plots.plot_comparison(comp)
    ax = fig.axes[0]
    assert ax.get_ylabel() == "Young's modulus, E [kPa]"
    assert [t.get_text() for t in ax.get_xticklabels()] == ["sphere", "sphere"]
    legend = [t.get_text() for t in ax.get_legend().get_texts()]
    assert any("ground truth" in t for t in legend)
    assert any("paper" in t for t in legend)
    # each method's thick interval contains its estimate (kPa)
    for _, r in comp.iterrows():
        assert r["E_lo_pa"] <= r["E_pa"] <= r["E_hi_pa"]
    summary = pd.read_csv(out / "summary.csv")
    pooled = pd.read_csv(out / "pooled.csv").iloc[0]
    sub = summary[summary["material"] == pooled["material"]]
    fig = plots.plot_forest(sub, pooled, gt=(110e3, 10e3), title="x")
    ax = fig.axes[0]
    assert ax.get_xlabel() == "Young's modulus, E [kPa]"
    ticks = [t.get_text() for t in ax.get_yticklabels()]
    assert "pooled mean" in ticks and "new specimen" in ticks


def test_stiffening_plot_with_a_fit_object():
    class Fake:
        preferred = "single"
        law = "E(t) = c0 + c1·exp(c2·t)"

        def predict(self, t, level=0.9):
            m = 100e3 + 30e3 * np.exp(-np.asarray(t) / 30)
            return pd.DataFrame({"t_s": t, "median_pa": m, "lo_pa": m - 1e3, "hi_pa": m + 1e3})

    t = np.array([1.0, 10, 30, 100])
    E = 100e3 + 30e3 * np.exp(-t / 30)
    fig = plots.plot_stiffening(t, E, E_lo=E - 500, E_hi=E + 500, fit=Fake(),
                                rested=(100e3, 99e3, 101e3))
    ax = fig.axes[0]
    assert ax.get_xlabel().endswith("[s]") and ax.get_ylabel().endswith("[kPa]")
    line = [ln for ln in ax.lines if "fitted" in ln.get_label()][0]
    assert np.max(line.get_ydata()) == pytest.approx(130.0, rel=1e-3)
    _band_contains(ax, "credible band", line.get_label())


def test_diagnostics_page_counts_failed_model_checks(fitted):
    """The diagnostics page counts failed model checks per method (Bayesian, least squares)."""
    from palpbayes.reporting.pages_diagnostics import _model_check_line

    out, _, _ = fitted
    res = load_results(out)
    line = _model_check_line(res)
    s = res.summary
    for method, label in (("bayes", "Bayesian"), ("lsq", "least-squares")):
        ran = s[(s["method"] == method) & s["model_ok"].notna()]
        if len(ran):
            bad = int((ran["model_ok"].astype(str).str.lower() == "false").sum())
            assert f"{bad} of {len(ran)} {label} fits" in line, line
    res.summary = s.drop(columns=["model_ok"])
    assert "not run" in _model_check_line(res)


def test_indentation_page_replays_every_trace_file(fitted, tmp_path):
    """"How much indentation did we need?": each trace of the campaign replayed with a ±2 %
    target (by the compare step, ``indentation.csv``) stops well before the end of its
    recording, and the page is in the report, drawn from that table; a results folder whose
    trace files are gone gets no table (and no error), and a report without the table no
    such page."""
    from palpbayes.campaign.indentation import indentation_study
    from palpbayes.reporting.pages_online import online_pages

    out, _, _ = fitted
    res = load_results(out)
    study = res.indentation
    assert len(study) == 4 and study["stopped"].all()
    again = indentation_study(res.traces, res.settings)  # the table is what the study gives
    pd.testing.assert_frame_equal(study[again.columns], again, check_dtype=False)
    assert set(study["material"]) == {"White", "Pink"} and set(study["tip"]) == {"sphere"}
    assert (study["depth_stop_m"] < 0.5 * study["depth_full_m"]).all()
    assert (study["peak_force_stop_n"] < study["peak_force_full_n"]).all()
    # the intervals at the stop are within the target
    half = (study["E_stop_hi_pa"] - study["E_stop_lo_pa"]) / (2 * study["E_stop_pa"])
    assert (half <= 0.02).all()
    info = report(res, tmp_path / "r.pdf")
    assert "How much indentation did we need?" in info.titles
    moved = res.traces.assign(file=str(tmp_path / "gone.csv"))
    assert indentation_study(moved, res.settings).empty
    gone = ResultsFolder(**{**res.__dict__, "indentation": None})
    assert online_pages(gone) == []
