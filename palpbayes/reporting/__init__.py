"""The PDF report of a results folder: what a researcher attaches to a lab notebook.

:func:`report` reads a results folder (:mod:`palpbayes.campaign.results`: ``summary.csv``,
``posterior/*.nc``, ``settings.json``, ``traces.csv`` and, when present, ``comparison.csv``,
``pooled.csv``, ``budget.csv``, ``stiffening.csv``, ``groundtruth.csv`` /
``groundtruth_summary.csv``) and writes a multi-page PDF (A4 landscape, written atomically):

1. title page: campaign, date, palpbayes version, the results folder it was built from,
   settings, contents;
2. summary table in the layout of the paper's Table III (units in the headers): ground truth,
   least squares and Bayes E ± sd per material × tip, errors, whether each new-specimen
   interval covers the ground truth (with the overall count), the paper's robot numbers and,
   for spheres, the paper's Hertz fit of the same traces;
3. the same comparison as a figure; then finite thickness: the half-space (the paper's)
   least squares, the same fits read as a free and a bonded layer, and the Bayesian layer
   model against the Instron, and, when ``gap.csv`` is there, "Why does the robot read stiffer
   than the Instron?" (the paper's published gap against the layer model's prediction,
   :mod:`palpbayes.gap`, with a verdict per tip);
4. one page per material × tip: force-depth data of a representative trace with the
   posterior-predictive band and the least-squares curve, residuals, posterior of E and of
   (E, z_surf), per-trace intervals with the pooled result; sphere pages also state the
   paper's Hertz fit (``summary.csv`` ``E_hertz_pa``) against the exact Sneddon law;
5. convergence diagnostics (the fits that did not converge and, counted apart, the converged
   fits with a warning, each with its notes in full; or the statement that all converged with
   the largest R-hat and smallest ESS) and the walkers of the worst fit;
6. the uncertainty budget (table and chart);
7. the stiffening law E(t) vs rest time (:mod:`palpbayes.stiffening`) for every material × tip
   whose palpations have at least
   :data:`~palpbayes.campaign.stiffening_tables.STIFFENING_MIN_REST_TIMES` distinct rest
   times, and ``stiffening.csv`` (the compare step's tables: the report fits nothing);
8. "How much indentation did we need?": every trace whose file could be read, replayed
   through the online estimator (:mod:`palpbayes.online`) with a ±2 % precision target by
   the compare step (``indentation.csv``); the median depth and peak force at the stop per
   material × tip, against the recorded indentation;
9. viscoelastic fits, when the folder has ``rheology.csv`` (``palpbayes fit --rheology``;
   :mod:`~palpbayes.reporting.pages_rheology`): a table of every trace × relaxation model (the
   parameters with 90 % intervals, the model check, flag codes and, with several models,
   PSIS-LOO's ``elpd_diff`` ± se and the preferred model), then per trace and model force against
   time with the fit's band and the segments, E*(t) with its band (every model of the trace),
   force against depth per segment (the hysteresis), the parameters and the flags in words, all
   read from ``rheology.csv`` and the stored fits ``rheology/*.nc``; a folder with only
   ``rheology.csv`` gets a title page and these pages;
10. methods: models, priors, noise model, least squares, the sampler's stopping rule (numbers
    from ``settings.json``), pooling (:data:`palpbayes.pooling.POOLING_SETTINGS`, tau prior
    from ``pooled.csv``), ground-truth window.

Tables continue on further pages beyond :data:`TABLE_ROWS_PER_PAGE` rows ('… (continued, 2/3)'),
comparison charts beyond :data:`CHART_GROUPS_PER_PAGE` material × tip groups (whole materials
per page) and budget pages beyond :data:`BUDGET_GROUPS_PER_PAGE` groups, so a campaign of any
size stays readable.

This package only draws: reading a results folder is :mod:`palpbayes.campaign.results`, fitting a
campaign first (``palpbayes report CAMPAIGN``) is :func:`palpbayes.campaign.pipeline.run_pipeline`.
Both modules' public names used by notebooks (``load_results``, ``load_fit``, ``ResultsFolder``,
``run_pipeline``, ``example_campaign_dir``) are re-exported here for compatibility.
Matplotlib is used through its object API only (figures are rendered by the PDF backend;
:mod:`matplotlib.pyplot` is never imported), so the report works under any backend.

Modules: :mod:`~palpbayes.reporting.build` (:func:`report`, page order),
:mod:`~palpbayes.reporting.format` (numbers and cells), :mod:`~palpbayes.reporting.tables` (the
summary table, drawn tables, pagination), :mod:`~palpbayes.reporting.layout` (page geometry),
:mod:`~palpbayes.reporting.methods` (the methods text), one ``pages_*`` module per page kind
(title, summary, layer, group, diagnostics, budget, stiffening, online, rheology, methods) and
:mod:`~palpbayes.reporting.layout_check` (every page checked before it is saved: no text over
text, off the page or wider than its table cell; ``tests/integration/test_report_layout.py``).
"""

from __future__ import annotations

from ..campaign.compare_text import format_comparison
from ..campaign.pipeline import example_campaign_dir, run_pipeline
from ..campaign.reference import paper_estimates
from ..campaign.results import ResultsFolder, load_fit, load_results
from .build import RASTER_DPI, REPORT_NAME, ReportInfo, report
from .layout import BUDGET_GROUPS_PER_PAGE, CHART_GROUPS_PER_PAGE, PAGE_SIZE, TABLE_ROWS_PER_PAGE
from .methods import MOVES_TEXT
from .tables import (
    BAYES_E_COL,
    BAYES_NEW_COL,
    GT_COL,
    HERTZ_COL,
    INSTRON_COL,
    INSTRON_COVER_COL,
    LS_E_COL,
    coverage_counts,
    summary_table,
)

__all__ = [
    "PAGE_SIZE",
    "REPORT_NAME",
    "RASTER_DPI",
    "TABLE_ROWS_PER_PAGE",
    "CHART_GROUPS_PER_PAGE",
    "BUDGET_GROUPS_PER_PAGE",
    "MOVES_TEXT",
    "ReportInfo",
    "summary_table",
    "coverage_counts",
    "GT_COL",
    "LS_E_COL",
    "BAYES_E_COL",
    "BAYES_NEW_COL",
    "INSTRON_COL",
    "INSTRON_COVER_COL",
    "HERTZ_COL",
    "report",
    # re-exported from palpbayes.campaign (results, pipeline, compare_text, reference): the
    # report's inputs and its comparison text, for notebooks
    "format_comparison",
    "paper_estimates",
    "ResultsFolder",
    "load_results",
    "load_fit",
    "example_campaign_dir",
    "run_pipeline",
]
