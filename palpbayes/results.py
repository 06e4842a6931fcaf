"""The results folder of a campaign fit, read back: the tables and the per-trace posteriors.

A results folder is written by :func:`palpbayes.campaign.fit_campaign` (``palpbayes fit``), the
ground-truth step (``palpbayes groundtruth``) and the compare step (``palpbayes compare``):

    summary.csv               one row per trace × method (:data:`palpbayes.fitjob.SUMMARY_COLUMNS`)
    settings.json             palpbayes version, fit options, source, seed
    traces.csv                geometry and file of every trace
    posterior/<trace_id>.nc   the Bayesian posterior of each trace (arviz netCDF)
    comparison.csv, pooled.csv, budget.csv, stiffening.csv   the compare step's tables
    groundtruth.csv, groundtruth_summary.csv                  per-test and per-material GT

:func:`load_results` reads the tables into a :class:`ResultsFolder`; :func:`load_fit` rebuilds
one trace's :class:`~palpbayes.bayes.BayesResult` for plotting.  Reading only: nothing here
writes (docs/design.md §4).
"""

from __future__ import annotations

import json
import os
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from . import layout
from .contact import registered_kinds
from .errors import DataFileError, InputError
from .noise import PAPER_NOISE_PP

if TYPE_CHECKING:
    from .bayes.result import BayesResult

__all__ = [
    "PER_FILE_NAME",
    "SUMMARY_NAME",
    "TIP_ORDER",
    "MATERIAL_ORDER",
    "ordered",
    "ResultsFolder",
    "load_results",
    "load_fit",
]

#: Per-test ground-truth table of a results folder (``palpbayes groundtruth``).
PER_FILE_NAME = layout.GROUNDTRUTH
#: Per-material ground-truth table of a results folder.
SUMMARY_NAME = layout.GROUNDTRUTH_SUMMARY

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


_STR_COLUMNS = ("trace_id", "material", "tip", "method", "flags", "specimen", "file", "input",
                "distribution", "representative_trace")


def _read_csv(path: Path) -> pd.DataFrame | None:
    """A table with its label columns as strings (missing labels as ''), or None."""
    if not path.is_file():
        return None
    try:
        head = pd.read_csv(path, nrows=0).columns
        df = pd.read_csv(path, dtype={c: str for c in _STR_COLUMNS if c in head})
        for c in ("material", "flags", "specimen"):
            if c in df.columns:
                df[c] = df[c].fillna("")
        return df
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
        ``summary.csv``: one row per trace × method (:data:`palpbayes.fitjob.SUMMARY_COLUMNS`).
    settings
        ``settings.json`` as a dict ({} if absent).
    traces
        ``traces.csv``: geometry and file of every trace.
    comparison, pooled, budget, stiffening
        The compare step's tables.
    groundtruth, groundtruth_summary
        Per-test and per-material ground truth.
    """

    path: Path
    summary: pd.DataFrame
    settings: dict = field(default_factory=dict)
    traces: pd.DataFrame | None = None
    comparison: pd.DataFrame | None = None
    pooled: pd.DataFrame | None = None
    budget: pd.DataFrame | None = None
    stiffening: pd.DataFrame | None = None
    groundtruth: pd.DataFrame | None = None
    groundtruth_summary: pd.DataFrame | None = None

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
    summary = _read_csv(p / layout.SUMMARY)
    if summary is None:
        raise InputError(f"{p}: no {layout.SUMMARY}; run 'palpbayes fit' first, or give a campaign "
                         "folder or manifest to fit it")
    if summary.empty:
        raise DataFileError(p / layout.SUMMARY, "has no rows")
    settings: dict = {}
    if (p / layout.SETTINGS).is_file():
        try:
            settings = json.loads((p / layout.SETTINGS).read_text(encoding="utf-8"))
        except (json.JSONDecodeError, UnicodeDecodeError) as exc:
            raise DataFileError(p / layout.SETTINGS, f"not valid JSON ({exc})") from None
    return ResultsFolder(
        path=p, summary=summary, settings=settings,
        traces=_read_csv(p / layout.TRACES), comparison=_read_csv(p / layout.COMPARISON),
        pooled=_read_csv(p / layout.POOLED), budget=_read_csv(p / layout.BUDGET),
        stiffening=_read_csv(p / layout.STIFFENING),
        groundtruth=_read_csv(p / PER_FILE_NAME),
        groundtruth_summary=_read_csv(p / SUMMARY_NAME),
    )


def load_fit(results: ResultsFolder | str | os.PathLike, trace_id: str) -> BayesResult:
    """Rebuild the Bayesian result of one trace from its netCDF posterior (for plots).

    The fitted points come from re-reading the trace file (``traces.csv``) with the options of
    ``settings.json``, so the plots also show the loading samples outside the fit window; if the
    file is gone or its points differ from the stored ones, the stored fitted points
    (``constant_data.z``, ``observed_data.force``) are used alone.  The least-squares fit is
    recomputed on the same points (deterministic, milliseconds).  ``budget`` is None: the
    per-trace budget table is not stored (``budget.csv`` holds the group budgets).  The
    posterior flags and the model checks come back from the netCDF's posterior attributes, so a
    flagged fit is reloaded as flagged.

    Returns
    -------
    palpbayes.bayes.BayesResult
    """
    from .bayes.diagnostics import compute_diagnostics
    from .bayes.result import BayesResult
    from .checks import CheckResult
    from .errors import FitError
    from .fitdata import ModelSpec, prepare
    from .io.manifest import load_trace, tip_from_row
    from .lsq import fit_lsq_data
    from .pooling_inputs import fitdata_from_posterior, posterior_attrs, read_posterior

    res = results if isinstance(results, ResultsFolder) else load_results(results)
    path = layout.posterior_path(res.path, trace_id)
    if not path.is_file():
        raise InputError(f"{path}: no posterior for trace {trace_id!r}")
    idata = read_posterior(path)
    attrs = posterior_attrs(idata)
    opts = res.options
    z_fit = np.asarray(idata.constant_data["z"], dtype=float).ravel()
    f_fit = np.asarray(idata.observed_data["force"], dtype=float).ravel()
    nu = float(attrs.get("nu", opts.get("nu", 0.3)))
    row = None
    if res.traces is not None:
        sel = res.traces[res.traces["trace_id"].astype(str) == trace_id]
        row = sel.iloc[0] if len(sel) else None
    if row is None:
        raise InputError(f"{res.path}: traces.csv has no row for {trace_id!r}; cannot rebuild "
                         "the contact model")
    thickness = None
    if opts.get("thickness_correction"):
        thickness = float(row["thickness_m"])
    model = ModelSpec(tip_from_row(row), nu=nu, thickness=thickness,
                      bonded=bool(opts.get("bonded", True)))
    data = None
    f_unc = float(attrs.get("f_unc_n", opts.get("f_unc", PAPER_NOISE_PP)))
    fraction = attrs.get("fit_fraction", opts.get("fit_fraction"))
    file = str(row.get("file", "") or "")
    if file and Path(file).is_file():
        try:
            trace = load_trace(row)
            cand = prepare(trace, model, f_unc=f_unc,
                           fit_fraction=None if fraction is None else float(fraction),
                           max_depth=opts.get("max_depth"), tare=bool(opts.get("tare")))
            if cand.z.shape == z_fit.shape and np.allclose(cand.z, z_fit, rtol=0, atol=1e-12) \
                    and np.allclose(cand.force, f_fit, rtol=0, atol=1e-12):
                data = cand
        except InputError:
            data = None
    if data is None:  # the trace file is gone or changed: the fitted points stored in the netCDF
        data = fitdata_from_posterior(idata, model)
    names = [n for n in ("E_star", "z_surf", "sigma", "F0", "F1", "phi", "nu_t")
             if n in idata.posterior]
    srow = res.summary[(res.summary["trace_id"].astype(str) == trace_id)
                       & (res.summary["method"] == "bayes")]
    acc = float(srow["acceptance"].iloc[0]) if len(srow) else float("nan")
    steps = int(srow["n_steps"].iloc[0]) if len(srow) and pd.notna(srow["n_steps"].iloc[0]) \
        else int(attrs.get("n_steps", 0))
    diag = compute_diagnostics(idata, names, np.full(len(names), np.nan), acc, steps, False)
    try:
        lsq = fit_lsq_data(data, trace_id=trace_id)
    except FitError:
        lsq = None
    pattrs = dict(idata.posterior.attrs)
    flags = pattrs.get("flags", [])
    flags = [str(flags)] if isinstance(flags, str) else [str(f) for f in np.ravel(flags)]
    checks = [CheckResult(c["name"], c["statistic"], c["passed"], c["flag"], {})
              for c in json.loads(str(pattrs.get("model_checks", "[]")))]
    return BayesResult(idata=idata, diagnostics=diag, budget=None, data=data,
                       noise=str(attrs.get("noise_model", "gaussian")), trace_id=trace_id,
                       lsq=lsq, warnings=[f for f in flags if f], checks=checks,
                       baseline=str(attrs.get("baseline_model", "constant")),
                       z_ref=float(attrs.get("z_ref_m", 0.0)))
