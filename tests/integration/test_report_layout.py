"""Every kind of PDF page is laid out without text drawn over text, text off the page or a table
cell's text wider than its cell (issue 46, item 3), checked on the figures before they are saved
(:func:`palpbayes.reporting.layout_check.watch_pages`).

Three reports here, each built once (module fixtures, ~35 s together on two cores): a single
real AFM curve whose fit converges but fails its model checks (``palpbayes fit`` then
``palpbayes report DIR``: the diagnostics page with a fit that has warnings), viscoelastic fits
with both models (the rheology title, table and fit pages) and a small stiffness map
(``palpbayes map``'s six pages).  The campaign report's pages (title, summary, comparison,
layer, gap, twin, group, diagnostics, walkers, budget, indentation, methods) are checked on
test_report.py's own run of it.
"""

from __future__ import annotations

import contextlib
import io
import re
import warnings
from pathlib import Path

import pandas as pd
import pytest
from matplotlib.figure import Figure

from palpbayes.cli import main
from palpbayes.paper import PAPER_TIPS
from palpbayes.reporting.layout_check import page_observers, text_boxes, watch_pages


def _run(argv: list[str]) -> tuple[list, dict[str, str]]:
    """``palpbayes ARGV`` with every page checked; (problems, page name -> its text)."""
    texts: dict[str, str] = {}

    def keep(title: str, fig: Figure) -> None:
        texts[title] = " ".join(b.text for b in text_boxes(fig))  # the painted texts

    page_observers.append(keep)
    try:
        with watch_pages() as problems, contextlib.redirect_stdout(io.StringIO()), \
                warnings.catch_warnings():
            warnings.simplefilter("ignore")
            assert main(argv) == 0
    finally:
        page_observers.remove(keep)
    return problems, texts


def _plain(text: str) -> str:
    return re.sub(r"\s+", " ", text)


def _assert_clean(problems: list, texts: dict[str, str], at_least: int) -> None:
    assert len(texts) >= at_least, list(texts)
    assert not problems, "\n".join(map(str, problems))


@pytest.fixture(scope="module")
def single_fit_report(shared_data, tmp_path_factory):
    """A real AFM curve: the fit converges, its model checks fail (warnings in its notes)."""
    curve = shared_data("afm-curves/force-save-example.csv")
    out = tmp_path_factory.mktemp("layout-single") / "fit"
    with contextlib.redirect_stdout(io.StringIO()):
        assert main(["fit", str(curve), "--out", str(out), "--tip", "paraboloid", "--radius",
                     "10e-6", "--nu", "0.5", "--method", "both", "--engine", "exact",
                     "--no-progress"]) == 0
    return out, *_run(["report", str(out)])


@pytest.fixture(scope="module")
def rheology_report(tmp_path_factory):
    from palpbayes.contact.viscoelastic import PowerLawKernel
    from palpbayes.rheology import fit_traces, rheology_options
    from palpbayes.sim import simulate_viscoelastic

    out = tmp_path_factory.mktemp("layout-rheology") / "res"
    recs = [simulate_viscoelastic(PowerLawKernel(60e3, 0.15), PAPER_TIPS["paraboloid"],
                                  depth=3e-3, speed=speed / 6e4, hold_time=2.0, rate=200.0,
                                  rng=3, trace_id=f"Medium_paraboloid_v{speed}_r01")
            for speed in (100, 900)]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fit_traces(recs, rheology_options(("power-law", "sls"), nu=0.45), out, progress=False)
    return _run(["report", str(out)])


@pytest.fixture(scope="module")
def map_report(tmp_path_factory):
    root = tmp_path_factory.mktemp("layout-map")
    with contextlib.redirect_stdout(io.StringIO()):
        assert main(["simulate", str(root / "block"), "--map", "--grid", "5x5", "--step",
                     "5e-3", "--lump-ratio", "20", "--lump-radius", "5e-3", "--lump-depth",
                     "5.5e-3", "--lump-x", "10e-3", "--lump-y", "10e-3", "--heterogeneity",
                     "0.03", "--seed", "4"]) == 0
    return _run(["map", str(root / "block" / "manifest.csv"), "--out", str(root / "map"),
                 "--workers", "1", "--no-progress", "--lump-max-steps", "1000"])


def test_single_fit_report_pages_do_not_overprint_or_clip(single_fit_report):
    _, problems, texts = single_fit_report
    _assert_clean(problems, texts, 5)


def test_rheology_report_pages_do_not_overprint_or_clip(rheology_report):
    problems, texts = rheology_report
    _assert_clean(problems, texts, 6)


def test_map_report_pages_do_not_overprint_or_clip(map_report):
    problems, texts = map_report
    _assert_clean(problems, texts, 6)


def test_diagnostics_say_what_is_true_and_show_every_warning(single_fit_report):
    """A converged fit with warnings is said to have converged and to carry warnings (not
    "NOT converged or flagged"); the flagged-fits table shows its notes in full, warnings
    first; the text names summary.csv's real columns."""
    out, _, texts = single_fit_report
    diag = _plain(" ".join(t for name, t in texts.items() if "Convergence diagnostics" in name))
    assert "The Bayesian fit converged" in diag and "It carries a warning" in diag
    assert "NOT converge" not in diag
    assert "flags column" not in diag
    for col in ("notes", "flag_codes", "flag_level", "misfit_checks", "misfit_effect"):
        assert col in diag, col
    summary = pd.read_csv(out / "summary.csv")
    notes = summary.loc[summary["method"] == "bayes", "notes"].iloc[0]
    flat = re.sub(r"\s+", "", diag)
    for flag in notes.split("; "):
        assert re.sub(r"\s+", "", flag) in flat, flag  # wrapped, never cut
    assert "[…]" not in diag and "[...]" not in diag


def test_pages_are_checked_before_they_are_saved(tmp_path: Path):
    """The hook sees every page of a report, the title page included."""
    from palpbayes.reporting.layout import Page, write_pages

    seen: list[str] = []
    pages = [Page("", lambda fig: fig.text(0.5, 0.5, "title")),
             Page("Overprinted", lambda fig: [fig.text(0.1, 0.5, "one two three"),
                                              fig.text(0.12, 0.5, "four five six")])]
    page_observers.append(lambda title, fig: seen.append(title))
    try:
        with watch_pages() as problems:
            write_pages(pages, tmp_path / "x.pdf", footer="f", meta={})
    finally:
        page_observers.pop()
    assert seen == ["page 1: title page", "page 2: Overprinted"]
    assert [p.kind for p in problems] == ["overlap"] and "Overprinted" in problems[0].page
