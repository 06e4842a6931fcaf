"""The results folder of a campaign fit, read back: the tables and the per-trace posteriors.

A results folder is written by :func:`palpbayes.campaign.fit_campaign` (``palpbayes fit``), the
ground-truth step (``palpbayes groundtruth``) and the compare step (``palpbayes compare``):

    summary.csv               one row per trace × method (:data:`~.fitjob.SUMMARY_COLUMNS`)
    settings.json             palpbayes version, fit options, source, seed
    traces.csv                geometry and file of every trace
    posterior/<trace_id>.nc   the Bayesian posterior of each trace (arviz netCDF)
    comparison.csv, pooled.csv, budget.csv, stiffening.csv   the compare step's tables
    groundtruth.csv, groundtruth_summary.csv                  per-test and per-material GT
    rheology.csv, rheology/<trace_id>_<model>.nc              viscoelastic fits (fit --rheology)

:func:`load_results` reads the tables into a :class:`ResultsFolder`; :func:`load_fit` rebuilds
one trace's :class:`~palpbayes.bayes.BayesResult`, equal to the one that was saved;
:func:`load_rheology_table` reads ``rheology.csv`` (its stored fits:
:func:`palpbayes.rheology.load_rheology_fit`).  Reading only: nothing here writes
(docs/design.md §4).
"""

from __future__ import annotations

import json
import os
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from .. import outputs
from ..contact import registered_kinds
from ..errors import DataFileError, InputError
from ..flagcodes import flag_columns

if TYPE_CHECKING:
    from ..bayes.result import BayesResult

__all__ = [
    "TIP_ORDER",
    "MATERIAL_ORDER",
    "ordered",
    "ResultsFolder",
    "load_results",
    "load_fit",
    "load_rheology_table",
]

#: Order of tips in tables and figures: the contact registry's display order (the paper's
#: flat, sphere, paraboloid first); kinds not registered after, as found.
TIP_ORDER = registered_kinds()
#: Order of materials in tables and figures (the paper's foams first).
MATERIAL_ORDER = ("White", "Pink", "Grey")


def ordered(values: Iterable[str], preferred: Sequence[str]) -> list[str]:
    """The distinct ``values`` (as strings), those in ``preferred`` first in its order."""
    vals = list(dict.fromkeys(str(v) for v in values))
    first = [p for p in preferred if p in vals]
    return first + [v for v in vals if v not in first]


#: Columns renamed since a results folder may have been written (old name -> new name).
RENAMED_COLUMNS = {"gt_in_interval": "gt_in_new_interval", "z_score": "gt_z_new"}

_STR_COLUMNS = ("trace_id", "material", "tip", "method", "notes", "flag_codes", "flag_level",
                "flags", "specimen", "file", "input", "distribution", "representative_trace",
                "nu_source")


def _read_csv(path: Path) -> pd.DataFrame | None:
    """A table with its label columns as strings (missing labels as ''), or None."""
    if not path.is_file():
        return None
    try:
        head = pd.read_csv(path, nrows=0).columns
        df = pd.read_csv(path, dtype={c: str for c in _STR_COLUMNS if c in head})
        for c in ("material", "notes", "flag_codes", "flag_level", "flags", "specimen"):
            if c in df.columns:
                df[c] = df[c].fillna("")
        if "flags" in df.columns and "notes" not in df.columns:  # written before the rename
            cols = pd.DataFrame([flag_columns(t) for t in df.pop("flags")], index=df.index)
            df = pd.concat([df, cols], axis=1)
        return df.rename(columns={k: v for k, v in RENAMED_COLUMNS.items() if v not in df})
    except (pd.errors.EmptyDataError, pd.errors.ParserError, UnicodeDecodeError) as exc:
        raise DataFileError(path, f"cannot be read as CSV ({exc})",
                            "rerun the step that writes it") from None


@dataclass
class ResultsFolder:
    """The tables of a results folder (None for a file that is not there).

    Attributes
    ----------
    path
        The folder.
    summary
        ``summary.csv``: one row per trace × method
        (:data:`palpbayes.campaign.fitjob.SUMMARY_COLUMNS`).
    settings
        ``settings.json`` as a dict ({} if absent).
    traces
        ``traces.csv``: geometry and file of every trace.
    comparison, pooled, budget, stiffening, stiffening_parameters, stiffening_curves
        The compare step's tables.
    indentation
        Each trace replayed online (``indentation.csv``, the compare step).
    groundtruth, groundtruth_summary
        Per-test and per-material ground truth.
    gap
        The paper's robot-vs-Instron gap decomposed (``gap.csv``, :mod:`palpbayes.gap`).
    gap_strain
        The same at finite strain (``gap_strain.csv``, :mod:`palpbayes.gap_strain`).
    """

    path: Path
    summary: pd.DataFrame
    settings: dict = field(default_factory=dict)
    traces: pd.DataFrame | None = None
    comparison: pd.DataFrame | None = None
    pooled: pd.DataFrame | None = None
    budget: pd.DataFrame | None = None
    stiffening: pd.DataFrame | None = None
    stiffening_parameters: pd.DataFrame | None = None
    stiffening_curves: pd.DataFrame | None = None
    indentation: pd.DataFrame | None = None
    groundtruth: pd.DataFrame | None = None
    groundtruth_summary: pd.DataFrame | None = None
    gap: pd.DataFrame | None = None
    gap_strain: pd.DataFrame | None = None

    @property
    def options(self) -> dict:
        """The fit options (``settings.json`` ``options_fields``)."""
        return dict(self.settings.get("options_fields") or {})

    @property
    def name(self) -> str:
        """Campaign name: the campaign folder's name, else the results folder's."""
        camp = self.settings.get("campaign_dir")
        return Path(camp).name if camp else self.path.resolve().name

    def groups(self) -> list[tuple[str, str]]:
        """(material, tip) pairs in a stable order (paper order first)."""
        df = self.summary
        mats = ordered(df["material"].fillna("").astype(str), MATERIAL_ORDER)
        tips = ordered(df["tip"].astype(str), TIP_ORDER)
        have = set(zip(df["material"].fillna("").astype(str), df["tip"].astype(str),
                       strict=True))
        return [(m, t) for m in mats for t in tips if (m, t) in have]

    def bayes_rows(self) -> pd.DataFrame:
        return self.summary[self.summary["method"] == "bayes"]


def load_results(path: str | os.PathLike) -> ResultsFolder:
    """Read the tables of a results folder.

    Raises
    ------
    InputError
        ``path`` has no ``summary.csv``.
    """
    p = Path(path)
    summary = _read_csv(p / outputs.SUMMARY)
    if summary is None:
        raise InputError(f"{p}: no {outputs.SUMMARY}; run 'palpbayes fit' first, or give a "
                         "campaign folder or manifest to fit it")
    if summary.empty:
        raise DataFileError(p / outputs.SUMMARY, "has no rows")
    settings: dict = {}
    if (p / outputs.SETTINGS).is_file():
        try:
            settings = json.loads((p / outputs.SETTINGS).read_text(encoding="utf-8"))
        except (json.JSONDecodeError, UnicodeDecodeError) as exc:
            raise DataFileError(p / outputs.SETTINGS, f"not valid JSON ({exc})") from None
    return ResultsFolder(
        path=p, summary=summary, settings=settings,
        traces=_read_csv(p / outputs.TRACES), comparison=_read_csv(p / outputs.COMPARISON),
        pooled=_read_csv(p / outputs.POOLED), budget=_read_csv(p / outputs.BUDGET),
        stiffening=_read_csv(p / outputs.STIFFENING),
        stiffening_parameters=_read_csv(p / outputs.STIFFENING_PARAMETERS),
        stiffening_curves=_read_csv(p / outputs.STIFFENING_CURVES),
        indentation=_read_csv(p / outputs.INDENTATION),
        groundtruth=_read_csv(p / outputs.GROUNDTRUTH),
        groundtruth_summary=_read_csv(p / outputs.GROUNDTRUTH_SUMMARY),
        gap=_read_csv(p / outputs.GAP), gap_strain=_read_csv(p / outputs.GAP_STRAIN),
    )


def load_rheology_table(path: str | os.PathLike) -> pd.DataFrame | None:
    """``rheology.csv`` of a results folder (``palpbayes fit --rheology``): one row per trace ×
    relaxation model, ``trace_id``, ``rheology``, ``notes``, ``flag_codes`` and ``error`` as
    strings; None when the folder has none.

    Raises
    ------
    DataFileError
        The table cannot be read, has no rows or lacks ``trace_id`` / ``rheology``.
    """
    p = Path(path) / outputs.RHEOLOGY_TABLE
    if not p.is_file():
        return None
    try:
        head = pd.read_csv(p, nrows=0).columns
        text = ("trace_id", "source", "rheology", "segments", "flag_codes", "notes", "error")
        df = pd.read_csv(p, dtype={c: str for c in text if c in head})
    except (pd.errors.EmptyDataError, pd.errors.ParserError, UnicodeDecodeError) as exc:
        raise DataFileError(p, f"cannot be read as CSV ({exc})",
                            "rerun 'palpbayes fit --rheology ... --force'") from None
    missing = [c for c in ("trace_id", "rheology") if c not in df.columns]
    if missing or df.empty:
        raise DataFileError(p, f"no column {missing[0]!r}" if missing else "has no rows",
                            "rerun 'palpbayes fit --rheology ... --force'")
    for c in text:
        if c in df.columns:
            df[c] = df[c].fillna("")
    return df


def load_fit(results: ResultsFolder | str | os.PathLike, trace_id: str) -> BayesResult:
    """The Bayesian result of one trace, as it was saved (for plots and tables).

    Equal in every field to the :class:`~palpbayes.bayes.BayesResult` that
    :func:`~palpbayes.campaign.fitjob.fit_trace` saved: draws, estimates and intervals,
    diagnostics, ``converged``, warnings, model checks (with their details), the per-trace
    uncertainty budget and the contact model (:meth:`BayesResult.from_idata
    <palpbayes.bayes.BayesResult.from_idata>`).  The fitted data come from re-reading the trace
    file (``traces.csv``) with the reader and fit options of ``settings.json``, so the plots
    also show the loading samples outside the fit window; if the file is gone, or its points
    differ from the stored ones, the stored fitted points (``constant_data.z``,
    ``observed_data.force``) stand in for the loading segment (no pre-contact baseline).  The
    least-squares fit is recomputed on those data (deterministic, milliseconds).

    Raises
    ------
    InputError
        No posterior for ``trace_id``, or one written without the fit's state (an older
        palpbayes: refit).
    """
    from ..bayes.result import BayesResult, saved_model
    from ..errors import FitError
    from ..fitdata import prepare
    from ..io.manifest import load_trace
    from ..lsq import fit_lsq_data
    from ..pooling.inputs import fitdata_from_posterior, read_posterior

    res = results if isinstance(results, ResultsFolder) else load_results(results)
    path = outputs.posterior_path(res.path, trace_id)
    if not path.is_file():
        raise InputError(f"{path}: no posterior for trace {trace_id!r}")
    idata = read_posterior(path)
    try:
        model = saved_model(idata)
    except InputError as exc:
        raise InputError(f"{path}: {exc}") from None
    stored = fitdata_from_posterior(idata, model)
    data = None
    row = None
    if res.traces is not None:
        sel = res.traces[res.traces["trace_id"].astype(str) == trace_id]
        row = sel.iloc[0] if len(sel) else None
    file = "" if row is None else str(row.get("file", "") or "")
    if file and Path(file).is_file():
        opts = res.options
        try:
            trace = load_trace(row, **res.settings.get("read_options", {}))
            cand = prepare(trace, model, f_unc=stored.f_unc, fit_fraction=stored.fit_fraction,
                           max_depth=opts.get("max_depth"), tare=bool(opts.get("tare")))
            if np.array_equal(cand.z, stored.z) and np.array_equal(cand.force, stored.force):
                data = cand
        except InputError:
            data = None
    if data is None:  # the trace file is gone or changed: the fitted points stored in the netCDF
        data = stored
    try:  # the paper's least squares: a half-space
        lsq = fit_lsq_data(replace(data, model=model.half_space()), trace_id=trace_id)
    except FitError:
        lsq = None
    return BayesResult.from_idata(idata, data, lsq)
