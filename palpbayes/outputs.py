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
      stiffening_parameters.csv  its parameters, 90 % intervals  (compare)
      stiffening_curves.csv    its E(t) band per group           (compare)
      indentation.csv          each trace replayed online: where it stopped (compare)
      groundtruth.csv          per compression test              (groundtruth)
      groundtruth_summary.csv  per material                      (groundtruth)
      groundtruth_laws.csv     per material × hyperelastic law   (groundtruth --law)
      gap.csv                  the paper's robot-vs-Instron gap   (report, paper's materials)
      gap_strain.csv           the same gap at finite strain      (report, paper's materials)
      rheology.csv             one row per trace × relaxation model    (fit --rheology)
      rheology/<trace>_<model>.nc  a viscoelastic fit's draws, bands  (fit --rheology)
      rheology_pooled.csv      one row per specimen × tip, speeds pooled (fit --rheology power-law)
      report.pdf               the PDF report                    (report)

Modules use these constants and helpers instead of literals, so that a file added here is also
removed by ``fit --force`` (:data:`FIT_OUTPUTS`; :data:`RHEOLOGY_OUTPUTS` and the folder
:data:`RHEOLOGY_DIR` for ``fit --rheology``) and a renamed file cannot leave a reader behind.
"""

from __future__ import annotations

import os
from pathlib import Path

__all__ = [
    "SETTINGS", "TRACES", "SUMMARY", "POSTERIOR_DIR", "PARTIAL_DIR", "COMPARISON", "POOLED",
    "BUDGET", "STIFFENING", "STIFFENING_PARAMETERS", "STIFFENING_CURVES",
    "INDENTATION", "GROUNDTRUTH", "GROUNDTRUTH_SUMMARY", "GROUNDTRUTH_LAWS", "GAP", "GAP_STRAIN",
    "SHIPPED_GAP_STRAIN", "REPORT",
    "COMPARE_OUTPUTS",
    "FIT_OUTPUTS", "REPLAY_HISTORY", "REPLAY_SUMMARY", "REPLAY_FIGURE", "posterior_path",
    "posterior_file", "partial_path", "RHEOLOGY_TABLE", "RHEOLOGY_DIR", "RHEOLOGY_OUTPUTS",
    "RHEOLOGY_POOLED",
    "rheology_fit_path",
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
#: The preferred stiffening law's parameters with 90 % intervals, per material × tip
#: (``palpbayes compare``).
STIFFENING_PARAMETERS = "stiffening_parameters.csv"
#: The preferred stiffening law's median and 90 % band of E(t) per material × tip
#: (``palpbayes compare``).
STIFFENING_CURVES = "stiffening_curves.csv"
#: Each trace replayed through the online estimator: where a ±2 % rule stopped
#: (``palpbayes compare``, :mod:`palpbayes.campaign.indentation`).
INDENTATION = "indentation.csv"
#: Per compression test ground truth (``palpbayes groundtruth``).
GROUNDTRUTH = "groundtruth.csv"
#: Per material ground truth (``palpbayes groundtruth``).
GROUNDTRUTH_SUMMARY = "groundtruth_summary.csv"
#: Hyperelastic laws compared per material (``palpbayes groundtruth --law``).
GROUNDTRUTH_LAWS = "groundtruth_laws.csv"
#: The paper's robot-vs-Instron gap decomposed (:func:`palpbayes.gap.gap_table`), written by
#: the report pipeline when the campaign has the paper's materials.
GAP = "gap.csv"
#: The gap at finite strain (:func:`palpbayes.gap_strain.strain_table`: a foam that softens
#: pressed on the blocks' finite-strain twins), copied from the package's data by the report
#: pipeline beside ``gap.csv``.
GAP_STRAIN = "gap_strain.csv"
#: The finite-strain gap table shipped with the source checkout, relative to the repository
#: root (``python -m palpbayes.gap_strain OUT.csv`` writes it: minutes of finite elements).
SHIPPED_GAP_STRAIN = Path("data") / "gap-strain" / GAP_STRAIN
#: One row per trace × relaxation model (``palpbayes fit --rheology power-law|sls``).
RHEOLOGY_TABLE = "rheology.csv"
#: Folder of the stored viscoelastic fits ``<trace_id>_<rheology>.nc``
#: (``palpbayes fit --rheology``; read by the report).
RHEOLOGY_DIR = "rheology"
#: One row per specimen × tip: the power law pooled over its traces at several speeds
#: (``palpbayes fit MANIFEST --rheology power-law``, :mod:`palpbayes.rheology.campaign`).
RHEOLOGY_POOLED = "rheology_pooled.csv"
#: The PDF report (``palpbayes report``).
REPORT = "report.pdf"
#: One row per online update of a replayed trace (``palpbayes replay --out``).
REPLAY_HISTORY = "replay.csv"
#: Where the stopping rule fired, against the whole trace (``palpbayes replay --out``).
REPLAY_SUMMARY = "replay_summary.csv"
#: The interval of E narrowing with depth (``palpbayes replay --out``).
REPLAY_FIGURE = "replay.png"

#: Tables written by ``palpbayes compare`` (derived from the fit: stale after a refit).
COMPARE_OUTPUTS = (COMPARISON, POOLED, BUDGET, STIFFENING, STIFFENING_PARAMETERS,
                   STIFFENING_CURVES, INDENTATION)
#: Files that depend on the fit, removed by ``fit --force`` before a new run (the folders
#: :data:`POSTERIOR_DIR` and :data:`PARTIAL_DIR` are emptied as well).  The ground-truth tables
#: come from the compression tests, not from the fit, and are kept.
FIT_OUTPUTS = (SUMMARY, SETTINGS, TRACES, *COMPARE_OUTPUTS, REPORT)
#: Files that depend on a viscoelastic fit, removed before ``fit --rheology`` writes anew (the
#: folder :data:`RHEOLOGY_DIR` is emptied of its ``*.nc`` as well); the elastic fit's files are
#: kept, and ``fit --force`` of the elastic fit keeps these.
RHEOLOGY_OUTPUTS = (RHEOLOGY_TABLE, RHEOLOGY_POOLED, REPORT)


def posterior_file(posterior_dir: str | os.PathLike, trace_id: str) -> Path:
    """``posterior_dir/<trace_id>.nc``: a trace's netCDF posterior in a posterior folder."""
    return Path(posterior_dir) / f"{trace_id}.nc"


def posterior_path(results_dir: str | os.PathLike, trace_id: str) -> Path:
    """``results_dir/posterior/<trace_id>.nc``."""
    return posterior_file(Path(results_dir) / POSTERIOR_DIR, trace_id)


def partial_path(results_dir: str | os.PathLike, trace_id: str) -> Path:
    """``results_dir/.partial/<trace_id>.json``."""
    return Path(results_dir) / PARTIAL_DIR / f"{trace_id}.json"


def rheology_fit_path(results_dir: str | os.PathLike, trace_id: str, rheology: str) -> Path:
    """``results_dir/rheology/<trace_id>_<rheology>.nc``: one trace's stored viscoelastic fit
    with one relaxation model (``power-law``, ``sls``)."""
    return Path(results_dir) / RHEOLOGY_DIR / f"{trace_id}_{rheology}.nc"
