"""Layout of a results folder: every file name palpbayes reads or writes there, in one place.

A results folder (``palpbayes fit MANIFEST --out DIR``) holds::

    DIR/
      settings.json            fit options, seed, versions      (fit)
      traces.csv               the manifest's rows as fitted     (fit)
      summary.csv              one row per trace × method        (fit)
      posterior/<trace>.nc     netCDF posterior of a Bayes fit   (fit)
      .partial/<trace>.json    per-trace rows for --resume       (fit)
      comparison.csv           material × tip × method           (compare)
      pooled.csv               hierarchical pooling per group    (compare)
      budget.csv               uncertainty budget per group      (compare)
      stiffening.csv           stiffening law per group          (compare)
      groundtruth.csv          per compression test              (groundtruth)
      groundtruth_summary.csv  per material                      (groundtruth)
      gap.csv                  the paper's robot-vs-Instron gap   (report, paper's materials)
      report.pdf               the PDF report                    (report)

Modules use these constants and helpers instead of literals, so that a file added here is also
removed by ``fit --force`` (:data:`FIT_OUTPUTS`) and a renamed file cannot leave a reader behind.
"""

from __future__ import annotations

import os
from pathlib import Path

__all__ = [
    "SETTINGS", "TRACES", "SUMMARY", "POSTERIOR_DIR", "PARTIAL_DIR", "COMPARISON", "POOLED",
    "BUDGET", "STIFFENING", "GROUNDTRUTH", "GROUNDTRUTH_SUMMARY", "GAP", "REPORT",
    "COMPARE_OUTPUTS",
    "FIT_OUTPUTS", "REPLAY_HISTORY", "REPLAY_SUMMARY", "REPLAY_FIGURE", "posterior_path",
    "posterior_file", "partial_path",
]

#: Fit options, seed and versions (``palpbayes fit``).
SETTINGS = "settings.json"
#: The manifest rows that were fitted (``palpbayes fit``).
TRACES = "traces.csv"
#: One row per trace and method (``palpbayes fit``).
SUMMARY = "summary.csv"
#: Folder of per-trace netCDF posteriors ``<trace_id>.nc`` (``palpbayes fit``, Bayes).
POSTERIOR_DIR = "posterior"
#: Folder of per-trace JSON records ``<trace_id>.json`` kept for ``--resume``.
PARTIAL_DIR = ".partial"
#: Per material × tip × method comparison (``palpbayes compare``).
COMPARISON = "comparison.csv"
#: Hierarchical pooling per material × tip (``palpbayes compare``, Bayes rows only).
POOLED = "pooled.csv"
#: Uncertainty budget per material × tip (``palpbayes compare``).
BUDGET = "budget.csv"
#: Stiffening law per material × tip (``palpbayes compare``, series with rest times only).
STIFFENING = "stiffening.csv"
#: Per compression test ground truth (``palpbayes groundtruth``).
GROUNDTRUTH = "groundtruth.csv"
#: Per material ground truth (``palpbayes groundtruth``).
GROUNDTRUTH_SUMMARY = "groundtruth_summary.csv"
#: The paper's robot-vs-Instron gap decomposed (:func:`palpbayes.gap.gap_table`), written by
#: the report pipeline when the campaign has the paper's materials.
GAP = "gap.csv"
#: The PDF report (``palpbayes report``).
REPORT = "report.pdf"
#: One row per online update of a replayed trace (``palpbayes replay --out``).
REPLAY_HISTORY = "replay.csv"
#: Where the stopping rule fired, against the whole trace (``palpbayes replay --out``).
REPLAY_SUMMARY = "replay_summary.csv"
#: The interval of E narrowing with depth (``palpbayes replay --out``).
REPLAY_FIGURE = "replay.png"

#: Tables written by ``palpbayes compare`` (derived from the fit: stale after a refit).
COMPARE_OUTPUTS = (COMPARISON, POOLED, BUDGET, STIFFENING)
#: Files that depend on the fit, removed by ``fit --force`` before a new run (the folders
#: :data:`POSTERIOR_DIR` and :data:`PARTIAL_DIR` are emptied as well).  The ground-truth tables
#: come from the compression tests, not from the fit, and are kept.
FIT_OUTPUTS = (SUMMARY, SETTINGS, TRACES, *COMPARE_OUTPUTS, REPORT)


def posterior_file(posterior_dir: str | os.PathLike, trace_id: str) -> Path:
    """``posterior_dir/<trace_id>.nc``: a trace's netCDF posterior in a posterior folder."""
    return Path(posterior_dir) / f"{trace_id}.nc"


def posterior_path(results_dir: str | os.PathLike, trace_id: str) -> Path:
    """``results_dir/posterior/<trace_id>.nc``."""
    return posterior_file(Path(results_dir) / POSTERIOR_DIR, trace_id)


def partial_path(results_dir: str | os.PathLike, trace_id: str) -> Path:
    """``results_dir/.partial/<trace_id>.json``."""
    return Path(results_dir) / PARTIAL_DIR / f"{trace_id}.json"
